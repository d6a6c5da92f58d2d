#include "indentsim/solvers/line_forces.hpp"

#include <limits>

namespace indentsim {

std::vector<NodalLineForces> nodal_line_forces(const Mesh& mesh, const BulkModel& bulk) {
  std::vector<NodalLineForces> nodal(static_cast<std::size_t>(mesh.nodes()));
  for (int ei = 0; ei < mesh.elements_x(); ++ei)
    for (int ej = 0; ej < mesh.elements_y(); ++ej) {
      const ElementVector fe = bulk.element_force(ei, ej);
      const auto nodes = mesh.element_nodes(ei, ej);
      // Vertices 2 and 4 are on the line above the element: the element is "below" them.
      for (int vertex : {2, 4}) {
        nodal[nodes[vertex - 1]].normal_below += fe[v_index(vertex)];
        nodal[nodes[vertex - 1]].tangential_below += fe[u_index(vertex)];
      }
      // Vertices 1 and 3 are on the line below it: the element is "above" them.
      for (int vertex : {1, 3}) {
        nodal[nodes[vertex - 1]].normal_above += fe[v_index(vertex)];
        nodal[nodes[vertex - 1]].tangential_above += fe[u_index(vertex)];
      }
    }
  return nodal;
}

double tributary_measure(const Mesh& mesh, int i) {
  const double left = i > 0 ? mesh.x(i - 1) : mesh.x(i);
  const double right = i + 1 < mesh.nodes_x() ? mesh.x(i + 1) : mesh.x(i);
  return mesh.kinematics().tributary_measure(left, mesh.x(i), right);
}

std::vector<LineForce> line_forces(const Mesh& mesh, const std::vector<NodalLineForces>& nodal) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<LineForce> layers(static_cast<std::size_t>(mesh.nodes_y()));
  const double whole_body = mesh.kinematics().symmetry_factor();
  for (int j = 0; j < mesh.nodes_y(); ++j) {
    double below = 0.0, above = 0.0;
    for (int i = 0; i < mesh.nodes_x(); ++i) {
      below += nodal[mesh.node(i, j)].normal_below;
      above += nodal[mesh.node(i, j)].normal_above;
    }
    layers[j].y = mesh.y(j);
    layers[j].below = j > 0 ? -whole_body * below : nan;
    layers[j].above = j < mesh.top_row() ? whole_body * above : nan;
  }
  return layers;
}

std::vector<LineForce> line_forces(const Mesh& mesh, const BulkModel& bulk) {
  return line_forces(mesh, nodal_line_forces(mesh, bulk));
}

}  // namespace indentsim
