#include "indentsim/analysis/indentation_analysis.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <Eigen/Dense>
#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <unsupported/Eigen/NonLinearOptimization>

#include "indentsim/geometry/punch.hpp"

namespace indentsim {

double PowerLawFit::force_at(double h) const { return h > h_f ? B * std::pow(h - h_f, m) : 0.0; }

namespace {

// The fit's unknowns, scaled to O(1): x = (q, m, s) with
//   P(h) = q P_max ((h - h_f) / (h_max - h_f))^m,   h_f = h_low - (h_max - h_low) e^s,
// so that q ~ 1, m ~ 1.2-2 and h_f stays below the lowest point fitted whatever LM tries.
// Residuals are relative to P_max.
struct UnloadingResidual {
  using Scalar = double;
  using InputType = Eigen::VectorXd;
  using ValueType = Eigen::VectorXd;
  using JacobianType = Eigen::MatrixXd;
  enum { InputsAtCompileTime = Eigen::Dynamic, ValuesAtCompileTime = Eigen::Dynamic };

  const std::vector<double>& h;
  const std::vector<double>& P;
  double P_max, h_max, h_low;

  int inputs() const { return 3; }
  int values() const { return static_cast<int>(h.size()); }
  double residual_depth(const Eigen::VectorXd& x) const { return h_low - (h_max - h_low) * std::exp(x[2]); }

  int operator()(const Eigen::VectorXd& x, Eigen::VectorXd& r) const {
    const double h_f = residual_depth(x), span = h_max - h_f;
    for (std::size_t i = 0; i < h.size(); ++i)
      r[static_cast<Eigen::Index>(i)] = x[0] * std::pow((h[i] - h_f) / span, x[1]) - P[i] / P_max;
    return 0;
  }
  int df(const Eigen::VectorXd& x, Eigen::MatrixXd& J) const {
    const double h_f = residual_depth(x), span = h_max - h_f;
    const double dhf_ds = -(h_max - h_low) * std::exp(x[2]);
    for (std::size_t i = 0; i < h.size(); ++i) {
      const auto k = static_cast<Eigen::Index>(i);
      const double t = (h[i] - h_f) / span, tm = std::pow(t, x[1]);
      J(k, 0) = tm;
      J(k, 1) = x[0] * tm * std::log(t);
      // dt/dh_f = (h - h_max) / span^2
      J(k, 2) = x[0] * x[1] * std::pow(t, x[1] - 1.0) * (h[i] - h_max) / (span * span) * dhf_ds;
    }
    return 0;
  }
};

}  // namespace

PowerLawFit fit_unloading(const std::vector<double>& depth, const std::vector<double>& force, double lower,
                          double upper) {
  if (depth.size() != force.size() || depth.empty()) throw AnalysisError("an unloading branch needs points");
  const double P_max = force.front(), h_max = depth.front();
  if (!(P_max > 0.0)) throw AnalysisError("the unloading branch starts at a force <= 0");
  std::vector<double> h, P;
  for (std::size_t i = 0; i < depth.size(); ++i)
    if (force[i] >= lower * P_max && force[i] <= upper * P_max) {
      if (!h.empty() && depth[i] > h.back())
        throw AnalysisError(fmt::format("the depth does not decrease along the unloading branch (point {} at h = {:g} m "
                                        "after {:g} m)",
                                        i + 1, depth[i], h.back()));
      h.push_back(depth[i]);
      P.push_back(force[i]);
    }
  if (h.size() < 4)
    throw AnalysisError(fmt::format("the unloading branch from h_max = {:g} m has {} point(s) with {:g}% <= P / P_max <= "
                                    "{:g}%; the fit P = B (h - h_f)^m needs at least 4 (a longer or denser branch, "
                                    "or a wider analysis.fit_range)",
                                    h_max, h.size(), 100 * lower, 100 * upper));
  const double h_low = h.back();
  if (!(h_low < h_max)) throw AnalysisError("the unloading branch has no depth range to fit");
  UnloadingResidual residual{h, P, P_max, h_max, h_low};

  // Start from the power law through the highest and lowest points fitted, for the exponent
  // (of a grid from flat-punch-like 1 to beyond the paraboloid's 1.5) that fits best.
  Eigen::VectorXd best(3), r(static_cast<Eigen::Index>(h.size()));
  double best_norm = std::numeric_limits<double>::infinity();
  for (double m : {1.05, 1.2, 1.35, 1.5, 1.7, 2.0, 2.5, 3.0}) {
    const double q = std::pow(P.back() / P.front(), 1.0 / m);
    const double h_f = (h_low - q * h.front()) / (1.0 - q);
    if (!(h_f < h_low)) continue;
    Eigen::VectorXd x(3);
    x << P.front() / P_max * std::pow((h_max - h_f) / (h.front() - h_f), m), m,
        std::log((h_low - h_f) / (h_max - h_low));
    residual(x, r);
    if (r.norm() < best_norm) {
      best_norm = r.norm();
      best = x;
    }
  }
  if (!std::isfinite(best_norm)) throw AnalysisError("the unloading branch does not decrease in force with depth");
  Eigen::LevenbergMarquardt<UnloadingResidual> lm(residual);
  lm.parameters.xtol = 1e-12;
  lm.parameters.ftol = 1e-14;
  lm.parameters.maxfev = 2000;
  lm.minimize(best);
  residual(best, r);

  PowerLawFit fit;
  fit.h_f = residual.residual_depth(best);
  fit.m = best[1];
  fit.h_max = h_max;
  const double span = h_max - fit.h_f;
  fit.B = best[0] * P_max / std::pow(span, fit.m);
  fit.stiffness = fit.m * best[0] * P_max / span;
  fit.points = static_cast<int>(h.size());
  fit.rms_residual = r.norm() / std::sqrt(static_cast<double>(h.size()));
  if (!std::isfinite(fit.stiffness) || !(fit.m > 0.0))
    throw AnalysisError("the unloading fit did not converge to a power law");
  return fit;
}

std::vector<CurveBranch> measured_unloading_branches(const std::vector<double>& depth, const std::vector<double>& force,
                                                     const AnalysisInput& settings,
                                                     const std::vector<std::size_t>& rows) {
  const auto row = [&](std::size_t k) { return k < rows.size() ? rows[k] : k + 1; };
  const double lower = settings.fit_range[0], upper = settings.fit_range[1];
  std::vector<CurveBranch> branches;
  std::size_t loading_start = 0, i = 0;
  const std::size_t n = force.size();
  while (i + 1 < n) {
    while (i + 1 < n && force[i + 1] >= force[i]) ++i;  // loading (or holding)
    std::size_t peak = i;
    while (i + 1 < n && force[i + 1] <= force[i]) ++i;  // unloading
    if (i == peak) continue;
    // A fall that does not reach the fit range's lower end is a hold's noise, not an unloading.
    if (!(force[peak] > 0.0) || force[i] > lower * force[peak]) continue;
    // The unloading starts where the depth is deepest: at the end of a hold at P_max (whose
    // creep a noisy force would otherwise cut short), h_max of ISO 14577.
    std::size_t deepest = peak;
    for (std::size_t k = peak; k <= i && force[k] >= upper * force[peak]; ++k)
      if (depth[k] > depth[deepest]) deepest = k;
    peak = deepest;
    // Load control: the depth must fall with the force over the part fitted.  A depth that still
    // grows there (creep, a "nose") or jumps back is data the power law cannot describe.
    double previous = depth[peak];
    std::size_t previous_k = peak;
    for (std::size_t k = peak + 1; k <= i; ++k) {
      if (force[k] > upper * force[peak] || force[k] < lower * force[peak]) continue;
      if (depth[k] > previous)
        throw AnalysisError(fmt::format("the depth is not monotone in the unloading branch from row {}: it rises from "
                                        "{:.6g} m (row {}) to {:.6g} m (row {}) while the force falls (creep at the "
                                        "start of unloading, or noise; ISO 14577 asks for a hold before unloading)",
                                        row(peak), previous, row(previous_k), depth[k], row(k)));
      previous = depth[k];
      previous_k = k;
    }
    branches.push_back(CurveBranch{loading_start, peak, i});
    loading_start = i;
  }
  if (branches.empty())
    throw AnalysisError(fmt::format("has no unloading branch: the force never falls from a maximum to below {:g}% of "
                                    "it (analysis.fit_range[0]; a partial unloading needs a higher lower bound)",
                                    100 * lower));
  return branches;
}

double contact_depth_factor(const AnalysisContext& context) {
  if (context.settings.epsilon) return *context.settings.epsilon;
  switch (context.shape) {
    case PunchShapeKind::cone: return 0.72;
    case PunchShapeKind::flat: return 1.0;
    case PunchShapeKind::sphere:
    case PunchShapeKind::profile:
    case PunchShapeKind::area_function: return 0.75;  // Oliver and Pharr's own choice for a calibrated Berkovich
  }
  return 0.75;
}

namespace {

/// The projected contact area of radius (half-width) r: pi r^2, or the width 2 r per unit thickness.
double projected_area(SceneKind scene, double r) {
  return scene == SceneKind::axisymmetric ? std::numbers::pi * r * r : 2.0 * r;
}

/// int P dh over [from, to] of the curve (trapezoids), positive for either direction.
double work(const std::vector<double>& depth, const std::vector<double>& force, std::size_t from, std::size_t to) {
  double w = 0.0;
  for (std::size_t k = from; k < to; ++k) w += 0.5 * (force[k] + force[k + 1]) * (depth[k + 1] - depth[k]);
  return std::abs(w);
}

}  // namespace

namespace {
/// Oliver and Pharr's E_r = sqrt(pi) / (2 beta) S / sqrt(A) (J. Mater. Res. 7, 1992, eq. 2).
double reduced_modulus_of(double stiffness, double area, const AnalysisContext& context) {
  return std::sqrt(std::numbers::pi) / (2.0 * context.settings.beta) * stiffness / std::sqrt(area);
}
}  // namespace

ContactOfStiffness contact_of_stiffness(double P_max, double h_max, double stiffness, const AnalysisContext& context) {
  ContactOfStiffness a;
  // A flat punch's contact does not shrink on unloading: its area is the punch's, h_c = h_max.
  a.h_c = h_max - contact_depth_factor(context) * P_max / stiffness;
  const auto rim = context.punch->rim();
  a.contact_radius = rim ? *rim : (a.h_c > 0.0 ? context.punch->geometric_contact_radius(a.h_c) : 0.0);
  if (!rim && a.h_c > 0.0 && !(context.punch->surface_height(a.contact_radius) >= a.h_c * (1.0 - 1e-9)))
    throw AnalysisError(
        context.shape == PunchShapeKind::area_function
            ? fmt::format("the contact depth h_c = {:g} m is where punch.area_coefficients give no growing positive "
                          "area (A = pi r^2 with r = {:g} m): the calibration does not hold at this depth",
                          a.h_c, a.contact_radius)
            : fmt::format("the contact depth h_c = {:g} m lies beyond the indenter's shape ({}): no area function "
                          "there",
                          a.h_c, context.punch->name()));
  if (!rim && !(a.h_c > 0.0))
    throw AnalysisError(fmt::format("the contact depth h_c = h_max - epsilon P_max / S = {:g} m is not positive: the "
                                    "unloading is too compliant for Oliver-Pharr (S = {:g} N/m)",
                                    a.h_c, stiffness));
  a.area = projected_area(context.scene, a.contact_radius);
  if (a.area > 0.0) a.hardness = P_max / a.area;
  if (context.scene == SceneKind::axisymmetric && a.area > 0.0) {
    a.reduced_modulus = reduced_modulus_of(stiffness, a.area, context);
    if (context.specimen_nu) {
      const double nu = *context.specimen_nu, nu_i = context.settings.indenter_nu;
      const double indenter = context.settings.indenter_E ? (1.0 - nu_i * nu_i) / *context.settings.indenter_E : 0.0;
      const double inverse = 1.0 / *a.reduced_modulus - indenter;
      if (inverse > 0.0) a.specimen_modulus = (1.0 - nu * nu) / inverse;
    }
  }
  return a;
}

namespace {

/// The least-squares slope of y against x over indices [first, last].
double slope_over(const std::vector<double>& x, const std::vector<double>& y, std::size_t first, std::size_t last) {
  const double n = static_cast<double>(last - first + 1);
  double mx = 0.0, my = 0.0;
  for (std::size_t k = first; k <= last; ++k) mx += x[k] / n, my += y[k] / n;
  double sxy = 0.0, sxx = 0.0;
  for (std::size_t k = first; k <= last; ++k) sxy += (x[k] - mx) * (y[k] - my), sxx += (x[k] - mx) * (x[k] - mx);
  return sxx > 0.0 ? sxy / sxx : 0.0;
}

constexpr double hold_force_tolerance = 5e-3;  // a hold's force stays within 0.5% of the peak's

// The hold's stress exponent (HoldAnalysis::stress_exponent): under a self-similar tip the
// indentation strain rate is h'/h and the hardness goes as P / h^d (d = 2, a wedge's 1), so over
// the hold's last half, by least squares, n = d ln(h'/h) / d ln(P / h^d) -- the power-law
// creep's m once the creep has forgotten the loading (similarity: h ~ t^(1/(2m)) at constant P).
// h' by central differences in time.
std::optional<double> hold_stress_exponent(const std::vector<double>& time, const std::vector<double>& depth,
                                           const std::vector<double>& force, std::size_t start, std::size_t peak,
                                           const AnalysisContext& context) {
  if (!sharp_tip(context.shape)) return std::nullopt;
  const double d = context.scene == SceneKind::axisymmetric ? 2.0 : 1.0;
  const std::size_t first = std::max(start + 1, peak - (peak - start) / 2);
  std::vector<double> log_hardness, log_rate;
  for (std::size_t k = first; k < peak; ++k) {
    const double rate = (depth[k + 1] - depth[k - 1]) / (time[k + 1] - time[k - 1]);
    if (!(rate > 0.0 && depth[k] > 0.0 && force[k] > 0.0)) return std::nullopt;
    log_hardness.push_back(std::log(force[k]) - d * std::log(depth[k]));
    log_rate.push_back(std::log(rate / depth[k]));
  }
  if (log_hardness.size() < 3) return std::nullopt;
  const double n = slope_over(log_hardness, log_rate, 0, log_hardness.size() - 1);
  if (!(n > 0.0) || !std::isfinite(n)) return std::nullopt;
  return n;
}
constexpr double unloading_rate_window = 0.8;  // the unloading rate is taken down to 80% of P_max

}  // namespace

std::optional<HoldAnalysis> analyze_hold(const std::vector<double>& time, const std::vector<double>& depth,
                                         const std::vector<double>& force, const CurveBranch& branch, double stiffness,
                                         const AnalysisContext& context) {
  if (time.size() != depth.size() || time.empty()) return std::nullopt;
  const std::size_t peak = branch.peak;
  const double held = force[peak];
  if (!(held > 0.0)) return std::nullopt;
  std::size_t start = peak;
  while (start > branch.loading_start && std::abs(force[start - 1] - held) <= hold_force_tolerance * held) --start;
  if (peak - start < 2 || !(time[peak] > time[start])) return std::nullopt;
  HoldAnalysis hold;
  hold.start = start;
  hold.duration = time[peak] - time[start];
  hold.creep_depth = depth[peak] - depth[start];
  // The depth rate at the hold's end, over its last half (the creep rate decays through a hold).
  hold.depth_rate = slope_over(time, depth, peak - std::max<std::size_t>(1, (peak - start) / 2), peak);
  hold.stress_exponent = hold_stress_exponent(time, depth, force, start, peak, context);
  std::size_t last = peak + 1;
  while (last + 1 <= branch.end && force[last + 1] >= unloading_rate_window * held) ++last;
  if (last > branch.end) return hold;
  const double rate = -slope_over(time, force, peak, last);
  if (!(rate > 0.0)) return hold;
  hold.unloading_rate = rate;
  // The depth rate at the start of unloading is P'_u / S_e + h'_hold with P'_u < 0; S = P'_u / h'
  // then gives 1/S_e = 1/S + h'_hold / |P'_u| (MODEL.md §13.4 says why the sign is +).
  const double compliance = 1.0 / stiffness + hold.depth_rate / rate;
  if (!(compliance > 0.0)) return hold;
  hold.stiffness = 1.0 / compliance;
  hold.corrected = contact_of_stiffness(force[peak], depth[peak], *hold.stiffness, context);
  return hold;
}

BranchAnalysis analyze_branch(const std::vector<double>& depth, const std::vector<double>& force,
                              const CurveBranch& branch, const AnalysisContext& context,
                              const std::optional<TrueContact>& truth) {
  BranchAnalysis a;
  a.h_max = depth[branch.peak];
  a.P_max = force[branch.peak];
  const std::vector<double> h(depth.begin() + static_cast<std::ptrdiff_t>(branch.peak),
                              depth.begin() + static_cast<std::ptrdiff_t>(branch.end) + 1);
  const std::vector<double> P(force.begin() + static_cast<std::ptrdiff_t>(branch.peak),
                              force.begin() + static_cast<std::ptrdiff_t>(branch.end) + 1);
  a.fit = fit_unloading(h, P, context.settings.fit_range[0], context.settings.fit_range[1]);
  a.residual_depth = a.fit.h_f;
  a.total_work = work(depth, force, branch.loading_start, branch.peak);
  a.elastic_work = work(depth, force, branch.peak, branch.end);

  const ContactOfStiffness contact = contact_of_stiffness(a.P_max, a.h_max, a.fit.stiffness, context);
  a.h_c = contact.h_c;
  a.contact_radius = contact.contact_radius;
  a.area = contact.area;
  a.hardness = contact.hardness;
  a.reduced_modulus = contact.reduced_modulus;
  a.specimen_modulus = contact.specimen_modulus;
  const bool axisymmetric = context.scene == SceneKind::axisymmetric;
  if (truth) {
    a.exact_stiffness = truth->stiffness;
    a.true_contact_radius = truth->half_width;
    a.true_area = projected_area(context.scene, truth->half_width);
    if (*a.true_area > 0.0) {
      a.true_hardness = a.P_max / *a.true_area;
      if (axisymmetric)
        a.true_reduced_modulus =
            reduced_modulus_of(truth->stiffness.value_or(a.fit.stiffness), *a.true_area, context);
      if (a.area > 0.0) a.pile_up_ratio = *a.true_area / a.area;
    }
  }
  if (context.coating && a.contact_radius > 0.0) {
    const CoatingContext& c = *context.coating;
    BranchAnalysis::Coating coating;
    coating.depth_over_thickness = a.h_max / c.thickness;
    coating.radius_over_thickness = a.contact_radius / c.thickness;
    coating.film_share = gao_weights(c.thickness / a.contact_radius, c.substrate_nu).I0;
    coating.film_modulus = c.film_E;
    // The specimen's contact modulus E* from E_r, the indenter's compliance taken out.
    const auto film_modulus = [&](const std::optional<double>& reduced_modulus,
                                  double radius) -> std::optional<double> {
      if (!reduced_modulus || !(radius > 0.0)) return std::nullopt;
      const double nu_i = context.settings.indenter_nu;
      const double indenter = context.settings.indenter_E ? (1.0 - nu_i * nu_i) / *context.settings.indenter_E : 0.0;
      const double compliance = 1.0 / *reduced_modulus - indenter;
      if (!(compliance > 0.0)) return std::nullopt;
      return gao_film_modulus(1.0 / compliance, c.film_nu, c.substrate_E, c.substrate_nu, c.thickness / radius);
    };
    coating.film_modulus_gao = film_modulus(a.reduced_modulus, a.contact_radius);
    if (a.true_contact_radius)
      coating.film_modulus_gao_true_contact = film_modulus(a.true_reduced_modulus, *a.true_contact_radius);
    a.coating = coating;
  }
  return a;
}

namespace {
/// A number, or null when there is none (or it is not finite).
nlohmann::ordered_json number_or_null(const std::optional<double>& v) {
  return v && std::isfinite(*v) ? nlohmann::ordered_json(*v) : nlohmann::ordered_json(nullptr);
}
}  // namespace

nlohmann::ordered_json branch_json(const BranchAnalysis& a, const AnalysisContext& context) {
  const bool axisymmetric = context.scene == SceneKind::axisymmetric;
  nlohmann::ordered_json j;
  j["P_max"] = a.P_max;
  j["h_max"] = a.h_max;
  j["fit"] = {{"B", a.fit.B},
              {"m", a.fit.m},
              {"h_f", a.fit.h_f},
              {"points", a.fit.points},
              {"range", context.settings.fit_range},
              {"rms_residual", a.fit.rms_residual}};
  j["S_fit"] = a.fit.stiffness;
  j["S_exact"] = number_or_null(a.exact_stiffness);
  j["epsilon"] = contact_depth_factor(context);
  j["beta"] = context.settings.beta;
  j["h_c"] = a.h_c;
  j["contact_radius"] = a.contact_radius;
  j["A_c"] = a.area;
  j["H"] = a.hardness;
  j["E_r"] = number_or_null(a.reduced_modulus);
  if (!axisymmetric) j["E_r_note"] = "not defined in plane strain: a half-plane's compliance depends on the specimen size";
  j["E"] = number_or_null(a.specimen_modulus);
  j["h_f"] = a.residual_depth;
  j["W_t"] = a.total_work;
  j["W_e"] = a.elastic_work;
  j["W_e_over_W_t"] = a.total_work > 0 ? a.elastic_work / a.total_work : 0.0;
  j["true_contact_radius"] = number_or_null(a.true_contact_radius);
  j["true_area"] = number_or_null(a.true_area);
  j["true_H"] = number_or_null(a.true_hardness);
  j["true_E_r"] = number_or_null(a.true_reduced_modulus);
  j["pile_up_ratio"] = number_or_null(a.pile_up_ratio);
  if (a.coating)
    j["coating"] = {{"h_max_over_t", a.coating->depth_over_thickness},
                    {"contact_radius_over_t", a.coating->radius_over_thickness},
                    {"film_share_gao_I0", a.coating->film_share},
                    {"film_E_gao", number_or_null(a.coating->film_modulus_gao)},
                    {"film_E_gao_true_contact", number_or_null(a.coating->film_modulus_gao_true_contact)},
                    {"film_E_true", a.coating->film_modulus},
                    {"film_alone_E_r", number_or_null(a.coating->film_alone_reduced_modulus)},
                    {"film_alone_H", number_or_null(a.coating->film_alone_hardness)}};
  if (a.hold) {
    const HoldAnalysis& h = *a.hold;
    nlohmann::ordered_json hold{{"start_index", h.start},       {"duration_s", h.duration},
                                {"creep_depth", h.creep_depth}, {"depth_rate_at_end", h.depth_rate},
                                {"unloading_rate", number_or_null(h.unloading_rate)},
                                {"S_corrected", number_or_null(h.stiffness)}};
    if (h.corrected) {
      hold["h_c_corrected"] = h.corrected->h_c;
      hold["A_c_corrected"] = h.corrected->area;
      hold["H_corrected"] = h.corrected->hardness;
      hold["E_r_corrected"] = number_or_null(h.corrected->reduced_modulus);
      hold["E_corrected"] = number_or_null(h.corrected->specimen_modulus);
    }
    hold["correction"] = "Feng and Ngan 2002: 1/S_corrected = 1/S_fit + depth_rate_at_end / unloading_rate";
    hold["stress_exponent"] = number_or_null(h.stress_exponent);
    hold["strain_rate_sensitivity"] =
        number_or_null(h.stress_exponent ? std::optional<double>(1.0 / *h.stress_exponent) : std::nullopt);
    hold["stress_exponent_method"] =
        "Mayo and Nix 1988, Lucas and Oliver 1999: n = d ln(h'/h) / d ln(P/h^2) over the hold's last half "
        "(P/h for a wedge); self-similar tips only";
    j["hold"] = hold;
  } else {
    j["hold"] = nullptr;
  }
  return j;
}

nlohmann::ordered_json analysis_units(SceneKind scene) {
  if (scene == SceneKind::axisymmetric)
    return {{"depth", "m"}, {"force", "N"}, {"stiffness", "N/m"}, {"area", "m^2"}, {"stress", "Pa"},
            {"work", "J"},  {"B", "N/m^m"}, {"time", "s"}, {"depth_rate", "m/s"}, {"force_rate", "N/s"}};
  return {{"depth", "m"},
          {"force", "N/m (per unit thickness)"},
          {"stiffness", "N/m per m"},
          {"area", "m (the contact width 2a)"},
          {"stress", "Pa"},
          {"work", "J/m"},
          {"B", "N/m per m^m"},
          {"time", "s"},
          {"depth_rate", "m/s"},
          {"force_rate", "N/m/s"}};
}

}  // namespace indentsim
