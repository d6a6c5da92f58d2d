#pragma once
// The files of `indentsim fit`: what it reads (a load case with the command line's curve, or a fit
// file with one [[data]] table per data set) and what it writes (fit.json, fit_curves.csv).
//
// A fit file:
//   [fit]
//   free = ["material.yield_stress", "material.n"]
//   bounds = { "material.n" = [0.01, 0.6] }   # optional; physically safe defaults otherwise
//   starts = 3                                  # optional
//   out = "out/fit"                             # optional
//   single_level = true                         # optional: no coarse phase (--single-level)
//   [[data]]                                    # a force-depth curve
//   case = "sphere.toml"                        # relative to the fit file
//   curve = "sphere.csv"                        # columns alpha [m] and P [N] unless told:
//   depth_column = "Depth"  force_column = "Load"  depth_unit = "nm"  force_unit = "mN"
//                                               # (plane strain: P in N/m, force_unit = "mN/m", ...;
//                                               # a unit of the other scene is refused)
//   weight = 1.0
//   set = ["mesh.contact_nodes=16"]             # overrides of this data set's case
//   [[data]]                                    # a residual imprint after unloading to 0
//   case = "sphere.toml"
//   imprint = "imprint.csv"                     # columns r and depth (down positive), in m unless
//   radius_column = "r"  depth_column = "depth"  unit = "um"   # told or given in the header
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "indentsim/input/curve_csv.hpp"
#include "indentsim/fitting/fit.hpp"

namespace indentsim {

/// The command line of `indentsim fit`.
struct FitCommandLine {
  std::string input;                    ///< CASE.toml (with --data) or FIT.toml
  std::vector<std::string> data_files;  ///< --data: force-depth curves of the case
  std::vector<std::string> free;        ///< --free keys (comma-separated lists allowed)
  std::vector<std::string> bounds;      ///< --bounds key=lower:upper
  std::vector<std::string> overrides;   ///< --set, on every data set's case
  CurveColumns columns;                 ///< --depth-column, --force-column, --depth-unit, --force-unit
  std::optional<int> starts;
  std::optional<int> mesh_refinements;  ///< --mesh-refinements (FitSettings::mesh_refinements)
  std::optional<int> threads;           ///< --threads (FitSettings::threads): the machine's, not the fit's
  std::string out;
  bool finite_differences = false;
  bool single_level = false;  ///< --single-level: no coarse phase (FitSettings::coarse_first)
  bool resume = false;        ///< --resume: continue from the output folder's fit_checkpoint.json
  bool no_design = false;     ///< --no-design: no experiment-design table (FitSettings::design_experiments)
  bool no_profile = false;    ///< --no-profile: linearized intervals only (FitSettings::profile)
};

struct FitJob {
  FitProblem problem;
  std::string out_dir;
  /// What was done to the data before the fit, one line each (a curve reduced to the points the
  /// model resolves: reduce_to_resolution).
  std::vector<std::string> notes;
};

/// Reads and checks everything a fit needs; throws InputError naming the file and the key.
FitJob read_fit_job(const FitCommandLine& command_line);

/// DIR/fit.json: parameters with standard errors and bounds, correlation, singular values,
/// identifiability, the quality verdict and warnings, residuals, forward runs (and failed ones),
/// wall time, every start.
nlohmann::json fit_json(const FitProblem& problem, const FitResult& result);
/// DIR/fit_curves.csv: data set, abscissa, data, model, residual (SI), for the figure.
std::string fit_curves_csv(const FitProblem& problem, const FitResult& result);

/// Writes a fit's files into `dir` (created if needed), each atomically: fit.json,
/// fit_curves.csv and fitted_case.toml (fitted_case_K.toml for the K-th data set beyond the first).
void write_fit_results(const std::filesystem::path& dir, const FitProblem& problem, const FitResult& result);

/// DIR/fit_checkpoint.json: where a fit stood after its last accepted iteration (FitCheckpoint),
/// with a fingerprint of its problem (the data, the cases, the free parameters and bounds, the
/// settings that steer the optimiser) so that only the same fit continues from it.
inline constexpr const char* fit_checkpoint_name = "fit_checkpoint.json";
std::string fit_fingerprint(const FitProblem& problem);
void write_fit_checkpoint(const std::filesystem::path& dir, const FitProblem& problem, const FitCheckpoint& checkpoint);
/// The checkpoint in `dir`.  Throws InputError naming the file when there is none, when it is
/// damaged, or when it is another fit's (its fingerprint differs: the data, a case or a setting changed).
FitCheckpoint read_fit_checkpoint(const std::filesystem::path& dir, const FitProblem& problem);

/// A fit as `indentsim fit` runs it: a checkpoint in the job's folder after every accepted
/// iteration (`resume`: continued from the one there), the results written when it ends and the
/// checkpoint then removed.  Throws what fit() throws; a stopped fit leaves its checkpoint.
FitResult run_fit_job(FitJob& job, bool resume);

}  // namespace indentsim
