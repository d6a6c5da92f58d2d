#pragma once
// Field output of a run: what users look at besides the P-alpha curve.
//  - layers.csv   the paper's layer forces P^-(y_j), P^+(y_j) on every horizontal mesh line;
//  - profiles.csv sigma_N, sigma_T from the layer forces along the top surface and chosen depths,
//                 next to the Gauss-point stresses extrapolated and averaged to the nodes;
//  - fields/step_NNNNNN.vtu + fields.pvd  ParaView files (a time series over the increments).
// Every file is written to a temporary name and renamed, so a reader never sees half a file.
#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "indentsim/solvers/assembly.hpp"
#include "indentsim/solvers/contact.hpp"
#include "indentsim/solvers/line_forces.hpp"
#include "indentsim/geometry/mesh.hpp"

namespace indentsim {

/// Gauss-point stresses extrapolated to each element's vertices and averaged over the elements
/// that share a node, within one material region (an interface node takes the layer above's):
/// (sigma11, sigma22, sigma12, sigma33, e_u) per node.
struct NodalStresses {
  std::vector<std::array<double, 5>> values;  ///< indexed by Mesh::node(i, j)
};
NodalStresses average_to_nodes(const Mesh& mesh, const BulkModel& bulk);

/// The displacement (u, v) of node `node` from the equation-numbered solution `u` (a fixed
/// component is 0).
std::array<double, 2> nodal_displacement(const Mesh& mesh, const double* u, int node);

/// Which state a table or a VTU shows: the increment and its depth (columns `step`, `alpha` of
/// layers.csv and profiles.csv; field data of a VTU).
struct FieldFrame {
  int step = 0;
  double alpha = 0.0;
};

/// The layer forces of one state; `header` starts the table with its column names.
std::string layers_csv(const std::vector<LineForce>& layers, double punch_force, const FieldFrame& frame, bool header);

/// Mesh lines of the profiles: the top surface and, for each depth, the nearest mesh line.
std::vector<int> profile_lines(const Mesh& mesh, const std::vector<double>& depths);
std::string profiles_csv(const Mesh& mesh, const std::vector<int>& lines, const std::vector<NodalLineForces>& layer,
                         const NodalStresses& nodal, const FieldFrame& frame, bool header);

/// A VTK XML unstructured grid of the current state.
std::string vtu_document(const FieldFrame& frame, const Mesh& mesh, const double* u, const BulkModel& bulk,
                         const NodalStresses& nodal, const ContactDiscretization& contact, const ContactResult& contact_state);

/// Keeps DIR/fields.pvd listing every VTU written so far.  The time value of each is the
/// increment number, which grows strictly along a run: the depth alpha does not (a load history
/// returns to alpha = 0), so it is field data of each VTU instead.
class FieldSeries {
public:
  explicit FieldSeries(std::filesystem::path dir);
  void add(int step, const std::string& vtu_text);
  /// Lists a VTU already on disk (a resumed run keeps the fields written before).
  void add_existing(int step, const std::string& relative_file);
  const std::filesystem::path& pvd_path() const { return pvd_; }

private:
  void write_pvd();
  std::filesystem::path dir_, pvd_;
  std::vector<std::pair<int, std::string>> entries_;
};

}  // namespace indentsim
