#pragma once
// A whole run, as `indentsim run` / `resume`, the Python module and a sweep all do it: a load case
// (or a checkpoint) in, the run folder's files out.  In order: mesh.target_error's pilot chooses
// contact_nodes; the folder is locked (run_folder.hpp); the error estimate's companion runs
// (error_estimate.hpp); the increments, with checkpoints on schedule (checkpoint.hpp); the final
// files; and, when the target was missed, one more run on the refined mesh.  SIGINT/SIGTERM
// (interruption.hpp) stop a run after its last converged increment is checkpointed.
//
// What a run says as it goes reaches a RunObserver: the CLI prints it, a sweep and the Python
// module keep quiet.  How it ended is the RunReport.
#include <filesystem>
#include <string>
#include <vector>

#include "indentsim/output/run_output.hpp"
#include "indentsim/input/load_case.hpp"
#include "indentsim/simulation/load_stepping.hpp"
#include "indentsim/simulation/simulation.hpp"

namespace indentsim {

/// The hooks of a run; each does nothing unless overridden.
class RunObserver {
public:
  virtual ~RunObserver() = default;
  /// A line on what the run does: the mesh, the near field, the target error's choice, the times.
  virtual void note(const std::string& /*line*/) {}
  /// A warning (plausibility, the error estimate's caveats, the solver's remarks).
  virtual void warning(const std::string& /*text*/) {}
  /// The increments begin (after the pilot and the error estimate's companions).
  virtual void increments_started() {}
  /// After each converged increment, of `planned` increments on the load path.
  virtual void increment(const IncrementRecord& /*record*/, int /*planned*/, const std::string& /*force_unit*/) {}
  /// The increments are over, however they ended (a progress line is closed here).
  virtual void increments_ended() {}
  /// The last converged state, after the run's files are written (the Python module copies its
  /// fields here).
  virtual void final_state(const Simulation& /*simulation*/) {}
};

/// How a run ended.  Input errors never get this far (InputError is thrown before anything is
/// written); an I/O error marks the folder failed and IoError propagates.
struct RunReport {
  RunStatus status = RunStatus::finished;  ///< finished, not_converged or stopped
  /// not_converged: the solver's reason; stopped: the signal and the checkpoint to resume from.
  std::string message;
  int stop_signal = 0;
  std::filesystem::path resume_checkpoint;  ///< stopped: the checkpoint just written
  int last_step = 0;                        ///< the last converged increment
  std::filesystem::path dir;                ///< the run folder
  std::filesystem::path curve_file;         ///< dir / curve.csv
  LoadCase load_case;                       ///< as run (mesh.target_error: the mesh it chose)
  std::vector<IncrementRecord> curve;       ///< every converged increment, as curve.csv has them
  double wall_seconds = 0.0;

  /// The CLI's exit status: 0 finished, 3 not converged, 128 + signal when stopped.
  int exit_status() const;
};

/// Solves `load_case` into its output.dir.
RunReport run_load_case(LoadCase load_case, RunObserver& observer);

/// Continues a run from a checkpoint: `argument` is a checkpoint file, a run folder or its
/// checkpoints folder (the newest checkpoint that can resume), `overrides` may branch the load
/// path (which then needs its own folder: `out`, else InputError), `out` ("" for the run's own
/// folder) is where the continuation is written.
RunReport resume_run(const std::string& argument, const std::vector<std::string>& overrides, const std::string& out,
                     RunObserver& observer);

/// "mesh: N x M nodes, ..." and the near field's line, as the run prints them.
std::string describe_mesh(const Simulation& simulation);
std::string describe_near_field(const Simulation& simulation);

}  // namespace indentsim
