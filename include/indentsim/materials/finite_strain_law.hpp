#pragma once
// Material laws of finite strain (docs/MODEL.md §12): a deformation gradient in, the nominal
// stress P and its tangent dP/dF out, with the history of every Gauss point of the mesh (index =
// 4 * element + point), as PointLaw is for small strain.  The small-strain laws act unchanged on
// logarithmic strains (materials/finite_strain.hpp):
//   HenckyPointLaw       a law of the Hencky strain 1/2 ln(F F^T): elasticity, or Ilyushin's
//                        secant law (with its unloading theorem, in Hencky strains);
//   J2LogStrainPointLaw  J2 flow theory in the multiplicative split F = F_e F_p: the radial
//                        return of J2Law on the trial elastic strain 1/2 ln(F C_p^-1 F^T).
// Both take the small-strain law's stress as the Cauchy or the Kirchhoff stress, as the
// ElasticStressMeasure says (MODEL.md §12.2).
#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/StdVector>

#include "indentsim/materials/finite_strain.hpp"
#include "indentsim/materials/point_law.hpp"

namespace indentsim {

/// The response of one Gauss point at a deformation gradient.
struct FiniteStrainResponse {
  NominalStress nominal = NominalStress::Zero();      ///< first Piola-Kirchhoff stress P
  NominalTangent tangent = NominalTangent::Zero();    ///< dP/dF, consistent
  VoigtVector kirchhoff = VoigtVector::Zero();        ///< tau = J sigma (11, 22, 12, 33)
  bool plastic = false;                               ///< on a plastic branch now
};

class FiniteStrainPointLaw {
public:
  virtual ~FiniteStrainPointLaw() = default;
  virtual FiniteStrainResponse respond(std::size_t point, const Deformation& F) const = 0;
  /// dP/dF of the elastic unloading from the committed state at F (the state's stress, the
  /// elastic moduli: J2's elastic predictor, Ilyushin's unloading theorem), for the exact
  /// unloading stiffness.
  virtual NominalTangent unloading_tangent(std::size_t point, const Deformation& F) const = 0;
  /// Accepts F as the converged state of the point.
  virtual void commit(std::size_t point, const Deformation& F) = 0;
  virtual bool has_yielded(std::size_t point) const = 0;
  /// As PointLaw::set_loading: the branch of a law that follows the global load history.
  virtual void set_loading(bool /*beyond_previous_peak*/) {}
  /// As PointLaw::set_time_step: the duration a rate-dependent law flows over.
  virtual void set_time_step(double /*seconds*/) {}
  /// The carried state of every point, flattened, and its restoration (checkpoints).
  virtual std::vector<double> history() const = 0;
  virtual void restore(const std::vector<double>& history) = 0;
  /// dP/dF is symmetric (a strain energy's second derivative and associative flow): not with the
  /// Cauchy stress measure, whose tau = J s adds J s m^T.
  virtual bool symmetric_tangent() const = 0;
};

/// A law of the Hencky strain e = 1/2 ln(F F^T): the small-strain law's stress at e is the
/// measure's stress (Cauchy: sigma = D e, Abaqus's; Kirchhoff: tau = D e, Hencky's hyperelastic
/// law, Anand, J. Appl. Mech. 46, 1979).  Without a small-strain law, elasticity.
class HenckyPointLaw final : public FiniteStrainPointLaw {
public:
  /// `law` may be null (elasticity).
  HenckyPointLaw(const ElasticMaterial& elastic, std::unique_ptr<PointLaw> law, ElasticStressMeasure measure);
  FiniteStrainResponse respond(std::size_t point, const Deformation& F) const override;
  NominalTangent unloading_tangent(std::size_t point, const Deformation& F) const override;
  void commit(std::size_t point, const Deformation& F) override;
  bool has_yielded(std::size_t point) const override { return law_ && law_->has_yielded(point); }
  void set_loading(bool beyond_previous_peak) override {
    if (law_) law_->set_loading(beyond_previous_peak);
  }
  void set_time_step(double seconds) override {
    if (law_) law_->set_time_step(seconds);
  }
  std::vector<double> history() const override { return law_ ? law_->history() : std::vector<double>{}; }
  void restore(const std::vector<double>& history) override;
  bool symmetric_tangent() const override { return measure_ == ElasticStressMeasure::kirchhoff; }

private:
  ConstitutiveMatrix elastic_;
  std::unique_ptr<PointLaw> law_;
  ElasticStressMeasure measure_;
};

/// History of one Gauss point of J2 in the multiplicative split.
struct J2FiniteState {
  SymmetricTensor inverse_plastic_metric = identity_tensor();  ///< C_p^-1 = F_p^-1 F_p^-T
  double equivalent_plastic_strain = 0.0;
};

/// J2 flow theory with isotropic hardening in the logarithmic-strain framework (de Souza Neto,
/// Peric and Owen, 2008, box 14.3): b_e^tr = F C_p^-1 F^T, the small-strain radial return on
/// e_e^tr = 1/2 ln b_e^tr gives the measure's stress and e_e, and C_p^-1 = F^-1 exp(2 e_e) F^-T.
/// The exponential map keeps plastic flow isochoric exactly (det C_p = 1).
class J2LogStrainPointLaw final : public FiniteStrainPointLaw {
public:
  J2LogStrainPointLaw(const J2Law& law, std::size_t points, ElasticStressMeasure measure);
  FiniteStrainResponse respond(std::size_t point, const Deformation& F) const override;
  NominalTangent unloading_tangent(std::size_t point, const Deformation& F) const override;
  void commit(std::size_t point, const Deformation& F) override;
  bool has_yielded(std::size_t point) const override { return state_[point].equivalent_plastic_strain > 0.0; }
  void set_time_step(double seconds) override { time_step_ = seconds; }
  std::vector<double> history() const override;
  void restore(const std::vector<double>& history) override;
  bool symmetric_tangent() const override { return measure_ == ElasticStressMeasure::kirchhoff; }
  const J2FiniteState& state(std::size_t point) const { return state_[point]; }

private:
  /// The response and the state it leaves.
  FiniteStrainResponse respond(const Deformation& F, const J2FiniteState& old, J2FiniteState* updated) const;
  J2Law law_;
  std::vector<J2FiniteState, Eigen::aligned_allocator<J2FiniteState>> state_;
  ElasticStressMeasure measure_;
  double time_step_ = 0.0;
};

}  // namespace indentsim
