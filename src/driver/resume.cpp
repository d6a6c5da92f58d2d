#include "indentsim/driver/resume.hpp"

#include <algorithm>
#include <stdexcept>

#include <fmt/format.h>

#include "indentsim/base/error.hpp"
#include "indentsim/simulation/load_stepping.hpp"
#include "indentsim/simulation/run_configuration.hpp"

namespace indentsim {

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

  // The new load path must pass through the history already computed.
  const std::vector<double> before = plan_increments(stored.load), after = plan_increments(run.load_case.load);
  const std::size_t done = static_cast<std::size_t>(c.state.next_target);
  if (done == 0 || done > before.size()) fail("its state does not fit its own load path");
  if (after.size() < done || !std::equal(before.begin(), before.begin() + static_cast<std::ptrdiff_t>(done), after.begin()))
    throw InputError(source, "load.path",
                     fmt::format("must follow the checkpointed history for its first {} increments (up to alpha = "
                                 "{:.6g} m): keep the path's waypoints and increments up to there",
                                 done - 1, before[done - 1]));
  if (!(c.planned_contact_half_width > 0.0)) fail("holds no valid mesh plan");
  for (std::size_t k = 0; k < done; ++k)
    if (c.curve[k].alpha != before[k]) fail(fmt::format("its curve row {} is not at the depth its load path plans", k));
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
  // The curve's last row must be what the state gives: the force and the contact set follow from
  // the displacement.
  const ContactResult contact = run.simulation->contact();
  const IncrementRecord& last = c.curve.back();
  double largest = 0.0;
  for (const auto& r : c.curve) largest = std::max(largest, r.force);
  if (std::abs(contact.force - last.force) > 1e-9 * largest || contact.contact_nodes != last.contact_nodes)
    fail(fmt::format("its last curve row (P = {:.10g}, {} contact nodes) is not what its state gives (P = {:.10g}, "
                     "{} contact nodes)",
                     last.force, last.contact_nodes, contact.force, contact.contact_nodes));
  return run;
}

}  // namespace indentsim
