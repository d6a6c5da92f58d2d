#include "indentsim/layer_forces.hpp"

#include <limits>

namespace indentsim {

std::vector<LayerForce> layer_forces(const Mesh& mesh, const ElementMatrixSource& matrices, const double* u) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<LayerForce> layers(static_cast<std::size_t>(mesh.nodes_y()));
  for (int j = 0; j < mesh.nodes_y(); ++j) {
    layers[j].y = mesh.y(j);
    layers[j].below = j > 0 ? 0.0 : nan;
    layers[j].above = j < mesh.top_row() ? 0.0 : nan;
  }
  for (int ei = 0; ei < mesh.elements_x(); ++ei)
    for (int ej = 0; ej < mesh.elements_y(); ++ej) {
      const ElementVector fe = matrices.element_matrix(ei, ej) * gather(mesh, ei, ej, u);
      // This element lies above line ej (its vertices 1, 3) and below line ej + 1 (vertices 2, 4).
      layers[ej].above += 2.0 * (fe[v_index(1)] + fe[v_index(3)]);
      layers[ej + 1].below -= 2.0 * (fe[v_index(2)] + fe[v_index(4)]);
    }
  return layers;
}

}  // namespace indentsim
