#pragma once
// The paper's finite-difference view of equilibrium (MODEL.md, "Finite-difference view").
//
// At a node, the rows of the local stiffness matrices of the elements below it (rows 6 and 8,
// the v rows of their top vertices 2 and 4) give the normal layer force sigma_N^-, those of the
// elements above (rows 5 and 7, vertices 1 and 3) give sigma_N^+.  Summed along a horizontal mesh
// line y_j, both equal the force carried across that line, which must be the punch force P on
// every line: the base reaction below, the contact force on top.
#include <vector>

#include "indentsim/assembly.hpp"
#include "indentsim/mesh.hpp"

namespace indentsim {

struct LayerForce {
  double y = 0.0;
  /// P^-(y_j) = -2 sum (K_e u_e)[rows 6, 8] over the elements below the line (NaN on the base).
  double below = 0.0;
  /// P^+(y_j) = +2 sum (K_e u_e)[rows 5, 7] over the elements above the line (NaN on the top).
  double above = 0.0;
};

/// Layer forces for every horizontal mesh line, both halves of the model, per unit thickness.
std::vector<LayerForce> layer_forces(const Mesh& mesh, const ElementMatrixSource& matrices, const double* u);

}  // namespace indentsim
