#pragma once
// Material laws (docs/MODEL.md §4-5).
//
// Linear elasticity in plane strain, and Ilyushin's small elasto-plastic deformations: a secant
// law sigma = lambda~ tr(eps) I + 2 mu~ eps with lambda~ = lambda + (2/3) mu omega(e_u),
// mu~ = mu (1 - omega(e_u)).  Equivalently sigma = K tr(eps) I + 2 mu (1 - omega) e (e the
// deviatoric strain): the bulk response stays elastic, only the deviatoric part softens.
// Strains and stresses are in Voigt form (eps11, eps22, gamma12 = 2 eps12) / (s11, s22, s12).
#include <optional>
#include <string>

#include <Eigen/Core>

#include "indentsim/load_case.hpp"

namespace indentsim {

/// Plane-strain constitutive matrix acting on (eps11, eps22, gamma12 = 2 eps12).
using PlaneStrainMatrix = Eigen::Matrix3d;
using VoigtVector = Eigen::Vector3d;

struct LameConstants {
  double lambda = 0.0;
  double mu = 0.0;
};

struct ElasticMaterial {
  double E = 0.0;
  double nu = 0.0;

  LameConstants lame() const;
  /// E* = E / (1 - nu^2), the plane-strain modulus of Hertz line contact.
  double plane_strain_modulus() const { return E / (1.0 - nu * nu); }
  double bulk_modulus() const { return E / (3.0 * (1.0 - 2.0 * nu)); }
  PlaneStrainMatrix stiffness() const;
};

/// D for given Lamé constants: sigma = lambda tr(eps) I + 2 mu eps, eps33 = 0.
PlaneStrainMatrix plane_strain_stiffness(const LameConstants& lame);

/// e_u = (sqrt 2 / 3) sqrt((e11-e22)^2 + e22^2 + e11^2 + 6 e12^2) with eps33 = 0 (docs/MODEL.md §4);
/// equal to sqrt(2/3 e:e) with e the deviatoric strain.
double strain_intensity(const VoigtVector& strain);

/// Response of the secant law at one strain.
struct SecantResponse {
  VoigtVector stress = VoigtVector::Zero();
  double stress33 = 0.0;          ///< sigma33 = lambda~ tr(eps) (plane strain)
  double strain_intensity = 0.0;  ///< e_u
  double omega = 0.0;             ///< omega(e_u)
  bool plastic = false;           ///< e_u > e0
  PlaneStrainMatrix tangent = PlaneStrainMatrix::Zero();  ///< d sigma / d eps (consistent, symmetric)
  PlaneStrainMatrix secant = PlaneStrainMatrix::Zero();   ///< sigma = secant * eps
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
  double stress33 = 0.0;
  J2State state;                 ///< the updated history (to be committed if the increment converges)
  bool plastic = false;          ///< the step yielded
  double equivalent_stress = 0.0;
  PlaneStrainMatrix tangent = PlaneStrainMatrix::Zero();  ///< consistent (algorithmic) tangent
};

/// Incremental J2 flow theory with isotropic hardening, plane strain.  Its hardening curve is the
/// uniaxial curve of an Ilyushin law: on proportional loading the equivalent plastic strain is
/// eps_p = e_u omega(e_u) and the yield stress sigma_y = sigma_u(e_u) = 3 mu (1 - omega) e_u, so
/// both models give the same stress (the conditions 0 < d(e_u omega)/de_u < 1 make the map
/// monotone and the hardening modulus positive).  Radial return (Simo and Hughes, Computational
/// Inelasticity, section 3.3) with its consistent tangent.
class J2Law {
public:
  explicit J2Law(const IlyushinLaw& curve);
  /// Yield stress and hardening modulus d sigma_y / d eps_p at equivalent plastic strain eps_p.
  double yield_stress(double equivalent_plastic_strain, double* hardening_modulus = nullptr) const;
  /// Stress at total strain `strain` from the committed history `old`.
  J2Response respond(const VoigtVector& strain, const J2State& old) const;
  const IlyushinLaw& curve() const { return curve_; }

private:
  IlyushinLaw curve_;
  double bulk_ = 0.0, mu_ = 0.0;
};

}  // namespace indentsim
