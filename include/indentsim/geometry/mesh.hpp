#pragma once
// Tensor-product mesh of rectangles on the half model (0, lx) x (-ly, 0), graded: uniform
// near the punch (the "fine zone"), growing geometrically towards the far edges.
//
// Nodes are numbered bottom-to-top, then left-to-right, as the paper numbers element
// vertices: node(i, j) = i * ny + j, with x_i increasing in i and y_j increasing in j
// (j = ny - 1 is the loaded surface y = 0).  Each node has two unknowns u (x) and v (y).
// Dirichlet conditions of the model: u = v = 0 on the base y = -ly, u = 0 on the axis x = 0
// (the symmetry plane of plane strain, the axis of revolution of axisymmetry).
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "indentsim/geometry/element.hpp"
#include "indentsim/geometry/kinematics.hpp"
#include "indentsim/input/load_case.hpp"

namespace indentsim {

/// How a mesh is laid out, derived from a load case before any array is allocated.
struct MeshPlan {
  double contact_half_width_estimate = 0.0;  ///< a* [m]
  double fine_spacing = 0.0;                 ///< h = a* / contact_nodes [m]
  double fine_width = 0.0;                   ///< x extent of the uniform zone [m]
  double fine_depth = 0.0;                   ///< y extent of the uniform zone [m]
  double growth = 1.0;                       ///< largest ratio of neighbouring element sizes
  std::int64_t nodes_x = 0, nodes_y = 0;

  std::int64_t nodes() const { return nodes_x * nodes_y; }
  std::int64_t unknowns() const { return 2 * nodes(); }
  /// A conservative estimate of the memory a run of this mesh needs (matrix, factors, state).
  double estimated_bytes() const;
};

/// Growth ratio used when the load case does not set one: tightens as contact_nodes grows, so
/// that refining the contact zone refines the far field in proportion (docs/MODEL.md §6: P depends on
/// the stiffness of the whole block).  Element size at distance d from the fine zone is about
/// (growth - 1) d, so growth - 1 ~ 1/contact_nodes halves every element when contact_nodes doubles.
double default_growth(int contact_nodes);

/// Plans the mesh for a load case; throws InputError if it cannot be built (e.g. too large).
/// `measured_half_width`, when given, replaces the Hertz estimate of the final contact half-width
/// (a pilot run measured it); an explicit mesh.contact_half_width still wins.
MeshPlan plan_mesh(const LoadCase& load_case, std::optional<double> measured_half_width = std::nullopt);

/// Node coordinates along one axis from 0 to `length`: uniform spacing `spacing` up to
/// `fine_length`, then geometric growth of ratio <= `growth`, closing exactly on `length`.
std::vector<double> graded_axis(double length, double fine_length, double spacing, double growth);
/// Number of nodes graded_axis would return, computed without allocating.
std::int64_t graded_axis_count(double length, double fine_length, double spacing, double growth);

/// The fewest element rows across a layer (docs/MODEL.md §14.3).
inline constexpr int min_rows_per_layer = 4;
/// An axis of depths (0 at the surface, ascending) with a node on every interface (ascending,
/// inside the axis; docs/MODEL.md §14.3): an interface on a node keeps the axis as it is, else
/// the nearest free node moves onto it (or, when that node is taken, the interface is inserted);
/// a layer with fewer than `min_rows` rows is divided evenly into `min_rows`; then any element
/// more than `ratio_limit` times the size of a neighbour is halved, until none is (the 2:1 rule),
/// so that a film thinner than the fine spacing refines the rows near it.
std::vector<double> lay_interfaces(std::vector<double> depths, const std::vector<double>& interfaces, int min_rows,
                                   double ratio_limit);

class Mesh {
public:
  /// x ascending from 0, y ascending from -ly to 0.
  Mesh(std::vector<double> x, std::vector<double> y);
  static Mesh from_plan(const LoadCase& load_case, const MeshPlan& plan);

  int nodes_x() const { return static_cast<int>(x_.size()); }
  int nodes_y() const { return static_cast<int>(y_.size()); }
  int nodes() const { return nodes_x() * nodes_y(); }
  int elements_x() const { return nodes_x() - 1; }
  int elements_y() const { return nodes_y() - 1; }
  int elements() const { return elements_x() * elements_y(); }
  int top_row() const { return nodes_y() - 1; }

  double x(int i) const { return x_[i]; }
  double y(int j) const { return y_[j]; }
  const std::vector<double>& x() const { return x_; }
  const std::vector<double>& y() const { return y_; }

  int node(int i, int j) const { return i * nodes_y() + j; }
  static int dof_u(int node) { return 2 * node; }
  static int dof_v(int node) { return 2 * node + 1; }

  int element(int ei, int ej) const { return ei * elements_y() + ej; }
  Rectangle rectangle(int ei, int ej) const { return {x_[ei + 1] - x_[ei], y_[ej + 1] - y_[ej], x_[ei]}; }
  /// Nodes of element (ei, ej) in the paper's vertex order.
  std::array<int, 4> element_nodes(int ei, int ej) const {
    return {node(ei, ej), node(ei, ej + 1), node(ei + 1, ej), node(ei + 1, ej + 1)};
  }
  /// Global unknowns of element (ei, ej) in the paper's order (u1..u4, v1..v4).
  std::array<int, 8> element_dofs(int ei, int ej) const;

  /// Equation number of a global unknown, or -1 where a Dirichlet condition fixes it.
  int equation(int dof) const { return equation_[dof]; }
  int equations() const { return equations_; }

  /// The element formulation used on this mesh.
  ElementKind element_kind() const { return element_kind_; }
  void set_element_kind(ElementKind kind) { element_kind_ = kind; }
  /// The scene's kinematics (plane strain unless set): B matrices, Gauss-point measures, units.
  const Kinematics& kinematics() const { return *kinematics_; }
  void set_scene(SceneKind kind) { kinematics_ = make_kinematics(kind); }

  /// Elements whose elastic matrices are equal: the same width and height class, and in a
  /// position-dependent kinematics (axisymmetry) the same column.  `column_class` numbers the
  /// columns so that elements (ei, ej) and (ei', ej') share a matrix when their column classes
  /// and height classes agree.
  int column_class(int ei) const { return kinematics_->position_dependent() ? ei : width_class_[ei]; }
  int column_classes() const { return kinematics_->position_dependent() ? elements_x() : width_classes_; }
  /// One rectangle per (column class, height class), at index c * height_classes() + h: what every
  /// element of the pair shares (its matrices and quadratures are tabulated on it).
  std::vector<Rectangle> class_rectangles() const;

  /// The material region of element row ej (docs/MODEL.md §14.1): 0 the substrate, k layer k
  /// from the surface.  Layers are horizontal bands between mesh lines, so a row has one region.
  int region(int ej) const { return row_region_.empty() ? 0 : row_region_[ej]; }
  int regions() const { return regions_; }
  /// Sets the region of every element row (one entry per row, each in [0, regions)).
  void set_row_regions(std::vector<int> row_region, int regions);

  /// Classes of equal element widths / heights: elements of one class pair share a matrix.
  int width_class(int ei) const { return width_class_[ei]; }
  int height_class(int ej) const { return height_class_[ej]; }
  int width_classes() const { return width_classes_; }
  int height_classes() const { return height_classes_; }

private:
  std::vector<double> x_, y_;
  std::vector<int> equation_;
  int equations_ = 0;
  std::vector<int> width_class_, height_class_;
  int width_classes_ = 0, height_classes_ = 0;
  std::vector<int> row_region_;
  int regions_ = 1;
  ElementKind element_kind_ = ElementKind::q1;
  std::shared_ptr<const Kinematics> kinematics_ = make_kinematics(SceneKind::plane_strain);
};

}  // namespace indentsim
