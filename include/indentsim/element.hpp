#pragma once
// The bilinear rectangle (Q1) of the paper, section "Obtaining Local Stiffness Matrix".
//
// Vertices are numbered as in the paper, bottom-to-top then left-to-right:
//   1 = (x0, y0), 2 = (x0, y1), 3 = (x1, y0), 4 = (x1, y1),
// and the 8 element unknowns are ordered (u1, u2, u3, u4, v1, v2, v3, v4), u = horizontal,
// v = vertical displacement.  The paper's "barycentric coordinates" are the Q1 shape functions.
#include <array>

#include <Eigen/Core>

#include "indentsim/material.hpp"

namespace indentsim {

using ElementMatrix = Eigen::Matrix<double, 8, 8>;
using ElementVector = Eigen::Matrix<double, 8, 1>;
/// Strain-displacement matrix: (eps11, eps22, gamma12) = B * element unknowns.
using StrainDisplacement = Eigen::Matrix<double, 3, 8>;

struct Rectangle {
  double width = 0.0;   ///< h   (x extent)
  double height = 0.0;  ///< tau (y extent)
};

/// Local index of the u / v unknown of vertex q (1-based as in the paper).
constexpr int u_index(int vertex) { return vertex - 1; }
constexpr int v_index(int vertex) { return vertex + 3; }

/// The paper's closed-form local stiffness matrix (A11, A12 = A21^T, A22), with the
/// printed typos corrected: the last row of A22 (and the missing diagonal entry of
/// A11's last row) follow from the symmetry of the bilinear form.
ElementMatrix closed_form_stiffness(const Rectangle& rect, const LameConstants& lame);

/// 2x2 Gauss points of the reference square, as (xi, eta) in [0,1]^2.
struct GaussPoint {
  double xi, eta, weight;
};
const std::array<GaussPoint, 4>& gauss_points_2x2();

/// B at a point (xi, eta) of the rectangle.
StrainDisplacement strain_displacement(const Rectangle& rect, double xi, double eta);

/// Stiffness by 2x2 Gauss quadrature with one constitutive matrix per Gauss point
/// (exact for bilinear shape functions on a rectangle with constant D).
ElementMatrix gauss_stiffness(const Rectangle& rect, const std::array<PlaneStrainMatrix, 4>& d);
ElementMatrix gauss_stiffness(const Rectangle& rect, const PlaneStrainMatrix& d);

}  // namespace indentsim
