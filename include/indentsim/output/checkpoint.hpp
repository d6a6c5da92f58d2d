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
#include <string>
#include <vector>

#include "indentsim/analysis/indentation_analysis.hpp"
#include "indentsim/simulation/load_stepping.hpp"
#include "indentsim/simulation/simulation_state.hpp"

namespace indentsim {

// Format 2: the condensed near field joined the state.  Format 3: the material history holds four
// strain components (eps33, the hoop strain of axisymmetry).  No older format is read.
// 4: the pilot's plastic zone growth; 5: the true contacts of the peaks passed, and the case as run
// (the pilot's measurements as keys); 6: the force scales the state's two displacements converged
// on (resume checks the state's equilibrium against them); 7: finite strain's history holds the
// largest far-field gradient; 8: the case as run names finite strain's elastic stress
// (material.elastic_stress): a format-7 finite-strain run took the Kirchhoff stress = D : e, which
// its case does not say, so it is not read as a Cauchy run.
// 9: the state holds force control's forces (the target converged to, the one before, the
// largest).
constexpr std::uint32_t checkpoint_format_version = 9;

struct Checkpoint {
  std::string load_case_toml;            ///< to_toml() of the load case as run
  double planned_contact_half_width = 0.0;  ///< the mesh plan's a* (no pilot run on resume)
  std::vector<double> mesh_x, mesh_y;    ///< node coordinates, to check the rebuilt mesh
  SimulationState state;
  std::vector<IncrementRecord> curve;    ///< every row written so far
  std::vector<double> free_surface_depths;  ///< per row, for summary.json
  /// The exact unloading stiffness and contact radius at each peak passed (summary.json's truth
  /// of the branches: they need the live state at the peak, which a resume no longer has).
  std::vector<std::pair<int, TrueContact>> true_contacts;
};

/// 64-bit FNV-1a: any single changed byte changes it.
std::uint64_t fnv1a(const void* data, std::size_t size, std::uint64_t seed = 0xcbf29ce484222325ull);

std::string serialize(const Checkpoint& checkpoint);
/// Throws InputError(source, "checkpoint", problem) for anything but a complete, intact,
/// current-version checkpoint.
Checkpoint deserialize(const std::string& bytes, const std::string& source);

void write_checkpoint(const std::filesystem::path& file, const Checkpoint& checkpoint);
Checkpoint read_checkpoint(const std::filesystem::path& file);

}  // namespace indentsim
