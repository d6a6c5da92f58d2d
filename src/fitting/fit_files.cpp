#include "indentsim/fitting/fit_files.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>

#include <fmt/format.h>
#include <toml++/toml.h>

#include "indentsim/fitting/forward_model.hpp"
#include "indentsim/input/csv_table.hpp"
#include "indentsim/base/error.hpp"
#include "indentsim/base/file_system.hpp"
#include "indentsim/output/checkpoint.hpp"

namespace indentsim {

namespace {

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

/// Splits "a,b" lists of --free.
std::vector<std::string> split_list(const std::vector<std::string>& items) {
  std::vector<std::string> keys;
  for (const auto& item : items) {
    std::stringstream in(item);
    for (std::string k; std::getline(in, k, ',');)
      if (!trim_csv_field(k).empty()) keys.push_back(trim_csv_field(k));
  }
  return keys;
}

/// A header field "r (um)" as its name and unit.
std::pair<std::string, std::string> field_name_and_unit(const std::string& field) {
  const std::string f = trim_csv_field(field);
  if (!f.empty() && (f.back() == ')' || f.back() == ']')) {
    const auto at = f.rfind(f.back() == ')' ? '(' : '[');
    if (at != std::string::npos)
      return {trim_csv_field(f.substr(0, at)), trim_csv_field(f.substr(at + 1, f.size() - at - 2))};
  }
  return {f, ""};
}

/// Does the file's header name both columns?  (A run's curve.csv names alpha and P.)
bool header_names(const std::filesystem::path& file, const std::string& a, const std::string& b) {
  const CsvTable t = read_csv_table(file, std::size_t{1} << 30, [&](const std::string& p) { throw InputError(file.string(), "curve", p); });
  for (const auto& row : t.rows) {
    bool has_a = false, has_b = false;
    for (const auto& f : row) {
      const std::string name = lower(field_name_and_unit(f).first);
      has_a = has_a || name == lower(a);
      has_b = has_b || name == lower(b);
    }
    if (has_a && has_b) return true;
  }
  return false;
}

/// An imprint profile: columns `radius_column` and `depth_column` (by header), lengths in `unit`,
/// in the header, or metres.
void read_imprint(const std::filesystem::path& file, const std::string& radius_column, const std::string& depth_column,
                  const std::string& unit, FitData& d) {
  const std::string name = file.string();
  const CsvTable t = read_csv_table(file, std::size_t{1} << 30, [&](const std::string& p) { throw InputError(name, "imprint", p); });
  std::optional<std::size_t> header;
  std::size_t rc = 0, dc = 0;
  for (std::size_t k = 0; k < t.rows.size() && !header; ++k) {
    std::optional<std::size_t> r, dd;
    for (std::size_t c = 0; c < t.rows[k].size(); ++c) {
      const std::string n = lower(field_name_and_unit(t.rows[k][c]).first);
      if (n == lower(radius_column)) r = c;
      if (n == lower(depth_column)) dd = c;
    }
    if (r && dd) {
      header = k;
      rc = *r;
      dc = *dd;
    }
  }
  if (!header)
    throw InputError(name, "radius_column", fmt::format("no header row names both \"{}\" and \"{}\"", printable(radius_column, 40),
                                                        printable(depth_column, 40)));
  const auto scale_of = [&](std::size_t column, const char* key) {
    std::string u = unit.empty() ? field_name_and_unit(t.rows[*header][column]).second : unit;
    if (u.empty()) u = "m";
    const double f = depth_unit_factor(u);
    if (f == 0.0) throw InputError(name, key, fmt::format("\"{}\" is not a length unit (nm, um, mm, m)", printable(u, 20)));
    return f;
  };
  const double r_scale = scale_of(rc, "unit"), d_scale = scale_of(dc, "unit");
  for (std::size_t k = *header + 1; k < t.rows.size(); ++k) {
    const auto& row = t.rows[k];
    double r = 0.0, depth = 0.0;
    if (rc >= row.size() || dc >= row.size() || !parse_csv_number(row[rc], r) || !parse_csv_number(row[dc], depth))
      throw InputError(name, fmt::format("row {}", k + 1), "needs a number in both the radius and the depth column");
    d.abscissa.push_back(r * r_scale);
    d.values.push_back(depth * d_scale);
  }
}

std::pair<double, double> parse_bounds(const std::string& text, const std::string& where, const std::string& key) {
  const auto colon = text.find(':');
  double lo = 0.0, hi = 0.0;
  if (colon == std::string::npos || !parse_csv_number(text.substr(0, colon), lo) || !parse_csv_number(text.substr(colon + 1), hi))
    throw InputError(where, key, fmt::format("bounds \"{}\" are not lower:upper numbers", printable(text, 60)));
  return {lo, hi};
}

RegionParameter parameter_or_fail(const std::string& key, const std::string& where) {
  const auto p = region_parameter_of_key(key);
  if (!p) throw InputError(where, printable(key, 60), fmt::format("is not a parameter a fit can free (free: {})", fittable_keys()));
  return *p;
}

FitData read_curve_data(const std::filesystem::path& file, LoadCase lc, CurveColumns columns) {
  const bool named = !columns.depth_column.empty() || !columns.force_column.empty();
  if (!named && header_names(file, "alpha", "P")) {
    columns.depth_column = "alpha";
    columns.force_column = "P";
  }
  // A case with a protocol in time reads the curve's time column (a run's curve.csv names it "time").
  if (!lc.load.times.empty() && columns.time_column.empty() && !columns.depth_column.empty() &&
      header_names(file, "time", columns.depth_column))
    columns.time_column = "time";
  // A plane-strain case's P is a force per unit thickness (N/m), an axisymmetric one's a force (N):
  // a curve whose unit (given, or in its header) says the other is data of the other scene.
  const bool plane_strain = lc.geometry.kind == SceneKind::plane_strain;
  columns.default_depth_unit = "m";
  columns.default_force_unit = plane_strain ? "N/m" : "N";
  columns.default_time_unit = "s";
  columns.force_per_length = true;
  const LoadDepthCurve curve = read_curve_csv(file, columns);
  if (curve.force_unit_declared && is_per_length_force_unit(curve.force_unit) != plane_strain) {
    const std::string from = columns.force_unit.empty() ? "from the file's header" : "given by --force-unit or force_unit";
    throw InputError(
        file.string(), "force_unit",
        plane_strain
            ? fmt::format("the forces are in {} ({}), a force as an axisymmetric case or an instrument measures it, but "
                          "the load case {} is plane strain (geometry.kind = \"plane_strain\"), whose P is a force per "
                          "unit thickness in N/m: give the curve of a plane-strain scene in N/m, or fit these data with "
                          "an axisymmetric case",
                          printable(curve.force_unit, 20), from, lc.source)
            : fmt::format("the forces are in {} ({}), a force per unit length as a plane-strain case gives it, but the "
                          "load case {} is axisymmetric (geometry.kind = \"axisymmetric\"), whose P is a force in N: "
                          "give the curve of an axisymmetric scene in N, or fit these data with a plane-strain case",
                          printable(curve.force_unit, 20), from, lc.source));
  }
  FitData d;
  d.file = file.string();
  if (!curve.time.empty()) {
    // A time history (docs/MODEL.md §13.6): the response at the data's times, the depth under
    // force control; the start of the protocol is the unloaded state, no information.
    const bool depth_response = lc.load.control == LoadControlKind::force;
    const double start = lc.load.times.empty() ? 0.0 : lc.load.times.front();
    const double lc_end = lc.load.times.empty() ? 0.0 : lc.load.times.back();
    const bool lc_times_empty = lc.load.times.empty();  // refused by name later (load.times)
    d.kind = FitDataKind::time_history;
    d.column = depth_response ? columns.depth_column : columns.force_column;
    d.unit = depth_response ? curve.depth_unit : curve.force_unit;
    d.load_case = std::move(lc);
    // Every time within the protocol's, checked here where the file's rows are known (a dense
    // history is reduced to the protocol's increments before the forward model sees it).
    const double end = lc_end;
    for (std::size_t i = 0; i < curve.time.size(); ++i) {
      if (!lc_times_empty && !(curve.time[i] >= start && curve.time[i] <= end + 1e-12 * (end - start)))
        throw InputError(file.string(), fmt::format("row {}", curve.rows[i]),
                         fmt::format("time {:.6g} s is outside the protocol's times [{:.6g}, {:.6g}] s (load.times of "
                                     "the load case {})",
                                     curve.time[i], start, end, d.load_case.source));
      if (curve.time[i] == start) continue;
      d.abscissa.push_back(curve.time[i]);
      d.values.push_back(depth_response ? curve.depth[i] : curve.force[i]);
    }
    return d;
  }
  d.kind = FitDataKind::force_depth_curve;
  d.column = columns.force_column.empty() ? "2" : columns.force_column;
  d.unit = curve.force_unit;
  d.load_case = std::move(lc);
  d.abscissa = curve.depth;
  d.values = curve.force;
  // A run's curve starts at the unloaded state alpha = 0, P = 0: it carries no information.
  while (!d.abscissa.empty() && d.abscissa.front() == 0.0 && d.values.front() == 0.0) {
    d.abscissa.erase(d.abscissa.begin());
    d.values.erase(d.values.begin());
  }
  return d;
}

}  // namespace

FitJob read_fit_job(const FitCommandLine& cl) {
  FitJob job;
  FitProblem& problem = job.problem;
  std::vector<std::string> free = split_list(cl.free);
  std::vector<std::pair<std::string, std::pair<double, double>>> bounds;
  for (const auto& b : cl.bounds) {
    const auto eq = b.find('=');
    if (eq == std::string::npos) throw InputError("--bounds", printable(b, 60), "expects key=lower:upper");
    bounds.emplace_back(b.substr(0, eq), parse_bounds(b.substr(eq + 1), "--bounds", b.substr(0, eq)));
  }
  std::string bounds_source = "--bounds";

  toml::table root;
  try {
    root = toml::parse_file(cl.input);
  } catch (const toml::parse_error& e) {
    throw InputError(cl.input, "toml", std::string(e.description()));
  }
  const bool fit_file = root.contains("fit") || root.contains("data");
  if (fit_file) {
    if (!cl.data_files.empty())
      throw InputError(cl.input, "--data", "is a fit file: its [[data]] tables name the data (no --data)");
    const std::filesystem::path base = std::filesystem::path(cl.input).parent_path();
    const toml::table* fit = root["fit"].as_table();
    if (!fit) throw InputError(cl.input, "fit", "a fit file needs a [fit] table (free = [...])");
    for (const auto& [k, v] : *fit) {
      const std::string key(k.str());
      if (key != "free" && key != "bounds" && key != "starts" && key != "out" && key != "single_level" &&
          key != "mesh_refinements")
        throw InputError(cl.input, "fit." + printable(key, 40),
                         "is not a fit key (free, bounds, starts, out, single_level, mesh_refinements)");
    }
    if (const auto* list = (*fit)["free"].as_array()) {
      for (const auto& item : *list) {
        const auto s = item.value<std::string>();
        if (!s) throw InputError(cl.input, "fit.free", "must list keys as strings");
        free.push_back(*s);
      }
    }
    if (const auto* b = (*fit)["bounds"].as_table()) {
      bounds_source = cl.input;
      for (const auto& [k, v] : *b) {
        const auto* pair = v.as_array();
        const auto lo = pair && pair->size() == 2 ? (*pair)[0].value<double>() : std::nullopt;
        const auto hi = pair && pair->size() == 2 ? (*pair)[1].value<double>() : std::nullopt;
        if (!lo || !hi) throw InputError(cl.input, "fit.bounds." + std::string(k.str()), "must be [lower, upper]");
        bounds.emplace_back(std::string(k.str()), std::pair{*lo, *hi});
      }
    }
    if (const auto* node = (*fit)["starts"].node()) {
      const auto s = node->value_exact<int64_t>();
      if (!s) throw InputError(cl.input, "fit.starts", "must be an integer");
      problem.settings.starts = static_cast<int>(std::clamp<int64_t>(*s, -1, 1000));
    }
    if (const auto* node = (*fit)["mesh_refinements"].node()) {
      const auto s = node->value_exact<int64_t>();
      if (!s) throw InputError(cl.input, "fit.mesh_refinements", "must be an integer");
      problem.settings.mesh_refinements = static_cast<int>(std::clamp<int64_t>(*s, -1, 1000));
    }
    if (const auto* node = (*fit)["out"].node()) {
      const auto o = node->value_exact<std::string>();
      if (!o) throw InputError(cl.input, "fit.out", "must be a folder name (a string)");
      job.out_dir = *o;
    }
    if (const auto* node = (*fit)["single_level"].node()) {
      const auto b = node->value_exact<bool>();
      if (!b) throw InputError(cl.input, "fit.single_level", "must be true or false");
      if (*b) problem.settings.coarse_first = false;
    }
    const toml::array* data = root["data"].as_array();
    if (!data || data->empty()) throw InputError(cl.input, "data", "a fit file needs at least one [[data]] table");
    int index = 0;
    for (const auto& node : *data) {
      ++index;
      const toml::table* t = node.as_table();
      const std::string where = fmt::format("data[{}]", index);
      if (!t) throw InputError(cl.input, where, "must be a table ([[data]])");
      static const std::vector<std::string> known{"case",        "curve",        "imprint",    "weight",
                                                  "set",         "depth_column", "force_column", "depth_unit",
                                                  "force_unit",  "time_column",  "time_unit",  "radius_column",
                                                  "unit"};
      for (const auto& [k, v] : *t)
        if (std::find(known.begin(), known.end(), std::string(k.str())) == known.end())
          throw InputError(cl.input, where + "." + printable(std::string(k.str()), 40), "is not a [[data]] key");
      const auto text = [&](const char* key) { return (*t)[key].value<std::string>(); };
      const auto case_file = text("case");
      if (!case_file) throw InputError(cl.input, where + ".case", "names the load case of this data set (required)");
      std::vector<std::string> overrides = cl.overrides;
      if (const auto* set = (*t)["set"].as_array())
        for (const auto& s : *set)
          if (auto v = s.value<std::string>()) overrides.push_back(*v);
      LoadCase lc = read_load_case(base / *case_file, overrides);
      const auto curve = text("curve"), imprint = text("imprint");
      if (curve.has_value() == imprint.has_value())
        throw InputError(cl.input, where, "needs exactly one of curve = \"...\" and imprint = \"...\"");
      FitData d;
      if (curve) {
        CurveColumns columns{text("depth_column").value_or(""), text("force_column").value_or(""),
                             text("depth_unit").value_or(""), text("force_unit").value_or(""),
                             text("time_column").value_or(""), text("time_unit").value_or("")};
        d = read_curve_data(base / *curve, std::move(lc), columns);
      } else {
        d.kind = FitDataKind::imprint_profile;
        d.file = (base / *imprint).string();
        d.load_case = std::move(lc);
        read_imprint(base / *imprint, text("radius_column").value_or("r"), text("depth_column").value_or("depth"),
                     text("unit").value_or(""), d);
      }
      if (auto w = (*t)["weight"].value<double>()) {
        if (!(*w > 0.0 && std::isfinite(*w))) throw InputError(cl.input, where + ".weight", "must be > 0");
        d.weight = *w;
      }
      problem.data.push_back(std::move(d));
    }
  } else {
    if (cl.data_files.empty())
      throw InputError(cl.input, "--data", "a load case needs its measured curve: --data CURVE.csv (or give a fit file)");
    for (const auto& file : cl.data_files) {
      std::error_code ec;
      if (!std::filesystem::is_regular_file(file, ec)) throw InputError(file, "--data", "is not a readable file");
      problem.data.push_back(read_curve_data(file, read_load_case(cl.input, cl.overrides), cl.columns));
    }
  }
  if (cl.starts) problem.settings.starts = *cl.starts;
  if (problem.settings.starts < 1 || problem.settings.starts > 100)
    throw InputError(cl.starts ? "--starts" : cl.input, "starts", "must be between 1 and 100");
  if (cl.mesh_refinements) problem.settings.mesh_refinements = *cl.mesh_refinements;
  if (problem.settings.mesh_refinements < 0 || problem.settings.mesh_refinements > 4)
    throw InputError(cl.mesh_refinements ? "--mesh-refinements" : cl.input, "mesh_refinements",
                     "must be between 0 and 4 (each doubles the forward meshes' contact nodes)");
  if (cl.threads) {
    if (*cl.threads < 1 || *cl.threads > 1024) throw InputError("--threads", "threads", "must be between 1 and 1024");
    problem.settings.threads = *cl.threads;
  }
  if (!cl.out.empty()) job.out_dir = cl.out;
  if (job.out_dir.empty()) job.out_dir = "out/fit";
  problem.settings.finite_differences = cl.finite_differences;
  if (cl.single_level) problem.settings.coarse_first = false;
  if (cl.no_design) problem.settings.design_experiments = false;
  if (cl.no_profile) problem.settings.profile = false;

  if (free.empty()) throw InputError(cl.input, "--free", "name the parameters to fit, e.g. --free material.yield_stress,material.n");
  for (const auto& key : free) {
    FreeParameter f;
    f.parameter = parameter_or_fail(key, "--free");
    // A layer the case does not have is named by check_problem; its start is read there.
    const LoadCase& first = problem.data.front().load_case;
    const double start = f.parameter.region <= first.layers.size() ? value_of(first, f.parameter) : 1.0;
    std::tie(f.lower, f.upper) = default_bounds(f.parameter.which, start);
    problem.free.push_back(f);
  }
  for (const auto& [key, range] : bounds) {
    const RegionParameter p = parameter_or_fail(key, bounds_source);
    auto it = std::find_if(problem.free.begin(), problem.free.end(), [&](const FreeParameter& f) { return f.parameter == p; });
    if (it == problem.free.end()) throw InputError(bounds_source, key, "has bounds but is not free");
    it->lower = range.first;
    it->upper = range.second;
  }
  // Data the case cannot produce, and fewer points than parameters, are refused before any run.
  std::size_t points = 0;
  for (const auto& d : problem.data) {
    // The forward model steps the data's depths (forward_model.cpp says so too).
    refuse_unfittable_load(d.load_case, d.kind);
    points += d.values.size();
    if (d.kind == FitDataKind::force_depth_curve)
      for (std::size_t i = 0; i < d.abscissa.size(); ++i)
        if (d.abscissa[i] > d.load_case.max_depth() * (1.0 + 1e-12) || d.abscissa[i] < 0.0)
          throw InputError(d.file, fmt::format("point {}", i + 1),
                           fmt::format("depth {:.6g} m is outside the load case's depths [0, {:.6g}] m ({}): deepen "
                                       "load.path",
                                       d.abscissa[i], d.load_case.max_depth(), d.load_case.source));
  }
  if (points < problem.free.size())
    throw InputError(problem.data.front().file, "data",
                     fmt::format("{} point(s) for {} free parameter(s): at least as many points as parameters", points,
                                 problem.free.size()));
  // Each depth is an increment of every forward run: a curve of far more rows than the case has
  // increments is reduced to what the model resolves (forward_model.hpp), and says so.
  for (auto& d : problem.data) {
    const CurveReduction reduction = reduce_to_resolution(d);
    if (reduction.reduced) job.notes.push_back(reduction.note);
  }
  return job;
}

nlohmann::json fit_json(const FitProblem& problem, const FitResult& r) {
  using nlohmann::json;
  const auto number = [](double v) { return std::isfinite(v) ? json(v) : json(nullptr); };
  json j;
  j["units"] = "SI: E, yield_stress in Pa; depths and radii in m; forces in N (N/m in plane strain)";
  json parameters = json::object();
  std::vector<std::string> order;
  for (std::size_t k = 0; k < problem.free.size(); ++k) {
    const auto& f = problem.free[k];
    order.push_back(key_of(f.parameter));
    const ParameterDetermination& pd = r.determination[k];
    parameters[key_of(f.parameter)] = {{"value", r.values[k]},
                                       {"std_error", number(r.std_errors[k])},
                                       {"model_shift", number(pd.model_shift)},
                                       {"model_shift_increments", number(pd.model_shift_increments)},
                                       {"std_error_total", number(pd.total_std_error)},
                                       {"interval_95", {number(pd.lower), number(pd.upper)}},
                                       {"profile_interval_95_noise",
                                        pd.profiled ? json{number(pd.profile_lower), number(pd.profile_upper)}
                                                    : json(nullptr)},
                                       {"profile_open_at_a_bound", pd.profile_open},
                                       {"relative_half_width_95", number(pd.relative_half_width)},
                                       {"determined", pd.determined},
                                       {"verdict", pd.verdict},
                                       {"lower", f.lower},
                                       {"upper", f.upper},
                                       {"start", value_of(problem.data.front().load_case, f.parameter)}};
  }
  j["parameters"] = parameters;
  j["free"] = order;
  json correlation = json::array(), covariance = json::array();
  for (Eigen::Index a = 0; a < r.correlation.rows(); ++a) {
    json row = json::array(), crow = json::array();
    for (Eigen::Index b = 0; b < r.correlation.cols(); ++b) {
      row.push_back(number(r.correlation(a, b)));
      crow.push_back(number(r.covariance(a, b)));
    }
    correlation.push_back(row);
    covariance.push_back(crow);
  }
  j["correlation"] = correlation;
  j["covariance"] = covariance;
  j["singular_values"] = r.singular_values;
  j["condition_number"] = number(r.condition_number);
  j["identifiable"] = r.identifiable;
  j["determination_limit"] = determination_limit;
  j["model_error_estimated"] = r.model_error_estimated;
  j["model_shift_over_noise"] = number(r.model_to_noise);
  j["increments_shift_over_noise"] = number(r.increments_to_noise);
  j["increments_factor"] = r.increments_factor;
  j["values_with_the_model_error_taken_off"] = r.corrected_values.empty() ? json(nullptr) : json(r.corrected_values);
  j["weakest_direction"] = r.weakest_direction;
  j["poorly_determined"] = r.poorly_determined.empty() ? json(nullptr) : json(r.poorly_determined);
  j["rms_residual"] = {{"relative", r.rms_relative}};
  j["quality"] = r.quality;
  j["quality_problems"] = r.quality_problems;
  j["quality_limits"] = {{"rms_relative", poor_fit_rms_limit}, {"at_bound", at_bound_tolerance}};
  j["warnings"] = r.warnings;
  json data = json::array();
  for (std::size_t d = 0; d < problem.data.size(); ++d) {
    const auto& in = problem.data[d];
    const auto& out = r.data[d];
    const bool forces = values_are_forces(in);
    const bool history = in.kind == FitDataKind::time_history;
    data.push_back({{"file", in.file},
                    {"case", in.load_case.source},
                    {"kind", history ? "time_history" : forces ? "force_depth_curve" : "imprint_profile"},
                    {"response", history ? json(forces ? "force" : "depth") : json(nullptr)},
                    {"points", in.values.size()},
                    {"rows", in.rows > 0 ? in.rows : in.values.size()},
                    {"weight", in.weight},
                    {"rms_residual", out.rms_residual},
                    {"rms_residual_unit", forces ? (in.load_case.geometry.kind == SceneKind::plane_strain ? "N/m" : "N") : "m"},
                    {"rms_relative", out.rms_relative},
                    {"gradients", out.gradients},
                    {"mesh_contact_half_width", out.contact_half_width_planned}});
  }
  j["data"] = data;
  j["forward_runs"] = r.forward_runs;
  j["failed_runs"] = r.failed_runs;
  j["refused_evaluations"] = r.refused_evaluations;
  j["coarse_runs"] = r.coarse_runs;
  j["iterations"] = r.iterations;
  j["wall_s"] = r.wall_seconds;
  j["mesh_replanned"] = r.mesh_replanned;
  json starts = json::array();
  // Costs are comparable within a phase's meshes only: a coarse start's is on other meshes.
  for (std::size_t k = 0; k < r.starts.size(); ++k) {
    const StartOutcome& s = r.starts[k];
    starts.push_back({{"start", s.start}, {"result", s.result}, {"cost", number(s.cost)}, {"iterations", s.iterations},
                      {"converged", s.converged}, {"message", s.message}, {"phase", s.phase},
                      {"selected", k == r.selected_start}});
  }
  j["starts"] = starts;
  // The experiment that would determine what the data do not: per candidate addition, each
  // parameter's predicted noise-only 95% half-width (relative) and how much narrower that is.
  json design = json::array();
  for (const CandidateExperiment& c : r.experiment_design) {
    json per = json::object();
    for (std::size_t k = 0; k < c.relative_half_width.size(); ++k)
      per[order[k]] = {{"relative_half_width_95_noise", number(c.relative_half_width[k])},
                       {"narrower_by", number(c.shrink[k])}};
    design.push_back({{"addition", c.name},
                      {"what", c.description},
                      {"parameters", per},
                      {"failure", c.failure.empty() ? json(nullptr) : json(c.failure)}});
  }
  json today = json::object();
  for (std::size_t k = 0; k < r.noise_relative_half_width.size(); ++k) today[order[k]] = number(r.noise_relative_half_width[k]);
  j["experiment_design"] = {{"today_relative_half_width_95_noise", today}, {"additions", design}};
  return j;
}

std::string fit_curves_csv(const FitProblem& problem, const FitResult& r) {
  // x: alpha [m], r [m] or t [s]; data and model: P, the imprint's depth, or a time history's
  // response (history_depth: alpha [m] under force control; history_force: P).
  std::string out = "data_set,kind,x,data,model,residual\n";
  for (std::size_t d = 0; d < problem.data.size(); ++d) {
    const auto& in = problem.data[d];
    const char* kind = in.kind == FitDataKind::force_depth_curve ? "curve"
                       : in.kind == FitDataKind::imprint_profile ? "imprint"
                       : values_are_forces(in)                  ? "history_force"
                                                                : "history_depth";
    for (std::size_t i = 0; i < in.values.size(); ++i)
      out += fmt::format("{},{},{:.10g},{:.10g},{:.10g},{:.10g}\n", d + 1, kind, in.abscissa[i], in.values[i],
                         r.data[d].model[i], r.data[d].model[i] - in.values[i]);
  }
  return out;
}

void write_fit_results(const std::filesystem::path& dir, const FitProblem& problem, const FitResult& result) {
  std::filesystem::create_directories(dir);
  write_file_atomically(dir / "fit.json", fit_json(problem, result).dump(2) + "\n");
  write_file_atomically(dir / "fit_curves.csv", fit_curves_csv(problem, result));
  for (std::size_t d = 0; d < result.data.size(); ++d)
    write_file_atomically(dir / (d == 0 ? std::string("fitted_case.toml") : fmt::format("fitted_case_{}.toml", d + 1)),
                          to_toml(result.data[d].fitted_case));
}

namespace {

nlohmann::json outcome_json(const StartOutcome& o) {
  using nlohmann::json;
  return {{"phase", o.phase},           {"index", o.index},         {"start", o.start},
          {"result", o.result},         {"cost", std::isfinite(o.cost) ? json(o.cost) : json(nullptr)},
          {"iterations", o.iterations}, {"converged", o.converged}, {"message", o.message}};
}

StartOutcome outcome_of(const nlohmann::json& j) {
  StartOutcome o;
  o.phase = j.at("phase").get<std::string>();
  o.index = j.at("index").get<int>();
  o.start = j.at("start").get<std::vector<double>>();
  o.result = j.at("result").get<std::vector<double>>();
  o.cost = j.at("cost").is_null() ? std::numeric_limits<double>::infinity() : j.at("cost").get<double>();
  o.iterations = j.at("iterations").get<int>();
  o.converged = j.at("converged").get<bool>();
  o.message = j.at("message").get<std::string>();
  return o;
}

}  // namespace

std::string fit_fingerprint(const FitProblem& problem) {
  // Exact text of everything that steers the fit: doubles to 17 digits round-trip.
  std::string text;
  for (const FitData& d : problem.data) {
    text += fmt::format("data {} {} {}\n", static_cast<int>(d.kind), d.weight, to_toml(d.load_case));
    for (std::size_t i = 0; i < d.values.size(); ++i) text += fmt::format("{:.17g} {:.17g}\n", d.abscissa[i], d.values[i]);
  }
  for (const FreeParameter& f : problem.free) text += fmt::format("free {} {:.17g} {:.17g}\n", key_of(f.parameter), f.lower, f.upper);
  const FitSettings& s = problem.settings;
  text += fmt::format("settings {} {} {} {} {} {} {}\n", s.starts, s.max_iterations, s.finite_differences, s.coarse_first,
                      s.replan_mesh, s.mesh_refinements, s.profile);
  return fmt::format("{:016x}", fnv1a(text.data(), text.size()));
}

void write_fit_checkpoint(const std::filesystem::path& dir, const FitProblem& problem, const FitCheckpoint& c) {
  nlohmann::json j;
  j["what"] = "indentsim fit checkpoint: continue with `indentsim fit ... --resume` (the same command)";
  j["fingerprint"] = fit_fingerprint(problem);
  nlohmann::json finished = nlohmann::json::array();
  for (const StartOutcome& o : c.finished) finished.push_back(outcome_json(o));
  j["finished"] = finished;
  nlohmann::json in_progress = nlohmann::json::array();  // starts side by side: one each
  for (const StartOutcome& o : c.in_progress) in_progress.push_back(outcome_json(o));
  j["in_progress"] = in_progress;
  j["forward_runs"] = c.forward_runs;
  j["coarse_runs"] = c.coarse_runs;
  j["iterations"] = c.iterations;
  j["failed_runs"] = c.failed_runs;
  j["refused_evaluations"] = c.refused_evaluations;
  std::filesystem::create_directories(dir);
  write_file_atomically(dir / fit_checkpoint_name, j.dump(1) + "\n");
}

FitCheckpoint read_fit_checkpoint(const std::filesystem::path& dir, const FitProblem& problem) {
  const std::filesystem::path file = dir / fit_checkpoint_name;
  std::ifstream in(file);
  if (!in) throw InputError(file.string(), "--resume", "there is no fit checkpoint here to resume from (a fit that ended removed it)");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(file.string(), "--resume", fmt::format("the checkpoint is damaged: {}", e.what()));
  }
  if (!j.is_object() || !j.contains("fingerprint") || !j["fingerprint"].is_string())
    throw InputError(file.string(), "fingerprint", "the checkpoint is damaged: no fingerprint");
  if (j["fingerprint"].get<std::string>() != fit_fingerprint(problem))
    throw InputError(file.string(), "fingerprint",
                     "the checkpoint is another fit's: the data, a load case, the free parameters, their bounds or "
                     "the fit's settings differ from this command's");
  FitCheckpoint c;
  try {
    for (const auto& o : j.at("finished")) c.finished.push_back(outcome_of(o));
    // A list; one object or null in checkpoints written before starts ran side by side.
    const nlohmann::json& in_progress = j.at("in_progress");
    if (in_progress.is_array())
      for (const auto& o : in_progress) c.in_progress.push_back(outcome_of(o));
    else if (!in_progress.is_null())
      c.in_progress.push_back(outcome_of(in_progress));
    c.forward_runs = j.at("forward_runs").get<int>();
    c.coarse_runs = j.at("coarse_runs").get<int>();
    c.iterations = j.at("iterations").get<int>();
    c.failed_runs = j.at("failed_runs").get<int>();
    c.refused_evaluations = j.at("refused_evaluations").get<int>();
  } catch (const nlohmann::json::exception& e) {
    throw InputError(file.string(), "--resume", fmt::format("the checkpoint is damaged: {}", e.what()));
  }
  const std::size_t p = problem.free.size();
  const auto sized = [&](const StartOutcome& o) { return o.start.size() == p && o.result.size() == p; };
  if (!std::all_of(c.finished.begin(), c.finished.end(), sized) || !std::all_of(c.in_progress.begin(), c.in_progress.end(), sized))
    throw InputError(file.string(), "--resume", "the checkpoint is damaged: a start has the wrong number of parameters");
  return c;
}

FitResult run_fit_job(FitJob& job, bool resume) {
  const std::filesystem::path dir = job.out_dir;
  std::optional<FitCheckpoint> restored;
  if (resume) restored = read_fit_checkpoint(dir, job.problem);
  // The settings point at this call's locals only while it runs, whatever ends it.
  struct Detach {
    FitSettings& settings;
    ~Detach() {
      settings.resume_from = nullptr;
      settings.on_checkpoint = nullptr;
    }
  } detach{job.problem.settings};
  job.problem.settings.resume_from = restored ? &*restored : nullptr;
  const FitProblem& problem = job.problem;
  job.problem.settings.on_checkpoint = [&dir, &problem](const FitCheckpoint& c) { write_fit_checkpoint(dir, problem, c); };
  FitResult result = fit(job.problem);
  write_fit_results(dir, job.problem, result);
  std::error_code ec;
  std::filesystem::remove(dir / fit_checkpoint_name, ec);
  return result;
}

}  // namespace indentsim
