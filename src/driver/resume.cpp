#include "indentsim/driver/resume.hpp"

#include <algorithm>
#include <stdexcept>

#include <fmt/format.h>

#include "indentsim/base/error.hpp"
#include "indentsim/simulation/load_control.hpp"
#include "indentsim/simulation/load_stepping.hpp"
#include "indentsim/simulation/run_configuration.hpp"

namespace indentsim {

namespace {

// What a checkpoint's state can prove about itself, checked before a run continues from it (a file
// edited with its checksum recomputed passes the byte format's checks):
// - it is a converged state: the Newton system's residual at u, on the force scale u converged on,
//   within the tolerance the run converges to.  Recomputed from the same doubles it is the
//   residual Newton accepted, up to rounding in the recomputation (measured at 0.92 of the
//   tolerance at most on every checkpoint of the shipped cases): twice the tolerance leaves room
//   for that, and no edit of u, of the history or of the embedded case's material that moves a
//   nodal force by more than that passes;
// - every Gauss point's history is one its law can carry at the committed strain;
// - the previous state (the predictor's), as far as it can be checked: a model without history
//   must be in equilibrium there too; an inelastic one, whose history has moved on since, must at
//   least touch the punch without penetrating it;
// - the curve's last row and its free-surface depth follow from u.
// Earlier rows cannot be recomputed without solving the increments again: they are trusted.
template <class Fail>
void check_restored_state(Simulation& sim, const Checkpoint& c, const Fail& fail) {
  const double tolerance = sim.load_case().solver.tolerance;
  const double residual = sim.equilibrium_residual();
  if (!(residual <= 2.0 * tolerance))
    fail(fmt::format("its state is not a converged one: Newton's scaled residual there is {:.3g}, where the run "
                     "converges every increment to {:g} (was its displacement, material history or load case "
                     "changed after it was written?)",
                     residual, tolerance));
  if (const auto violation = sim.bulk().history_violation()) fail("its material history: " + *violation);
  const SimulationState& state = c.state;
  const std::size_t rows = c.curve.size();
  if (state.has_previous) {
    const double before = rows >= 2 ? c.curve[rows - 2].alpha : 0.0;
    const bool between = (state.alpha_previous - before) * (state.alpha - state.alpha_previous) >= 0.0;
    const bool previous_row = c.curve.back().cutbacks == 0;  // one commit since the row before
    if (previous_row ? state.alpha_previous != before : !between)
      fail(fmt::format("its previous depth {:.10g} m is not {} (rows at {:.10g} and {:.10g} m)", state.alpha_previous,
                       previous_row ? "the previous row's" : "between the last two rows'", before, state.alpha));
    const double previous = sim.previous_state_residual();
    if (!(previous <= 2.0 * tolerance))
      fail(fmt::format("its previous displacement is not a converged state at alpha = {:.10g} m (scaled residual "
                       "{:.3g}, tolerance {:g})",
                       state.alpha_previous, previous, tolerance));
  }
  const ContactResult contact = sim.contact();
  const IncrementRecord& last = c.curve.back();
  double largest = 0.0;
  for (const auto& r : c.curve) largest = std::max(largest, r.force);
  if (std::abs(contact.force - last.force) > 1e-9 * largest || contact.contact_nodes != last.contact_nodes)
    fail(fmt::format("its last curve row (P = {:.10g}, {} contact nodes) is not what its state gives (P = {:.10g}, "
                     "{} contact nodes)",
                     last.force, last.contact_nodes, contact.force, contact.contact_nodes));
  // The same functions of the same doubles as when the row was written: equal to the last bit.
  const double half_width = sim.contact_half_width(), surface = sim.free_surface_depth();
  if (half_width != last.half_width || sim.bulk().plastic_points() != last.plastic_points ||
      sim.bulk().max_strain_intensity() != last.max_strain_intensity || surface != c.free_surface_depths.back())
    fail(fmt::format("its last curve row (a = {:.10g} m, {} plastic points, e_u max {:.10g}, free surface at "
                     "{:.10g} m) is not what its state gives ({:.10g} m, {}, {:.10g}, {:.10g} m)",
                     last.half_width, last.plastic_points, last.max_strain_intensity, c.free_surface_depths.back(),
                     half_width, sim.bulk().plastic_points(), sim.bulk().max_strain_intensity(), surface));
}

}  // namespace

Checkpoint make_checkpoint(const Simulation& sim, const std::vector<IncrementRecord>& curve,
                           const std::vector<double>& free_surface_depths,
                           const std::vector<std::pair<int, TrueContact>>& true_contacts) {
  Checkpoint c;
  c.load_case_toml = to_toml(case_as_run(sim.load_case(), sim.configuration()));
  c.planned_contact_half_width = sim.plan().contact_half_width_estimate;
  c.mesh_x = sim.mesh().x();
  c.mesh_y = sim.mesh().y();
  c.state = sim.state();
  c.curve = curve;
  c.free_surface_depths = free_surface_depths;
  c.true_contacts = true_contacts;
  return c;
}

ResumedRun resume_from(const Checkpoint& c, const std::string& source, const std::vector<std::string>& overrides) {
  const auto fail = [&](const std::string& problem) { throw InputError(source, "checkpoint", problem); };
  LoadCase stored;
  try {
    stored = parse_load_case(c.load_case_toml, source);
  } catch (const InputError& e) {
    fail("its load case is not valid: " + e.key() + ": " + e.problem());
  }
  ResumedRun run;
  run.load_case = parse_load_case(c.load_case_toml, source, overrides);
  if (const std::string key = first_physics_difference(stored, run.load_case); !key.empty())
    throw InputError(source, key, "cannot change when resuming: the checkpointed history depends on it");
  // The tolerance the increments before were converged to: case.toml records one for the run.
  if (run.load_case.solver.tolerance != stored.solver.tolerance)
    throw InputError(source, "solver.tolerance",
                     fmt::format("cannot change when resuming: the checkpointed increments were converged to {:g} and "
                                 "the run's case.toml records one tolerance; run the case again with the new one",
                                 stored.solver.tolerance));

  if (run.load_case.load.control != stored.load.control)
    throw InputError(source, "load.control",
                     fmt::format("cannot change when resuming: the checkpointed path steps the {}",
                                 stored.load.control == LoadControlKind::force ? "force" : "depth"));
  // The mesh and the residual's force row were planned for the largest force of the path.
  if (stored.load.control == LoadControlKind::force &&
      run.load_case.load.largest_target() != stored.load.largest_target())
    throw InputError(source, "load.path",
                     fmt::format("under force control a resumed path keeps the largest force {:g} (the mesh was planned "
                                 "for the depth it reaches): run the case again for another",
                                 stored.load.largest_target()));
  // The new load path must pass through the history already computed.
  const std::vector<double> before = plan_increments(stored.load), after = plan_increments(run.load_case.load);
  const std::unique_ptr<LoadControl> control = LoadControl::of(stored);
  const std::size_t done = static_cast<std::size_t>(c.state.next_target);
  if (done == 0 || done > before.size()) fail("its state does not fit its own load path");
  // The rows written keep their times (curve.csv's time column is continued, not rewritten).  With
  // the path's waypoints kept, a plan moved by other times (a total spread by duration) is the
  // times' doing, and named so.
  const std::vector<double> times_before = plan_times(stored.load), times_after = plan_times(run.load_case.load);
  const bool times_kept =
      times_before.empty() == times_after.empty() &&
      (times_before.empty() ||
       (times_after.size() >= done && std::equal(times_before.begin(), times_before.begin() + static_cast<std::ptrdiff_t>(done),
                                                 times_after.begin())));
  const bool path_kept =
      after.size() >= done && std::equal(before.begin(), before.begin() + static_cast<std::ptrdiff_t>(done), after.begin());
  if (!times_kept && (path_kept || run.load_case.load.path == stored.load.path))
    throw InputError(source, "load.times",
                     fmt::format("must follow the checkpointed history for its first {} increments (up to t = {} s): "
                                 "keep the times of the waypoints up to there, given or not as they were",
                                 done - 1, times_before.empty() ? 0.0 : times_before[done - 1]));
  if (!path_kept)
    throw InputError(source, "load.path",
                     fmt::format("must follow the checkpointed history for its first {} increments (up to {}): keep "
                                 "the path's waypoints and increments up to there",
                                 done - 1, control->describe(before[done - 1])));
  if (!(c.planned_contact_half_width > 0.0)) fail("holds no valid mesh plan");
  for (std::size_t k = 0; k < done; ++k)
    if (c.curve.size() <= k ||
        !control->at_target(c.curve[k], before[k], stored.load.largest_target(), stored.solver.tolerance))
      fail(fmt::format("its curve row {} is not at the {} its load path plans", k,
                       control->kind() == LoadControlKind::force ? "force" : "depth"));
  // The run continues on the near field it had (bit for bit), unless --set asks for the whole mesh.
  SimulationState state = c.state;
  if (run.load_case.solver.far_field == FarFieldChoice::full) state.near_field = NearField{};
  // The configuration is the run's own (its mesh plan, the pilot's plastic zone as checkpointed),
  // so a resumed run makes the same choices and says so in its summary.
  const RunConfiguration configuration = resolve_choices(
      run.load_case, RunPlan{plan_mesh(run.load_case, c.planned_contact_half_width), state.plastic_zone_growth});
  run.simulation = std::make_unique<Simulation>(run.load_case, configuration, state.near_field);
  if (run.simulation->mesh().x() != c.mesh_x || run.simulation->mesh().y() != c.mesh_y)
    fail("its mesh does not match the mesh its load case gives (written by another version of indentsim?)");
  try {
    run.simulation->restore(state);
  } catch (const std::invalid_argument& e) {
    fail(std::string("its state does not fit its load case: ") + e.what());
  }
  check_restored_state(*run.simulation, c, fail);
  return run;
}

}  // namespace indentsim
