#pragma once
// Ilyushin's small elasto-plastic deformations on the mesh (MODEL.md, "Material").
//
// Only what the scene needs: the elastic stiffness K (cached closed-form element matrices) is
// assembled once per mesh, and the bulk response is K u plus a correction from the elements
// that have yielded.  An element whose four Gauss points are all below the elastic limit
// contributes exactly its cached elastic matrix, so below the limit the result is the
// elastic model's, bit for bit.  Yielded elements are integrated with 2x2 Gauss points: the
// secant stress for the residual, the consistent tangent for the Jacobian.
#include <vector>

#include "indentsim/assembly.hpp"
#include "indentsim/material.hpp"

namespace indentsim {

class IlyushinBulk : public BulkModel {
public:
  IlyushinBulk(const ElasticStiffness& elastic, const IlyushinLaw& law);

  void internal_force(const double* u, double* f) override;
  void tangent(const double* u, double* values) override;
  void commit(const double* u) override;
  long plastic_points() const override { return plastic_points_; }
  double max_strain_intensity() const override { return max_strain_intensity_; }
  /// Secant element matrix at the committed state: f_e = K_e u_e exactly (sigma = D_secant eps).
  ElementMatrix element_matrix(int ei, int ej) const override;
  std::array<GaussPointState, 4> gauss_point_states(int ei, int ej) const override;

  const IlyushinLaw& law() const { return law_; }
  /// Strain intensity at each Gauss point of the committed state (element-major, 4 per element).
  const std::vector<double>& committed_strain_intensity() const { return strain_intensity_; }
  /// Elements with at least one yielded Gauss point at the committed state.
  const std::vector<int>& yielded_elements() const { return yielded_; }

private:
  /// True if any Gauss point of the element is beyond the elastic limit at u.
  bool yields(int ei, int ej, const double* u, std::array<VoigtVector, 4>& strains) const;

  const ElasticStiffness& elastic_;
  const Mesh& mesh_;
  const StiffnessPattern& pattern_;
  IlyushinLaw law_;
  std::vector<double> committed_u_;
  std::vector<double> strain_intensity_;
  std::vector<int> yielded_;
  long plastic_points_ = 0;
  double max_strain_intensity_ = 0.0;
};

}  // namespace indentsim
