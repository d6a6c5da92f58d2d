#pragma once
// Checkpoints: everything needed to continue a run bit for bit, in one versioned, checksummed
// binary file written atomically (temporary file, flush, fsync, rename, fsync of the folder), so
// a kill at any moment leaves the previous checkpoint intact.
//
// Layout (little-endian, as this machine writes it):
//   "INDSIMCK" | u32 format version | u64 payload length | payload | u64 FNV-1a of all before
// The payload holds the load case as run (TOML text and its hash), the mesh plan and node
// coordinates, the simulation state (depths, displacement and predictor state, active contact
// set, material history at every Gauss point, increment controller, condensed near field), and
// the curve so far.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "indentsim/load_stepping.hpp"
#include "indentsim/simulation.hpp"

namespace indentsim {

// Format 2 (the condensed near field joined the state) reads no format-1 file.
constexpr std::uint32_t checkpoint_format_version = 2;

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

/// Writes DIR/checkpoint_<step>.ck and keeps the newest `keep` checkpoints of the folder.
std::filesystem::path save_checkpoint(const std::filesystem::path& dir, const Checkpoint& checkpoint, int keep = 2);

/// Fault injection for the robustness tests, from the environment variable INDENTSIM_FAULT:
/// "increment:N" kills the process (SIGKILL) after the N-th reported increment is written,
/// "checkpoint:N" kills it halfway through writing the N-th checkpoint.  Does nothing when the
/// variable is unset.
void inject_fault(const char* event);

/// The first key among the physics and mesh keys (geometry, punch, material, mesh) where two
/// load cases differ, or "" if they agree: what a resumed run may not change.
std::string first_physics_difference(const LoadCase& a, const LoadCase& b);

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
