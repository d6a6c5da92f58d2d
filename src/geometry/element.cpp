#include "indentsim/geometry/element.hpp"

#include <cmath>

namespace indentsim {

ElementMatrix closed_form_stiffness(const Rectangle& rect, const LameConstants& lame) {
  const double h = rect.width, tau = rect.height;
  const double lam = lame.lambda, mu = lame.mu, l2m = lam + 2.0 * mu;

  // A11: coupling of horizontal unknowns, (lambda + 2 mu) d/dx d/dx + mu d/dy d/dy.
  const double a_diag = mu * h / (3 * tau) + l2m * tau / (3 * h);   // same vertex
  const double a_vert = -mu * h / (3 * tau) + l2m * tau / (6 * h);  // 1-2, 3-4: same x
  const double a_horz = mu * h / (6 * tau) - l2m * tau / (3 * h);   // 1-3, 2-4: same y
  const double a_diag2 = -mu * h / (6 * tau) - l2m * tau / (6 * h); // 1-4, 2-3: opposite
  // A22: coupling of vertical unknowns, (lambda + 2 mu) d/dy d/dy + mu d/dx d/dx.
  const double b_diag = mu * tau / (3 * h) + l2m * h / (3 * tau);
  const double b_vert = mu * tau / (6 * h) - l2m * h / (3 * tau);
  const double b_horz = -mu * tau / (3 * h) + l2m * h / (6 * tau);
  const double b_diag2 = -mu * tau / (6 * h) - l2m * h / (6 * tau);
  // A12: lambda du/dx dv/dy + mu du/dy dv/dx, independent of the element's aspect.
  const double p = (lam + mu) / 4, m = (mu - lam) / 4;

  Eigen::Matrix4d a11, a22, a12;
  a11 << a_diag, a_vert, a_horz, a_diag2,  //
      a_vert, a_diag, a_diag2, a_horz,     //
      a_horz, a_diag2, a_diag, a_vert,     //
      a_diag2, a_horz, a_vert, a_diag;
  a22 << b_diag, b_vert, b_horz, b_diag2,  //
      b_vert, b_diag, b_diag2, b_horz,     //
      b_horz, b_diag2, b_diag, b_vert,     //
      b_diag2, b_horz, b_vert, b_diag;
  a12 << p, m, -m, -p,  //
      -m, -p, p, m,     //
      m, p, -p, -m,     //
      -p, -m, m, p;

  ElementMatrix k;
  k.topLeftCorner<4, 4>() = a11;
  k.topRightCorner<4, 4>() = a12;
  k.bottomLeftCorner<4, 4>() = a12.transpose();
  k.bottomRightCorner<4, 4>() = a22;
  return k;
}

const std::array<GaussPoint, 4>& gauss_points_2x2() {
  static const std::array<GaussPoint, 4> points = [] {
    const double g = 0.5 / std::sqrt(3.0);
    const double lo = 0.5 - g, hi = 0.5 + g;
    // Ordered like the vertices: bottom-to-top, then left-to-right.
    return std::array<GaussPoint, 4>{GaussPoint{lo, lo, 0.25}, GaussPoint{lo, hi, 0.25},
                                     GaussPoint{hi, lo, 0.25}, GaussPoint{hi, hi, 0.25}};
  }();
  return points;
}

}  // namespace indentsim
