#pragma once
// Global assembly straight into a compressed-sparse-column pattern that is fixed for the
// life of a mesh: the pattern is built once, every element knows where its 64 entries go,
// and a Newton iteration only rewrites values (no allocation, no search).
#include <algorithm>
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "indentsim/geometry/element.hpp"
#include "indentsim/materials/material.hpp"
#include "indentsim/geometry/mesh.hpp"

namespace indentsim {

class StiffnessPattern {
public:
  explicit StiffnessPattern(const Mesh& mesh);
  /// A symmetric pattern given column by column (sorted rows, the diagonal present); it has no
  /// element positions (element_positions is not available).  For a condensed system, whose
  /// interface unknowns (`dense_block`, increasing) are coupled all to all.
  StiffnessPattern(std::vector<std::int64_t> column_start, std::vector<std::int64_t> row_index,
                   std::vector<std::int64_t> dense_block = {});

  std::int64_t size() const { return size_; }
  std::int64_t nonzeros() const { return static_cast<std::int64_t>(row_index_.size()); }
  const std::vector<std::int64_t>& column_start() const { return column_start_; }
  const std::vector<std::int64_t>& row_index() const { return row_index_; }
  /// Unknowns coupled all to all (a condensed near field's interface, docs/DESIGN.md §7; empty
  /// for a mesh's own pattern).  A fill-reducing order eliminates them last, as one block.
  const std::vector<std::int64_t>& dense_block() const { return dense_block_; }
  /// An unknown every fill-reducing order must eliminate last, or -1: force control's depth, whose
  /// pivot the reference factorization cannot choose (force_controlled_equations.hpp).
  std::int64_t eliminated_last() const { return eliminated_last_; }
  void eliminate_last(std::int64_t unknown) { eliminated_last_ = unknown; }

  /// Position in the value array of local entry (a, b) of an element, or -1 when either
  /// unknown is fixed by a Dirichlet condition.  64 entries per element, row-major.
  const std::int32_t* element_positions(int element) const { return &element_position_[64 * static_cast<std::size_t>(element)]; }
  std::int64_t diagonal_position(int equation) const { return diagonal_[equation]; }
  /// Positions of every stored entry of row `equation` (the pattern is symmetric).
  std::vector<std::int64_t> row_positions(int equation) const;

  /// values[p] += ke(a, b) at the element's positions.
  void scatter(int element, const ElementMatrix& ke, std::vector<double>& values) const;
  /// y = A x for a matrix with this pattern.
  void multiply(const std::vector<double>& values, const double* x, double* y) const;

private:
  std::int64_t size_ = 0;
  std::vector<std::int64_t> column_start_, row_index_, diagonal_, dense_block_;
  std::int64_t eliminated_last_ = -1;
  std::vector<std::int32_t> element_position_;
};

/// Where one element sits in a Newton system (the whole mesh's free equations, or a condensed
/// near field): its 8 unknowns in the system's numbering (-1 where a Dirichlet condition fixes
/// one) and the positions of its 64 entries in the system's pattern (-1 likewise).  Element
/// loops over either system go through these, so there is one loop for both.
struct ElementSlot {
  int ei = 0, ej = 0;
  std::array<std::int32_t, 8> unknowns{};
  std::array<std::int64_t, 64> positions{};
};
/// The slots of every element of the mesh in its free-equation system.
std::vector<ElementSlot> whole_mesh_slots(const Mesh& mesh, const StiffnessPattern& pattern);

/// Gathers an element's 8 unknowns (paper order) from the vector of free equations.
ElementVector gather(const Mesh& mesh, int ei, int ej, const double* u);

/// The material state at one Gauss point of the committed solution.
struct GaussPointState {
  VoigtVector stress = VoigtVector::Zero();  ///< (sigma11, sigma22, sigma12, sigma33) [Pa]: 33 out of plane or hoop
  double strain_intensity = 0.0;             ///< e_u
  double omega = 0.0;                        ///< Ilyushin's omega (0 when elastic)
  bool plastic = false;
};

/// What a Newton iteration needs of the bulk: internal forces f(u) and their tangent df/du in a
/// fixed pattern (of the whole mesh, or of a condensed near field).
class BulkOperator {
public:
  virtual ~BulkOperator() = default;
  /// f = f_int(u) over the unknowns of the pattern.
  virtual void internal_force(const double* u, double* f) = 0;
  /// values = d f_int / du at u, in the fixed pattern.
  virtual void tangent(const double* u, double* values) = 0;
};

/// The bulk part of the discrete equations on the whole mesh (free equations), and the committed
/// state for output.
class BulkModel : public BulkOperator {
public:
  /// Accepts u as the converged state of an increment (history, secant matrices, statistics).
  virtual void commit(const double* u) = 0;
  /// Integration points beyond the elastic limit at the committed state.
  virtual long plastic_points() const = 0;
  /// The largest strain intensity e_u over all integration points at the committed state.
  virtual double max_strain_intensity() const = 0;
  /// States at the four Gauss points of element (ei, ej), committed solution (paper vertex order).
  virtual std::array<GaussPointState, 4> gauss_point_states(int ei, int ej) const = 0;
  /// Internal force vector of element (ei, ej) at the committed state (paper order).  For the
  /// elastic and secant laws it is K_e u_e with the current (secant) local stiffness matrix: the
  /// rows the paper's layer forces are made of.
  virtual ElementVector element_force(int ei, int ej) const = 0;
  /// The carried material history (everything commit() accumulated), flattened, and its
  /// restoration; after restore(history, u) the model is as it was after commit(u).
  virtual std::vector<double> history() const = 0;
  virtual void restore(const std::vector<double>& history, const double* u) = 0;
  /// What is wrong with a restored history (a checkpoint's), or nothing: every point's history
  /// one its law can carry at the committed strain, and the statistics what the points give.
  /// restore() itself trusts its input (a run also restores its own last reported state).
  virtual std::optional<std::string> history_violation() const { return std::nullopt; }
  /// The largest displacement-gradient component |du_i/dX_j| (and u_r/R) reached so far in the
  /// elements a condensed far field models in small strain, where the bulk's own kinematics are
  /// finite (what that linearization neglects), beside the limit the near field grows at; nothing
  /// where the bulk is small-strain throughout.
  struct FarFieldCheck {
    double largest_gradient;
    double limit;
  };
  virtual std::optional<FarFieldCheck> far_field_check() const { return std::nullopt; }
};

/// Linear elasticity on the mesh: one element matrix per class of equal rectangles and material
/// region (the paper's closed form in plane strain, Gauss quadrature else), and the assembled
/// stiffness K.
class ElasticStiffness : public BulkModel {
public:
  /// `by_region`: the elastic constants of each of the mesh's material regions (Mesh::region).
  ElasticStiffness(const Mesh& mesh, std::vector<ElasticMaterial> by_region, const StiffnessPattern& pattern);
  ElasticStiffness(const Mesh& mesh, const ElasticMaterial& material, const StiffnessPattern& pattern)
      : ElasticStiffness(mesh, std::vector<ElasticMaterial>{material}, pattern) {}

  ElementVector element_force(int ei, int ej) const override;
  std::vector<double> history() const override { return {}; }
  void restore(const std::vector<double>& history, const double* u) override;
  void internal_force(const double* u, double* f) override { pattern_.multiply(values_, u, f); }
  void tangent(const double*, double* values) override { std::copy(values_.begin(), values_.end(), values); }
  void commit(const double* u) override;
  long plastic_points() const override { return 0; }
  double max_strain_intensity() const override { return max_strain_intensity_; }
  std::array<GaussPointState, 4> gauss_point_states(int ei, int ej) const override;
  const ElementMatrix& cached_matrix(int ei, int ej) const {
    return by_class_[static_cast<std::size_t>(mesh_.column_class(ei)) * row_region_.size() + row_class_[ej]];
  }
  /// The elastic constants of element row ej's region.
  const ElasticMaterial& material(int ej) const { return by_region_[static_cast<std::size_t>(mesh_.region(ej))]; }
  /// B and the measure at the 2x2 Gauss points of element (ei, ej), tabulated per class like its
  /// matrix: every element pass (strains, inelastic forces and tangents) reads them here
  /// (recomputing B for every element at every increment was a sixth of a small elastic run).
  const ElementQuadrature& quadrature(int ei, int ej) const { return quadrature_by_class_[class_of(ei, ej)]; }
  const std::vector<double>& values() const { return values_; }
  const Mesh& mesh() const { return mesh_; }
  const StiffnessPattern& pattern() const { return pattern_; }
  /// f = K u
  void multiply(const double* u, double* f) const { pattern_.multiply(values_, u, f); }

private:
  std::size_t class_of(int ei, int ej) const {
    return static_cast<std::size_t>(mesh_.column_class(ei)) * mesh_.height_classes() + mesh_.height_class(ej);
  }
  /// Strains at the Gauss points of element (ei, ej) from the global u.
  std::array<VoigtVector, 4> strains(int ei, int ej, const double* u) const;

  const Mesh& mesh_;
  const StiffnessPattern& pattern_;
  /// The rows' classes for the matrices: one per (height class, region) pair that occurs, so that
  /// a region adds matrices only for the rows it has (row_class_ per element row; each class's
  /// height class and region).
  std::vector<std::size_t> row_class_;
  std::vector<int> row_height_class_, row_region_;
  /// Element matrices at column class * row classes + row class.
  std::vector<ElementMatrix, Eigen::aligned_allocator<ElementMatrix>> by_class_;
  std::vector<ElementQuadrature, Eigen::aligned_allocator<ElementQuadrature>> quadrature_by_class_;
  std::vector<double> values_;
  std::vector<ElasticMaterial> by_region_;
  std::vector<double> committed_u_;
  double max_strain_intensity_ = 0.0;
};

}  // namespace indentsim
