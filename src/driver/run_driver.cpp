// A whole run from a load case or a checkpoint to its folder's files (run_driver.hpp).
#include "indentsim/driver/run_driver.hpp"

#include <chrono>
#include <future>
#include <memory>
#include <optional>
#include <thread>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "indentsim/output/checkpoint.hpp"
#include "indentsim/driver/resume.hpp"
#include "indentsim/output/checkpoint_folder.hpp"
#include "indentsim/base/error.hpp"
#include "indentsim/simulation/error_estimate.hpp"
#include "indentsim/base/file_system.hpp"
#include "indentsim/base/interruption.hpp"
#include "indentsim/geometry/kinematics.hpp"
#include "indentsim/simulation/load_stepping.hpp"
#include "indentsim/output/run_folder.hpp"

namespace fs = std::filesystem;

namespace indentsim {

int RunReport::exit_status() const {
  switch (status) {
    case RunStatus::not_converged: return 3;
    case RunStatus::stopped: return 128 + stop_signal;
    default: return 0;
  }
}

std::string describe_near_field(const Simulation& sim) {
  const NearField& near = sim.near_field();
  if (!near.condensed) return fmt::format("Newton systems: the whole mesh ({} unknowns)", sim.system_unknowns());
  return fmt::format("Newton systems: {} unknowns of the near field ({} contact candidates, {} x {} elements that may "
                     "yield); the elastic far field is condensed",
                     sim.system_unknowns(), near.contact_nodes, near.elements_x, near.elements_y);
}

std::string describe_mesh(const Simulation& sim) {
  const auto& p = sim.plan();
  return fmt::format("mesh: {} x {} nodes, {} unknowns; fine zone {:.4g} m x {:.4g} m at spacing {:.4g} m "
                     "(estimated final contact half-width {:.4g} m), growth {:.3f}; linear solver {}",
                     p.nodes_x, p.nodes_y, sim.mesh().equations(), p.fine_width, p.fine_depth, p.fine_spacing,
                     p.contact_half_width_estimate, p.growth,
                     sim.linear_solver() == LinearSolverKind::cholmod ? "CHOLMOD" : "KLU");
}

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::string companions_note(const LoadCase& lc) {
  const std::vector<int> levels = companion_contact_nodes(lc);
  return fmt::format("error estimate: companion run{} at contact_nodes = {}", levels.size() > 1 ? "s" : "",
                     fmt::join(levels, " and "));
}

/// mesh.error_estimate: the companion runs of `sim` (before anything is written), timed as the
/// run's "error estimate" phase; null when it is off or unavailable.
std::unique_ptr<DiscretizationErrorEstimate> estimate_error(Simulation& sim, RunObserver& observer) {
  const LoadCase& lc = sim.load_case();
  if (lc.mesh.error_estimate == ErrorEstimateChoice::off) return nullptr;
  if (const auto why = error_estimate_unavailable(lc)) {
    observer.warning(*why);
    return nullptr;
  }
  observer.note(companions_note(lc));
  const PhaseTimes::Scope timing = sim.times().measure("error estimate");
  auto estimate = std::make_unique<DiscretizationErrorEstimate>(sim);
  for (const auto& warning : estimate->warnings()) observer.warning(warning);
  return estimate;
}

/// A new run's simulation and its error estimate: there (null when off or unavailable), or still
/// being computed by its companions on a second thread (`companions` valid).
struct NewRun {
  std::unique_ptr<Simulation> simulation;
  std::unique_ptr<DiscretizationErrorEstimate> estimate;
  std::future<std::unique_ptr<DiscretizationErrorEstimate>> companions;
};

/// Plans a new run, builds its model and starts its companions.  The companions need only the
/// load case and the plan, so where a second core is there they run on it while this thread
/// builds the main run's model and steps its first increments (drive() takes their estimate as
/// soon as it is there; curve.csv's estimate cells stay empty until then).  Each run is single-threaded
/// and deterministic (worker_threads.hpp), so the estimate is the same either way.  On one core
/// the companions run after the model, as on a resume.
NewRun start_run(const LoadCase& lc, RunObserver& observer) {
  PhaseTimes times;
  RunPlan plan;
  {
    const PhaseTimes::Scope timing = times.measure("planning");
    plan = plan_run(lc);
  }
  NewRun run;
  const bool estimate = lc.mesh.error_estimate != ErrorEstimateChoice::off && !error_estimate_unavailable(lc);
  if (estimate && std::thread::hardware_concurrency() >= 2)
    run.companions = std::async(std::launch::async,
                                [lc, plan] { return std::make_unique<DiscretizationErrorEstimate>(lc, plan); });
  run.simulation = std::make_unique<Simulation>(lc, plan, std::move(times));  // validates the mesh size
  Simulation& sim = *run.simulation;
  observer.note(describe_mesh(sim));
  observer.note(describe_near_field(sim));
  if (run.companions.valid()) observer.note(companions_note(lc));
  else run.estimate = estimate_error(sim, observer);
  return run;
}

/// Steps the simulation to the end of its load path, writing outputs and checkpoints; on
/// SIGINT/SIGTERM it checkpoints after the increment in progress and stops.  Ends the folder's
/// summary.json with the run's status; any exception marks the folder "failed" and propagates.
RunReport drive(Simulation& sim, RunOutput& output, RunObserver& observer, NewRun* pending = nullptr) {
  const auto start = std::chrono::steady_clock::now();
  const LoadCase& lc = sim.load_case();
  const fs::path checkpoint_dir = fs::path(lc.output.dir) / "checkpoints";
  const CheckpointSchedule schedule = CheckpointSchedule::of(lc);
  const int planned = static_cast<int>(plan_increments(lc.load).size()) - 1;
  const std::string force_unit = make_kinematics(lc.geometry.kind)->force_unit();
  std::size_t warnings_shown = 0;
  const auto pass_warnings = [&] {
    for (; warnings_shown < sim.warnings().size(); ++warnings_shown) observer.warning(sim.warnings()[warnings_shown]);
  };
  int last_checkpoint = output.records().empty() ? -1 : output.records().back().step;
  const auto checkpoint = [&] {
    last_checkpoint = output.records().back().step;
    return save_checkpoint(checkpoint_dir, make_checkpoint(sim, output.records(), output.free_surface_depths(), output.true_contacts()),
                           schedule);
  };
  // The estimate of companions still running (start_run): taken as soon as it is there, and
  // waited for before a checkpoint and before the end, which need every row on disk.  The wait
  // is the run's "error estimate" phase.
  const auto settle_estimate = [&](bool wait) {
    if (!pending || !pending->companions.valid()) return;
    if (!wait && pending->companions.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return;
    const PhaseTimes::Scope timing = sim.times().measure("error estimate");
    try {
      pending->estimate = pending->companions.get();
      for (const auto& warning : pending->estimate->warnings()) observer.warning(warning);
    } catch (const Interrupted&) {
      pending->estimate.reset();  // stopped by the signal that stops the run: rows without estimate
    }
    output.set_error_estimate(pending->estimate.get());
  };
  RunReport report;
  report.dir = lc.output.dir;
  report.curve_file = output.curve_path();
  report.load_case = lc;
  observer.increments_started();
  try {
    try {
      sim.run([&](const IncrementRecord& r) {
        settle_estimate(schedule.due(r.step));
        {
          const PhaseTimes::Scope timing = sim.times().measure("output");
          output.increment(sim.snapshot(r));
          inject_fault("increment");
          if (schedule.due(r.step)) checkpoint();
        }
        pass_warnings();
        if (r.step > 0) observer.increment(r, planned, force_unit);
        if (const int signal = interruption_requested()) throw Interrupted(signal);
      });
      settle_estimate(true);
      if (lc.output.checkpoint_every > 0 && last_checkpoint != output.records().back().step) {
        const PhaseTimes::Scope timing = sim.times().measure("output");
        checkpoint();
      }
    } catch (const SolverError& e) {
      report.status = RunStatus::not_converged;
      report.message = e.what();
    } catch (const Interrupted& i) {
      settle_estimate(true);
      report.resume_checkpoint = checkpoint();
      report.status = RunStatus::stopped;
      report.stop_signal = i.signal();
      report.message = fmt::format("stopped by signal {}; resume with: indentsim resume {}", i.signal(),
                                   report.resume_checkpoint.string());
    }
    observer.increments_ended();
    settle_estimate(true);
    {
      const PhaseTimes::Scope timing = sim.times().measure("output");
      const IncrementRecord last = output.records().empty() ? IncrementRecord{} : output.records().back();
      output.finish(sim.snapshot(last), report.status, report.message, sim.times());
    }
    pass_warnings();
  } catch (const std::exception& e) {
    observer.increments_ended();
    try {
      settle_estimate(true);  // the rows held back, with or without their estimate
    } catch (...) {
      output.set_error_estimate(nullptr);
    }
    output.fail(e.what());
    throw;
  }
  observer.final_state(sim);
  report.curve = output.records();
  report.last_step = report.curve.empty() ? 0 : report.curve.back().step;
  if (sim.near_field_growths() > 0 || sim.near_field_rebuilds() > 0)
    observer.note(fmt::format("the near field grew {} time(s) ahead of the plastic zone and {} time(s) after an "
                              "increment left it; {}",
                              sim.near_field_rebuilds(), sim.near_field_growths(), describe_near_field(sim)));
  observer.note(fmt::format("largest condition estimate of a Newton matrix: {:.3g} ({})",
                            sim.largest_condition_estimate(),
                            sim.linear_solver() == LinearSolverKind::cholmod ? "CHOLMOD 1/rcond" : "KLU condest"));
  std::string phases;
  for (const auto& [name, seconds] : sim.times().phases())
    phases += fmt::format("{}{} {:.3g} s", phases.empty() ? "" : ", ", name, seconds);
  observer.note(fmt::format("time: {}", phases));
  report.wall_seconds = seconds_since(start);
  return report;
}

}  // namespace

RunReport run_load_case(LoadCase lc, RunObserver& observer) {
  const auto start = std::chrono::steady_clock::now();
  RunFolder folder(lc.output.dir, lc.source);  // one run per folder: locked before anything is solved
  // Force control: the depth the largest force reaches sizes the mesh (the depth pilot).
  lc = with_depth_estimate(std::move(lc));
  // mesh.target_error: pilots choose contact_nodes (and, for a path-dependent run, the
  // increments); the run checks its own estimates and is refined once if it missed.  The case as
  // run (case.toml, checkpoints) has the chosen mesh and increments.
  std::optional<TargetErrorChoice> target;
  if (lc.mesh.target_error) {
    target.emplace();
    lc = plan_case_for_target(lc, *target);
    for (const auto& a : target->attempts)
      observer.note(fmt::format("target error {:.3g}: the pilot at contact_nodes = {}, {} increments estimates {:.3g}{}",
                                target->target, a.contact_nodes, a.increments, a.relative_error,
                                a.increment_change ? fmt::format("; halving its increments moves P {:.3g}",
                                                                 *a.increment_change)
                                                   : std::string()));
    observer.note(fmt::format("target error {:.3g}: running contact_nodes = {}, {} increments", target->target,
                              lc.mesh.contact_nodes, lc.load.total_increments()));
  }
  for (;;) {
    NewRun run = start_run(lc, observer);  // before anything is written
    Simulation& sim = *run.simulation;
    const auto& estimate = run.estimate;
    folder.clear_earlier_run();
    // case.toml holds the case as run: what the pilot measured and what "auto" chose.
    const LoadCase as_run = case_as_run(lc, sim.configuration());
    RunOutput output = run.companions.valid() ? RunOutput(folder.dir(), as_run, true)
                                              : RunOutput(folder.dir(), as_run, estimate.get());
    output.set_configuration(run.simulation->configuration());
    if (target) output.set_target_choice(*target);
    RunReport report = drive(sim, output, observer, &run);
    report.wall_seconds = seconds_since(start);
    if (!target || report.status != RunStatus::finished || target->retried) return report;
    const std::optional<double> reached = relative_force_error(*estimate, output.records());
    std::optional<double> change;
    if (const auto& s = estimate->increment_sensitivity()) change = s->relative_change();
    const bool mesh_missed = reached && *reached > target->target;
    const bool increments_missed = change && *change > target->target;
    if (!mesh_missed && !increments_missed) return report;
    target->attempts.push_back({"run", lc.mesh.contact_nodes, lc.load.total_increments(), reached.value_or(0.0), change});
    target->retried = true;
    lc = refine_case_for_target(lc, target->attempts.back(), target->target);
    observer.note(fmt::format("target error {:.3g} missed (estimate {:.3g}{}): running once more at contact_nodes = "
                              "{}, {} increments",
                              target->target, reached.value_or(0.0),
                              change ? fmt::format("; halving the increments moves P {:.3g}", *change) : std::string(),
                              lc.mesh.contact_nodes, lc.load.total_increments()));
  }
}

RunReport resume_run(const std::string& argument, const std::vector<std::string>& overrides, const std::string& out,
                     RunObserver& observer) {
  const auto start = std::chrono::steady_clock::now();
  const fs::path file = choose_checkpoint(argument);
  const Checkpoint checkpoint = read_checkpoint(file);
  // The run folder the checkpoint sits in (RUN/checkpoints/checkpoint_N.ck), wherever it has been
  // moved or copied: it, not the folder the case was first run in, is where the run continues.
  std::error_code ec;
  fs::path home;
  if (file.parent_path().filename() == "checkpoints") {
    const fs::path run_dir = file.parent_path().parent_path().empty() ? fs::path(".") : file.parent_path().parent_path();
    if (fs::is_regular_file(run_dir / "case.toml", ec)) home = run_dir;
  }
  std::vector<std::string> all = overrides;
  const std::string target = !out.empty() ? out : home.string();
  if (!target.empty()) all.push_back("output.dir=" + toml_string(target));
  ResumedRun run = resume_from(checkpoint, file.string(), all);  // everything checked before writing
  const LoadCase stored = parse_load_case(checkpoint.load_case_toml, file.string());
  const LoadCase as_run = case_as_run(run.load_case, run.simulation->configuration());  // case.toml's
  const fs::path dir = run.load_case.output.dir;
  const bool in_place = fs::equivalent(dir, home.empty() ? fs::path(stored.output.dir) : home, ec);
  if (in_place) {
    // Continuing in the run's own folder is for a plain continuation only: a branch (another load
    // path) must never overwrite the run it branches from.
    if (!same_run(stored, run.load_case))
      throw InputError(file.string(), "--out",
                       fmt::format("a branch (another load path) is a new run: give it its own folder with --out; "
                                   "\"{}\" is left as it is",
                                   dir.string()));
    if (fs::is_regular_file(dir / "case.toml", ec)) {
      const LoadCase folder_case = read_load_case(dir / "case.toml");
      if (!same_run(folder_case, as_run))
        throw InputError(file.string(), "--out",
                         fmt::format("\"{}\" now holds another run; give the continuation its own folder with --out",
                                     dir.string()));
    }
  }
  RunFolder folder(dir, file.string());
  const int step = checkpoint.curve.back().step;
  observer.note(fmt::format("resuming {} after increment {} (alpha = {:.6g} m)", file.string(), step,
                            checkpoint.state.alpha));
  // The companions are run again (they are cheap and not checkpointed), before anything is written.
  const auto estimate = estimate_error(*run.simulation, observer);
  folder.clear_earlier_run(in_place ? std::optional<int>(step) : std::nullopt);
  RunOutput output(folder.dir(), as_run, estimate.get(), checkpoint.curve, checkpoint.free_surface_depths);
  output.set_configuration(run.simulation->configuration());
  output.restore_true_contacts(checkpoint.true_contacts);
  output.resumed(run.simulation->snapshot(checkpoint.curve.back()));
  RunReport report = drive(*run.simulation, output, observer);
  report.wall_seconds = seconds_since(start);
  return report;
}

}  // namespace indentsim
