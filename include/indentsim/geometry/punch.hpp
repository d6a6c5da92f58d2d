#pragma once
// The rigid punch: its shape g(r), the height of its surface above its lowest point at distance r
// from the axis (the symmetry plane in plane strain).  The contact condition of docs/MODEL.md §3
// (vertical gap d = g(r) - alpha - v >= 0) takes g from here and nothing else.
//
//   SphericalPunch  g = R - sqrt(R^2 - r^2): a sphere in axisymmetry, the paper's cylinder in
//                   plane strain.
//   ConicalPunch    g = r cot(theta), theta the half-angle between axis and face (70.3 deg: the
//                   Berkovich- and Vickers-equivalent cone); optionally blunted by a spherical cap
//                   of radius R_t tangent to the face at r_t = R_t cos(theta).  A wedge in plane strain.
//   FlatPunch       g = 0 for r <= R (a cylinder of radius R, a strip of half-width R).
//   ProfilePunch    a measured tip: g at points r_0 = 0 < r_1 < ... , interpolated by the monotone
//                   cubic of Fritsch and Carlson (SIAM J. Numer. Anal. 17, 1980), so that a
//                   rising profile never dips between its points.
//   AreaFunctionPunch  a calibrated tip's area function A(h_c) (Oliver and Pharr 1992) as the
//                   axisymmetric profile of equal area: pi r^2 = A(g(r)), so g = A^-1(pi r^2).
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "indentsim/geometry/kinematics.hpp"
#include "indentsim/input/load_case.hpp"

namespace indentsim {

class PunchShape {
public:
  virtual ~PunchShape() = default;
  /// "sphere" | "cone" | "flat" | "profile" | "area_function", as punch.shape spells it.
  virtual std::string name() const = 0;
  /// g(r) >= 0; +inf where the punch has no surface (beyond its rim or its last point).
  virtual double surface_height(double r) const = 0;
  /// g'(r) (one-sided at kinks), for Sneddon's integral.
  virtual double slope(double r) const = 0;
  /// The radius of a flat punch's rim, where the contact edge stays; none for a smooth punch,
  /// whose contact edge is free and found from the pressures.
  virtual std::optional<double> rim() const { return std::nullopt; }
  /// The radius where the punch surface meets the undeformed surface at depth alpha: g(r) = alpha.
  virtual double geometric_contact_radius(double alpha) const;
  /// The contact radius expected at depth alpha on an elastic block of depth `block_depth` (to
  /// size the mesh).  Axisymmetry: Sneddon's depth of a smooth axisymmetric punch,
  ///   alpha = a int_0^{pi/2} g'(a sin phi) dphi        (Sneddon 1965, eq. 6.1),
  /// solved for a.  Plane strain: alpha = (2/pi) (P/E*) [ln(2d/a) - nu/(2(1-nu))] with the
  /// half-plane's P/E* = a int_0^{pi/2} g'(a sin phi) sin phi dphi of a pressure bounded at the
  /// edges (Johnson, Contact Mechanics §5.6 for Hertz's cylinder; for other profiles the
  /// logarithm is a sizing rule).  Never beyond the geometric radius.
  virtual double contact_estimate(SceneKind scene, double alpha, double block_depth, double nu) const;
  /// A warning when the depth pushes the small-slope model (vertical gap) beyond its range.
  virtual std::optional<std::string> slope_warning(double /*alpha*/) const { return std::nullopt; }
  /// The order p of P - P_exact ~ h^p on bilinear elements, for the error estimate
  /// (error_estimate.hpp): 2 where the pressure is bounded (measured 1.6-2.3 in the
  /// work-precision study).
  virtual double force_convergence_order() const { return 2.0; }
};

class SphericalPunch final : public PunchShape {
public:
  explicit SphericalPunch(double radius) : radius_(radius) {}
  std::string name() const override { return "sphere"; }
  double surface_height(double r) const override;
  double slope(double r) const override;
  double geometric_contact_radius(double alpha) const override;
  /// Plane strain: the Hertz line-contact estimate (hertz::estimate_half_width).
  double contact_estimate(SceneKind scene, double alpha, double block_depth, double nu) const override;
  std::optional<std::string> slope_warning(double alpha) const override;
  double radius() const { return radius_; }

private:
  double radius_;
};

class ConicalPunch final : public PunchShape {
public:
  /// half_angle in radians; tip_radius 0 for a sharp cone.
  ConicalPunch(double half_angle, double tip_radius);
  std::string name() const override { return "cone"; }
  double surface_height(double r) const override;
  double slope(double r) const override;
  std::optional<std::string> slope_warning(double alpha) const override;
  /// Where the spherical cap meets the face (0 for a sharp cone).
  double cap_radius() const { return cap_radius_; }

private:
  double half_angle_, tip_radius_, cot_, cap_radius_, cap_height_;
};

class FlatPunch final : public PunchShape {
public:
  explicit FlatPunch(double radius) : radius_(radius) {}
  std::string name() const override { return "flat"; }
  double surface_height(double r) const override;
  double slope(double) const override { return 0.0; }
  std::optional<double> rim() const override { return radius_; }
  double geometric_contact_radius(double) const override { return radius_; }
  double contact_estimate(SceneKind, double, double, double) const override { return radius_; }
  /// The pressure under a flat punch is singular at its rim, p ~ (a - r)^(-1/2) (Boussinesq;
  /// Sneddon 1965 §5): bilinear elements miss the singular part within the rim's element, and P
  /// converges at first order (measured 1.12 from contact_nodes 10, 20, 40 on flat_punch.toml).
  double force_convergence_order() const override { return 1.0; }

private:
  double radius_;
};

class ProfilePunch final : public PunchShape {
public:
  /// Points (r, g), r from 0 strictly increasing, g from 0 non-decreasing (checked by the reader).
  explicit ProfilePunch(std::vector<std::pair<double, double>> points);
  std::string name() const override { return "profile"; }
  double surface_height(double r) const override;
  double slope(double r) const override;
  std::optional<std::string> slope_warning(double alpha) const override;

private:
  std::size_t interval(double r) const;
  std::vector<double> r_, g_, d_;  ///< points and the Fritsch-Carlson slopes at them
};

class AreaFunctionPunch final : public PunchShape {
public:
  /// The coefficients C0 ... C8 of area_function_area (load_case.hpp), SI.
  explicit AreaFunctionPunch(std::vector<double> coefficients);
  std::string name() const override { return "area_function"; }
  /// The depth h whose area is pi r^2: the smallest h with A(h) >= pi r^2 (found by doubling a
  /// bracket, then Newton's steps kept inside it); +inf where A no longer grows before reaching it.
  double surface_height(double r) const override;
  /// dg/dr = 2 pi r / A'(g(r)).
  double slope(double r) const override;
  /// sqrt(A(alpha) / pi): the area the analysis takes is A(h_c) itself.
  double geometric_contact_radius(double alpha) const override;
  std::optional<std::string> slope_warning(double alpha) const override;

private:
  std::vector<double> c_;
};

/// The punch a load case describes.
std::shared_ptr<const PunchShape> make_punch(const PunchInput& input);

}  // namespace indentsim
