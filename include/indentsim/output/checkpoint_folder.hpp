#pragma once
// A run folder's checkpoints: when a run writes them and which it keeps (CheckpointSchedule,
// save_checkpoint), which belong to the folder's run, and which one `indentsim resume` continues.
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include "indentsim/input/load_case.hpp"
#include "indentsim/output/checkpoint.hpp"

namespace indentsim {

/// When a run checkpoints, and which checkpoints it keeps: every `every` increments (0: only at
/// the end and on a signal), and at every reversal of the load path (each peak and valley,
/// where users branch); the newest `keep` are kept (0: all), and every reversal's always.
struct CheckpointSchedule {
  int every = 10;
  int keep = 2;
  std::set<int> waypoint_steps;

  static CheckpointSchedule of(const LoadCase& load_case);
  /// Whether the increment `step` (> 0) is checkpointed when it converges.
  bool due(int step) const;
};

/// Writes DIR/checkpoint_<step>.ck and prunes the folder as `schedule` says.  Throws IoError.
std::filesystem::path save_checkpoint(const std::filesystem::path& dir, const Checkpoint& checkpoint,
                                      const CheckpointSchedule& schedule);

/// Whether two load cases describe the same run: the same physics and mesh (first_physics_difference)
/// and the same load path and increments.  Output and solver keys may differ.
bool same_run(const LoadCase& a, const LoadCase& b);

/// One checkpoint of a folder, as `indentsim resume DIR --list` shows it.
struct CheckpointListing {
  std::filesystem::path file;
  int step = 0;
  double alpha = 0.0, force = 0.0;
  bool reversal = false;         ///< a peak or valley of the load path
  bool of_the_folders_run = true;  ///< belongs to the run whose case.toml is in the folder
  std::string problem;           ///< why it cannot be resumed ("" when it can)
  LoadCase load_case;            ///< the run it belongs to (when readable)
};

/// The checkpoints (checkpoint_NNNNNN.ck) of a run folder or of its checkpoints/ folder, by step.
/// Each is read and checked; the run's own case.toml (in the run folder), when present, tells
/// which belong to the folder's run.
std::vector<CheckpointListing> list_checkpoints(const std::filesystem::path& folder);

/// What `indentsim resume ARG` continues: ARG itself when it is a file; for a folder the newest
/// resumable checkpoint of the folder's own run.  Throws InputError (a folder without such a
/// checkpoint, or with checkpoints of several runs and no case.toml to tell them apart).
std::filesystem::path choose_checkpoint(const std::filesystem::path& argument);

}  // namespace indentsim
