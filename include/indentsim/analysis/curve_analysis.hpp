#pragma once
// `indentsim analyze`: the Oliver-Pharr analysis (indentation_analysis.hpp) of every unloading
// branch of one load-depth curve, from a file.
//
//   a run's folder (or its curve.csv): the curve (alpha, P), the indenter and the specimen's nu
//     from its case.toml, and what the run recorded at each peak in summary.json (the exact
//     unloading stiffness, the true contact radius).  Only analysis.* keys may be changed.
//   a measured curve (CSV): the columns, units and indenter of an AnalysisSetup (a small TOML
//     file and/or --set); branches found by the force (load control), see
//     measured_unloading_branches.
//
// What cannot be analysed is an InputError naming the curve's file, the branch and the problem:
// the CLI exits 2 and writes nothing.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "indentsim/analysis/indentation_analysis.hpp"
#include "indentsim/input/load_case.hpp"

namespace indentsim {

class PunchShape;

struct AnalyzedBranch {
  CurveBranch branch;
  std::string label;  ///< where it is: "steps 20-34" of a run, "rows 412-1030" of a measured file
  BranchAnalysis result;
};

struct CurveAnalysis {
  std::filesystem::path curve_file;
  bool simulated = false;  ///< a run's own curve (true contact known) or a measured one
  SceneKind scene = SceneKind::axisymmetric;
  PunchInput punch;
  AnalysisInput settings;
  std::optional<double> specimen_nu;
  std::optional<CoatingContext> coating;  ///< a coated run's film (docs/MODEL.md §14.4)
  std::string depth_unit = "m", force_unit = "N";  ///< the units the file was read in
  std::vector<double> depth, force;                ///< the whole curve [m], [N] (or N/m)
  std::vector<double> time;                        ///< [s], or empty: a curve without time
  std::vector<AnalyzedBranch> branches;
};

/// Warnings for branches whose hardness or modulus no solid has (H outside 1e5-1e12 Pa, E_r
/// outside 1e3-2e12 Pa): a depth in nm declared as m, a force in mN as N, give H off by 1e3-1e18.
std::vector<std::string> implausible_results(const CurveAnalysis& analysis);

/// A coated run's branches where the substrate moves E_r or H by more than
/// analysis.substrate_tolerance from the film alone's (docs/MODEL.md §14.4), one warning each.
std::vector<std::string> substrate_effect_warnings(const CurveAnalysis& analysis);
/// True when `path` is a run's folder, or the curve.csv in one (beside its case.toml).
bool is_run_output(const std::filesystem::path& path);

/// Analyses a run's curve; `overrides` may set analysis.* keys only.
CurveAnalysis analyze_run_curve(const std::filesystem::path& path, const std::vector<std::string>& overrides);

/// Analyses a measured curve with the setup's columns, units and indenter.
CurveAnalysis analyze_measured_curve(const std::filesystem::path& csv, const AnalysisSetup& setup);

/// How a measured curve is read (`indentsim analyze`'s flags): the indenter file and the
/// columns and units, each "" when not given.
struct MeasuredCurveOptions {
  std::string indenter_file, depth_column, force_column, depth_unit, force_unit, time_column, time_unit;
  bool given() const {
    return !indenter_file.empty() || !depth_column.empty() || !force_column.empty() || !depth_unit.empty() ||
           !force_unit.empty() || !time_column.empty() || !time_unit.empty();
  }
};

/// `indentsim analyze CURVE`: a run's folder (or its curve.csv; only analysis.* overrides apply,
/// and `measured` must be empty) or a measured CSV read as `measured` says.  Throws InputError
/// naming the file and the key for anything that cannot be analysed.
CurveAnalysis analyze_curve(const std::filesystem::path& curve, std::vector<std::string> overrides,
                            const MeasuredCurveOptions& measured);

/// analysis.json: the inputs, the units (stated once), the curve in SI and every branch.
nlohmann::ordered_json analysis_json(const CurveAnalysis& analysis);

/// The results as a few lines for the terminal.
std::string analysis_table(const CurveAnalysis& analysis);

/// Where analysis.json goes by default: the run's folder, or beside a measured file
/// (NAME.analysis.json).
std::filesystem::path default_analysis_path(const std::filesystem::path& curve, bool simulated);

}  // namespace indentsim
