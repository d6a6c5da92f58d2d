#include "indentsim/simulation/simulation.hpp"
#include "indentsim/solvers/unloading_stiffness.hpp"
#include "indentsim/base/worker_threads.hpp"

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

// Measured (CHANGELOG, with Debian's OpenBLAS): CHOLMOD is faster than KLU from the smallest
// meshes tried (1.6x at 684 unknowns, 2.1x at 1860, 6.2x at 40k); below ~1000 unknowns both take
// milliseconds and KLU, the user's default, is kept.
constexpr int cholmod_crossover_unknowns = 1000;
constexpr double max_relative_contact = 0.1;  // a / lx and a / ly beyond which the run warns
constexpr double min_plausible_modulus = 1e3, max_plausible_modulus = 2e12;  // [Pa]

// Plastic scenes spread their contact wider than the elastic Hertz estimate, up to the punch's
// chord sqrt(2 R alpha) when the material flows freely.  A coarse pilot run of the same load
// case (8 elements across the chord, 4 increments) measures the final contact half-width and
// how far the plastic zone reaches at each of its increments; the real mesh is planned from the
// first with a 5% margin, the condensed near field from the second, as it grows with the depth.
// The pilot sets mesh.contact_half_width itself, so it never runs a pilot of its own, and solves
// its small mesh whole.  Should it fail, the chord is a safe upper bound and the near field falls
// back to its default.
struct PilotResult {
  double contact_half_width = 0.0;
  PlasticZoneGrowth plastic_zone;
};

PilotResult pilot_run(const LoadCase& lc) {
  const double depth = lc.max_depth();
  // Where the punch meets the undeformed surface: the sphere's chord sqrt(2 R alpha - alpha^2).
  const double chord = make_punch(lc.punch)->geometric_contact_radius(depth);
  LoadCase pilot = lc;
  pilot.mesh = MeshInput{};
  pilot.mesh.contact_nodes = 8;
  pilot.mesh.contact_half_width = chord;
  pilot.load.path = {0.0, depth};
  pilot.load.increments = 4;
  pilot.solver.tolerance = std::max(lc.solver.tolerance, 1e-9);
  pilot.solver.far_field = FarFieldChoice::full;
  double widest = 0.0;
  try {
    Simulation sim(pilot);
    PlasticZoneGrowth growth;
    sim.run([&](const IncrementRecord& r) {
      widest = std::max(widest, r.half_width);
      if (r.step == 0) return;
      const Mesh& mesh = sim.mesh();
      PlasticExtent zone;
      for (int ei = 0; ei < mesh.elements_x(); ++ei)
        for (int ej = 0; ej < mesh.elements_y(); ++ej)
          for (std::size_t g = 0; g < 4; ++g)
            if (sim.plasticity()->law().has_yielded(4 * static_cast<std::size_t>(mesh.element(ei, ej)) + g)) {
              zone.width = std::max(zone.width, mesh.x(ei + 1));
              zone.depth = std::max(zone.depth, -mesh.y(ej));
            }
      growth.depths.push_back(r.alpha);
      growth.extents.push_back(zone);
    });
    return {widest > 0.0 ? std::min(chord, 1.05 * widest) : chord, growth};
  } catch (const SolverError&) {
    return {chord, {}};
  }
}

// Deformation theory is exact for monotone loading; Ilyushin's unloading rule is switched on
// only when the load path itself unloads (a scene that never unloads does not pay for it).
bool unloads(const std::vector<double>& path) {
  for (std::size_t k = 1; k < path.size(); ++k)
    if (path[k] < path[k - 1]) return true;
  return false;
}

// "auto": KLU below the measured crossover, CHOLMOD's supernodal Cholesky above it.
LinearSolverKind choose_linear_solver(LinearSolverChoice choice, int unknowns) {
  switch (choice) {
    case LinearSolverChoice::klu: return LinearSolverKind::klu;
    case LinearSolverChoice::cholmod: return LinearSolverKind::cholmod;
    case LinearSolverChoice::automatic: break;
  }
  return unknowns >= cholmod_crossover_unknowns ? LinearSolverKind::cholmod : LinearSolverKind::klu;
}

// Every surface node within 1.3 a + 2 h of the axis may touch (a the planned final contact
// half-width, h the fine spacing); every element within 1.3 times the pilot's plastic zone plus
// 2 h (or, without a pilot, within 2.5 a) may yield.  Generous on purpose: a near field too
// small is detected after the increment and grown (Simulation::grow_near_field), which costs a
// new condensation; one too large only costs unknowns.  "auto" solves the whole mesh only when the
// near field would hold more than 80% of its unknowns: measured on deep_plastic.toml, a near field
// of 55% of the unknowns still cut the time per increment by 40% (docs/DESIGN.md, section 7).
NearField choose_near_field(const LoadCase& lc, const Mesh& mesh, const MeshPlan& plan, bool plastic,
                            const std::optional<PlasticExtent>& plastic_zone) {
  NearField near;
  if (lc.solver.far_field == FarFieldChoice::full) return near;
  const double a = plan.contact_half_width_estimate, h = plan.fine_spacing;
  const double contact_width = 1.3 * a + 2.0 * h;
  while (near.contact_nodes < mesh.nodes_x() && mesh.x(near.contact_nodes) <= contact_width) ++near.contact_nodes;
  near.contact_nodes = std::min(mesh.nodes_x(), near.contact_nodes + 1);
  if (plastic) {
    const double width = plastic_zone ? std::max(1.3 * plastic_zone->width, contact_width) + 2.0 * h : 2.5 * a;
    const double depth = plastic_zone ? 1.3 * plastic_zone->depth + 2.0 * h : 2.5 * a;
    while (near.elements_x < mesh.elements_x() && mesh.x(near.elements_x) < width) ++near.elements_x;
    while (near.elements_y < mesh.elements_y() && -mesh.y(mesh.top_row() - near.elements_y) < depth) ++near.elements_y;
    near.contact_nodes = std::max(near.contact_nodes, near.elements_x + 1);
  }
  const double near_unknowns = 2.0 * (near.elements_x + 1) * (near.elements_y + 1) + near.contact_nodes;
  near.condensed = lc.solver.far_field == FarFieldChoice::condense || near_unknowns <= 0.8 * mesh.equations();
  return near;
}

}  // namespace

// "auto": the paper's exact Q1 element unless the scene locks it -- nearly incompressible
// elasticity (nu >= 0.45), nearly perfect plasticity (isochoric flow with kappa > 0.95 or
// n < 0.1), or a plastic material under a cone, whose strain is set by the angle and not by the
// depth, so the flow under it is fully plastic and isochoric from the first increment (Q1 locks:
// on berkovich_cone with Ilyushin's law it overestimates P/h^2 by 1%, with a sawtooth 1.5x as
// large) -- where mean dilatation (B-bar) is used.
ElementKind choose_element(const LoadCase& lc) {
  switch (lc.mesh.element) {
    case ElementChoice::q1: return ElementKind::q1;
    case ElementChoice::bbar: return ElementKind::bbar;
    case ElementChoice::automatic: break;
  }
  const auto& m = lc.material;
  const bool near_incompressible = m.nu >= 0.45;
  const bool plastic = m.model != MaterialModel::elastic;
  const bool near_perfect_plasticity =
      plastic && (m.hardening == HardeningLaw::linear ? m.kappa > 0.95 : m.n < 0.1);
  const bool sharp_plastic_indentation = plastic && lc.punch.shape == PunchShapeKind::cone;
  return near_incompressible || near_perfect_plasticity || sharp_plastic_indentation ? ElementKind::bbar
                                                                                       : ElementKind::q1;
}

std::vector<std::string> plausibility_warnings(const LoadCase& lc, const MeshPlan& plan) {
  std::vector<std::string> warnings;
  // Unit slips: a modulus given in GPa or MPa instead of Pa runs, and gives forces 1e6-1e9 off.
  if (lc.material.E < min_plausible_modulus || lc.material.E > max_plausible_modulus)
    warnings.push_back(fmt::format("material.E = {:g} Pa is outside the moduli of solids ({:g} Pa to {:g} Pa): "
                                   "pascals are meant (210 GPa is 210e9)",
                                   lc.material.E, min_plausible_modulus, max_plausible_modulus));
  // The model is small-strain with the gap measured vertically (docs/MODEL.md §3): both need slopes
  // and depths small against the punch's size.
  if (auto slope = make_punch(lc.punch)->slope_warning(lc.max_depth())) warnings.push_back(*slope);
  // A contact that is not small against the specimen: its edges and base shape P well beyond the
  // discretization error (docs/user-guide.md, "Choosing the specimen").
  const double a = plan.contact_half_width_estimate;
  for (const auto& [key, size] : {std::pair<const char*, double>{"geometry.lx", lc.geometry.lx}, {"geometry.ly", lc.geometry.ly}})
    if (a > max_relative_contact * size)
      warnings.push_back(fmt::format("the contact half-width (about {:.3g} m) is {:.2g} of {} = {:.3g} m: the "
                                     "specimen's edges change P far beyond the discretization error (keep a / {} "
                                     "below {:g}; is punch.radius in metres?)",
                                     a, a / size, key, size, key, max_relative_contact));
  return warnings;
}

RunPlan plan_run(const LoadCase& load_case, std::optional<double> planned_contact_half_width) {
  RunPlan plan{plan_mesh(load_case), {}};  // also refuses a mesh too large before any work
  if (planned_contact_half_width) {
    plan.mesh = plan_mesh(load_case, planned_contact_half_width);
  } else if (load_case.material.model != MaterialModel::elastic && !load_case.mesh.contact_half_width) {
    const PilotResult pilot = pilot_run(load_case);
    plan.mesh = plan_mesh(load_case, pilot.contact_half_width);
    plan.plastic_zone = pilot.plastic_zone;
  }
  return plan;
}

Simulation::Simulation(LoadCase load_case, std::optional<double> planned_contact_half_width,
                       std::optional<NearField> near_field)
    : load_case_(std::move(load_case)) {
  RunPlan run_plan;
  {
    const PhaseTimes::Scope timing = times_.measure("planning");
    run_plan = plan_run(load_case_, planned_contact_half_width);
  }
  build(run_plan, near_field);
}

Simulation::Simulation(LoadCase load_case, const RunPlan& plan, PhaseTimes times)
    : load_case_(std::move(load_case)), times_(std::move(times)) {
  build(plan, std::nullopt);
}

void Simulation::build(const RunPlan& run_plan, const std::optional<NearField>& near_field) {
  limit_library_threads();  // one BLAS/OpenMP thread per run (worker_threads.hpp)
  const auto& m = load_case_.material;
  const ElasticMaterial material{m.E, m.nu};
  std::optional<IlyushinLaw> law;
  if (m.model != MaterialModel::elastic) {
    law.emplace(material, m.e0, m.hardening, m.kappa, m.n);
    if (auto violation = law->admissibility_violation())
      throw InputError(load_case_.source, m.hardening == HardeningLaw::linear ? "material.kappa" : "material.n",
                       *violation);
  }
  plan_ = run_plan.mesh;
  const PhaseTimes::Scope timing = times_.measure("model");
  mesh_ = std::make_unique<Mesh>(Mesh::from_plan(load_case_, plan_));
  mesh_->set_element_kind(choose_element(load_case_));
  pattern_ = std::make_unique<StiffnessPattern>(*mesh_);
  stiffness_ = std::make_unique<ElasticStiffness>(*mesh_, material, *pattern_);
  bulk_ = stiffness_.get();
  if (law) {
    const std::size_t points = 4 * static_cast<std::size_t>(mesh_->elements());
    std::unique_ptr<PointLaw> point_law;
    if (m.model == MaterialModel::j2) point_law = std::make_unique<J2PointLaw>(J2Law(*law), points);
    else point_law = std::make_unique<IlyushinPointLaw>(*law, unloads(load_case_.load.path), points);
    plastic_ = std::make_unique<InelasticBulk>(*stiffness_, std::move(point_law));
    bulk_ = plastic_.get();
  }
  contact_ = std::make_unique<ContactBoundary>(*mesh_, make_punch(load_case_.punch), *pattern_, stiffness_->values());
  settings_.displacement_scale = load_case_.max_depth();
  // Newton's residual is measured against the nodal forces of the scene: E* alpha_max per unit
  // thickness in plane strain, times the ring 2 pi a* in axisymmetry (docs/DESIGN.md §3).
  settings_.force_scale = mesh_->kinematics().nodal_force_scale(
      material.plane_strain_modulus() * load_case_.max_depth(), plan_.contact_half_width_estimate);
  settings_.tolerance = load_case_.solver.tolerance;
  settings_.max_iterations = load_case_.solver.max_newton;
  // Plastic Newton iterations contract linearly (each moves the yield front across Gauss points
  // where the tangent jumps), so a factorization kept as GMRES's preconditioner serves several of
  // them; elastic contact converges in two or three exact steps on a small condensed system.
  const JacobianChoice jacobian = load_case_.solver.jacobian == JacobianChoice::automatic
                                      ? (law ? JacobianChoice::krylov : JacobianChoice::reuse)
                                      : load_case_.solver.jacobian;
  settings_.newton_linear = jacobian == JacobianChoice::krylov ? NewtonLinearSolve::krylov : NewtonLinearSolve::direct;
  settings_.chord_steps = jacobian == JacobianChoice::reuse;
  if (near_field) {
    state_.near_field = *near_field;
  } else if (run_plan.plastic_zone.empty()) {
    state_.near_field = choose_near_field(load_case_, *mesh_, plan_, law.has_value(), std::nullopt);
  } else {
    // Whether to condense is decided on the zone of the deepest point; the near field starts as
    // large as the first increments need and grows with the zone (anticipate_plastic_zone).
    state_.plastic_zone_growth = run_plan.plastic_zone;
    state_.near_field = choose_near_field(load_case_, *mesh_, plan_, true, state_.plastic_zone_growth.at(load_case_.max_depth()));
    if (state_.near_field.condensed) {
      const std::vector<double> targets = plan_increments(load_case_.load);
      const auto first = std::find_if(targets.begin(), targets.end(), [](double t) { return t > 0.0; });
      if (first != targets.end()) state_.near_field = near_field_for_depth(*first);
    }
  }
  build_system();

  state_.u.assign(static_cast<std::size_t>(mesh_->equations()), 0.0);

  const std::vector<std::string> implausible = plausibility_warnings(load_case_, plan_);
  state_.warnings.insert(state_.warnings.end(), implausible.begin(), implausible.end());
}

Simulation::~Simulation() = default;

void Simulation::run(const std::function<void(const IncrementRecord&)>& on_increment) {
  const std::vector<double> targets = plan_increments(load_case_.load);
  while (state_.next_target < targets.size()) {
    const IncrementRecord r = advance_to(targets[state_.next_target]);
    ++state_.next_target;  // before reporting: a checkpoint taken now continues with the next depth
    if (on_increment) on_increment(r);
  }
}

// One increment, as a script: a trial depth, the Newton solve with its globalisation ladder,
// then either the commit of a converged trial (after checking the condensation's assumptions),
// or a cutback.
IncrementRecord Simulation::advance_to(double target) {
  const PhaseTimes::Scope timing = times_.measure("stepping");
  const auto start = std::chrono::steady_clock::now();
  anticipate_plastic_zone(target);
  SolveCounters counters;
  int cutbacks = 0;
  double step = target - state_.alpha;
  // The state of the last reported increment, saved before a converged sub-step (after a
  // cutback) moves the simulation past it: an interruption returns to it.
  std::optional<SimulationState> reported;
  const auto stop_if_requested = [&] {
    if (const int signal = interruption_requested()) {
      if (reported) restore(*reported);
      throw Interrupted(signal);
    }
  };
  for (;;) {
    stop_if_requested();
    double trial = state_.alpha + step;
    if (std::abs(target - trial) <= 1e-12 * std::abs(target)) trial = target;
    if (solve_at(trial, counters, stop_if_requested)) {
      if (trial != target && !reported) reported = state();
      from_system(system_guess_, guess_);
      if (grow_near_field(guess_, trial)) {
        ++near_field_growths_;
        build_system();
        continue;  // the same trial depth on the larger near field
      }
      commit(trial);
      if (trial == target) break;
      // Grow the sub-step back after an easy one.
      if (last_report_.iterations <= 3) step *= 2.0;
      step = std::copysign(std::min(std::abs(step), std::abs(target - state_.alpha)), target - state_.alpha);
      continue;
    }
    if (cutbacks >= load_case_.solver.max_cutbacks) {
      const NewtonReport& report = last_report_;
      throw SolverError(fmt::format(
          "the increment from alpha = {:.6g} m to {:.6g} m did not converge after {} cutbacks (last try: "
          "alpha = {:.6g} m, {} Newton iterations, scaled residual {:.3g}, KINSOL flag {}{}{})",
          state_.alpha, target, cutbacks, trial, report.iterations, report.residual, report.kinsol_flag,
          report.message.empty() ? "" : ": ", report.message));
    }
    step *= 0.5;
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
bool Simulation::solve_at(double trial, SolveCounters& counters, const std::function<void()>& stop_if_requested) {
  // Laws that follow the global load history (Ilyushin's unloading rule) need to know whether
  // this trial goes beyond the deepest point so far.
  if (plastic_) plastic_->set_loading(trial >= state_.deepest);
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
void Simulation::commit(double trial) {
  state_.u_previous.swap(state_.u);
  state_.u.swap(guess_);
  state_.alpha_previous = state_.alpha;
  state_.alpha = trial;
  state_.has_previous = true;
  state_.deepest = std::max(state_.deepest, state_.alpha);
  largest_condition_ = std::max(largest_condition_, last_report_.condition_estimate);
  bulk_->commit(state_.u.data());
}

void Simulation::predict(double trial, long& iterations, long& factorizations) {
  // The first increment into a virgin specimen has nothing to extrapolate: its previous states
  // are the unloaded one (alpha = 0), so the secant would predict no displacement at all.
  const bool virgin = state_.deepest <= 0.0;
  // A specimen clear of the punch carries no load: its displacement stays the committed one for
  // any shallower depth (and is the best start for a deeper one), where the secant would go on
  // with the springback of the increment that released it (the Berkovich cone: 8 Newton
  // iterations for an increment with nothing to solve).
  if (state_.has_previous && !virgin && !clear_of_punch())
    extrapolate(state_.u_previous, state_.alpha_previous, state_.u, state_.alpha, trial, guess_);
  else
    guess_ = state_.u;
  to_system(guess_, system_guess_);
  if (!virgin || !plastic_) return;
  // The elastic contact solution at the same depth settles the contact set before plasticity
  // enters, which the coupled Newton otherwise has to find through the kinks of both at once.
  equations_->use_bulk(system_elastic_bulk());
  const NewtonReport elastic = newton_->solve(trial, system_guess_);
  equations_->use_bulk(system_bulk());
  if (const int signal = interruption_requested()) throw Interrupted(signal);  // nothing committed yet
  iterations += elastic.iterations;
  factorizations += elastic.factorizations;
  if (!elastic.converged) to_system(state_.u, system_guess_);
}

bool Simulation::clear_of_punch() const {
  for (const ContactCandidate& c : contact_->candidates())
    if (ContactBoundary::penetration(c, state_.u[static_cast<std::size_t>(c.equation)], state_.alpha) >= 0.0) return false;
  return true;
}

void Simulation::build_system() {
  if (newton_) retired_symbolic_analyses_ += newton_->total_symbolic_analyses();
  newton_.reset();
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
  settings_.linear = linear_solver_ = choose_linear_solver(load_case_.solver.linear, static_cast<int>(system_unknowns()));
  newton_ = std::make_unique<NewtonSolver>(*equations_, settings_);
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

void Simulation::from_system(const std::vector<double>& u_system, std::vector<double>& u) const {
  if (condensation_) condensation_->expand(u_system, u);
  else u = u_system;
}

// The near field for the plastic zone the pilot saw at twice `depth` (at most the deepest point of
// the path): sized ahead, so that it is rebuilt a few times over a run (each rebuild is a new
// condensation) while the Newton systems of the early increments stay small -- the factorization
// of the near field is most of a plastic run's time and grows as its unknowns^1.5.
NearField Simulation::near_field_for_depth(double depth) const {
  const double ahead = std::min(load_case_.max_depth(), 2.0 * depth);
  NearField near = choose_near_field(load_case_, *mesh_, plan_, true, state_.plastic_zone_growth.at(ahead));
  near.condensed = true;
  return near;
}

// Before an increment to `target`: if the near field does not hold the pilot's plastic zone at
// that depth (with the margins of choose_near_field), grow it ahead.  Only the load path and the
// pilot decide, so a run resumed from a checkpoint (which holds state_.near_field) grows it at the same
// increments.  grow_near_field stays the check after the fact.
void Simulation::anticipate_plastic_zone(double target) {
  if (!condensation_ || state_.plastic_zone_growth.empty()) return;
  const double depth = std::max(target, state_.deepest);
  const NearField needed =
      choose_near_field(load_case_, *mesh_, plan_, true, state_.plastic_zone_growth.at(std::min(depth, load_case_.max_depth())));
  if (needed.elements_x <= state_.near_field.elements_x && needed.elements_y <= state_.near_field.elements_y &&
      needed.contact_nodes <= state_.near_field.contact_nodes)
    return;
  const NearField ahead = near_field_for_depth(depth);
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
  // A far element that would leave the elastic range: the near elements must reach it.
  bool yields = false;
  if (plastic_) {
    const int top = mesh_->elements_y() - 1;
    for (int ei = 0; ei < mesh_->elements_x() && !yields; ++ei)
      for (int ej = 0; ej < mesh_->elements_y(); ++ej) {
        if (ei < state_.near_field.elements_x && ej > top - state_.near_field.elements_y) continue;
        if (plastic_->inelastic_at(ei, ej, u.data())) {
          yields = true;
          break;
        }
      }
  }
  if (!penetrates && !yields) return false;
  const auto grown = [](int count, int limit) { return std::min(limit, count + count / 2 + 2); };
  if (yields) {
    state_.near_field.elements_x = grown(state_.near_field.elements_x, mesh_->elements_x());
    state_.near_field.elements_y = grown(state_.near_field.elements_y, mesh_->elements_y());
  }
  if (penetrates) state_.near_field.contact_nodes = grown(state_.near_field.contact_nodes, mesh_->nodes_x());
  if (plastic_) state_.near_field.contact_nodes = std::max(state_.near_field.contact_nodes, std::min(state_.near_field.elements_x + 1, mesh_->nodes_x()));
  return true;
}

ContactResult Simulation::contact() const {
  std::vector<double> internal_force(state_.u.size());
  bulk_->internal_force(state_.u.data(), internal_force.data());
  return evaluate_contact(*contact_, state_.u.data(), internal_force.data(), state_.alpha);
}

IncrementSnapshot Simulation::snapshot(const IncrementRecord& record) const {
  return IncrementSnapshot(
      record, state_.alpha, free_surface_depth(), *mesh_, state_.u, *bulk_, *contact_, [this] { return contact(); },
      [this](const ContactResult& c) { return elastic_unloading_stiffness(*stiffness_, *contact_, c); });
}

double Simulation::unloading_stiffness() const {
  return elastic_unloading_stiffness(*stiffness_, *contact_, contact());
}

double Simulation::contact_half_width() const {
  return indentsim::contact_half_width(*contact_, contact());
}

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
  state_ = s;
  state_.history.clear();     // the bulk model holds the live history
  state_.in_contact.clear();  // implied by u
  bulk_->restore(s.history, state_.u.data());
  if (rebuild) build_system();
  if (contact().in_contact != s.in_contact)
    throw std::invalid_argument("the saved contact set does not follow from the saved displacement");
}

double Simulation::free_surface_depth() const {
  double depth = -std::numeric_limits<double>::infinity();
  for (const auto& c : contact_->candidates()) depth = std::max(depth, -state_.u[c.equation] - c.surface_height);
  return depth;
}

std::optional<std::vector<double>> Simulation::force_sensitivities(const std::vector<MaterialParameter>& parameters) {
  std::optional<Sensitivities> s = sensitivities(parameters);
  if (!s) return std::nullopt;
  return std::move(s->force);
}

std::optional<Simulation::Sensitivities> Simulation::sensitivities(const std::vector<MaterialParameter>& parameters,
                                                                   bool with_displacement) {
  const MaterialInput& m = load_case_.material;
  for (MaterialParameter p : parameters)
    if (p == MaterialParameter::nu) return std::nullopt;  // nu also shapes the condensed far field
  std::vector<double> u_system;
  to_system(state_.u, u_system);
  const std::size_t n = u_system.size();
  BulkOperator& bulk = system_bulk();
  const ContactBoundary& contact = condensation_ ? condensation_->contact() : *contact_;
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
  // Right-hand sides -dF/d(theta): an active contact row c (v + alpha - g) does not depend on theta.
  const auto& candidates = contact.candidates();
  std::vector<char> active(candidates.size());
  for (std::size_t k = 0; k < candidates.size(); ++k)
    active[k] = ContactBoundary::active(candidates[k], force[candidates[k].equation], u_system[candidates[k].equation], state_.alpha);
  std::vector<std::vector<double>> du = d_force;
  for (auto& rhs : du) {
    for (double& v : rhs) v = -v;
    for (std::size_t k = 0; k < candidates.size(); ++k)
      if (active[k]) rhs[candidates[k].equation] = 0.0;
  }
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
      case MaterialParameter::nu: return std::nullopt;
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

std::vector<LayerForce> Simulation::layer_forces() const {
  return indentsim::layer_forces(*mesh_, *bulk_);
}

void Simulation::check_fine_zone(double half_width) {
  if (state_.warned_fine_zone || half_width <= plan_.fine_width) return;
  state_.warned_fine_zone = true;
  state_.warnings.push_back(fmt::format(
      "at alpha = {:.4g} m the contact half-width {:.4g} m left the fine mesh zone ({:.4g} m): accuracy drops; "
      "set mesh.contact_half_width or mesh.fine_width larger",
      state_.alpha, half_width, plan_.fine_width));
}

IncrementRecord Simulation::record(double wall_seconds, long iterations, long factorizations, int cutbacks) {
  const ContactResult c = contact();
  IncrementRecord r;
  r.step = state_.rows++;
  r.alpha = state_.alpha;
  r.force = c.force;
  r.half_width = indentsim::contact_half_width(*contact_, c);
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
  if (state_.alpha == load_case_.max_depth() && c.force > 0.0 && c.contact_nodes < 4) {
    const std::string coarse = fmt::format("the contact zone spans only {} node(s) at the deepest point: the result "
                                           "is coarse; raise mesh.contact_nodes",
                                           c.contact_nodes);
    if (std::find(state_.warnings.begin(), state_.warnings.end(), coarse) == state_.warnings.end()) state_.warnings.push_back(coarse);
  }
  return r;
}

}  // namespace indentsim
