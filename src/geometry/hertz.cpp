#include "indentsim/geometry/hertz.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace indentsim::hertz {

double force(double a, double radius, double e_star) {
  return std::numbers::pi * e_star * a * a / (4.0 * radius);
}

double half_width(double p, double radius, double e_star) {
  return std::sqrt(4.0 * p * radius / (std::numbers::pi * e_star));
}

double pressure(double x, double a, double p) {
  if (a <= 0.0 || std::abs(x) >= a) return 0.0;
  const double p0 = 2.0 * p / (std::numbers::pi * a);
  return p0 * std::sqrt(1.0 - (x * x) / (a * a));
}

double estimate_half_width(double alpha, double radius, double depth, double nu) {
  if (alpha <= 0.0) return 0.0;
  const double chord = std::sqrt(std::max(0.0, 2.0 * radius * alpha - alpha * alpha));
  const double poisson_term = nu / (2.0 * (1.0 - nu));
  // alpha = (a^2 / 2R) [ln(2d/a) - c]  =>  a = sqrt(2 R alpha / [ln(2d/a) - c]).
  double a = chord;
  for (int iteration = 0; iteration < 100; ++iteration) {
    const double bracket = std::max(1.0, std::log(2.0 * depth / a) - poisson_term);
    const double next = std::min(chord, std::sqrt(2.0 * radius * alpha / bracket));
    if (std::abs(next - a) <= 1e-12 * a) return next;
    a = next;
  }
  return a;
}

}  // namespace indentsim::hertz
