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

/// The element formulation.  `q1`: the paper's element, fully integrated (exact stiffness).
/// `bbar`: mean dilatation (Hughes' B-bar) -- the in-plane dilatation eps11 + eps22 at each Gauss
/// point is replaced by its element mean, eps_bar = eps + (theta_mean - theta)/2 (1, 1, 0); with
/// eps33 = 0 this is the volumetric constraint that locks Q1 when nu -> 1/2 or under isochoric
/// plastic flow, relaxed to one constraint per element.
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

/// B at a point (xi, eta) of the rectangle (B-bar for ElementKind::bbar).
StrainDisplacement strain_displacement(const Rectangle& rect, double xi, double eta,
                                       ElementKind kind = ElementKind::q1);

/// Stiffness by 2x2 Gauss quadrature with one constitutive matrix per Gauss point
/// (exact for bilinear shape functions on a rectangle with constant D).
ElementMatrix gauss_stiffness(const Rectangle& rect, const std::array<PlaneStrainMatrix, 4>& d,
                              ElementKind kind = ElementKind::q1);
ElementMatrix gauss_stiffness(const Rectangle& rect, const PlaneStrainMatrix& d, ElementKind kind = ElementKind::q1);

}  // namespace indentsim
