#pragma once
// J2's flow rule (docs/MODEL.md §5.2, §13.3): how much equivalent plastic strain dgamma a trial
// state of von Mises stress sigma_e^trial flows in a step of duration dt.  Every rule's radial
// return is one scalar equation
//   sigma_e^trial - 3 mu dgamma = R(dgamma)      (the end-of-step von Mises stress)
// with R rising in dgamma: the rate-independent rule's R is the flow stress sigma_y(eps_p,n +
// dgamma); Perzyna's is sigma_y (1 + (dgamma / (dt rate0))^(1/m)), the yield stress plus the
// overstress backward Euler's rate needs; Norton's is sigma_ref (dgamma / (dt A))^(1/m).  J2Law
// scales the trial deviator back by dgamma, and its consistent tangent takes R' = dR/ddgamma in
// place of the hardening modulus (Simo and Hughes, Computational Inelasticity, §3.3 and §3.7 for
// viscoplasticity).  The rules know nothing of the element or the scene.
#include <memory>
#include <optional>

#include "indentsim/input/load_case.hpp"
#include "indentsim/materials/hardening.hpp"

namespace indentsim {

class FlowRule {
public:
  virtual ~FlowRule() = default;
  /// The return of a trial state of von Mises stress `trial_equivalent` from history `eps_p_old`
  /// (shear modulus `mu`) over a step of `time_step` seconds: dgamma and R'(dgamma) (in
  /// PlasticCorrection::hardening_modulus); nullopt when the step is elastic.
  virtual std::optional<PlasticCorrection> correct(double trial_equivalent, double eps_p_old, double mu,
                                                   double time_step) const = 0;
  /// The von Mises stress up to which a virgin point stays elastic over any step (0: it flows at
  /// any stress).
  virtual double initial_yield() const = 0;
  /// The step's duration enters the return.
  virtual bool rate_dependent() const = 0;
};

/// The rate-independent return on a hardening curve (time plays no part).
class RateIndependentFlow final : public FlowRule {
public:
  explicit RateIndependentFlow(std::shared_ptr<const HardeningCurve> hardening) : hardening_(std::move(hardening)) {}
  std::optional<PlasticCorrection> correct(double trial_equivalent, double eps_p_old, double mu,
                                           double /*time_step*/) const override {
    return hardening_->correct(trial_equivalent, eps_p_old, mu);
  }
  double initial_yield() const override { return hardening_->initial_yield(); }
  bool rate_dependent() const override { return false; }

private:
  std::shared_ptr<const HardeningCurve> hardening_;
};

/// Perzyna's overstress, eps_p' = rate0 <sigma_e / sigma_y(eps_p) - 1>^m (Perzyna, Adv. Appl.
/// Mech. 9, 1966), on any hardening curve: elastic inside the yield surface, flowing outside at a
/// rate set by the overstress.  rate0 -> infinity, or a step far longer than the relaxation time,
/// gives the rate-independent return.
class PerzynaFlow final : public FlowRule {
public:
  PerzynaFlow(std::shared_ptr<const HardeningCurve> hardening, double reference_strain_rate, double exponent)
      : hardening_(std::move(hardening)), rate0_(reference_strain_rate), m_(exponent) {}
  std::optional<PlasticCorrection> correct(double trial_equivalent, double eps_p_old, double mu,
                                           double time_step) const override;
  double initial_yield() const override { return hardening_->initial_yield(); }
  bool rate_dependent() const override { return true; }

private:
  std::shared_ptr<const HardeningCurve> hardening_;
  double rate0_, m_;
};

/// Norton's power-law creep, eps_p' = A (sigma_e / sigma_ref)^m (Norton 1929): no yield surface,
/// every stressed point creeps; A -> 0 gives elasticity.
class NortonFlow final : public FlowRule {
public:
  NortonFlow(double creep_coefficient, double reference_stress, double exponent)
      : A_(creep_coefficient), sigma_ref_(reference_stress), m_(exponent) {}
  std::optional<PlasticCorrection> correct(double trial_equivalent, double eps_p_old, double mu,
                                           double time_step) const override;
  double initial_yield() const override { return 0.0; }
  bool rate_dependent() const override { return true; }

private:
  double A_, sigma_ref_, m_;
};

/// The flow rule a J2 material states (material.rate and its parameters, material.hardening).
std::shared_ptr<const FlowRule> make_flow_rule(const MaterialInput& material);

}  // namespace indentsim
