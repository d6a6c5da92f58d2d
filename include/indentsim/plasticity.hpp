#pragma once
// Inelastic bulk models on the mesh: Ilyushin's deformation theory (docs/MODEL.md §4-5), with
// Ilyushin's unloading rule when the load path unloads, and incremental J2 flow theory.
//
// Only what the scene needs: the elastic stiffness K (cached closed-form element matrices) is
// assembled once per mesh, and the bulk response is K u plus a correction from the elements
// with an inelastic Gauss point (yielding now, or carrying history).  An element whose four
// Gauss points are elastic contributes exactly its cached matrix, so below the elastic limit
// the result is the elastic model's.  Inelastic elements are integrated with 2x2 Gauss points:
// stresses for the residual, consistent tangents for the Jacobian.
#include <map>
#include <memory>
#include <optional>
#include <unordered_map>
#include <vector>

#include "indentsim/assembly.hpp"
#include "indentsim/material.hpp"

namespace indentsim {

/// One strain per Gauss point of the mesh (index = 4 * element + point).
using PointStrains = std::vector<VoigtVector, Eigen::aligned_allocator<VoigtVector>>;

/// The response of one Gauss point, with its committed history.
struct PointResponse {
  VoigtVector stress = VoigtVector::Zero();
  ConstitutiveMatrix tangent = ConstitutiveMatrix::Zero();
  double strain_intensity = 0.0;
  double omega = 0.0;
  bool plastic = false;  ///< on a plastic branch now
};

/// A material law with history at every Gauss point of the mesh (index = 4 * element + point).
class PointLaw {
public:
  virtual ~PointLaw() = default;
  /// True when the point responds exactly elastically at `strain` (no yielding, no history).
  virtual bool elastic(std::size_t point, const VoigtVector& strain) const = 0;
  virtual PointResponse respond(std::size_t point, const VoigtVector& strain) const = 0;
  /// d sigma / d theta at fixed strain and fixed history, for theta = e0, kappa or n; nullopt when
  /// the stress depends on the parameter through the history as well (then only finite
  /// differences of whole runs give the sensitivity).
  virtual std::optional<VoigtVector> stress_parameter_derivative(std::size_t /*point*/, const VoigtVector& /*strain*/,
                                                                 MaterialParameter /*parameter*/) const {
    return std::nullopt;
  }
  /// Takes d eps / d theta at every point of the current (converged) state, from the state's
  /// displacement sensitivity, for a law whose history is a function of the state at an earlier
  /// time (Ilyushin's peak strain): afterwards stress_parameter_derivative can account for the
  /// history's own dependence on theta.  Laws without such a history ignore it.
  virtual void record_strain_derivatives(MaterialParameter /*parameter*/, PointStrains /*d_strain*/) {}
  /// Accepts `strain` as the converged state of the point.
  virtual void commit(std::size_t point, const VoigtVector& strain) = 0;
  /// The point has yielded at some time.
  virtual bool has_yielded(std::size_t point) const = 0;
  /// Whether the load path is beyond its deepest point so far (for laws whose branch follows
  /// the global load history); incremental laws ignore it.
  virtual void set_loading(bool /*beyond_previous_peak*/) {}
  /// The carried state of every point, flattened, and its restoration (checkpoints).
  virtual std::vector<double> history() const = 0;
  virtual void restore(const std::vector<double>& history) = 0;
};

/// Ilyushin's deformation theory.  Without unloading rule: the secant law, path independent.
/// With it (load paths that unload), Ilyushin's unloading theorem: once the depth falls below
/// the deepest point reached so far, the whole body unloads elastically from the state at that
/// peak, sigma = sigma(eps*) + D (eps - eps*) with eps* the strain at the peak; reloading stays on
/// that elastic branch until the peak depth is regained, where the state is the peak state again
/// (the elastic branch is reversible), and the deformation law resumes, continuously.
/// Limits: the deformation law itself ignores local unloading inside the body while the punch
/// goes deeper, and the unloading branch is linear elastic (no reverse yielding, no Bauschinger
/// effect).  J2 flow theory has neither limitation.
class IlyushinPointLaw : public PointLaw {
public:
  IlyushinPointLaw(const IlyushinLaw& law, bool unloading_rule, std::size_t points);
  bool elastic(std::size_t point, const VoigtVector& strain) const override;
  PointResponse respond(std::size_t point, const VoigtVector& strain) const override;
  /// On loading the secant law has no history: d sigma_L(eps)/d theta.  On the unloading branch
  /// sigma = sigma_L(eps*) + D (eps - eps*) depends on theta through the peak strain as well:
  ///   d sigma / d theta = d sigma_L(eps*)/d theta + (C_L(eps*) - D) d eps*/d theta
  /// (C_L the loading law's tangent; D does not depend on e0, kappa, n), with d eps*/d theta as
  /// recorded at the peak (record_strain_derivatives); nullopt when it was not recorded.
  std::optional<VoigtVector> stress_parameter_derivative(std::size_t point, const VoigtVector& strain,
                                                         MaterialParameter parameter) const override;
  /// While loading, the current state is the peak: d eps/d theta becomes d eps*/d theta.  The peak
  /// moves with every loading commit, which forgets what was recorded.
  void record_strain_derivatives(MaterialParameter parameter, PointStrains d_strain) override;
  void commit(std::size_t point, const VoigtVector& strain) override;
  bool has_yielded(std::size_t point) const override { return peak_intensity_[point] > law_.elastic_limit(); }
  void set_loading(bool beyond_previous_peak) override { loading_ = !unloading_rule_ || beyond_previous_peak; }
  std::vector<double> history() const override;
  void restore(const std::vector<double>& history) override;
  const IlyushinLaw& law() const { return law_; }

private:
  IlyushinLaw law_;
  bool unloading_rule_;
  bool loading_ = true;
  ConstitutiveMatrix elastic_;
  PointStrains peak_strain_;                                      // eps* per point
  std::vector<double> peak_intensity_;                            // e_u(eps*) per point
  std::map<MaterialParameter, PointStrains> peak_strain_derivative_;  // d eps*/d theta, as recorded
};

/// J2 flow theory with the hardening curve of an Ilyushin law; plastic strain and equivalent
/// plastic strain are the carried state.
class J2PointLaw : public PointLaw {
public:
  J2PointLaw(const J2Law& law, std::size_t points);
  bool elastic(std::size_t point, const VoigtVector& strain) const override;
  PointResponse respond(std::size_t point, const VoigtVector& strain) const override;
  void commit(std::size_t point, const VoigtVector& strain) override;
  bool has_yielded(std::size_t point) const override { return state_[point].equivalent_plastic_strain > 0.0; }
  std::vector<double> history() const override;
  void restore(const std::vector<double>& history) override;

private:
  J2Law law_;
  double initial_yield_ = 0.0;
  std::vector<J2State, Eigen::aligned_allocator<J2State>> state_;
};

class InelasticBulk : public BulkModel {
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

  const PointLaw& law() const { return *law_; }
  const ElasticStiffness& elastic() const { return elastic_; }
  void set_loading(bool beyond_previous_peak) {
    kept_.clear();  // the branch of the law may change
    law_->set_loading(beyond_previous_peak);
  }

  /// The one element loop of inelastic assembly, for any Newton system (the whole mesh, or a
  /// condensed near field, given by its element slots): adds to f (or to the tangent's values)
  /// each element's departure from linear elasticity at u, f_e - K_e u_e (or d f_e / d u_e - K_e).
  /// Elements whose four Gauss points respond elastically (the whole far field) add nothing.
  /// The Gauss-point responses of the force pass are kept, so that the tangent at the same u (the
  /// Jacobian KINSOL asks for after a residual) does not run the return map again.
  void add_force_corrections(const std::vector<ElementSlot>& slots, const double* u, double* f) const;
  void add_tangent_corrections(const std::vector<ElementSlot>& slots, const double* u, double* values) const;
  /// True if a Gauss point of element (ei, ej) is inelastic at u (free-equation vector).
  bool inelastic_at(int ei, int ej, const double* u) const;
  /// Adds d f_int / d theta at fixed u (theta = e0, kappa or n) over the slots' elements to df;
  /// false (df then unusable) when the law cannot give it at this state (PointLaw).
  bool add_parameter_derivative(const std::vector<ElementSlot>& slots, const double* u, MaterialParameter parameter,
                                double* df) const;
  /// Hands the law d eps/d theta at the Gauss points of the slots' elements, from a displacement
  /// sensitivity du (free-equation vector of the slots' system): PointLaw::record_strain_derivatives.
  void record_strain_derivatives(const std::vector<ElementSlot>& slots, const double* du, MaterialParameter parameter);
  /// The whole mesh's element slots (its free-equation system).
  const std::vector<ElementSlot>& slots() const { return slots_; }

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
