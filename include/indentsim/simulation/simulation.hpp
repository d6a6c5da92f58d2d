#pragma once
// A run, from load case to P-alpha curve: plans and builds the mesh, assembles the elastic
// stiffness, sets up contact and the Newton solver, and steps the depth along the load path.
// The CLI is a thin layer over this class; the tests drive it directly.
#include <cstdint>
#include <functional>
#include <optional>
#include <memory>
#include <string>
#include <vector>

#include "indentsim/solvers/assembly.hpp"
#include "indentsim/solvers/condensation.hpp"
#include "indentsim/solvers/contact.hpp"
#include "indentsim/solvers/line_forces.hpp"
#include "indentsim/input/load_case.hpp"
#include "indentsim/simulation/increment_snapshot.hpp"
#include "indentsim/simulation/load_control.hpp"
#include "indentsim/simulation/load_stepping.hpp"
#include "indentsim/simulation/run_configuration.hpp"
#include "indentsim/simulation/simulation_state.hpp"
#include "indentsim/materials/material_parameter.hpp"
#include "indentsim/geometry/mesh.hpp"
#include "indentsim/base/phase_times.hpp"
#include "indentsim/solvers/inelastic_bulk.hpp"
#include "indentsim/solvers/solver.hpp"

namespace indentsim {

class Simulation {
public:
  /// Throws InputError when the load case asks for a model not available or a mesh too large.
  /// `planned_contact_half_width`, when given, sizes the mesh without a pilot run (a resumed run
  /// rebuilds exactly the mesh of the run it continues), and `near_field`, when given, is the
  /// condensed near field to solve for (a resumed run continues on the near field it had).
  explicit Simulation(LoadCase load_case, std::optional<double> planned_contact_half_width = std::nullopt,
                      std::optional<NearField> near_field = std::nullopt);
  /// A run on a given plan, no pilot: the error estimate's companion runs (error_estimate.hpp)
  /// use the main run's planned contact width with fewer contact nodes, and a new run whose plan
  /// was made first (its companions start from the plan) continues from it.  `times` holds the
  /// phases timed before (planning).
  Simulation(LoadCase load_case, const RunPlan& plan, PhaseTimes times = {});
  /// A run on a given configuration (a resumed run's: the configuration of the run it continues),
  /// starting on the near field `start` instead of the configuration's.
  Simulation(LoadCase load_case, const RunConfiguration& configuration, const NearField& start);
  ~Simulation();

  const LoadCase& load_case() const { return load_case_; }
  const MeshPlan& plan() const { return config_.plan.mesh; }
  /// Every choice of the run, "auto" resolved (resolve_choices).
  const RunConfiguration& configuration() const { return config_; }
  const Mesh& mesh() const { return *mesh_; }
  const ContactDiscretization& contact_boundary() const { return *contact_; }
  const BulkModel& bulk() const { return *bulk_; }
  /// The inelastic model, or nullptr for an elastic load case (which never enters plasticity code).
  /// The bulk's nonlinear part (plasticity, finite strain), or null for a linear elastic run.
  const NonlinearBulk* plasticity() const { return plastic_.get(); }
  /// Newton report of the last attempt (for diagnostics and tests).
  const NewtonReport& last_newton_report() const { return last_report_; }

  /// Steps the whole load path, calling `on_increment` after every converged increment (the
  /// initial state alpha = 0 included).  Throws SolverError when an increment cannot converge
  /// within the allowed cutbacks; the increments reported before stay valid.
  void run(const std::function<void(const IncrementRecord&)>& on_increment = {});

  /// Solves one increment from the current state to `target` of the load control: a depth
  /// alpha, or a force P (with cutbacks), over `duration` seconds (what a rate-dependent law
  /// flows over; 0 on a path without time).
  IncrementRecord advance_to(double target, double duration = 0.0);
  /// What the load path steps (load.control).
  const LoadControl& load_control() const { return *control_; }

  /// The run state, with the bulk model's material history and the contact set filled in.
  SimulationState state() const;
  /// Continues from a saved state (same load case physics, same mesh); throws
  /// std::invalid_argument when the state does not fit this mesh and model.
  void restore(const SimulationState& state);
  std::uint64_t next_target() const { return state_.next_target; }

  /// The current (converged) state as the writers read it, `record` its row; valid until the
  /// simulation moves on.
  IncrementSnapshot snapshot(const IncrementRecord& record) const;

  /// Newton's measure of how far the current state is from equilibrium: the largest |F_i| of the
  /// Newton system's residual at u (the condensed near field's, or the whole mesh's) over the
  /// force scale u converged on (SimulationState::residual_scale), the measure the iterations
  /// drive below solver.tolerance.
  double equilibrium_residual();
  /// The same measure for the previous converged state (u_previous at alpha_previous), as far as
  /// the current state allows: the whole residual for a model without history; for an inelastic
  /// model, whose history has moved on since, only the contact rows' kinematic part (no surface
  /// node past the punch: max(0, c_k * penetration)).
  double previous_state_residual();

  double alpha() const { return state_.alpha; }
  const std::vector<double>& displacement() const { return state_.u; }
  ContactResult contact() const;
  double contact_half_width() const;
  /// The exact unloading stiffness -dP/d(alpha) at the current state (unloading_stiffness.hpp).
  double unloading_stiffness() const;
  /// The same of a contact state `c` evaluated at the current state.
  double unloading_stiffness(const ContactResult& c) const;
  /// The depth at which the punch would first touch the current surface (touch_depth): after
  /// separation, the residual depth of the imprint where the punch left it.
  double free_surface_depth() const;
  std::vector<LineForce> line_forces() const;
  /// dP/d(theta) and du/d(theta) at the current state for each parameter, by forward sensitivity
  /// through the converged Newton system: at fixed depth F(u(theta); theta) = 0, so J du/d(theta) =
  /// -dF/d(theta) (one factorization of J at u, one solve per parameter), and P = -f sum r_k over
  /// the contact nodes moves with dr_k = dF_k/d(theta) + K_t du/d(theta).  Available for the elastic
  /// model and for Ilyushin's law, for E, e0, yield_stress, kappa and n (E at fixed e0, or at fixed
  /// yield_stress when the load case gives the material that way).  On Ilyushin's unloading branch
  /// the stresses depend on theta through the peak strain too: a call at the peak (any loading
  /// state) records d eps*/d theta for the unloading states after it, so the call must be made at
  /// the last loading state before the path turns (ForwardModel calls it at every data depth of a
  /// curve, and at each descent_starts() increment of an imprint's path).
  /// nullopt otherwise (nu, J2's history, an unloading state without the peak's record, or one
  /// restored from a checkpoint): finite differences of whole runs are then the way.  Counts its
  /// factorization.
  struct Sensitivities {
    std::vector<double> force;                      ///< dP/d(theta) [N or N/m per unit of theta]
    std::vector<std::vector<double>> displacement;  ///< [parameter][equation] du/d(theta), whole mesh
                                                    ///< (empty unless asked for)
  };
  std::optional<Sensitivities> sensitivities(const std::vector<MaterialParameter>& parameters,
                                             bool with_displacement = false);
  /// The force part of sensitivities().
  std::optional<std::vector<double>> force_sensitivities(const std::vector<MaterialParameter>& parameters);
  long symbolic_analyses() const {
    return retired_symbolic_analyses_ + (newton_ ? newton_->total_symbolic_analyses() : 0) +
           (depth_newton_ ? depth_newton_->total_symbolic_analyses() : 0);
  }
  /// The largest condition estimate of any converged increment's Jacobian so far.
  double largest_condition_estimate() const { return largest_condition_; }
  /// The sparse direct solver chosen for this run (solver.linear, "auto" resolved).
  LinearSolverKind linear_solver() const { return config_.linear_solver; }
  /// Warnings raised so far (each once), e.g. a contact zone that left the fine zone.
  const std::vector<std::string>& warnings() const { return state_.warnings; }
  /// The part of the mesh the Newton iterations solve for (condensed or not).
  const NearField& near_field() const { return state_.near_field; }
  /// Unknowns of each Newton system: the condensed near field, or all free equations.
  std::int64_t system_unknowns() const;
  /// Times the near field had to grow (a far element would have yielded, or a far surface node
  /// would have penetrated the punch) and an increment was repeated.
  int near_field_growths() const { return near_field_growths_; }
  /// How often the near field was grown ahead of the plastic zone (anticipate_plastic_zone).
  int near_field_rebuilds() const { return near_field_rebuilds_; }
  /// The pilot's plastic zone by depth (empty without a pilot); a resumed run has it from its
  /// checkpoint.
  const PlasticZoneGrowth& plastic_zone_growth() const { return state_.plastic_zone_growth; }
  /// Wall-clock time of this simulation's phases: planning (with the pilot run), model (mesh,
  /// assembly, laws, contact, condensation, KINSOL set-up), stepping (the increments, including a
  /// rebuild when the near field grows).  The driver adds its own (output).
  PhaseTimes& times() { return times_; }
  const PhaseTimes& times() const { return times_; }

private:
  /// Builds mesh, laws, contact and the Newton system on `configuration`, on the near field
  /// `start` if given.
  void build(const RunConfiguration& configuration, const std::optional<NearField>& start = std::nullopt);
  /// The point laws of the specimen's material regions, and the bulk over them (plastic_).
  void build_material_laws();
  struct SolveCounters {
    long iterations = 0, factorizations = 0;
  };
  /// The Newton solve at `trial` of the load control, reached over `time_step` seconds, with its
  /// globalisation ladder; true if it converged (the solution in system_guess_).
  bool solve_at(double trial, double time_step, SolveCounters& counters, const std::function<void()>& stop_if_requested);
  /// Force control's target 0: the specimen off the punch, solved at a depth clear of it and
  /// reported where the punch just touches it (touch_depth).
  bool solve_released(SolveCounters& counters);
  /// The Newton solve at fixed depth from x (the Newton system's unknowns, under force control
  /// with the depth last, which is set to `depth`).
  NewtonReport solve_at_depth(double depth, std::vector<double>& x, Globalization globalization);
  /// The depth of a converged system solution: the unknown under force control, else `trial`.
  double solved_depth(double trial) const;
  /// Makes the converged trial (in guess_, at depth `depth`) the current state.
  void commit(double trial, double depth);
  /// Sets the law's branch to the committed state's: Ilyushin's loading flag is set for each trial
  /// (solve_at), and at a committed state it is alpha >= deepest.
  void take_committed_branch();
  IncrementRecord record(double wall_seconds, long iterations, long factorizations, int cutbacks);
  /// Initial guess for `trial` of the load control into guess_ and system_guess_ (counts any solve
  /// it needs).
  void predict(double trial, long& iterations, long& factorizations);
  /// Force control: a first depth for target force `trial` where the state has none to
  /// extrapolate (a virgin specimen, or one off the punch).
  double first_depth_guess(double trial) const;
  /// The depth at which the punch first touches the committed surface, min_k (g_k - v_k) at the
  /// candidates' reference abscissae; of a whole-mesh displacement u.
  double touch_depth() const;
  double touch_depth_of(const std::vector<double>& u) const;
  /// The depth an increment to `target` is expected to reach: the target itself under depth
  /// control; under force control the depth estimate scaled by the punch's force exponent.
  double expected_depth(double target) const;
  /// Under force control, why a failed increment failed if the force has reached a limit load
  /// (dP/dalpha small against P / alpha), as the tail of its message; "" otherwise.
  std::string limit_load_note() const;
  /// Every surface node of the committed state strictly below the punch (no contact, no load).
  bool clear_of_punch() const;
  void check_fine_zone(double half_width);
  /// (Re)builds the Newton system for the state's near field: condensation, operators, contact, KINSOL.
  void build_system();
  /// The bulk operators the Newton system uses (plastic, and linear elastic for the predictor).
  BulkOperator& system_bulk();
  BulkOperator& system_elastic_bulk();
  /// The contact rows of the Newton system (the condensed near field's candidates, or all).
  const ContactDiscretization& system_contact() const { return condensation_ ? condensation_->contact() : *contact_; }
  /// Hands the committed whole-mesh displacement u to contact rows that carry history (friction),
  /// the mesh's and the Newton system's.
  void hold_committed_contact_state(const std::vector<double>& u);
  /// The Newton system's residual at the whole-mesh displacement u, max |F_i| / force_scale.
  double system_residual(const std::vector<double>& u, double alpha, double force_scale);
  /// The Newton system's unknowns of a whole-mesh displacement u at depth alpha (alpha appended
  /// under force control), and back.
  void to_system(const std::vector<double>& u, double alpha, std::vector<double>& x) const;
  void to_system(const std::vector<double>& u, std::vector<double>& u_system) const;
  void from_system(const std::vector<double>& u_system, std::vector<double>& u) const;
  /// In a condensed run: grows the near field if the converged full solution `u` at depth `alpha` breaks the
  /// condensation's assumption; true if it grew (the increment must be repeated).
  bool grow_near_field(const std::vector<double>& u, double alpha);
  /// Grows the near field ahead of the pilot's plastic zone before an increment to `target`.
  void anticipate_plastic_zone(double target);

  LoadCase load_case_;
  RunConfiguration config_;
  std::unique_ptr<Mesh> mesh_;
  std::unique_ptr<StiffnessPattern> pattern_;
  std::unique_ptr<ElasticStiffness> stiffness_;
  std::unique_ptr<NonlinearBulk> plastic_;
  BulkModel* bulk_ = nullptr;  // stiffness_ or plastic_
  std::unique_ptr<ContactDiscretization> contact_;
  NewtonSettings settings_;
  std::unique_ptr<FarFieldCondensation> condensation_;      // null when the whole mesh is solved
  std::unique_ptr<CondensedBulk> condensed_bulk_, condensed_elastic_;
  std::unique_ptr<ContactEquations> equations_;             // at fixed depth
  std::unique_ptr<IncrementEquations> controlled_;          // force control's bordered system, else null
  std::unique_ptr<NewtonSolver> newton_;                    // null until the system is built
  std::unique_ptr<NewtonSolver> depth_newton_;              // force control's solves at fixed depth (built when needed)
  std::unique_ptr<LoadControl> control_;
  long retired_symbolic_analyses_ = 0;                      // of systems replaced by a larger near field
  int near_field_growths_ = 0;
  int near_field_rebuilds_ = 0;

  /// The run state (its material history lives in the bulk model: state() adds it).
  SimulationState state_;
  std::vector<double> guess_, system_guess_;  // the trial solution of an increment
  NewtonReport last_report_;
  PhaseTimes times_;
  double largest_condition_ = 0.0;
};

}  // namespace indentsim
