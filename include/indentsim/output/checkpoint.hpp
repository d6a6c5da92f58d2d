#pragma once
// Checkpoints: everything needed to continue a run bit for bit, in one versioned, checksummed
// binary file written atomically (temporary file, flush, fsync, rename, fsync of the folder), so
// a kill at any moment leaves the previous checkpoint intact.
//
// Layout (little-endian, as this machine writes it):
//   "INDSIMCK" | u32 format version | u64 payload length | payload | u64 FNV-1a of all before
// The payload holds the load case as run (TOML text and its hash), the mesh plan and node
// coordinates, the run state (SimulationState: its fields in the order of visit_fields, which the
// writer, the reader and the checks all walk), and the curve so far.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "indentsim/simulation/load_stepping.hpp"
#include "indentsim/simulation/simulation.hpp"

namespace indentsim {

// Format 2: the condensed near field joined the state.  Format 3: the material history holds four
// strain components (eps33, the hoop strain of axisymmetry).  No older format is read.
constexpr std::uint32_t checkpoint_format_version = 4;  // 4: the pilot's plastic zone growth

struct Checkpoint {
  std::string load_case_toml;            ///< to_toml() of the load case as run
  double planned_contact_half_width = 0.0;  ///< the mesh plan's a* (no pilot run on resume)
  std::vector<double> mesh_x, mesh_y;    ///< node coordinates, to check the rebuilt mesh
  SimulationState state;
  std::vector<IncrementRecord> curve;    ///< every row written so far
  std::vector<double> free_surface_depths;  ///< per row, for summary.json
};

/// 64-bit FNV-1a: any single changed byte changes it.
std::uint64_t fnv1a(const void* data, std::size_t size, std::uint64_t seed = 0xcbf29ce484222325ull);

std::string serialize(const Checkpoint& checkpoint);
/// Throws InputError(source, "checkpoint", problem) for anything but a complete, intact,
/// current-version checkpoint.
Checkpoint deserialize(const std::string& bytes, const std::string& source);

void write_checkpoint(const std::filesystem::path& file, const Checkpoint& checkpoint);
Checkpoint read_checkpoint(const std::filesystem::path& file);

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

/// Builds a checkpoint of a running simulation and the rows it has reported.
Checkpoint make_checkpoint(const Simulation& sim, const std::vector<IncrementRecord>& curve,
                           const std::vector<double>& free_surface_depths);

/// A simulation continuing a checkpoint, with `overrides` (--set) applied to its load case:
/// validates everything (throws InputError naming the file and the problem) before returning.
struct ResumedRun {
  LoadCase load_case;
  std::unique_ptr<Simulation> simulation;
};
ResumedRun resume_from(const Checkpoint& checkpoint, const std::string& source, const std::vector<std::string>& overrides);

}  // namespace indentsim
