#pragma once
// The bilinear rectangle (Q1) of the paper, section "Obtaining Local Stiffness Matrix".
//
// Vertices are numbered as in the paper, bottom-to-top then left-to-right:
//   1 = (x0, y0), 2 = (x0, y1), 3 = (x1, y0), 4 = (x1, y1),
// and the 8 element unknowns are ordered (u1, u2, u3, u4, v1, v2, v3, v4), u = horizontal,
// v = vertical displacement.  The paper's "barycentric coordinates" are the Q1 shape functions.
#include <array>

#include <Eigen/Core>

#include "indentsim/materials/material.hpp"

namespace indentsim {

using ElementMatrix = Eigen::Matrix<double, 8, 8>;
using ElementVector = Eigen::Matrix<double, 8, 1>;
/// Strain-displacement matrix: (eps11, eps22, gamma12, eps33) = B * element unknowns.
using StrainDisplacement = Eigen::Matrix<double, 4, 8>;

struct Rectangle {
  double width = 0.0;   ///< h   (x extent)
  double height = 0.0;  ///< tau (y extent)
  double x0 = 0.0;      ///< abscissa of its left side (the radius, in axisymmetry)
};

/// The element formulation.  `q1`: the paper's element, fully integrated (exact stiffness in plane
/// strain).  `bbar`: mean dilatation (Hughes' B-bar) -- the dilatation at each Gauss point is
/// replaced by its element mean: the volumetric constraint that locks Q1 when nu -> 1/2 or under
/// isochoric plastic flow, relaxed to one constraint per element.  The B matrices of both are the
/// kinematics' (include/indentsim/geometry/kinematics.hpp).
enum class ElementKind { q1, bbar };

/// Local index of the u / v unknown of vertex q (1-based as in the paper).
constexpr int u_index(int vertex) { return vertex - 1; }
constexpr int v_index(int vertex) { return vertex + 3; }

/// The paper's closed-form local stiffness matrix (A11, A12 = A21^T, A22), with the
/// printed misprints corrected: the last row of A22 and the missing diagonal entry of A11's last
/// row follow from the rectangle's symmetry (the four vertices are equivalent, so every diagonal
/// entry of a block is the same), docs/MODEL.md §6.2.
ElementMatrix closed_form_stiffness(const Rectangle& rect, const LameConstants& lame);

/// 2x2 Gauss points of the reference square, as (xi, eta) in [0,1]^2.
struct GaussPoint {
  double xi, eta, weight;
};
const std::array<GaussPoint, 4>& gauss_points_2x2();

}  // namespace indentsim
