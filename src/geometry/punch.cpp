#include "indentsim/geometry/punch.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <fmt/format.h>

#include "indentsim/geometry/hertz.hpp"

namespace indentsim {

namespace {
constexpr double infinity = std::numeric_limits<double>::infinity();
constexpr double max_relative_depth = 0.05;  // alpha / R beyond which a sphere's depth is warned about
constexpr double max_slope = 0.6;            // the face slope beyond which the vertical gap is warned about

/// The smallest r in [0, upper] with f(r) >= target for a non-decreasing f (bisection to round-off).
template <class F>
double invert_increasing(F f, double target, double upper) {
  double lo = 0.0, hi = upper;
  for (int it = 0; it < 200 && hi - lo > 1e-15 * hi; ++it) {
    const double mid = 0.5 * (lo + hi);
    (f(mid) >= target ? hi : lo) = mid;
  }
  return hi;
}

/// int_0^{pi/2} f(sin phi) dphi by the 64-point midpoint rule: the integrals of a punch's slope
/// over its contact (below), enough for a mesh size.
template <class F>
double quarter_turn_integral(F f) {
  constexpr int n = 64;
  constexpr double width = std::numbers::pi / (2.0 * n);
  double sum = 0.0;
  for (int k = 0; k < n; ++k) sum += f(std::sin((k + 0.5) * width));
  return sum * width;
}

/// A radius where g(r) >= alpha (+inf beyond a rim counts), by doubling.
double radius_above(const PunchShape& shape, double alpha) {
  double r = 1e-12;
  for (int it = 0; it < 400 && shape.surface_height(r) < alpha; ++it) r *= 2.0;
  return r;
}
}  // namespace

double PunchShape::geometric_contact_radius(double alpha) const {
  return invert_increasing([&](double r) { return surface_height(r); }, alpha, radius_above(*this, alpha));
}

double PunchShape::contact_estimate(SceneKind scene, double alpha, double block_depth, double nu) const {
  if (alpha <= 0.0) return 0.0;
  const double geometric = geometric_contact_radius(alpha);
  if (scene == SceneKind::axisymmetric) {
    // Sneddon's depth h(a) = a int_0^{pi/2} g'(a sin phi) dphi, increasing in a for a convex
    // (or any rising) profile.
    const auto depth_of = [&](double a) { return a * quarter_turn_integral([&](double s) { return slope(a * s); }); };
    return invert_increasing(depth_of, alpha, geometric);
  }
  // Plane strain: a smooth symmetric punch whose pressure stays bounded at the edges x = +-a of
  // its contact carries P / E* = int_0^a g'(x) x / sqrt(a^2 - x^2) dx = a int_0^{pi/2} g'(a sin phi)
  // sin phi dphi (the 2-D punch problem: pi a^2 / 4R for Hertz's cylinder, a cot(theta) for a
  // wedge).  A 2-D contact's approach has meaning only against a depth d, and is set by that
  // force: alpha = (2 / pi) (P / E*) [ln(2d/a) - nu/(2(1-nu))], which for the cylinder is
  // Johnson's (Contact Mechanics §5.6; hertz.hpp).  The form g(a) [ln ...] taken for every
  // profile before is the cylinder's only: it put an elastic wedge's contact pi/2 too narrow,
  // outside its fine zone.
  const double poisson_term = nu / (2.0 * (1.0 - nu));
  const auto depth_of = [&](double a) {
    const double force_over_modulus = a * quarter_turn_integral([&](double s) { return slope(a * s) * s; });
    return 2.0 / std::numbers::pi * force_over_modulus *
           std::max(1.0, std::log(2.0 * block_depth / a) - poisson_term);
  };
  return invert_increasing(depth_of, alpha, geometric);
}

// ---------------------------------------------------------------------------------------------
double SphericalPunch::surface_height(double r) const {
  const double ar = std::abs(r);
  if (ar >= radius_) return infinity;
  // R - sqrt(R^2 - r^2) written without cancellation for r << R.
  return ar * ar / (radius_ + std::sqrt((radius_ - ar) * (radius_ + ar)));
}

double SphericalPunch::slope(double r) const {
  const double ar = std::abs(r);
  return ar >= radius_ ? infinity : ar / std::sqrt((radius_ - ar) * (radius_ + ar));
}

double SphericalPunch::geometric_contact_radius(double alpha) const {
  return std::sqrt(std::max(0.0, 2.0 * radius_ * alpha - alpha * alpha));  // the chord
}

double SphericalPunch::contact_estimate(SceneKind scene, double alpha, double block_depth, double nu) const {
  if (scene == SceneKind::plane_strain) return hertz::estimate_half_width(alpha, radius_, block_depth, nu);
  // Hertz: a = sqrt(R h) for a paraboloid, within the chord.
  return std::min(std::sqrt(radius_ * alpha), geometric_contact_radius(alpha));
}

std::optional<std::string> SphericalPunch::slope_warning(double alpha) const {
  const double relative_depth = alpha / radius_;
  if (relative_depth <= max_relative_depth) return std::nullopt;
  return fmt::format("the depth reaches {:.3g} R: the small-strain contact model (vertical gap, small slopes) is "
                     "being pushed beyond its range (alpha / R up to {:.2g}); read the results as qualitative",
                     relative_depth, max_relative_depth);
}

// ---------------------------------------------------------------------------------------------
ConicalPunch::ConicalPunch(double half_angle, double tip_radius)
    : half_angle_(half_angle), tip_radius_(tip_radius), cot_(1.0 / std::tan(half_angle)) {
  // The cap meets the face where the sphere's slope r / sqrt(R^2 - r^2) equals cot(theta).
  cap_radius_ = tip_radius_ * std::cos(half_angle_);
  cap_height_ = tip_radius_ - std::sqrt(tip_radius_ * tip_radius_ - cap_radius_ * cap_radius_);
}

double ConicalPunch::surface_height(double r) const {
  const double ar = std::abs(r);
  if (ar < cap_radius_) return ar * ar / (tip_radius_ + std::sqrt((tip_radius_ - ar) * (tip_radius_ + ar)));
  return cap_height_ + (ar - cap_radius_) * cot_;
}

double ConicalPunch::slope(double r) const {
  const double ar = std::abs(r);
  if (ar < cap_radius_) return ar / std::sqrt((tip_radius_ - ar) * (tip_radius_ + ar));
  return cot_;
}

std::optional<std::string> ConicalPunch::slope_warning(double) const {
  if (cot_ <= max_slope) return std::nullopt;
  return fmt::format("the cone's face rises at slope {:.3g} (half-angle {:.4g} deg): the small-slope contact model "
                     "(vertical gap) is pushed beyond its range (slopes up to {:g}, half-angles from {:.3g} deg)",
                     cot_, half_angle_ * 180.0 / std::numbers::pi, max_slope,
                     std::atan(1.0 / max_slope) * 180.0 / std::numbers::pi);
}

// ---------------------------------------------------------------------------------------------
double FlatPunch::surface_height(double r) const {
  // The rim node belongs to the face: a mesh node placed at R by rounding is on it.
  return std::abs(r) <= radius_ * (1.0 + 1e-9) ? 0.0 : infinity;
}

// ---------------------------------------------------------------------------------------------
ProfilePunch::ProfilePunch(std::vector<std::pair<double, double>> points) {
  for (const auto& [r, g] : points) {
    r_.push_back(r);
    g_.push_back(g);
  }
  // Fritsch-Carlson: secant slopes, harmonic-type means at interior points, zero at extrema and
  // flats, then the limiter alpha^2 + beta^2 <= 9 that keeps each cubic monotone.
  const std::size_t n = r_.size();
  std::vector<double> secant(n > 1 ? n - 1 : 0);
  for (std::size_t k = 0; k + 1 < n; ++k) secant[k] = (g_[k + 1] - g_[k]) / (r_[k + 1] - r_[k]);
  d_.assign(n, 0.0);
  if (n == 2) d_ = {secant[0], secant[0]};
  for (std::size_t k = 1; k + 1 < n; ++k)
    d_[k] = secant[k - 1] * secant[k] <= 0.0 ? 0.0 : 0.5 * (secant[k - 1] + secant[k]);
  if (n > 2) {
    d_[0] = secant[0];
    d_[n - 1] = secant[n - 2];
  }
  for (std::size_t k = 0; k + 1 < n; ++k) {
    if (secant[k] == 0.0) {
      d_[k] = d_[k + 1] = 0.0;
      continue;
    }
    const double a = d_[k] / secant[k], b = d_[k + 1] / secant[k];
    const double s = a * a + b * b;
    if (s > 9.0) {
      const double t = 3.0 / std::sqrt(s);
      d_[k] = t * a * secant[k];
      d_[k + 1] = t * b * secant[k];
    }
  }
}

std::size_t ProfilePunch::interval(double r) const {
  const auto it = std::upper_bound(r_.begin(), r_.end(), r);
  const std::size_t k = static_cast<std::size_t>(it - r_.begin());
  return std::clamp<std::size_t>(k == 0 ? 0 : k - 1, 0, r_.size() - 2);
}

double ProfilePunch::surface_height(double r) const {
  const double ar = std::abs(r);
  if (ar > r_.back()) return infinity;
  const std::size_t k = interval(ar);
  const double h = r_[k + 1] - r_[k], t = (ar - r_[k]) / h;
  // Cubic Hermite basis.
  const double h00 = (1 + 2 * t) * (1 - t) * (1 - t), h10 = t * (1 - t) * (1 - t), h01 = t * t * (3 - 2 * t),
               h11 = t * t * (t - 1);
  return h00 * g_[k] + h10 * h * d_[k] + h01 * g_[k + 1] + h11 * h * d_[k + 1];
}

double ProfilePunch::slope(double r) const {
  const double ar = std::abs(r);
  if (ar > r_.back()) return infinity;
  const std::size_t k = interval(ar);
  const double h = r_[k + 1] - r_[k], t = (ar - r_[k]) / h;
  const double d00 = 6 * t * (t - 1), d10 = (1 - t) * (1 - 3 * t), d01 = -6 * t * (t - 1), d11 = t * (3 * t - 2);
  return (d00 * g_[k] + d01 * g_[k + 1]) / h + d10 * d_[k] + d11 * d_[k + 1];
}

std::optional<std::string> ProfilePunch::slope_warning(double alpha) const {
  const double edge = geometric_contact_radius(alpha);
  double steepest = 0.0;
  for (std::size_t k = 0; k < r_.size() && r_[k] <= edge; ++k) steepest = std::max(steepest, d_[k]);
  if (steepest <= max_slope) return std::nullopt;
  return fmt::format("the profile rises at slopes up to {:.3g} within the contact: the small-slope contact model "
                     "(vertical gap) is pushed beyond its range (slopes up to {:g})",
                     steepest, max_slope);
}

AreaFunctionPunch::AreaFunctionPunch(std::vector<double> coefficients) : c_(std::move(coefficients)) {}

double AreaFunctionPunch::surface_height(double r) const {
  const double ar = std::abs(r);
  if (ar == 0.0) return 0.0;
  const double target = std::numbers::pi * ar * ar;
  // A bracket [lo, hi] of the depth whose area is the target, by doubling from below any tip's
  // scale (through depths where a calibration's A is not yet positive); where a positive area
  // stops growing before it reaches the target, the tip has no surface there (validation refuses
  // that within the depths a run reaches).
  double lo = 0.0, hi = 1e-15;
  for (int it = 0; area_function_area(c_, hi) < target; ++it) {
    if (it >= 400 || (area_function_area(c_, hi) > 0.0 && !(area_function_slope(c_, hi) > 0.0))) return infinity;
    lo = hi;
    hi *= 2.0;
  }
  // Newton's steps on A(h) = target, kept inside the bracket (bisection when a step leaves it).
  double h = hi;
  for (int it = 0; it < 200; ++it) {
    const double f = area_function_area(c_, h) - target;
    if (f == 0.0) return h;
    (f > 0.0 ? hi : lo) = h;
    double next = h - f / area_function_slope(c_, h);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    if (std::abs(next - h) <= 1e-16 * h || hi - lo <= 1e-16 * hi) return next;
    h = next;
  }
  return h;
}

double AreaFunctionPunch::slope(double r) const {
  const double ar = std::abs(r);
  if (ar == 0.0) {
    // At the tip: a pure C0 h^2 is a cone of slope sqrt(pi / C0); any lower power of h makes A grow
    // faster than r^2 near h = 0, and the tip is flat there.
    const bool cone = std::all_of(c_.begin() + 1, c_.end(), [](double c) { return c == 0.0; });
    return cone ? std::sqrt(std::numbers::pi / c_[0]) : 0.0;
  }
  const double h = surface_height(ar);
  if (!std::isfinite(h)) return infinity;
  return 2.0 * std::numbers::pi * ar / area_function_slope(c_, h);
}

double AreaFunctionPunch::geometric_contact_radius(double alpha) const {
  return std::sqrt(std::max(0.0, area_function_area(c_, alpha)) / std::numbers::pi);
}

std::optional<std::string> AreaFunctionPunch::slope_warning(double alpha) const {
  const double edge = geometric_contact_radius(alpha);
  double steepest = 0.0;
  for (int k = 1; k <= 32; ++k) steepest = std::max(steepest, slope(edge * k / 32.0));
  if (steepest <= max_slope) return std::nullopt;
  return fmt::format("the area function's profile of equal area rises at slopes up to {:.3g} within the contact: the "
                     "small-slope contact model (vertical gap) is pushed beyond its range (slopes up to {:g})",
                     steepest, max_slope);
}

std::shared_ptr<const PunchShape> make_punch(const PunchInput& p) {
  switch (p.shape) {
    case PunchShapeKind::cone:
      return std::make_shared<ConicalPunch>(p.half_angle * std::numbers::pi / 180.0, p.tip_radius);
    case PunchShapeKind::flat: return std::make_shared<FlatPunch>(p.radius);
    case PunchShapeKind::profile: return std::make_shared<ProfilePunch>(p.profile);
    case PunchShapeKind::area_function: return std::make_shared<AreaFunctionPunch>(p.area_coefficients);
    case PunchShapeKind::sphere: break;
  }
  return std::make_shared<SphericalPunch>(p.radius);
}

}  // namespace indentsim
