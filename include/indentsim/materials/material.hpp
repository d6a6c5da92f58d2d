#pragma once
// Material laws (docs/MODEL.md §4-5).
//
// Linear elasticity, and Ilyushin's small elasto-plastic deformations: a secant law
// sigma = lambda~ tr(eps) I + 2 mu~ eps with lambda~ = lambda + (2/3) mu omega(e_u),
// mu~ = mu (1 - omega(e_u)).  Equivalently sigma = K tr(eps) I + 2 mu (1 - omega) e (e the
// deviatoric strain): the bulk response stays elastic, only the deviatoric part softens.
//
// The laws are pointwise and know nothing of the element or the scene: strain in, stress and
// tangent (and new history) out, in four Voigt components
//   (eps11, eps22, gamma12 = 2 eps12, eps33) / (s11, s22, s12, s33),
// 1 the in-plane horizontal (radial) direction, 2 the vertical, 3 the out-of-plane direction: in
// plane strain eps33 = 0 and s33 is the out-of-plane stress; in axisymmetry 3 is the hoop
// direction, eps33 = u_r / r.  The kinematics (include/indentsim/geometry/kinematics.hpp) makes the strain.
#include <memory>
#include <optional>
#include <string>

#include <Eigen/Core>

#include "indentsim/input/load_case.hpp"
#include "indentsim/materials/flow_rule.hpp"
#include "indentsim/materials/hardening.hpp"
#include "indentsim/materials/material_parameter.hpp"

namespace indentsim {

/// Strain or stress in Voigt form (11, 22, 12, 33); the shear strain is the engineering one.
using VoigtVector = Eigen::Vector4d;
/// d stress / d strain acting on VoigtVector.
using ConstitutiveMatrix = Eigen::Matrix4d;

struct LameConstants {
  double lambda = 0.0;
  double mu = 0.0;
};

struct ElasticMaterial {
  double E = 0.0;
  double nu = 0.0;

  LameConstants lame() const;
  /// E* = E / (1 - nu^2), the contact modulus of Hertz and Sneddon (line and axisymmetric contact).
  double plane_strain_modulus() const { return E / (1.0 - nu * nu); }
  double bulk_modulus() const { return E / (3.0 * (1.0 - 2.0 * nu)); }
  ConstitutiveMatrix stiffness() const;
};

/// D for given Lamé constants: sigma = lambda tr(eps) I + 2 mu eps on (11, 22, 12, 33).
ConstitutiveMatrix isotropic_stiffness(const LameConstants& lame);

/// e_u = (sqrt 2 / 3) sqrt((e11-e22)^2 + (e22-e33)^2 + (e33-e11)^2 + 6 e12^2) (docs/MODEL.md §4);
/// equal to sqrt(2/3 e:e) with e the deviatoric strain.
double strain_intensity(const VoigtVector& strain);

/// Response of the secant law at one strain.
struct SecantResponse {
  VoigtVector stress = VoigtVector::Zero();
  double strain_intensity = 0.0;  ///< e_u
  double omega = 0.0;             ///< omega(e_u)
  bool plastic = false;           ///< e_u > e0
  ConstitutiveMatrix tangent = ConstitutiveMatrix::Zero();  ///< d sigma / d eps (consistent, symmetric)
  ConstitutiveMatrix secant = ConstitutiveMatrix::Zero();   ///< sigma = secant * eps
};

/// Ilyushin's deformation theory with the linear or power hardening law for omega(e_u).
class IlyushinLaw {
public:
  IlyushinLaw(const ElasticMaterial& elastic, double elastic_limit, HardeningLaw law, double kappa, double n);

  /// omega(e_u): linear  kappa (1 - e0/e_u);  power  1 - (e0/e_u)^(1-n);  0 for e_u <= e0.
  double omega(double e_u) const;
  /// d omega / d e_u (0 below the elastic limit; the law has a kink at e0).
  double omega_derivative(double e_u) const;
  /// Equivalent stress sigma_u = 3 mu (1 - omega) e_u of the uniaxial curve.
  double stress_intensity(double e_u) const { return 3.0 * lame_.mu * (1.0 - omega(e_u)) * e_u; }

  SecantResponse respond(const VoigtVector& strain) const;

  /// d omega / d theta at fixed e_u for theta = e0, kappa or n (0 below the elastic limit and for
  /// any other parameter): the hardening law's own dependence, for forward sensitivities.
  double omega_parameter_derivative(double e_u, MaterialParameter parameter) const;
  /// d sigma / d theta of the secant law at fixed strain for theta = e0, kappa or n: only the
  /// deviatoric part depends on them, d sigma / d theta = -2 mu (d omega / d theta) e.
  VoigtVector stress_parameter_derivative(const VoigtVector& strain, MaterialParameter parameter) const;

  double elastic_limit() const { return e0_; }
  const LameConstants& lame() const { return lame_; }
  const ElasticMaterial& elastic() const { return elastic_; }

  /// Checks 0 < omega < d(e_u omega)/de_u < 1 for e_u > e0 (Ilyushin's conditions) on a
  /// logarithmic sample of e_u up to 1e4 e0; returns a description of the first violation.
  std::optional<std::string> admissibility_violation() const;

private:
  ElasticMaterial elastic_;
  LameConstants lame_;
  double bulk_ = 0.0;
  double e0_ = 0.0;
  HardeningLaw law_;
  double kappa_ = 0.0, n_ = 0.0;
};

/// History of one Gauss point for J2 flow theory.
struct J2State {
  Eigen::Vector4d plastic_strain = Eigen::Vector4d::Zero();  ///< tensor components (11, 22, 33, 12)
  double equivalent_plastic_strain = 0.0;                    ///< hardening variable
};

struct J2Response {
  VoigtVector stress = VoigtVector::Zero();
  J2State state;                 ///< the updated history (to be committed if the increment converges)
  bool plastic = false;          ///< the step yielded
  double equivalent_stress = 0.0;
  ConstitutiveMatrix tangent = ConstitutiveMatrix::Zero();  ///< consistent (algorithmic) tangent
};

/// Incremental J2 flow theory with isotropic hardening (any kinematics: eps33 is given): radial
/// return (Simo and Hughes, Computational Inelasticity, section 3.3) with its consistent tangent,
/// the scalar return made by a flow rule (materials/flow_rule.hpp): rate-independent on a
/// hardening curve sigma_y(eps_p) (materials/hardening.hpp), or rate-dependent over the step's
/// duration.  With the curve of an Ilyushin law, on proportional loading the equivalent plastic
/// strain is eps_p = e_u omega(e_u) and the yield stress sigma_y = sigma_u(e_u) = 3 mu (1 - omega)
/// e_u, so both models give the same stress.
class J2Law {
public:
  /// The rate-independent return on the hardening curve of an Ilyushin law.
  explicit J2Law(const IlyushinLaw& curve);
  /// The rate-independent return on a hardening curve.
  J2Law(const ElasticMaterial& elastic, std::shared_ptr<const HardeningCurve> hardening);
  J2Law(const ElasticMaterial& elastic, std::shared_ptr<const FlowRule> flow);
  /// Stress at total strain `strain` from the committed history `old`, reached over a step of
  /// `time_step` seconds (which only a rate-dependent rule reads; 0 makes its step elastic: the
  /// instantaneous response).
  J2Response respond(const VoigtVector& strain, const J2State& old, double time_step = 0.0) const;
  const FlowRule& flow() const { return *flow_; }
  double shear_modulus() const { return mu_; }
  /// The elastic moduli D (the tangent of an elastic step).
  ConstitutiveMatrix elastic_stiffness() const { return isotropic_stiffness({bulk_ - 2.0 * mu_ / 3.0, mu_}); }
  double initial_yield() const { return initial_yield_; }

private:
  std::shared_ptr<const FlowRule> flow_;
  double bulk_ = 0.0, mu_ = 0.0, initial_yield_ = 0.0;
};

}  // namespace indentsim
