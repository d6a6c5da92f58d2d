#include "indentsim/simulation/simulation.hpp"
#include "indentsim/solvers/unloading_stiffness.hpp"
#include "indentsim/solvers/coulomb_contact.hpp"
#include "indentsim/solvers/coulomb_current_configuration_contact.hpp"
#include "indentsim/solvers/integrated_gap_contact.hpp"
#include "indentsim/solvers/current_configuration_contact.hpp"
#include "indentsim/solvers/finite_strain_bulk.hpp"
#include "indentsim/base/worker_threads.hpp"
#include "indentsim/materials/region_law.hpp"

#include "indentsim/base/interruption.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>

#include <fmt/format.h>

#include "indentsim/base/error.hpp"

namespace indentsim {

namespace {

// Under force control, an increment that fails where the loading tangent dP/dalpha has fallen
// below half the secant P / alpha is taken to be at a limit load (a power law P ~ alpha^m
// has tangent / secant = m, 1 to 2 for the shapes here).
constexpr double limit_tangent_ratio = 0.5;

// Deformation theory is exact for monotone loading; Ilyushin's unloading rule is switched on
// only when the load path itself unloads (a scene that never unloads does not pay for it).
bool unloads(const std::vector<double>& path) {
  for (std::size_t k = 1; k < path.size(); ++k)
    if (path[k] < path[k - 1]) return true;
  return false;
}

// Ilyushin's law of a material, checked: validate() refused a flow-stress law (power_law, ludwik,
// ...) under Ilyushin's model; what it cannot see is the law's admissibility, named here with
// the key of the region (`key_prefix` "layer[k]." for a layer).
IlyushinLaw ilyushin_law(const MaterialInput& m, const std::string& source, const std::string& key_prefix) {
  IlyushinLaw law(ElasticMaterial{m.E, m.nu}, m.e0, m.hardening, m.kappa, m.n);
  if (auto violation = law.admissibility_violation())
    throw InputError(source, key_prefix + (m.hardening == HardeningLaw::linear ? "material.kappa" : "material.n"),
                     *violation);
  return law;
}

// The small-strain point law of one material over `points` Gauss points: elasticity's, J2's or
// Ilyushin's (with his unloading rule where the path unloads).
std::unique_ptr<PointLaw> small_strain_law(const MaterialInput& m, std::size_t points, bool unloading_rule,
                                           const std::string& source, const std::string& key_prefix) {
  const ElasticMaterial material{m.E, m.nu};
  switch (m.model) {
    case MaterialModel::elastic: return std::make_unique<ElasticPointLaw>(material);
    case MaterialModel::j2:
      if (!m.flow_stress_law()) (void)ilyushin_law(m, source, key_prefix);  // omega(e_u)'s hardening, checked alike
      return std::make_unique<J2PointLaw>(J2Law(material, make_flow_rule(m)), points);
    case MaterialModel::ilyushin:
      return std::make_unique<IlyushinPointLaw>(ilyushin_law(m, source, key_prefix), unloading_rule, points);
  }
  throw std::logic_error("small_strain_law: unknown material model");
}

// The finite-strain point law of one material (docs/MODEL.md §12): the small-strain law on the
// logarithmic strains.
std::unique_ptr<FiniteStrainPointLaw> finite_strain_law(const MaterialInput& m, std::size_t points, bool unloading_rule,
                                                        const std::string& source, const std::string& key_prefix) {
  const ElasticMaterial material{m.E, m.nu};
  switch (m.model) {
    case MaterialModel::elastic: return std::make_unique<HenckyPointLaw>(material, nullptr, m.elastic_stress);
    case MaterialModel::j2:
      if (!m.flow_stress_law()) (void)ilyushin_law(m, source, key_prefix);
      return std::make_unique<J2LogStrainPointLaw>(J2Law(material, make_flow_rule(m)), points, m.elastic_stress);
    case MaterialModel::ilyushin:
      return std::make_unique<HenckyPointLaw>(
          material, std::make_unique<IlyushinPointLaw>(ilyushin_law(m, source, key_prefix), unloading_rule, points),
          m.elastic_stress);
  }
  throw std::logic_error("finite_strain_law: unknown material model");
}

}  // namespace

Simulation::Simulation(LoadCase load_case, std::optional<double> planned_contact_half_width,
                       std::optional<NearField> near_field) {
  RunConfiguration configuration;
  {
    const PhaseTimes::Scope timing = times_.measure("planning");
    load_case_ = with_depth_estimate(std::move(load_case));
    configuration = resolve_choices(load_case_, plan_run(load_case_, planned_contact_half_width), near_field);
  }
  build(configuration);
}

Simulation::Simulation(LoadCase load_case, const RunPlan& plan, PhaseTimes times)
    : load_case_(std::move(load_case)), times_(std::move(times)) {
  RunConfiguration configuration;
  {
    const PhaseTimes::Scope timing = times_.measure("planning");
    configuration = resolve_choices(load_case_, plan);
  }
  build(configuration);
}

Simulation::Simulation(LoadCase load_case, const RunConfiguration& configuration, const NearField& start)
    : load_case_(std::move(load_case)) {
  build(configuration, start);
}

void Simulation::build(const RunConfiguration& configuration, const std::optional<NearField>& start) {
  limit_library_threads();  // one BLAS/OpenMP thread per run (worker_threads.hpp)
  config_ = configuration;
  control_ = LoadControl::of(load_case_);
  const MeshPlan& plan = config_.plan.mesh;
  const PhaseTimes::Scope timing = times_.measure("model");
  mesh_ = std::make_unique<Mesh>(Mesh::from_plan(load_case_, plan));
  mesh_->set_element_kind(config_.element);
  pattern_ = std::make_unique<StiffnessPattern>(*mesh_);
  std::vector<ElasticMaterial> elastic_by_region;
  for (std::size_t r = 0; r < load_case_.regions(); ++r)
    elastic_by_region.push_back({load_case_.region_material(r).E, load_case_.region_material(r).nu});
  stiffness_ = std::make_unique<ElasticStiffness>(*mesh_, elastic_by_region, *pattern_);
  bulk_ = stiffness_.get();
  build_material_laws();
  if (config_.strain == StrainChoice::finite && load_case_.contact.friction > 0.0)
    contact_ = std::make_unique<CoulombCurrentConfigurationContact>(*mesh_, make_punch(load_case_.punch), *pattern_,
                                                                    stiffness_->values(), load_case_.contact.friction);
  else if (config_.strain == StrainChoice::finite)
    contact_ = std::make_unique<CurrentConfigurationContact>(*mesh_, make_punch(load_case_.punch), *pattern_,
                                                             stiffness_->values());
  else if (load_case_.contact.discretization == ContactDiscretizationChoice::integrated_gap)
    contact_ = std::make_unique<IntegratedGapContact>(*mesh_, make_punch(load_case_.punch), *pattern_,
                                                      stiffness_->values(), load_case_.contact.penalty);
  else if (load_case_.contact.friction > 0.0)
    contact_ = std::make_unique<CoulombNodeToRigidContact>(*mesh_, make_punch(load_case_.punch), *pattern_,
                                                           stiffness_->values(), load_case_.contact.friction);
  else
    contact_ = std::make_unique<NodeToRigidContact>(*mesh_, make_punch(load_case_.punch), *pattern_, stiffness_->values());
  settings_.displacement_scale = load_case_.max_depth();
  // Newton's residual is measured against the nodal forces of the scene: E* alpha_max per unit
  // thickness in plane strain, times the ring 2 pi a* in axisymmetry (docs/DESIGN.md §3).
  // With layers, the stiffest region's E* (a scale, not physics: the largest keeps the tolerance
  // conservative; docs/MODEL.md §14.1).
  double modulus = 0.0;
  for (const ElasticMaterial& material : elastic_by_region) modulus = std::max(modulus, material.plane_strain_modulus());
  settings_.force_scale =
      mesh_->kinematics().nodal_force_scale(modulus * load_case_.max_depth(), plan.contact_half_width_estimate);
  settings_.tolerance = load_case_.solver.tolerance;
  settings_.max_iterations = load_case_.solver.max_newton;
  const JacobianChoice jacobian = config_.jacobian;
  settings_.newton_linear = jacobian == JacobianChoice::krylov ? NewtonLinearSolve::krylov : NewtonLinearSolve::direct;
  settings_.chord_steps = jacobian == JacobianChoice::reuse;
  state_.near_field = start.value_or(config_.near_field);
  state_.plastic_zone_growth = config_.plan.plastic_zone;
  build_system();

  state_.u.assign(static_cast<std::size_t>(mesh_->equations()), 0.0);
  state_.residual_scale = settings_.force_scale;  // u = 0 at alpha = 0 is in equilibrium on any scale

  const std::vector<std::string> implausible = plausibility_warnings(load_case_, plan);
  state_.warnings.insert(state_.warnings.end(), implausible.begin(), implausible.end());
}

// The point laws of the specimen's regions (docs/MODEL.md §14.1): in finite strain every run has
// one (elasticity too); in small strain an elastic specimen has none (the assembled K is its bulk)
// and an elastic region of an inelastic specimen has the elastic point law.  A specimen of one
// region gets its law itself; several get a region law over them.
void Simulation::build_material_laws() {
  const std::size_t points = 4 * static_cast<std::size_t>(mesh_->elements());
  const std::size_t regions = load_case_.regions();
  const bool finite = config_.strain == StrainChoice::finite;
  if (!finite && !load_case_.any_inelastic()) return;
  const bool unloading_rule = unloads(load_case_.load.path);
  std::optional<PointRegions> point_regions;
  if (regions > 1) {
    std::vector<int> point_region(points);
    for (int ei = 0; ei < mesh_->elements_x(); ++ei)
      for (int ej = 0; ej < mesh_->elements_y(); ++ej)
        for (std::size_t g = 0; g < 4; ++g)
          point_region[4 * static_cast<std::size_t>(mesh_->element(ei, ej)) + g] = mesh_->region(ej);
    point_regions.emplace(std::move(point_region), static_cast<int>(regions));
  }
  const auto region_points = [&](std::size_t r) { return point_regions ? point_regions->points(static_cast<int>(r)) : points; };
  const auto key_prefix = [](std::size_t r) { return r == 0 ? std::string() : fmt::format("layer[{}].", r); };
  if (finite) {
    // docs/MODEL.md §12: the laws of the logarithmic strain, the bulk in finite strain, the
    // contact on the current surface -- every run, elastic ones too.
    std::vector<std::unique_ptr<FiniteStrainPointLaw>> laws;
    for (std::size_t r = 0; r < regions; ++r)
      laws.push_back(finite_strain_law(load_case_.region_material(r), region_points(r), unloading_rule,
                                       load_case_.source, key_prefix(r)));
    std::unique_ptr<FiniteStrainPointLaw> law =
        regions == 1 ? std::move(laws.front()) : std::make_unique<RegionFiniteStrainLaw>(*point_regions, std::move(laws));
    plastic_ = std::make_unique<FiniteStrainBulk>(*stiffness_, std::move(law));
  } else {
    std::vector<std::unique_ptr<PointLaw>> laws;
    for (std::size_t r = 0; r < regions; ++r)
      laws.push_back(small_strain_law(load_case_.region_material(r), region_points(r), unloading_rule,
                                      load_case_.source, key_prefix(r)));
    std::unique_ptr<PointLaw> law =
        regions == 1 ? std::move(laws.front()) : std::make_unique<RegionPointLaw>(*point_regions, std::move(laws));
    plastic_ = std::make_unique<InelasticBulk>(*stiffness_, std::move(law));
  }
  bulk_ = plastic_.get();
}

Simulation::~Simulation() = default;

void Simulation::run(const std::function<void(const IncrementRecord&)>& on_increment) {
  const std::vector<double> targets = plan_increments(load_case_.load);
  // Each increment's duration (docs/MODEL.md §13.2), 0 on a path without time.
  const std::vector<double> times = plan_times(load_case_.load);
  while (state_.next_target < targets.size()) {
    const std::size_t k = state_.next_target;
    const double duration = k > 0 && k < times.size() ? times[k] - times[k - 1] : 0.0;
    const IncrementRecord r = advance_to(targets[k], duration);
    ++state_.next_target;  // before reporting: a checkpoint taken now continues with the next depth
    if (on_increment) on_increment(r);
  }
}

// One increment, as a script: a trial depth, the Newton solve with its globalisation ladder,
// then either the commit of a converged trial (after checking the condensation's assumptions),
// or a cutback.
IncrementRecord Simulation::advance_to(double target, double duration) {
  const PhaseTimes::Scope timing = times_.measure("stepping");
  const auto start = std::chrono::steady_clock::now();
  anticipate_plastic_zone(expected_depth(target));
  SolveCounters counters;
  int cutbacks = 0;
  // The sub-steps are fractions of the increment, in the controlled quantity and in time alike
  // (a hold moves only in time): `done` converged so far, `share` the next one's.  Both are sums
  // and halvings of 1, exact in binary.
  const double from = control_->committed(state_), span = target - from;
  double done = 0.0, share = 1.0;
  // The state of the last reported increment, saved before a converged sub-step (after a
  // cutback) moves the simulation past it: an interruption returns to it.
  std::optional<SimulationState> reported;
  // An increment that ends without a row (a signal, or no convergence) leaves the run at its last
  // reported state, which a checkpoint and the final fields then show: the sub-steps' commits
  // undone, and the law's branch that of the committed state (Ilyushin's loading flag is set for
  // each trial: committed, it is alpha >= deepest).
  const auto return_to_reported = [&] {
    if (reported) restore(*reported);
    else take_committed_branch();
  };
  const auto stop_if_requested = [&] {
    if (const int signal = interruption_requested()) {
      return_to_reported();
      throw Interrupted(signal);
    }
  };
  for (;;) {
    stop_if_requested();
    const double reach = std::min(1.0, done + share);
    const double trial = reach == 1.0 ? target : from + reach * span;
    const double time_step = (reach - done) * duration;
    if (solve_at(trial, time_step, counters, stop_if_requested)) {
      if (reach != 1.0 && !reported) {
        // The committed state as it stands: its instantaneous response (commit()'s comment).
        if (plastic_) plastic_->set_time_step(0.0);
        reported = state();
        if (plastic_) plastic_->set_time_step(time_step);
      }
      from_system(system_guess_, guess_);
      const double depth = solved_depth(trial);
      if (grow_near_field(guess_, depth)) {
        ++near_field_growths_;
        build_system();
        continue;  // the same trial on the larger near field
      }
      commit(trial, depth);
      done = reach;
      if (reach == 1.0) break;
      // Grow the sub-step back after an easy one.
      if (last_report_.iterations <= 3) share *= 2.0;
      continue;
    }
    // (Past some 50 halvings a sub-step no longer moves the sum of the converged ones.)
    if (cutbacks >= load_case_.solver.max_cutbacks || !(done + 0.5 * share > done)) {
      const NewtonReport report = last_report_;  // a copy: returning to the reported state may rebuild the system
      const std::string limit = limit_load_note();  // of the sub-steps that converged, before they are undone
      return_to_reported();
      const std::optional<std::string> cause = report.cycling ? contact_->known_cycling_cause() : std::nullopt;
      throw SolverError(fmt::format(
          "the increment from {} to {} did not converge after {} cutbacks (last try: {}, {} Newton iterations, "
          "scaled residual {:.3g}, KINSOL flag {}{}{}){}{}{}",
          control_->describe(control_->committed(state_)), control_->describe(target), cutbacks,
          control_->describe(trial), report.iterations, report.residual, report.kinsol_flag,
          report.message.empty() ? "" : ": ", report.message, cause ? ": " : "", cause ? *cause : "", limit));
    }
    share *= 0.5;
    ++cutbacks;
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return record(seconds, counters.iterations, counters.factorizations, cutbacks);
}

// KINSOL's line search first, with the whole iteration budget: it takes the full semi-smooth
// Newton step whenever that lowers the residual enough, and damps the steps that overshoot --
// at a load reversal the first step from the loading state raised the residual six-fold and the
// contact set cycled (the Berkovich cone's first unloading increment: 10 plain iterations wasted
// before the line search took 9).  Then full steps, for a quarter of the budget: from where the
// line search stopped if it was still converging as its iterations ran out, else from the
// predictor again (full steps can cross a kink of the active set where damped ones stall).
// Plain steps first, as before, took 16% more Newton iterations and 10% more factorizations
// over 110 random load cases of both scenes, every shape and material (none took 2% fewer), in
// the same wall time (the damped steps keep a factorization longer, at more GMRES iterations);
// on the shipped unloading cases they were 6-10% slower (benchmarks/random_cases.py).  (Going
// on from the best iterate of an attempt that cycled or diverged was tried too: on the cones'
// unloading it took as many iterations in all, on some increments more.)  The solution is left
// in system_guess_.
bool Simulation::solve_at(double trial, double time_step, SolveCounters& counters,
                          const std::function<void()>& stop_if_requested) {
  // Laws that follow the global load history (Ilyushin's unloading rule) need to know whether
  // this trial goes beyond the deepest point so far; rate-dependent laws, how long it takes.
  if (plastic_) {
    plastic_->set_loading(control_->loads(state_, trial));
    plastic_->set_time_step(time_step);
  }
  // Friction's slip is measured from the committed state this (sub-)increment starts from.
  hold_committed_contact_state(state_.u);
  if (controlled_ && trial <= 0.0) return solve_released(counters);
  const int plain_budget = std::max(8, load_case_.solver.max_newton / 4);
  for (Globalization g : {Globalization::line_search, Globalization::none}) {
    if (g == Globalization::line_search || !last_report_.stopped_while_converging)
      predict(trial, counters.iterations, counters.factorizations);
    last_report_ = newton_->solve(trial, system_guess_, g, g == Globalization::none ? plain_budget : 0);
    counters.iterations += last_report_.iterations;
    counters.factorizations += last_report_.factorizations;
    if (last_report_.converged) return true;
    stop_if_requested();
  }
  return false;
}

// A converged trial becomes the state: the displacement (guess_, already mapped from the Newton
// system), the depth, and the material history, which moves with every converged (sub-)step.
void Simulation::take_committed_branch() {
  if (!plastic_) return;
  plastic_->set_loading(control_->loads(state_, control_->committed(state_)));
  plastic_->set_time_step(0.0);  // the committed state's instantaneous response (commit())
}

void Simulation::commit(double trial, double depth) {
  state_.u_previous.swap(state_.u);
  state_.u.swap(guess_);
  state_.residual_scale_previous = state_.residual_scale;
  state_.residual_scale = settings_.force_scale;
  state_.alpha_previous = state_.alpha;
  state_.alpha = depth;
  control_->commit(state_, trial);
  state_.has_previous = true;
  state_.deepest = std::max(state_.deepest, state_.alpha);
  largest_condition_ = std::max(largest_condition_, last_report_.condition_estimate);
  bulk_->commit(state_.u.data());
  // The committed state ends the step: what is evaluated at it from now on (its forces, the
  // fields, a checkpoint's equilibrium check) is its instantaneous response, which a rate-
  // dependent law flows nothing in.
  if (plastic_) plastic_->set_time_step(0.0);
  if (plastic_ && condensation_) plastic_->measure_far_field(condensation_->elements());
}

void Simulation::predict(double trial, long& iterations, long& factorizations) {
  // The first increment into a virgin specimen has nothing to extrapolate: its previous states
  // are the unloaded one (alpha = 0), so the secant would predict no displacement at all.
  const bool virgin = state_.deepest <= 0.0;
  // A specimen clear of the punch carries no load: its displacement stays the committed one for
  // any shallower depth (and is the best start for a deeper one), where the secant would go on
  // with the springback of the increment that released it (the Berkovich cone: 8 Newton
  // iterations for an increment with nothing to solve).
  // The secant runs in the controlled quantity; under force control the depth is extrapolated
  // along with u.
  const double now = control_->predictor_coordinate(control_->committed(state_));
  const double before = control_->predictor_coordinate(control_->previous(state_));
  const double next = control_->predictor_coordinate(trial);
  double depth = trial;
  if (state_.has_previous && !virgin && !clear_of_punch()) {
    extrapolate(state_.u_previous, before, state_.u, now, next, guess_);
    if (controlled_)
      depth = now != before ? state_.alpha + (next - now) / (now - before) * (state_.alpha - state_.alpha_previous)
                            : state_.alpha;
  } else {
    guess_ = state_.u;
    if (controlled_) depth = first_depth_guess(trial);
  }
  to_system(guess_, depth, system_guess_);
  if (virgin && plastic_) {
    // The elastic contact solution at the same depth settles the contact set before plasticity
    // enters, which the coupled Newton otherwise has to find through the kinks of both at once.
    equations_->use_bulk(system_elastic_bulk());
    const NewtonReport elastic = solve_at_depth(depth, system_guess_, Globalization::none);
    equations_->use_bulk(system_bulk());
    if (const int signal = interruption_requested()) throw Interrupted(signal);  // nothing committed yet
    iterations += elastic.iterations;
    factorizations += elastic.factorizations;
    if (!elastic.converged) to_system(state_.u, depth, system_guess_);
  }
  if (!controlled_) return;
  // Force control: the state at the predicted depth first.  The bordered Newton moves the depth,
  // and with it every contact row and Gauss point near its kink, at each iteration; from the
  // predicted depth's own solution it only has the depth's small correction left (on the
  // Berkovich cone, J2, 20 increments: 3.2 times the Newton iterations of depth control without
  // this step; docs/performance.md).
  // (A stop requested meanwhile fails this solve and the bordered one at their first residual;
  // solve_at then returns to the reported state.)
  std::vector<double> settled = system_guess_;
  const NewtonReport at_depth = solve_at_depth(depth, settled, Globalization::line_search);
  iterations += at_depth.iterations;
  factorizations += at_depth.factorizations;
  if (at_depth.converged) system_guess_.swap(settled);
}

NewtonReport Simulation::solve_at_depth(double depth, std::vector<double>& x, Globalization globalization) {
  if (!controlled_) return newton_->solve(depth, x, globalization);
  if (!depth_newton_) depth_newton_ = std::make_unique<NewtonSolver>(*equations_, settings_);
  x.pop_back();
  const NewtonReport report = depth_newton_->solve(depth, x, globalization);
  x.push_back(depth);
  return report;
}

double Simulation::expected_depth(double target) const { return indentsim::expected_depth(load_case_, target); }

double Simulation::first_depth_guess(double trial) const {
  if (!(state_.deepest > 0.0 && state_.largest_force > 0.0)) return expected_depth(trial);
  // Reloading an imprint: up the unloading curve from where the punch touches it (at the imprint's
  // depth) to the peak (at the deepest depth), along the shape's power law, and on beyond the peak
  // as the virgin curve would.
  const double touch = touch_depth();
  if (trial <= state_.largest_force)
    return touch + (state_.deepest - touch) *
                       std::pow(trial / state_.largest_force, 1.0 / force_exponent(load_case_.punch.shape));
  return state_.deepest + expected_depth(trial) - expected_depth(state_.largest_force);
}

double Simulation::touch_depth() const { return touch_depth_of(state_.u); }

double Simulation::touch_depth_of(const std::vector<double>& u) const {
  double depth = std::numeric_limits<double>::infinity();
  for (const auto& c : contact_->candidates()) depth = std::min(depth, c.surface_height - u[c.equation]);
  return depth;
}

double Simulation::solved_depth(double trial) const { return controlled_ ? system_guess_.back() : trial; }

bool Simulation::solve_released(SolveCounters& counters) {
  // Off the punch the force is 0 at every depth above the surface: the specimen's state is solved
  // with the punch held clear of it (a depth below the original surface by the deepest depth,
  // which no pile-up reaches), and the increment ends where the punch just touches it.
  const double clear = -load_case_.max_depth();
  std::vector<double> u_system;
  to_system(state_.u, clear, u_system);
  last_report_ = solve_at_depth(clear, u_system, Globalization::line_search);
  counters.iterations += last_report_.iterations;
  counters.factorizations += last_report_.factorizations;
  if (!last_report_.converged) return false;
  std::vector<double> u;
  from_system(u_system, u);
  if (contact_->touches(u.data(), clear)) {
    last_report_.converged = false;
    last_report_.message = "the released specimen's surface rises above the punch held clear of it";
    return false;
  }
  // The deepest depth at which the punch still clears the surface, to 1e-10 of the path's depth:
  // the contact's own test (in finite strain the gap is measured at the nodes' current abscissa),
  // bisected from min_k (g_k - v_k), where it touches at the reference abscissae.
  const double resolution = 1e-10 * load_case_.max_depth();
  double below = clear, above = touch_depth_of(u);
  if (!contact_->touches(u.data(), above - resolution)) {
    below = above - resolution;
  } else {
    while (above - below > resolution) {
      const double middle = 0.5 * (below + above);
      (contact_->touches(u.data(), middle) ? above : below) = middle;
    }
  }
  // A surface that sprang back to the original level (an elastic specimen) is touched at alpha = 0,
  // where the path starts: the depth is never negative.
  to_system(u, std::max(0.0, below), system_guess_);
  return true;
}

std::string Simulation::limit_load_note() const {
  if (!controlled_ || !state_.has_previous || !(state_.alpha > state_.alpha_previous) || !(state_.force > 0.0))
    return "";
  // A force that stops rising with the depth is a limit load: P(alpha) has no point beyond it.
  const double tangent = (state_.force - state_.force_previous) / (state_.alpha - state_.alpha_previous);
  const double ratio = tangent / (state_.force / state_.alpha);
  if (ratio > limit_tangent_ratio) return "";
  return fmt::format("; the largest force reached is {} at alpha = {:.6g} m, where dP/dalpha fell to {:.2g} of P / alpha: "
                     "the force approaches a limit load of the specimen, which force control cannot pass (a "
                     "depth-controlled run, load.control = \"depth\", follows the curve beyond it)",
                     control_->describe(state_.largest_force), state_.alpha, ratio);
}

bool Simulation::clear_of_punch() const { return !contact_->touches(state_.u.data(), state_.alpha); }

void Simulation::build_system() {
  if (newton_) retired_symbolic_analyses_ += newton_->total_symbolic_analyses();
  if (depth_newton_) retired_symbolic_analyses_ += depth_newton_->total_symbolic_analyses();
  newton_.reset();
  depth_newton_.reset();
  controlled_.reset();
  equations_.reset();
  condensed_bulk_.reset();
  condensed_elastic_.reset();
  condensation_.reset();
  if (state_.near_field.condensed) {
    condensation_ = std::make_unique<FarFieldCondensation>(*stiffness_, *contact_, state_.near_field);
    condensed_elastic_ = std::make_unique<CondensedBulk>(*condensation_, nullptr);
    if (plastic_) condensed_bulk_ = std::make_unique<CondensedBulk>(*condensation_, plastic_.get());
    equations_ = std::make_unique<ContactEquations>(condensation_->pattern(), system_bulk(), *condensed_elastic_,
                                                    condensation_->contact());
  } else {
    equations_ = std::make_unique<ContactEquations>(*pattern_, *bulk_, *stiffness_, *contact_);
  }
  settings_.linear = config_.linear_solver;
  controlled_ = control_->system_equations(*equations_, system_contact(), settings_.force_scale);
  newton_ = std::make_unique<NewtonSolver>(controlled_ ? *controlled_ : static_cast<IncrementEquations&>(*equations_),
                                           settings_);
}

BulkOperator& Simulation::system_bulk() {
  if (!condensation_) return *bulk_;
  return plastic_ ? static_cast<BulkOperator&>(*condensed_bulk_) : *condensed_elastic_;
}

BulkOperator& Simulation::system_elastic_bulk() {
  return condensation_ ? static_cast<BulkOperator&>(*condensed_elastic_) : *stiffness_;
}

std::int64_t Simulation::system_unknowns() const {
  return condensation_ ? condensation_->size() : mesh_->equations();
}

void Simulation::to_system(const std::vector<double>& u, std::vector<double>& u_system) const {
  if (condensation_) condensation_->restrict_to_near(u, u_system);
  else u_system = u;
}

void Simulation::to_system(const std::vector<double>& u, double alpha, std::vector<double>& x) const {
  to_system(u, x);
  if (controlled_) x.push_back(alpha);
}

void Simulation::from_system(const std::vector<double>& x, std::vector<double>& u) const {
  if (condensation_) {
    condensation_->expand(x, u);  // reads the near field's unknowns only
  } else {
    u = x;
    u.resize(static_cast<std::size_t>(mesh_->equations()));  // drops force control's depth
  }
}

// The near field for the plastic zone the pilot saw at twice `depth` (at most the deepest point of
// the path): sized ahead, so that it is rebuilt a few times over a run (each rebuild is a new
// condensation) while the Newton systems of the early increments stay small -- the factorization
// of the near field is most of a plastic run's time and grows as its unknowns^1.5.
// Before an increment to `target`: if the near field does not hold the pilot's plastic zone at
// that depth (with the margins of choose_near_field), grow it ahead.  Only the load path and the
// pilot decide, so a run resumed from a checkpoint (which holds state_.near_field) grows it at the same
// increments.  grow_near_field stays the check after the fact.
void Simulation::anticipate_plastic_zone(double target) {
  if (!condensation_ || state_.plastic_zone_growth.empty()) return;
  const double depth = std::max(target, state_.deepest);
  const NearField needed = near_field_needed(load_case_, *mesh_, plan(), state_.plastic_zone_growth, depth);
  if (needed.elements_x <= state_.near_field.elements_x && needed.elements_y <= state_.near_field.elements_y &&
      needed.contact_nodes <= state_.near_field.contact_nodes)
    return;
  const NearField ahead = near_field_for_depth(load_case_, *mesh_, plan(), state_.plastic_zone_growth, depth);
  state_.near_field.elements_x = std::max(state_.near_field.elements_x, ahead.elements_x);
  state_.near_field.elements_y = std::max(state_.near_field.elements_y, ahead.elements_y);
  state_.near_field.contact_nodes = std::max(state_.near_field.contact_nodes, ahead.contact_nodes);
  ++near_field_rebuilds_;
  build_system();
}

bool Simulation::grow_near_field(const std::vector<double>& u, double alpha) {
  if (!condensation_) return false;
  // A far surface node the punch would penetrate: the contact needs more candidates.
  const auto& candidates = contact_->candidates();
  const double tolerance = 1e-10 * load_case_.max_depth();
  bool penetrates = false;
  for (std::size_t k = static_cast<std::size_t>(state_.near_field.contact_nodes); k < candidates.size(); ++k)
    if (u[candidates[k].equation] + alpha - candidates[k].surface_height > tolerance) penetrates = true;
  // A far element that would leave the elastic range: the near elements must reach it, in the
  // direction it lies (beside the near field, below it, or both at a corner).  Growing both ways
  // at once spread a cone's near field, whose strains ran ahead in depth, over the whole width of
  // a graded 3 mm specimen: 26663 unknowns where 1392 wide sufficed.
  bool beside = false, below = false;
  if (plastic_) {
    const int top = mesh_->elements_y() - 1;
    for (int ei = 0; ei < mesh_->elements_x() && !(beside && below); ++ei)
      for (int ej = 0; ej < mesh_->elements_y(); ++ej) {
        const bool outside_x = ei >= state_.near_field.elements_x;
        const bool outside_y = ej <= top - state_.near_field.elements_y;
        if (!(outside_x && !beside) && !(outside_y && !below)) continue;  // inside, or would tell nothing new
        if (plastic_->departs_at(ei, ej, u.data())) {
          beside = beside || outside_x;
          below = below || outside_y;
        }
      }
  }
  if (!penetrates && !beside && !below) return false;
  const auto grown = [](int count, int limit) { return std::min(limit, count + count / 2 + 2); };
  if (beside) state_.near_field.elements_x = grown(state_.near_field.elements_x, mesh_->elements_x());
  if (below) state_.near_field.elements_y = grown(state_.near_field.elements_y, mesh_->elements_y());
  if (penetrates) state_.near_field.contact_nodes = grown(state_.near_field.contact_nodes, mesh_->nodes_x());
  if (plastic_) state_.near_field.contact_nodes = std::max(state_.near_field.contact_nodes, std::min(state_.near_field.elements_x + 1, mesh_->nodes_x()));
  return true;
}

ContactResult Simulation::contact() const {
  std::vector<double> internal_force(state_.u.size());
  bulk_->internal_force(state_.u.data(), internal_force.data());
  return contact_->evaluate(state_.u.data(), internal_force.data(), state_.alpha);
}

namespace {

// Largest |f_i| over the force scale (an edited non-finite value counts as infinite).
double scaled_max(const std::vector<double>& f, double force_scale) {
  double largest = 0.0;
  for (double fi : f) largest = std::max(largest, std::abs(fi));
  return std::isfinite(largest) ? largest / force_scale : std::numeric_limits<double>::infinity();
}

}  // namespace

double Simulation::equilibrium_residual() {
  // The increment that converged u started from u_previous (from the unloaded state at first).
  hold_committed_contact_state(state_.has_previous ? state_.u_previous : std::vector<double>(state_.u.size(), 0.0));
  return system_residual(state_.u, state_.alpha, state_.residual_scale);
}

void Simulation::hold_committed_contact_state(const std::vector<double>& u) {
  if (!contact_->carries_history()) return;
  contact_->hold_committed_state(u.data());
  if (!condensation_) return;
  std::vector<double> u_system;
  to_system(u, u_system);
  condensation_->contact().hold_committed_state(u_system.data());
}

double Simulation::previous_state_residual() {
  // The previous state's own increment started from a state the checkpoint does not hold: for a
  // history-carrying bulk or contact, what the contact alone proves.
  if (!plastic_ && !contact_->carries_history()) return system_residual(state_.u_previous, state_.alpha_previous, state_.residual_scale_previous);
  std::vector<double> u_system;
  to_system(state_.u_previous, u_system);
  return scaled_max(system_contact().admissibility_violation(u_system.data(), state_.alpha_previous),
                    state_.residual_scale_previous);
}

double Simulation::system_residual(const std::vector<double>& u, double alpha, double force_scale) {
  std::vector<double> u_system, f;
  to_system(u, u_system);
  f.resize(u_system.size());
  equations_->residual(u_system.data(), alpha, f.data());
  return scaled_max(f, force_scale);
}

IncrementSnapshot Simulation::snapshot(const IncrementRecord& record) const {
  return IncrementSnapshot(
      record, state_.alpha, free_surface_depth(), *mesh_, state_.u, *bulk_, *contact_, [this] { return contact(); },
      [this](const ContactResult& c) { return unloading_stiffness(c); });
}

double Simulation::unloading_stiffness() const { return unloading_stiffness(contact()); }

double Simulation::unloading_stiffness(const ContactResult& c) const {
  std::vector<double> internal_force(state_.u.size());
  if (!contact_->rows_pin_unknowns() || contact_->carries_history())
    bulk_->internal_force(state_.u.data(), internal_force.data());
  // Finite strain unloads along its tangent at the state, not along K.
  if (plastic_)
    if (const auto tangent = plastic_->unloading_tangent(state_.u.data()))
      return unloading_stiffness_of_tangent(*pattern_, *tangent, *contact_, state_.u.data(), internal_force.data(),
                                            state_.alpha, c);
  return elastic_unloading_stiffness(*stiffness_, *contact_, state_.u.data(), internal_force.data(), state_.alpha, c);
}

double Simulation::contact_half_width() const { return contact().half_width; }

SimulationState Simulation::state() const {
  SimulationState s = state_;
  s.history = bulk_->history();
  s.in_contact = contact().in_contact;
  return s;
}

void Simulation::restore(const SimulationState& s) {
  const std::size_t n = static_cast<std::size_t>(mesh_->equations());
  if (s.u.size() != n || (s.has_previous && s.u_previous.size() != n))
    throw std::invalid_argument("the saved displacement does not fit this mesh");
  const NearField& near = s.near_field;
  if (near.condensed && (near.contact_nodes < 1 || near.contact_nodes > mesh_->nodes_x() || near.elements_x < 0 ||
                         near.elements_x > mesh_->elements_x() || near.elements_y < 0 ||
                         near.elements_y > mesh_->elements_y()))
    throw std::invalid_argument("the saved near field does not fit this mesh");
  const PlasticZoneGrowth& zone = s.plastic_zone_growth;
  if (zone.depths.size() != zone.extents.size() || !std::is_sorted(zone.depths.begin(), zone.depths.end()) ||
      !std::all_of(zone.depths.begin(), zone.depths.end(), [](double d) { return std::isfinite(d) && d > 0.0; }) ||
      !std::all_of(zone.extents.begin(), zone.extents.end(), [](const PlasticExtent& e) {
        return std::isfinite(e.width) && std::isfinite(e.depth) && e.width >= 0.0 && e.depth >= 0.0;
      }))
    throw std::invalid_argument("the saved plastic zone growth is not a list of depths and extents");
  const bool rebuild = !(near == state_.near_field);
  // The bulk model checks the history fits its points (its content is checked on resume, by
  // history_violation); should it refuse, nothing else changed (resume_from discards the simulation).
  bulk_->restore(s.history, s.u.data());
  state_ = s;
  state_.history = {};     // the bulk model holds the live history
  state_.in_contact = {};  // implied by u
  // Whatever flag the state was taken with (a state saved after a trial set it, as advance_to's
  // `reported` is).
  take_committed_branch();
  if (rebuild) build_system();
  if (contact().in_contact != s.in_contact)
    throw std::invalid_argument("the saved contact set does not follow from the saved displacement");
}

double Simulation::free_surface_depth() const { return touch_depth(); }

std::optional<std::vector<double>> Simulation::force_sensitivities(const std::vector<MaterialParameter>& parameters) {
  std::optional<Sensitivities> s = sensitivities(parameters);
  if (!s) return std::nullopt;
  return std::move(s->force);
}

std::optional<Simulation::Sensitivities> Simulation::sensitivities(const std::vector<MaterialParameter>& parameters,
                                                                   bool with_displacement) {
  const MaterialInput& m = load_case_.material;
  // Several materials: the internal force is no longer homogeneous of degree one in one E
  // (docs/MODEL.md §14.1); finite differences of whole runs give the sensitivities.
  if (!load_case_.layers.empty()) return std::nullopt;
  for (MaterialParameter p : parameters)
    if (p == MaterialParameter::nu) return std::nullopt;  // nu also shapes the condensed far field
  if (contact_->carries_history()) return std::nullopt;  // friction's slip history: its derivative is not carried
  // At fixed force the depth moves with theta too: the derivatives at fixed depth are not built.
  if (controlled_) return std::nullopt;
  std::vector<double> u_system;
  to_system(state_.u, u_system);
  const std::size_t n = u_system.size();
  BulkOperator& bulk = system_bulk();
  const ContactDiscretization& contact = system_contact();
  const StiffnessPattern& pattern = equations_->pattern();
  std::vector<double> force(n);
  bulk.internal_force(u_system.data(), force.data());

  // dF/d(theta) at fixed u for the model's own parameters: E at fixed e0 scales every stress
  // (f_int is homogeneous of degree one in E, far field included, and on the unloading branch as
  // well, where eps* does not move with E: the displacements of a depth-driven frictionless
  // contact do not depend on E at fixed e0); e0, kappa and n act only in the inelastic near
  // elements, through omega and, unloading, through eps*.
  const std::vector<MaterialParameter> base{MaterialParameter::E, MaterialParameter::e0, MaterialParameter::kappa,
                                            MaterialParameter::n};
  std::vector<std::vector<double>> d_force(base.size(), std::vector<double>(n, 0.0));
  for (std::size_t i = 0; i < n; ++i) d_force[0][i] = force[i] / m.E;
  const std::vector<ElementSlot>* slots = nullptr;
  if (plastic_) {
    slots = condensation_ ? &condensation_->elements() : &plastic_->slots();
    for (std::size_t b = 1; b < base.size(); ++b)
      if (!plastic_->add_parameter_derivative(*slots, u_system.data(), base[b], d_force[b].data())) return std::nullopt;
  }
  // Right-hand sides -dF/d(theta): the contact rows' own derivative (contact_discretization.hpp).
  const auto& candidates = contact.candidates();
  const auto& rows = contact.row_equations();
  std::vector<double> row_force(rows.size()), d_row_force(rows.size());
  for (std::size_t k = 0; k < rows.size(); ++k) row_force[k] = force[rows[k]];
  std::vector<std::vector<double>> du = d_force;
  for (std::size_t b = 0; b < du.size(); ++b) {
    for (std::size_t k = 0; k < rows.size(); ++k) d_row_force[k] = d_force[b][rows[k]];
    // The elastic stiffness is proportional to E and does not depend on the plastic law.
    const double d_log_stiffness = base[b] == MaterialParameter::E ? 1.0 / m.E : 0.0;
    contact.write_parameter_derivative_rows(u_system.data(), state_.alpha, row_force.data(), d_row_force.data(),
                                            d_log_stiffness, du[b].data());
    for (double& v : du[b]) v = -v;
  }
  // P = -f sum r_k over the candidates carrying contact force.
  const ContactResult contact_state = contact.evaluate(u_system.data(), force.data(), state_.alpha);
  const std::vector<char>& active = contact_state.in_contact;
  newton_->solve_linearized(u_system, state_.alpha, du);
  // While loading this state is the peak of any unloading that follows.
  if (plastic_)
    for (std::size_t b = 1; b < base.size(); ++b) plastic_->record_strain_derivatives(*slots, du[b].data(), base[b]);
  std::vector<double> tangent(static_cast<std::size_t>(pattern.nonzeros()));
  bulk.tangent(u_system.data(), tangent.data());
  std::vector<double> base_derivative(base.size(), 0.0), k_du(n);
  for (std::size_t b = 0; b < base.size(); ++b) {
    pattern.multiply(tangent, du[b].data(), k_du.data());
    double sum = 0.0;
    for (std::size_t k = 0; k < candidates.size(); ++k)
      if (active[k]) sum -= d_force[b][candidates[k].equation] + k_du[candidates[k].equation];
    base_derivative[b] = contact.symmetry_factor() * sum;
  }
  // The user's parameters.  e0 = sigma_y / (3 mu) with mu = E / (2 (1 + nu)): at fixed E,
  // d e0 / d sigma_y = e0 / sigma_y; at fixed sigma_y, d e0 / dE = -e0 / E.  Each user parameter
  // is a combination sum_b c_b (base b) of the base derivatives.
  const bool by_yield_stress = m.yield_stress.has_value();
  std::vector<std::array<double, 4>> combination;
  for (MaterialParameter p : parameters) {
    switch (p) {
      case MaterialParameter::E: combination.push_back({1.0, by_yield_stress ? -m.e0 / m.E : 0.0, 0.0, 0.0}); break;
      case MaterialParameter::e0: combination.push_back({0.0, 1.0, 0.0, 0.0}); break;
      case MaterialParameter::yield_stress:
        combination.push_back({0.0, m.e0 / value_of(m, MaterialParameter::yield_stress), 0.0, 0.0});
        break;
      case MaterialParameter::kappa: combination.push_back({0.0, 0.0, 1.0, 0.0}); break;
      case MaterialParameter::n: combination.push_back({0.0, 0.0, 0.0, 1.0}); break;
      // nu shapes the condensed far field; K, prestrain, Q, b and the flow rule's parameters are
      // J2's, whose history has no derivative carried (the whole run's finite differences give theirs).
      case MaterialParameter::nu:
      case MaterialParameter::K:
      case MaterialParameter::prestrain:
      case MaterialParameter::Q:
      case MaterialParameter::b:
      case MaterialParameter::reference_strain_rate:
      case MaterialParameter::creep_coefficient:
      case MaterialParameter::reference_stress:
      case MaterialParameter::rate_exponent: return std::nullopt;
    }
  }
  // The whole mesh's du/d(theta): the condensed far field is linear elastic, K_FF u_F = -K_FR u_R,
  // so expanding is linear and applies to du as it does to u (for E, du = 0 anyway).
  std::vector<std::vector<double>> du_mesh(base.size());
  if (with_displacement)
    for (std::size_t b = 0; b < base.size(); ++b)
      if (std::any_of(combination.begin(), combination.end(), [b](const auto& c) { return c[b] != 0.0; }))
        from_system(du[b], du_mesh[b]);
  Sensitivities result;
  for (const auto& c : combination) {
    double dP = 0.0;
    std::vector<double> d_u(with_displacement ? state_.u.size() : 0, 0.0);
    for (std::size_t b = 0; b < base.size(); ++b) {
      if (c[b] == 0.0) continue;
      dP += c[b] * base_derivative[b];
      for (std::size_t i = 0; i < d_u.size(); ++i) d_u[i] += c[b] * du_mesh[b][i];
    }
    result.force.push_back(dP);
    if (with_displacement) result.displacement.push_back(std::move(d_u));
  }
  return result;
}

std::vector<LineForce> Simulation::line_forces() const {
  return indentsim::line_forces(*mesh_, *bulk_);
}

void Simulation::check_fine_zone(double half_width) {
  if (state_.warned_fine_zone || half_width <= plan().fine_width) return;
  state_.warned_fine_zone = true;
  state_.warnings.push_back(fmt::format(
      "at alpha = {:.4g} m the contact half-width {:.4g} m left the fine mesh zone ({:.4g} m): accuracy drops; "
      "set mesh.contact_half_width or mesh.fine_width larger",
      state_.alpha, half_width, plan().fine_width));
}

IncrementRecord Simulation::record(double wall_seconds, long iterations, long factorizations, int cutbacks) {
  const ContactResult c = contact();
  IncrementRecord r;
  r.step = state_.rows++;
  r.alpha = state_.alpha;
  r.force = c.force;
  r.half_width = c.half_width;
  r.contact_nodes = c.contact_nodes;
  r.newton_iterations = iterations;
  r.factorizations = factorizations;
  r.cutbacks = cutbacks;
  r.plastic_points = bulk_->plastic_points();
  r.max_strain_intensity = bulk_->max_strain_intensity();
  r.wall_seconds = wall_seconds;
  check_fine_zone(r.half_width);
  // Resolution is judged where the contact is largest, at the deepest point of the path (a history
  // that unloads ends with no contact, which says nothing about the mesh).
  if (control_->committed(state_) == load_case_.load.largest_target() && c.force > 0.0 && c.contact_nodes < 4) {
    const std::string coarse = fmt::format("the contact zone spans only {} node(s) at the deepest point: the result "
                                           "is coarse; raise mesh.contact_nodes",
                                           c.contact_nodes);
    if (std::find(state_.warnings.begin(), state_.warnings.end(), coarse) == state_.warnings.end()) state_.warnings.push_back(coarse);
  }
  return r;
}

}  // namespace indentsim
