#pragma once
// Hardening curves of J2 flow theory (docs/MODEL.md §12.1): the uniaxial flow stress
// sigma_y(eps_p) as a function of the equivalent plastic strain, and the plastic corrector of the
// radial return that the curve makes (J2Law calls it; it knows nothing of the element or the scene).
//
// The corrector solves the scalar return equation of Simo and Hughes (Computational Inelasticity,
// §3.3.1, eq. 3.3.16 with isotropic hardening),
//   f(dgamma) = sigma_eq_trial - 3 mu dgamma - sigma_y(eps_p_old + dgamma) = 0,
// whose left side falls strictly with dgamma when sigma_y never falls: one root in
// [0, (sigma_eq_trial - sigma_y(eps_p_old)) / (3 mu)], found by Newton's method kept inside that
// bracket (bisection where a Newton step leaves it).  Ilyushin's curves keep their own closed form.
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "indentsim/input/load_case.hpp"

namespace indentsim {

class IlyushinLaw;

/// The plastic part of one radial return: the equivalent plastic strain it adds and the hardening
/// modulus H = d sigma_y / d eps_p at the end of the step (for the consistent tangent).
struct PlasticCorrection {
  double dgamma = 0.0;
  double hardening_modulus = 0.0;
};

/// sigma_y(eps_p), non-decreasing in eps_p >= 0.
class HardeningCurve {
public:
  virtual ~HardeningCurve() = default;
  /// The uniaxial flow stress at equivalent plastic strain eps_p >= 0 [Pa].
  virtual double flow_stress(double eps_p) const = 0;
  /// d sigma_y / d eps_p (the right derivative at a kink of a table).
  virtual double hardening_modulus(double eps_p) const = 0;
  /// The initial yield stress sigma_y(0).
  double initial_yield() const { return flow_stress(0.0); }
  /// The plastic correction of a trial state of von Mises stress `trial_equivalent` from history
  /// `eps_p_old`, with shear modulus `mu`; nullopt when the trial state is elastic.
  virtual std::optional<PlasticCorrection> correct(double trial_equivalent, double eps_p_old, double mu) const;
};

/// The hardening curve of an Ilyushin law ("linear", "power"): sigma_y = sigma_u(e_u) with
/// eps_p = e_u omega(e_u), a curve given through e_u.  Its return equation is linear in e_u and
/// solved in closed form (the comment in correct()).
class IlyushinHardening final : public HardeningCurve {
public:
  explicit IlyushinHardening(const IlyushinLaw& law);
  ~IlyushinHardening() override;
  double flow_stress(double eps_p) const override;
  double hardening_modulus(double eps_p) const override;
  std::optional<PlasticCorrection> correct(double trial_equivalent, double eps_p_old, double mu) const override;

private:
  /// The intensity e_u whose plastic strain e_u omega(e_u) is eps_p (Newton; the map is monotone).
  double intensity_of_plastic_strain(double eps_p) const;
  std::unique_ptr<IlyushinLaw> law_;
};

/// sigma = sigma_y (1 + E eps_p / sigma_y)^n: the power law of the indentation literature (Dao et
/// al., Acta Mater. 49 (2001) 3899, eq. 1), the uniaxial curve sigma = R eps^n continued linearly
/// below yield; n = 0 is elastic-perfectly plastic.
class PowerLawHardening final : public HardeningCurve {
public:
  PowerLawHardening(double yield_stress, double E, double n) : sigma_y_(yield_stress), E_(E), n_(n) {}
  double flow_stress(double eps_p) const override;
  double hardening_modulus(double eps_p) const override;

private:
  double sigma_y_, E_, n_;
};

/// sigma = sigma_y + K eps_p^n (Ludwik 1909).
class LudwikHardening final : public HardeningCurve {
public:
  LudwikHardening(double yield_stress, double K, double n) : sigma_y_(yield_stress), K_(K), n_(n) {}
  double flow_stress(double eps_p) const override;
  double hardening_modulus(double eps_p) const override;

private:
  double sigma_y_, K_, n_;
};

/// sigma = K (eps_0 + eps_p)^n (Swift 1952); the initial yield stress is K eps_0^n.
class SwiftHardening final : public HardeningCurve {
public:
  SwiftHardening(double K, double prestrain, double n) : K_(K), eps0_(prestrain), n_(n) {}
  double flow_stress(double eps_p) const override;
  double hardening_modulus(double eps_p) const override;

private:
  double K_, eps0_, n_;
};

/// sigma = sigma_y + Q (1 - exp(-b eps_p)) (Voce 1948): saturates at sigma_y + Q.
class VoceHardening final : public HardeningCurve {
public:
  VoceHardening(double yield_stress, double Q, double b) : sigma_y_(yield_stress), Q_(Q), b_(b) {}
  double flow_stress(double eps_p) const override;
  double hardening_modulus(double eps_p) const override;

private:
  double sigma_y_, Q_, b_;
};

/// A measured curve: points (eps_p, sigma) from eps_p = 0, eps_p increasing, sigma not falling,
/// joined by straight lines; beyond the last point flat or along the last segment's slope.
class TableHardening final : public HardeningCurve {
public:
  TableHardening(std::vector<std::pair<double, double>> points, TableExtension extension);
  double flow_stress(double eps_p) const override;
  double hardening_modulus(double eps_p) const override;

private:
  /// The segment [k, k+1] holding eps_p (the last one beyond the table).
  std::size_t segment(double eps_p) const;
  std::vector<std::pair<double, double>> points_;
  TableExtension extension_;
};

/// The hardening curve a J2 material states (material.hardening and its parameters).
std::shared_ptr<const HardeningCurve> make_hardening_curve(const MaterialInput& material);

}  // namespace indentsim
