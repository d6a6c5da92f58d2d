#pragma once
// What indentation users read off a load-unload curve: hardness, modulus, contact depth, works.
//
// Oliver and Pharr (J. Mater. Res. 7, 1992; 19, 2004), as ISO 14577-1 Annex A applies it, on
// each unloading branch:
//   fit       P = B (h - h_f)^m over the branch's points with fit_range[0] P_max <= P <=
//             fit_range[1] P_max (ISO 14577 practice: 20% to 98%), in relative least squares,
//             by Levenberg-Marquardt (Eigen's unsupported module);
//   S         = dP/dh at h_max from the fit = m B (h_max - h_f)^(m - 1);
//   h_c       = h_max - epsilon P_max / S   (epsilon 0.75 sphere/paraboloid, 0.72 cone, 1 flat);
//   A_c       = pi r(h_c)^2 with g(r(h_c)) = h_c: the indenter's own area function (PunchShape);
//   H         = P_max / A_c,   E_r = sqrt(pi) / (2 beta) S / sqrt(A_c),
//   E         = (1 - nu^2) / (1 / E_r - (1 - nu_i^2) / E_i)   (E_i = inf: a rigid indenter);
//   W_t, W_e  the loading and unloading works (trapezoids), W_e / W_t.
// With a simulated run's own contact radius a at P_max (the contact solution) the same numbers
// with the true area pi a^2, and the pile-up ratio A_true / A_c (> 1: pile-up, < 1: sink-in).
//
// In plane strain P is a force per unit thickness and the "area" a width 2 r: S, h_f, the works,
// the true contact width and the mean pressure P / 2a are defined; E_r is not -- a half-plane's
// compliance grows with the specimen's size (log(L / a), Johnson, Contact Mechanics §2.8), so no
// area-based modulus exists.  The analysis says so instead of printing a number.
#include <stdexcept>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "indentsim/analysis/coating_analysis.hpp"
#include "indentsim/input/load_case.hpp"
#include "indentsim/simulation/load_stepping.hpp"

namespace indentsim {

class PunchShape;

/// A branch or a curve that cannot be analysed (too short, not monotone, no unloading...).
class AnalysisError : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

/// P = B (h - h_f)^m, fitted.
struct PowerLawFit {
  double B = 0.0, m = 0.0, h_f = 0.0;
  double h_max = 0.0;          ///< the branch's first (deepest) depth
  double stiffness = 0.0;      ///< S = dP/dh at h_max
  double rms_residual = 0.0;   ///< root mean square of (fit - P) / P_max over the points fitted
  int points = 0;              ///< points fitted
  double force_at(double h) const;
};

/// Fits P = B (h - h_f)^m to the points of an unloading branch (h decreasing from h_max) whose
/// force lies in [lower, upper] P_max.  Throws AnalysisError with fewer than 4 such points.
PowerLawFit fit_unloading(const std::vector<double>& depth, const std::vector<double>& force, double lower,
                          double upper);

/// The branches of a simulated (depth-controlled) curve are unloading_branches (load_stepping.hpp).

/// The unloading branches of a measured, load-controlled curve: from a maximum of the force while
/// the force falls; a fall that stays above fit_range[0] P_max is a hold's noise and is skipped.
/// Throws AnalysisError when there is no branch, or when the depth rises within the part of a
/// branch that is fitted (naming the rows: `rows[k]` is point k's row in the file).
std::vector<CurveBranch> measured_unloading_branches(const std::vector<double>& depth, const std::vector<double>& force,
                                                     const AnalysisInput& settings,
                                                     const std::vector<std::size_t>& rows = {});

/// What a simulated run adds at a reversal: the exact unloading stiffness and the true contact.
struct TrueContact {
  std::optional<double> stiffness;  ///< dP/dh of the elastic unloading tangent at the peak [N/m]
  double half_width = 0.0;          ///< contact radius (half-width) of the contact solution [m]
};

/// What Oliver and Pharr read off a peak (P_max, h_max) and an unloading stiffness S: the contact
/// depth h_c = h_max - epsilon P_max / S, its radius and projected area, H and E_r.
struct ContactOfStiffness {
  double h_c = 0.0, contact_radius = 0.0, area = 0.0, hardness = 0.0;
  std::optional<double> reduced_modulus, specimen_modulus;
};

/// A hold at the peak force before an unloading, in a curve with time (docs/MODEL.md §13.4): the
/// rows before the peak whose force stays within 0.5% of the peak's, at least three of them over
/// a positive time.
struct HoldAnalysis {
  std::size_t start = 0;        ///< index of the hold's first point; its last is the branch's peak
  double duration = 0.0;        ///< [s]
  double creep_depth = 0.0;     ///< the depth gained over the hold [m]
  double depth_rate = 0.0;      ///< dh/dt at its end [m/s]: least squares over its last half
  std::optional<double> unloading_rate;  ///< |dP/dt| at the start of unloading [N/s]: least squares
                                         ///< over the unloading down to 80% of P_max
  /// Feng and Ngan's (J. Mater. Res. 17, 2002) stiffness corrected for creep,
  /// 1/S_e = 1/S + depth_rate / unloading_rate, and the analysis with it; none without an
  /// unloading rate, or when the correction leaves no positive compliance.
  std::optional<double> stiffness;
  std::optional<ContactOfStiffness> corrected;
  /// The creep stress exponent n = d ln(h'/h) / d ln H over the hold's last half, H ~ P / h^2 (a
  /// wedge's P / h): Mayo and Nix (Acta Metall. 36, 1988), Lucas and Oliver (Metall. Mater. Trans.
  /// A 30, 1999); its strain-rate sensitivity is 1/n.  A self-similar tip only (cone, area
  /// function), with at least three points and a depth rising through them; else none.
  std::optional<double> stress_exponent;
};

struct BranchAnalysis {
  double P_max = 0.0, h_max = 0.0;
  PowerLawFit fit;
  double h_c = 0.0, contact_radius = 0.0;  ///< Oliver-Pharr contact depth and r(h_c)
  double area = 0.0;                       ///< A_c [m^2] (plane strain: width 2 r(h_c) [m])
  double hardness = 0.0;                   ///< P_max / A_c [Pa]
  std::optional<double> reduced_modulus;   ///< E_r [Pa]; none in plane strain
  std::optional<double> specimen_modulus;  ///< E from E_r, nu and the indenter [Pa]
  double residual_depth = 0.0;             ///< h_f of the fit [m]
  double total_work = 0.0, elastic_work = 0.0;  ///< W_t, W_e [J, or J/m in plane strain]
  // With a simulated run's true contact:
  std::optional<double> exact_stiffness, true_contact_radius, true_area, true_hardness, true_reduced_modulus,
      pile_up_ratio;
  std::optional<HoldAnalysis> hold;  ///< with time, a hold before the peak (analyze_hold)
  /// A coated specimen's branch (docs/MODEL.md §14.4): its depth and Oliver-Pharr contact radius
  /// against the film's thickness, the film's share I0 of the apparent modulus by Gao's weight,
  /// and the film's modulus from E_r by Gao's model beside the true one.
  struct Coating {
    double depth_over_thickness = 0.0, radius_over_thickness = 0.0, film_share = 0.0;
    std::optional<double> film_modulus_gao;
    /// The same from a simulated run's true contact (its radius and E_r): what Gao's model gives
    /// without Oliver and Pharr's error in the contact area.
    std::optional<double> film_modulus_gao_true_contact;
    double film_modulus = 0.0;
    /// The film alone on the same load path and mesh plan, analysed alike (analyze_run_curve's
    /// companion run): its E_r and H, what the substrate moves.
    std::optional<double> film_alone_reduced_modulus, film_alone_hardness;
  };
  std::optional<Coating> coating;
};

/// The settings and the indenter the analysis needs.
struct AnalysisContext {
  SceneKind scene = SceneKind::axisymmetric;
  const PunchShape* punch = nullptr;
  PunchShapeKind shape = PunchShapeKind::sphere;
  AnalysisInput settings;
  std::optional<double> specimen_nu;  ///< for the specimen modulus (a run's material.nu)
  std::optional<CoatingContext> coating;  ///< a coated run's film (coating_of)
};

/// epsilon of Oliver and Pharr for the shape, unless the settings give one.
double contact_depth_factor(const AnalysisContext& context);

/// Oliver and Pharr's contact at (P_max, h_max) with stiffness S; throws AnalysisError where the
/// contact depth is not positive or lies beyond the indenter's shape.
ContactOfStiffness contact_of_stiffness(double P_max, double h_max, double stiffness, const AnalysisContext& context);

BranchAnalysis analyze_branch(const std::vector<double>& depth, const std::vector<double>& force,
                              const CurveBranch& branch, const AnalysisContext& context,
                              const std::optional<TrueContact>& truth = std::nullopt);

/// The hold before the branch's peak in a curve with `time` [s] (one per point), and Feng and
/// Ngan's correction of the branch's stiffness S for its creep; none without a hold.
std::optional<HoldAnalysis> analyze_hold(const std::vector<double>& time, const std::vector<double>& depth,
                                         const std::vector<double>& force, const CurveBranch& branch, double stiffness,
                                         const AnalysisContext& context);

/// The branch's numbers as a JSON object, SI (analysis_units says which).
nlohmann::ordered_json branch_json(const BranchAnalysis& analysis, const AnalysisContext& context);
/// The units of branch_json's numbers in the scene, stated once per output.
nlohmann::ordered_json analysis_units(SceneKind scene);

}  // namespace indentsim
