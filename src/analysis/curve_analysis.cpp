#include "indentsim/analysis/curve_analysis.hpp"

#include "indentsim/simulation/simulation.hpp"

#include <cmath>
#include <fstream>
#include <tuple>
#include <utility>
#include <map>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "indentsim/input/curve_csv.hpp"
#include "indentsim/base/error.hpp"
#include "indentsim/geometry/punch.hpp"
#include "indentsim/base/version.hpp"

namespace fs = std::filesystem;

namespace indentsim {

namespace {

/// What the run recorded at each peak step (summary.json), when it was there to see it: a run
/// resumed after its peak has no live state of it, and then the analysis has no truth either.
std::map<std::size_t, TrueContact> recorded_truths(const fs::path& summary_file) {
  std::map<std::size_t, TrueContact> truths;
  std::ifstream in(summary_file);
  if (!in) return truths;
  const nlohmann::json summary = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  // A summary.json that is not the run's (damaged, edited) is said, not silently read as "no
  // truth": the analysis would lose the true contact numbers without a word.
  if (!summary.is_object() || !summary.contains("unloading") || !summary["unloading"].is_array())
    throw InputError(summary_file.string(), "summary.json",
                     "is damaged or not a run's summary (no \"unloading\" list): the true contact numbers of the "
                     "branches cannot be read; run the case again or analyse its curve.csv as a measured curve");
  for (const auto& u : summary["unloading"]) {
    if (!u.is_object() || !u.contains("step") || !u["step"].is_number_unsigned()) continue;
    if (!u.contains("analysis") || !u["analysis"].is_object()) continue;
    const auto& a = u["analysis"];
    if (!a.contains("true_contact_radius") || !a["true_contact_radius"].is_number()) continue;
    TrueContact t;
    t.half_width = a["true_contact_radius"].get<double>();
    if (a.contains("S_exact") && a["S_exact"].is_number()) t.stiffness = a["S_exact"].get<double>();
    truths[u["step"].get<std::size_t>()] = t;
  }
  return truths;
}

AnalysisContext context_of(const CurveAnalysis& c, const PunchShape& punch) {
  AnalysisContext context;
  context.scene = c.scene;
  context.punch = &punch;
  context.shape = c.punch.shape;
  context.settings = c.settings;
  context.specimen_nu = c.specimen_nu;
  context.coating = c.coating;
  return context;
}

nlohmann::ordered_json indenter_json(const PunchInput& p, const AnalysisInput& settings) {
  nlohmann::ordered_json j;
  j["shape"] = to_string(p.shape);
  switch (p.shape) {
    case PunchShapeKind::sphere:
    case PunchShapeKind::flat: j["radius"] = p.radius; break;
    case PunchShapeKind::cone:
      j["half_angle_degrees"] = p.half_angle;
      j["tip_radius"] = p.tip_radius;
      break;
    case PunchShapeKind::profile:
      if (!p.profile_file.empty()) j["profile_file"] = p.profile_file;
      j["profile_points"] = p.profile.size();
      break;
    case PunchShapeKind::area_function: j["area_coefficients"] = p.area_coefficients; break;
  }
  j["E"] = settings.indenter_E ? nlohmann::ordered_json(*settings.indenter_E) : nlohmann::ordered_json("rigid");
  j["nu"] = settings.indenter_nu;
  return j;
}

/// Analyses each branch into c.branches, labelled for messages; a branch that cannot be analysed
/// is an InputError naming the curve's file and the branch.
template <class Label, class Truth>
void analyze_branches(CurveAnalysis& c, const std::vector<CurveBranch>& branches, Label label_of, Truth truth_of) {
  const auto punch = make_punch(c.punch);
  const AnalysisContext context = context_of(c, *punch);
  for (const CurveBranch& b : branches) {
    const std::string label = label_of(b);
    try {
      BranchAnalysis a = analyze_branch(c.depth, c.force, b, context, truth_of(b));
      a.hold = analyze_hold(c.time, c.depth, c.force, b, a.fit.stiffness, context);
      c.branches.push_back({b, label, std::move(a)});
    } catch (const AnalysisError& e) {
      throw InputError(c.curve_file.string(), "unloading " + label, e.what());
    }
  }
}

/// The substrate's effect, measured (docs/MODEL.md §14.4): the film alone -- the run's case with
/// its top layer's material as the whole specimen's, on the same load path, mesh keys and pilot
/// measurements (case.toml records them) -- is run and analysed as the run was, and each of the
/// run's branches gets the film alone's E_r and H of the same branch.  Under force control the
/// film alone reaches its own depths (its depth pilot runs anew).
void measure_substrate_effect(CurveAnalysis& c, const LoadCase& lc) {
  LoadCase film = lc;
  film.material = lc.layers.front().material;
  film.layers.clear();
  film.mesh.error_estimate = ErrorEstimateChoice::off;
  if (film.load.control == LoadControlKind::force) film.load.depth_estimate.reset();
  CurveAnalysis alone = c;
  alone.coating.reset();
  alone.branches.clear();
  alone.depth.clear();
  alone.force.clear();
  try {
    Simulation sim(film);
    sim.run([&](const IncrementRecord& r) {
      alone.depth.push_back(r.alpha);
      alone.force.push_back(r.force);
    });
  } catch (const SolverError&) {
    return;  // the film alone does not reach the run's path: no measured substrate effect
  } catch (const InputError&) {
    return;  // nor a path valid for the film alone (a force-controlled film deeper than its tip's shape)
  }
  if (alone.depth.size() != c.depth.size()) return;
  std::vector<double> controlled = alone.depth;
  if (lc.load.control == LoadControlKind::force) controlled = plan_increments(lc.load);
  std::vector<CurveBranch> branches;
  for (const CurveBranch& b : unloading_branches(controlled))
    if (b.end < alone.depth.size()) branches.push_back(b);
  try {
    analyze_branches(alone, branches, [](const CurveBranch& b) { return fmt::format("steps {}-{}", b.peak, b.end); },
                     [](const CurveBranch&) { return std::optional<TrueContact>(); });
  } catch (const InputError&) {
    return;  // a branch the film alone cannot analyse: none measured
  }
  for (AnalyzedBranch& b : c.branches) {
    if (!b.result.coating) continue;
    for (const AnalyzedBranch& f : alone.branches)
      if (f.branch.peak == b.branch.peak) {
        b.result.coating->film_alone_reduced_modulus = f.result.reduced_modulus;
        b.result.coating->film_alone_hardness = f.result.hardness;
      }
  }
}

}  // namespace

std::vector<std::string> substrate_effect_warnings(const CurveAnalysis& c) {
  std::vector<std::string> warnings;
  const double tolerance = c.settings.substrate_tolerance;
  for (const AnalyzedBranch& b : c.branches) {
    if (!b.result.coating) continue;
    const auto& co = *b.result.coating;
    std::string moved;
    if (co.film_alone_reduced_modulus && b.result.reduced_modulus &&
        std::abs(*b.result.reduced_modulus / *co.film_alone_reduced_modulus - 1.0) > tolerance)
      moved += fmt::format("E_r by {:+.3g}%", 100.0 * (*b.result.reduced_modulus / *co.film_alone_reduced_modulus - 1.0));
    if (co.film_alone_hardness && *co.film_alone_hardness > 0.0 &&
        std::abs(b.result.hardness / *co.film_alone_hardness - 1.0) > tolerance)
      moved += fmt::format("{}H by {:+.3g}%", moved.empty() ? "" : " and ",
                           100.0 * (b.result.hardness / *co.film_alone_hardness - 1.0));
    if (moved.empty()) continue;
    warnings.push_back(fmt::format("{} (h_max/t = {:.3g}): the substrate moves {} from the film alone's, beyond "
                                   "analysis.substrate_tolerance = {:g}: these are not the film's properties",
                                   b.label, co.depth_over_thickness, moved, tolerance));
  }
  return warnings;
}

bool is_run_output(const fs::path& path) {
  std::error_code ec;
  const fs::path dir = fs::is_directory(path, ec) ? path : path.parent_path();
  if (!fs::is_directory(path, ec) && path.filename() != "curve.csv") return false;
  return fs::is_regular_file(dir / "case.toml", ec) && fs::is_regular_file(dir / "curve.csv", ec);
}

fs::path default_analysis_path(const fs::path& curve, bool simulated) {
  std::error_code ec;
  if (simulated) return (fs::is_directory(curve, ec) ? curve : curve.parent_path()) / "analysis.json";
  fs::path out = curve;
  return out.replace_extension(".analysis.json");
}

CurveAnalysis analyze_run_curve(const fs::path& path, const std::vector<std::string>& overrides) {
  std::error_code ec;
  const fs::path dir = fs::is_directory(path, ec) ? path : path.parent_path();
  for (const auto& o : overrides)
    if (o.rfind("analysis.", 0) != 0)
      throw InputError("--set", printable(o.substr(0, o.find('=')), 60),
                       "a run's analysis takes analysis.* keys only: its indenter and material are the run's own "
                       "(case.toml)");
  const LoadCase lc = read_load_case(dir / "case.toml", overrides);
  // A run whose path is in time writes its time column (docs/MODEL.md §13.2).
  const LoadDepthCurve curve = read_curve_csv(
      dir / "curve.csv", CurveColumns{"alpha", "P", "m", "N", lc.load.times.empty() ? "" : "time", "s"});

  CurveAnalysis c;
  c.curve_file = dir / "curve.csv";
  c.simulated = true;
  c.scene = lc.geometry.kind;
  c.punch = lc.punch;
  c.settings = lc.analysis;
  c.specimen_nu = lc.surface_material().nu;  // the top layer's, under a coated surface (MODEL.md §14.1)
  c.coating = coating_of(lc);
  c.depth = curve.depth;
  c.force = curve.force;
  c.time = curve.time;
  // The branches in the controlled quantity (run_branch_coordinate): the depth, or the planned
  // force of each row's step.
  std::vector<double> controlled = c.depth;
  if (lc.load.control == LoadControlKind::force) {
    const std::vector<double> targets = plan_increments(lc.load);
    for (std::size_t k = 0; k < controlled.size() && k < targets.size(); ++k) controlled[k] = targets[k];
  }
  const std::vector<CurveBranch> branches = unloading_branches(controlled);
  if (branches.empty())
    throw InputError(c.curve_file.string(), "curve",
                     "has no unloading branch: the run's load path never turns back (load.path)");
  const auto truths = recorded_truths(dir / "summary.json");
  // curve.csv holds one row per step from 0: the index is the step.
  analyze_branches(c, branches, [](const CurveBranch& b) { return fmt::format("steps {}-{}", b.peak, b.end); },
                   [&](const CurveBranch& b) -> std::optional<TrueContact> {
                     const auto truth = truths.find(b.peak);
                     if (truth == truths.end()) return std::nullopt;
                     return truth->second;
                   });
  if (!lc.layers.empty()) measure_substrate_effect(c, lc);
  return c;
}

std::vector<std::string> implausible_results(const CurveAnalysis& c) {
  constexpr double min_hardness = 1e5, max_hardness = 1e12, min_modulus = 1e3, max_modulus = 2e12;  // [Pa]
  std::vector<std::string> warnings;
  for (const AnalyzedBranch& b : c.branches) {
    const BranchAnalysis& r = b.result;
    const bool hardness_off = r.hardness > 0.0 && (r.hardness < min_hardness || r.hardness > max_hardness);
    const bool modulus_off =
        r.reduced_modulus && (*r.reduced_modulus < min_modulus || *r.reduced_modulus > max_modulus);
    if (!hardness_off && !modulus_off) continue;
    warnings.push_back(fmt::format(
        "{}: H = {:.3g} Pa{} is no solid's (H {:g} to {:g} Pa, E_r {:g} to {:g} Pa): are the depth unit ({}) and "
        "the force unit ({}) the file's?",
        b.label, r.hardness, r.reduced_modulus ? fmt::format(", E_r = {:.3g} Pa", *r.reduced_modulus) : "",
        min_hardness, max_hardness, min_modulus, max_modulus, c.depth_unit, c.force_unit));
  }
  return warnings;
}

CurveAnalysis analyze_curve(const fs::path& curve, std::vector<std::string> overrides,
                            const MeasuredCurveOptions& o) {
  if (is_run_output(curve)) {
    if (o.given())
      throw InputError(curve.string(), "--indenter",
                       "is a run's output: its indenter and columns are the run's own (only --set analysis.* applies)");
    return analyze_run_curve(curve, overrides);
  }
  std::error_code ec;
  if (!fs::exists(curve, ec))
    throw InputError(curve.string(), "curve", "does not exist (give a run's output folder or a CSV file of a "
                                              "load-depth curve)");
  if (!fs::is_regular_file(curve, ec))
    throw InputError(curve.string(), "curve", "is neither a run's output folder nor a CSV file of a load-depth curve");
  for (const auto& [key, value] : {std::pair{"curve.depth_column", o.depth_column}, {"curve.force_column", o.force_column},
                                   {"curve.depth_unit", o.depth_unit}, {"curve.force_unit", o.force_unit},
                                   {"curve.time_column", o.time_column}, {"curve.time_unit", o.time_unit}})
    if (!value.empty()) overrides.push_back(std::string(key) + "=" + toml_string(value));
  const AnalysisSetup setup = read_analysis_setup(
      o.indenter_file.empty() ? std::nullopt : std::optional<fs::path>(o.indenter_file), overrides);
  return analyze_measured_curve(curve, setup);
}

CurveAnalysis analyze_measured_curve(const fs::path& csv, const AnalysisSetup& setup) {
  const LoadDepthCurve curve = read_curve_csv(csv, setup.columns);
  CurveAnalysis c;
  c.curve_file = csv;
  c.scene = setup.scene;
  c.punch = setup.punch;
  c.settings = setup.analysis;
  c.specimen_nu = setup.specimen_nu;
  c.depth_unit = curve.depth_unit;
  c.force_unit = curve.force_unit;
  c.depth = curve.depth;
  c.force = curve.force;
  c.time = curve.time;
  std::vector<CurveBranch> branches;
  try {
    branches = measured_unloading_branches(c.depth, c.force, c.settings, curve.rows);
  } catch (const AnalysisError& e) {
    throw InputError(csv.string(), "curve", e.what());
  }
  analyze_branches(
      c, branches,
      [&](const CurveBranch& b) { return fmt::format("rows {}-{}", curve.rows[b.peak], curve.rows[b.end]); },
      [](const CurveBranch&) -> std::optional<TrueContact> { return std::nullopt; });
  return c;
}

nlohmann::ordered_json analysis_json(const CurveAnalysis& c) {
  const auto punch = make_punch(c.punch);
  const AnalysisContext context = context_of(c, *punch);
  nlohmann::ordered_json j;
  j["indentsim"] = version_line();
  j["curve"] = c.curve_file.string();
  j["origin"] = c.simulated ? "run" : "measured";
  j["read_in"] = {{"depth", c.depth_unit}, {"force", c.force_unit}};
  j["scene"] = to_string(c.scene);
  j["indenter"] = indenter_json(c.punch, c.settings);
  j["specimen_nu"] = c.specimen_nu ? nlohmann::ordered_json(*c.specimen_nu) : nlohmann::ordered_json(nullptr);
  j["units"] = analysis_units(c.scene);
  j["branches"] = nlohmann::ordered_json::array();
  for (const auto& b : c.branches) {
    nlohmann::ordered_json entry;
    entry["where"] = b.label;
    entry["index"] = {{"loading_start", b.branch.loading_start}, {"peak", b.branch.peak}, {"end", b.branch.end}};
    entry.update(branch_json(b.result, context));
    j["branches"].push_back(entry);
  }
  j["curve_si"] = {{"depth", c.depth}, {"force", c.force}};
  if (!c.time.empty()) j["curve_si"]["time"] = c.time;  // the holds' depth against time
  return j;
}

namespace {

/// The units the terminal table speaks: the input's (a curve read in nm and mN is reported in nm
/// and mN), or, for a curve in SI (a run's), the prefixed units its peak lies in (nm, um, mm, m;
/// uN, mN, N), as the figures choose them.  Stresses in Pa, MPa or GPa by size.
struct TableUnits {
  std::string length, force;
  double length_scale = 1.0, force_scale = 1.0;  ///< SI size of one unit

  explicit TableUnits(const CurveAnalysis& c) {
    double deepest = 0.0, largest = 0.0;
    for (double h : c.depth) deepest = std::max(deepest, std::abs(h));
    for (double p : c.force) largest = std::max(largest, std::abs(p));
    if (c.depth_unit != "m" && depth_unit_factor(c.depth_unit) > 0.0) {
      length = c.depth_unit;
      length_scale = depth_unit_factor(c.depth_unit);
    } else {
      std::tie(length, length_scale) = length_unit_of(deepest);
    }
    const bool per_length = c.scene == SceneKind::plane_strain;
    if (c.force_unit != "N" && c.force_unit != "N/m" && force_or_per_length_unit_factor(c.force_unit) > 0.0) {
      force = c.force_unit;
      force_scale = force_or_per_length_unit_factor(c.force_unit);
      // A plane-strain curve's force is per unit thickness, whatever its column's unit says.
      if (per_length && !is_per_length_force_unit(force)) force += "/m";
    } else {
      std::tie(force, force_scale) = largest < 1e-3 ? std::pair{std::string("uN"), 1e-6}
                                     : largest < 1.0 ? std::pair{std::string("mN"), 1e-3}
                                                     : std::pair{std::string("N"), 1.0};
      if (per_length) force += "/m";
    }
  }
  std::string depth(double h) const { return fmt::format("{:.5g} {}", h / length_scale, length); }
  std::string load(double p) const { return fmt::format("{:.5g} {}", p / force_scale, force); }
  std::string stiffness(double s) const {
    const bool per_length = force.size() > 2 && force.substr(force.size() - 2) == "/m";
    return fmt::format("{:.5g} {}", s * length_scale / force_scale,
                       per_length ? "(" + force + ")/" + length : force + "/" + length);
  }
  /// A radius, and an area, in the unit of their own size (a flat punch's contact radius is
  /// many depths).
  static std::string radius(double r) {
    const auto [name, scale] = length_unit_of(r);
    return fmt::format("{:.5g} {}", r / scale, name);
  }
  static std::string area(double a, bool axisymmetric) {
    if (!axisymmetric) return radius(a);
    const auto [name, scale] = length_unit_of(std::sqrt(std::abs(a) / 3.141592653589793));
    return fmt::format("{:.5g} {}^2", a / (scale * scale), name);
  }
  /// nm, um, mm or m for a length of this size.
  static std::pair<std::string, double> length_unit_of(double size) {
    return size < 1e-6 ? std::pair{std::string("nm"), 1e-9}
           : size < 1e-3 ? std::pair{std::string("um"), 1e-6}
           : size < 1.0  ? std::pair{std::string("mm"), 1e-3}
                         : std::pair{std::string("m"), 1.0};
  }
  static std::string stress(std::optional<double> v) {
    if (!v) return "-";
    const double m = std::abs(*v);
    return m >= 1e9 ? fmt::format("{:.5g} GPa", *v / 1e9)
           : m >= 1e6 ? fmt::format("{:.5g} MPa", *v / 1e6)
                      : fmt::format("{:.5g} Pa", *v);
  }
};

}  // namespace

std::string analysis_table(const CurveAnalysis& c) {
  const bool axi = c.scene == SceneKind::axisymmetric;
  const TableUnits u(c);
  std::string t = fmt::format("{}: {} unloading branch{} ({}, {} indenter; depths in {}, forces in {}; analysis.json in SI)\n",
                              c.curve_file.string(), c.branches.size(), c.branches.size() == 1 ? "" : "es",
                              to_string(c.scene), to_string(c.punch.shape), u.length, u.force);
  const auto stress = [](double v) { return TableUnits::stress(v); };
  for (const auto& b : c.branches) {
    const BranchAnalysis& a = b.result;
    t += fmt::format("  {}: P_max = {}, h_max = {}\n", b.label, u.load(a.P_max), u.depth(a.h_max));
    t += fmt::format("    fit P = B (h - h_f)^m over {:g}-{:g}% of P_max: m = {:.4g}, h_f = {}, {} points, "
                     "rms {:.2g}% of P_max\n",
                     100 * c.settings.fit_range[0], 100 * c.settings.fit_range[1], a.fit.m, u.depth(a.fit.h_f),
                     a.fit.points, 100 * a.fit.rms_residual);
    t += fmt::format("    S = {} (exact: {})   h_c = {}   {} = {}\n", u.stiffness(a.fit.stiffness),
                     a.exact_stiffness ? u.stiffness(*a.exact_stiffness) : std::string("-"), u.depth(a.h_c),
                     axi ? "A_c" : "2 r(h_c)", TableUnits::area(a.area, axi));
    t += fmt::format("    H = {}   E_r = {}   E = {}   W_e/W_t = {:.4g}\n", stress(a.hardness),
                     TableUnits::stress(a.reduced_modulus), TableUnits::stress(a.specimen_modulus),
                     a.total_work > 0 ? a.elastic_work / a.total_work : 0.0);
    if (a.true_area)
      t += fmt::format("    true contact: radius {}, H = {}, E_r = {}, pile-up ratio A_true/A_c = {}\n",
                       TableUnits::radius(*a.true_contact_radius), TableUnits::stress(a.true_hardness),
                       TableUnits::stress(a.true_reduced_modulus),
                       a.pile_up_ratio ? fmt::format("{:.5g}", *a.pile_up_ratio) : std::string("-"));
    if (a.coating) {
      const auto& co = *a.coating;
      t += fmt::format("    coating: h_max/t = {:.3g}, a/t = {:.3g}; the film's share of E_r by Gao's weight {:.3g}; "
                       "the film's E by Gao's model {}{} (true {})\n",
                       co.depth_over_thickness, co.radius_over_thickness, co.film_share,
                       TableUnits::stress(co.film_modulus_gao),
                       co.film_modulus_gao_true_contact
                           ? ", with the true contact " + TableUnits::stress(co.film_modulus_gao_true_contact)
                           : std::string(),
                       TableUnits::stress(co.film_modulus));
      if (co.film_alone_reduced_modulus)
        t += fmt::format("    the film alone (a companion run): E_r = {}, H = {}\n",
                         TableUnits::stress(co.film_alone_reduced_modulus), TableUnits::stress(co.film_alone_hardness));
    }
    if (a.hold) {
      const HoldAnalysis& h = *a.hold;
      t += fmt::format("    hold before it: {:.4g} s, creep {}, dh/dt at its end {}/s", h.duration, u.depth(h.creep_depth),
                       u.depth(h.depth_rate));
      if (h.unloading_rate) t += fmt::format(", unloading at {}/s", u.load(*h.unloading_rate));
      t += "\n";
      if (h.stress_exponent)
        t += fmt::format("    creep stress exponent over the hold's last half (Lucas-Oliver): n = {:.4g}, strain-rate "
                         "sensitivity 1/n = {:.4g}\n",
                         *h.stress_exponent, 1.0 / *h.stress_exponent);
      if (h.corrected)
        t += fmt::format("    corrected for creep (Feng-Ngan): S = {}   h_c = {}   H = {}   E_r = {}   E = {}\n",
                         u.stiffness(*h.stiffness), u.depth(h.corrected->h_c), stress(h.corrected->hardness),
                         TableUnits::stress(h.corrected->reduced_modulus),
                         TableUnits::stress(h.corrected->specimen_modulus));
    }
    if (!axi) t += "    E_r: not defined in plane strain (a half-plane's compliance depends on the specimen size)\n";
  }
  return t;
}

}  // namespace indentsim
