#pragma once
// The paper's finite-difference view of equilibrium (docs/MODEL.md §7;
// Yazici 2023, section "Obtaining the Finite Difference Equation at Any Point").
//
// The paper calls a horizontal line of nodes a layer and these its layer forces; here they are
// line forces, as a layer is a coating's (docs/MODEL.md §14).  The output file keeps the paper's
// name, layers.csv.
//
// At node (i, j), multiplying rows of the current (secant) local stiffness matrices by the
// element unknowns gives the paper's layer quantities:
//   sigma_N^- : rows 6 and 8 (v of vertices 2, 4) of the elements below the node,
//   sigma_N^+ : rows 5 and 7 (v of vertices 1, 3) of the elements above,
//   sigma_T^- : rows 2 and 4 (u of vertices 2, 4) of the elements below,
//   sigma_T^+ : rows 1 and 3 (u of vertices 1, 3) of the elements above.
// They are nodal forces: per unit thickness [N/m] in plane strain, whole-ring forces [N] in
// axisymmetry.  Discrete equilibrium at a free interior node
// is sigma_N^- + sigma_N^+ = 0 and sigma_T^- + sigma_T^+ = 0 (the finite-difference equations).
// Divided by the node's tributary measure w_i (a width, or a ring area) they approximate the stresses on the mesh line:
// sigma_N^- / w ~ sigma22 and sigma_T^- / w ~ sigma12 just below the line (on the top surface,
// -sigma_N^- / w is the contact pressure).  Summed along a line y_j, -f sum sigma_N^- (the force
// carried across the line; f = 2 for both halves of plane strain, 1 for the rings of axisymmetry,
// where the sum is the discrete 2 pi int sigma_zz r dr) equals the punch force P on every line:
// P^-(y_j) and P^+(y_j) = f sum sigma_N^+ in the paper.
#include <vector>

#include "indentsim/solvers/assembly.hpp"
#include "indentsim/geometry/mesh.hpp"

namespace indentsim {

/// The paper's sigma_N^-, sigma_N^+, sigma_T^-, sigma_T^+ at one node [N/m, or N].
struct NodalLineForces {
  double normal_below = 0.0, normal_above = 0.0;
  double tangential_below = 0.0, tangential_above = 0.0;
};

/// Layer forces at every node of the committed state, indexed by Mesh::node(i, j).
std::vector<NodalLineForces> nodal_line_forces(const Mesh& mesh, const BulkModel& bulk);

/// Tributary measure of node i of a horizontal line (Kinematics::tributary_measure): half of
/// each adjacent element in plane strain [m], the consistent ring area in axisymmetry [m^2].
double tributary_measure(const Mesh& mesh, int i);

struct LineForce {
  double y = 0.0;
  /// P^-(y_j) = -f sum_i sigma_N^-(i, j) (NaN on the base, which has no elements below).
  double below = 0.0;
  /// P^+(y_j) = +f sum_i sigma_N^+(i, j) (NaN on the top, which has no elements above).
  double above = 0.0;
};

/// Layer forces for every horizontal mesh line, of the whole body (in the unit of P).
std::vector<LineForce> line_forces(const Mesh& mesh, const std::vector<NodalLineForces>& nodal);
std::vector<LineForce> line_forces(const Mesh& mesh, const BulkModel& bulk);

}  // namespace indentsim
