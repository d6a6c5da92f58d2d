#pragma once
// The bulk in finite strain (docs/MODEL.md §12): total Lagrangian on the same meshes, Q1 or F-bar
// (FiniteStrainQuadrature), through a FiniteStrainPointLaw.  Every element of a Newton system is
// integrated in finite strain (f_e(u) - K_e u_e is its correction to the linear K u); a condensed
// far field stays linear elastic, and an element outside the near field whose displacement
// gradient exceeds small_strain_limit (or that yields) makes the near field grow.
#include <algorithm>
#include <memory>
#include <unordered_map>
#include <vector>

#include <Eigen/StdVector>

#include "indentsim/materials/finite_strain_law.hpp"
#include "indentsim/solvers/nonlinear_bulk.hpp"

namespace indentsim {

class FiniteStrainBulk final : public NonlinearBulk {
public:
  /// Where the far field may stay linear: |grad u| below 3e-3.  The small-strain stress of an
  /// element errs by about |grad u| of itself (the geometric terms are of the order of the
  /// gradient) and the far field holds a small share of the work, so P and S move by a few 1e-5
  /// (docs/performance.md), far below the discretization error the runs estimate; a tighter limit
  /// grows the near field over large far elements for nothing.
  static constexpr double small_strain_limit = 3e-3;

  FiniteStrainBulk(const ElasticStiffness& elastic, std::unique_ptr<FiniteStrainPointLaw> law);

  void internal_force(const double* u, double* f) override;
  void tangent(const double* u, double* values) override;
  void commit(const double* u) override;
  long plastic_points() const override { return plastic_points_; }
  /// e_u of the logarithmic strain.
  double max_strain_intensity() const override { return max_strain_intensity_; }
  /// Cauchy stress (the current configuration's), e_u of the logarithmic strain.
  std::array<GaussPointState, 4> gauss_point_states(int ei, int ej) const override;
  ElementVector element_force(int ei, int ej) const override;
  std::vector<double> history() const override;
  void restore(const std::vector<double>& history, const double* u) override;

  void add_force_corrections(const std::vector<ElementSlot>& slots, const double* u, double* f) const override;
  void add_tangent_corrections(const std::vector<ElementSlot>& slots, const double* u, double* values) const override;
  bool departs_at(int ei, int ej, const double* u) const override;
  bool has_yielded(std::size_t point) const override { return law_->has_yielded(point); }
  void set_loading(bool beyond_previous_peak) override {
    kept_.clear();
    law_->set_loading(beyond_previous_peak);
  }
  void set_time_step(double seconds) override {
    kept_.clear();  // responses kept for another step's duration
    law_->set_time_step(seconds);
  }
  bool symmetric_tangent() const override;
  /// Every element in finite strain with the laws' unloading tangents (the state's stress, elastic moduli).
  std::optional<std::vector<double>> unloading_tangent(const double* u) const override;
  const std::vector<ElementSlot>& slots() const override { return slots_; }
  /// The largest |grad u| component over the elements outside `near` slots at the committed
  /// state (the far field's strain, for the check that it may stay small).
  double largest_gradient_outside(const std::vector<ElementSlot>& near) const;
  void measure_far_field(const std::vector<ElementSlot>& near) override {
    far_field_gradient_ = std::max(far_field_gradient_, largest_gradient_outside(near));
  }
  /// Nothing when no far field was condensed at any commit (a run on the whole mesh).
  std::optional<FarFieldCheck> far_field_check() const override {
    if (far_field_gradient_ < 0.0) return std::nullopt;
    return FarFieldCheck{far_field_gradient_, small_strain_limit};
  }

private:
  struct KeptResponse {
    ElementVector ue;
    std::array<NominalStress, 4> stress;
    std::array<NominalTangent, 4> tangent;
  };
  const FiniteStrainQuadrature& quadrature(int ei, int ej) const {
    return quadrature_by_class_[static_cast<std::size_t>(mesh_.column_class(ei)) * mesh_.height_classes() +
                                mesh_.height_class(ej)];
  }
  /// The law's responses at the element's four points.
  KeptResponse respond(int ei, int ej, const ElementVector& ue) const;

  const ElasticStiffness& elastic_;
  const Mesh& mesh_;
  std::unique_ptr<FiniteStrainPointLaw> law_;
  std::vector<FiniteStrainQuadrature, Eigen::aligned_allocator<FiniteStrainQuadrature>> quadrature_by_class_;
  std::vector<ElementSlot> slots_;
  mutable std::unordered_map<int, KeptResponse> kept_;  ///< by element, from the last force pass
  std::vector<double> committed_u_;
  long plastic_points_ = 0;
  double max_strain_intensity_ = 0.0;
  double far_field_gradient_ = -1.0;  ///< the largest of largest_gradient_outside at the commits (-1: none)
};

}  // namespace indentsim
