#pragma once
// Static condensation of the far field (docs/DESIGN.md, section 7).
//
// Away from the punch the block stays linear elastic for the whole run: no node there touches the
// punch and no Gauss point leaves the elastic range.  Split the free unknowns into the near field
// R -- every unknown of the elements that may yield, and the vertical unknown of every surface
// node that may touch -- and the far field F.  No load acts on F, so its equations
//     K_FR u_R + K_FF u_F = 0   give   u_F = -K_FF^{-1} K_FR u_R,
// and the near-field equations become, exactly (not an approximation),
//     K_red u_R + (nonlinear corrections of the near elements) = contact reactions,
//     K_red = K_RR - K_RF K_FF^{-1} K_FR      (the Schur complement of K_FF).
// K_FF is symmetric positive definite (the far field holds the clamped base); it is factored once
// per mesh with CHOLMOD's supernodal Cholesky and K_red is formed once, column block by column
// block.  K_red is the near field's own sparse matrix plus a dense block on the interface B (the
// near unknowns coupled to far ones), so every Newton iteration factors a system of |R| unknowns
// instead of the whole mesh.  After each increment one solve with the kept factor recovers u_F,
// for output and to check the assumption (docs/DESIGN.md, section 7: the near field grows and the
// increment is repeated when a far element would yield or a far surface node would penetrate).
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "indentsim/solvers/assembly.hpp"
#include "indentsim/solvers/contact.hpp"
#include "indentsim/solvers/nonlinear_bulk.hpp"

namespace indentsim {

/// Which part of the mesh the Newton iterations solve for.  Element columns are counted from the
/// axis and element rows from the loaded surface, so the near elements are the block
/// [0, x_{elements_x}] x [y_{top - elements_y}, 0] under the punch.
struct NearField {
  bool condensed = false;  ///< false: the whole mesh is solved (nothing is condensed)
  int contact_nodes = 0;   ///< surface nodes from the axis that may touch the punch
  int elements_x = 0;      ///< element columns that may yield (0 for an elastic scene)
  int elements_y = 0;      ///< element rows that may yield
  bool operator==(const NearField&) const = default;
};

/// How far a plastic zone reaches from the axis and below the surface [m].
struct PlasticExtent {
  double width = 0.0, depth = 0.0;
};

/// How the plastic zone grows with the depth of indentation: the extents a pilot run measured at
/// its increments (depths increasing).  Between them the extent is interpolated linearly; below
/// the first it scales as sqrt(depth) -- the contact width of a sphere or cylinder, generous for
/// a cone, whose zone grows linearly -- and beyond the last it is the last.
struct PlasticZoneGrowth {
  std::vector<double> depths;
  std::vector<PlasticExtent> extents;
  PlasticExtent at(double depth) const;
  bool empty() const { return depths.empty(); }
};

/// The equations a near field holds, as flags over the mesh's equations: every unknown of its
/// element columns and rows (from the axis and the surface), and the vertical unknowns of its
/// first contact_nodes contact candidates (`candidate_equations`, from the axis), with their
/// horizontal unknowns where the contact writes rows for them (friction: `tangential_equations`,
/// per candidate, -1 for none; empty for frictionless contact).
std::vector<char> near_field_equations(const Mesh& mesh, const std::vector<int>& candidate_equations,
                                       const NearField& near, const std::vector<int>& tangential_equations = {});

class FarFieldCondensation {
public:
  /// Factors K_FF and forms K_red.  `contact` holds the candidates of the whole mesh; those among
  /// the first near.contact_nodes surface nodes become the condensed system's candidates.
  /// Throws std::runtime_error if K_FF is not positive definite (a far field not held by the base).
  FarFieldCondensation(const ElasticStiffness& stiffness, const ContactDiscretization& contact, const NearField& near);
  ~FarFieldCondensation();
  FarFieldCondensation(const FarFieldCondensation&) = delete;
  FarFieldCondensation& operator=(const FarFieldCondensation&) = delete;

  /// |R|, the unknowns each Newton iteration solves for.
  std::int64_t size() const { return pattern_->size(); }
  /// |B|, the near unknowns coupled to the far field (the dense block of K_red).
  std::int64_t interface_size() const { return static_cast<std::int64_t>(interface_.size()); }
  const StiffnessPattern& pattern() const { return *pattern_; }
  /// K_red in pattern().
  const std::vector<double>& values() const { return values_; }
  /// The contact candidates in the condensed numbering, scaled by K_red's diagonal.
  const ContactDiscretization& contact() const { return *contact_; }
  ContactDiscretization& contact() { return *contact_; }
  const std::vector<ElementSlot>& elements() const { return elements_; }
  /// Free equation of each condensed unknown.
  const std::vector<int>& near_equations() const { return near_equation_; }

  /// u_R from the vector of all free equations.
  void restrict_to_near(const std::vector<double>& u, std::vector<double>& u_near) const;
  /// All free equations from u_R: the far field from u_F = -K_FF^{-1} K_FR u_R.
  void expand(const std::vector<double>& u_near, std::vector<double>& u) const;

private:
  struct FarFactor;  // CHOLMOD's common block and the factor of K_FF
  const StiffnessPattern& full_pattern_;
  const std::vector<double>& full_values_;
  std::vector<int> near_equation_;   // condensed unknown -> free equation
  std::vector<int> far_equation_;    // far unknown -> free equation
  std::vector<std::int32_t> near_of_, far_of_;  // free equation -> condensed / far index, or -1
  std::vector<int> interface_;       // condensed unknowns coupled to the far field
  std::unique_ptr<StiffnessPattern> pattern_;
  std::vector<double> values_;
  std::unique_ptr<ContactDiscretization> contact_;
  std::vector<ElementSlot> elements_;
  std::unique_ptr<FarFactor> far_;
};

/// The near field's bulk operator: K_red u_R plus the nonlinear corrections of the near elements.
/// With `nonlinear` null it is linear elastic (an elastic scene, or a plastic run's predictor).
class CondensedBulk : public BulkOperator {
public:
  CondensedBulk(const FarFieldCondensation& condensation, const NonlinearBulk* nonlinear)
      : condensation_(condensation), nonlinear_(nonlinear) {}
  void internal_force(const double* u, double* f) override;
  void tangent(const double* u, double* values) override;

private:
  const FarFieldCondensation& condensation_;
  const NonlinearBulk* nonlinear_;
};

}  // namespace indentsim
