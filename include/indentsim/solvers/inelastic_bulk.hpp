#pragma once
// Inelastic bulk models on the mesh: the element loop over a PointLaw (materials/point_law.hpp).
//
// Only what the scene needs: the elastic stiffness K (cached closed-form element matrices) is
// assembled once per mesh, and the bulk response is K u plus a correction from the elements
// with an inelastic Gauss point (yielding now, or carrying history).  An element whose four
// Gauss points are elastic contributes exactly its cached matrix, so below the elastic limit
// the result is the elastic model's.  Inelastic elements are integrated with 2x2 Gauss points:
// stresses for the residual, consistent tangents for the Jacobian.
#include <memory>
#include <unordered_map>
#include <vector>

#include "indentsim/materials/point_law.hpp"
#include "indentsim/solvers/nonlinear_bulk.hpp"

namespace indentsim {

class InelasticBulk final : public NonlinearBulk {
public:
  InelasticBulk(const ElasticStiffness& elastic, std::unique_ptr<PointLaw> law);

  void internal_force(const double* u, double* f) override;
  void tangent(const double* u, double* values) override;
  void commit(const double* u) override;
  long plastic_points() const override { return plastic_points_; }
  double max_strain_intensity() const override { return max_strain_intensity_; }
  std::array<GaussPointState, 4> gauss_point_states(int ei, int ej) const override;
  ElementVector element_force(int ei, int ej) const override;
  std::vector<double> history() const override;
  void restore(const std::vector<double>& history, const double* u) override;
  std::optional<std::string> history_violation() const override;

  const PointLaw& law() const { return *law_; }
  const ElasticStiffness& elastic() const { return elastic_; }
  bool has_yielded(std::size_t point) const override { return law_->has_yielded(point); }
  void set_loading(bool beyond_previous_peak) override {
    kept_.clear();  // the branch of the law may change
    law_->set_loading(beyond_previous_peak);
  }
  void set_time_step(double seconds) override {
    kept_.clear();  // responses kept for another step's duration
    law_->set_time_step(seconds);
  }

  /// The one element loop of inelastic assembly, for any Newton system (the whole mesh, or a
  /// condensed near field, given by its element slots): adds to f (or to the tangent's values)
  /// each element's departure from linear elasticity at u, f_e - K_e u_e (or d f_e / d u_e - K_e).
  /// Elements whose four Gauss points respond elastically (the whole far field) add nothing.
  /// The Gauss-point responses of the force pass are kept, so that the tangent at the same u (the
  /// Jacobian KINSOL asks for after a residual) does not run the return map again.
  void add_force_corrections(const std::vector<ElementSlot>& slots, const double* u, double* f) const override;
  void add_tangent_corrections(const std::vector<ElementSlot>& slots, const double* u, double* values) const override;
  /// True if a Gauss point of element (ei, ej) is inelastic at u (free-equation vector).
  bool departs_at(int ei, int ej, const double* u) const override;
  /// Adds d f_int / d theta at fixed u (theta = e0, kappa or n) over the slots' elements to df;
  /// false (df then unusable) when the law cannot give it at this state (PointLaw).
  bool add_parameter_derivative(const std::vector<ElementSlot>& slots, const double* u, MaterialParameter parameter,
                                double* df) const override;
  /// Hands the law d eps/d theta at the Gauss points of the slots' elements, from a displacement
  /// sensitivity du (free-equation vector of the slots' system): PointLaw::record_strain_derivatives.
  void record_strain_derivatives(const std::vector<ElementSlot>& slots, const double* du,
                                 MaterialParameter parameter) override;
  const std::vector<ElementSlot>& slots() const override { return slots_; }

private:
  /// The four Gauss-point tangents of an inelastic element at its unknowns ue, from the force pass.
  struct KeptResponse {
    ElementVector ue;
    std::array<ConstitutiveMatrix, 4> tangents;
  };
  /// True if any Gauss point of the element is inelastic at u (strains returned).
  bool inelastic(int ei, int ej, const double* u, std::array<VoigtVector, 4>& strains) const;
  bool inelastic(int ei, int ej, const ElementVector& ue, std::array<VoigtVector, 4>& strains) const;
  /// The element's internal force from its Gauss-point strains; the points' tangents too, if asked.
  ElementVector element_force(int ei, int ej, const std::array<VoigtVector, 4>& strains,
                              std::array<ConstitutiveMatrix, 4>* tangents = nullptr) const;
  /// Calls visit(point, strain, ei, ej, g) for every Gauss point at u (point = 4 element + g).
  template <class Visit>
  void visit_points(const double* u, Visit&& visit) const {
    for (int ei = 0; ei < mesh_.elements_x(); ++ei)
      for (int ej = 0; ej < mesh_.elements_y(); ++ej) {
        const auto strains = elastic_.quadrature(ei, ej).strains(gather(mesh_, ei, ej, u));
        const std::size_t first = 4 * static_cast<std::size_t>(mesh_.element(ei, ej));
        for (std::size_t g = 0; g < 4; ++g) visit(first + g, strains[g], ei, ej, g);
      }
  }

  const ElasticStiffness& elastic_;
  const Mesh& mesh_;
  const StiffnessPattern& pattern_;
  std::unique_ptr<PointLaw> law_;
  std::vector<ElementSlot> slots_;  ///< the whole mesh's, for internal_force and tangent
  mutable std::unordered_map<int, KeptResponse> kept_;  ///< by element, from the last force pass
  std::vector<double> committed_u_;
  long plastic_points_ = 0;
  double max_strain_intensity_ = 0.0;
};

}  // namespace indentsim
