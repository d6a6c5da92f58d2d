#include "indentsim/material.hpp"

#include <cmath>

#include <fmt/format.h>

namespace indentsim {

LameConstants ElasticMaterial::lame() const {
  return {E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), E / (2.0 * (1.0 + nu))};
}

PlaneStrainMatrix ElasticMaterial::stiffness() const { return plane_strain_stiffness(lame()); }

PlaneStrainMatrix plane_strain_stiffness(const LameConstants& l) {
  PlaneStrainMatrix d;
  d << l.lambda + 2.0 * l.mu, l.lambda, 0.0,  //
      l.lambda, l.lambda + 2.0 * l.mu, 0.0,   //
      0.0, 0.0, l.mu;
  return d;
}

double strain_intensity(const VoigtVector& s) {
  const double e11 = s[0], e22 = s[1], e12 = 0.5 * s[2];
  const double sum = (e11 - e22) * (e11 - e22) + e22 * e22 + e11 * e11 + 6.0 * e12 * e12;
  return std::sqrt(2.0) / 3.0 * std::sqrt(sum);
}

IlyushinLaw::IlyushinLaw(const ElasticMaterial& elastic, double elastic_limit, HardeningLaw law, double kappa,
                         double n)
    : elastic_(elastic),
      lame_(elastic.lame()),
      bulk_(lame_.lambda + 2.0 * lame_.mu / 3.0),
      e0_(elastic_limit),
      law_(law),
      kappa_(kappa),
      n_(n) {}

double IlyushinLaw::omega(double e_u) const {
  if (e_u <= e0_) return 0.0;
  const double ratio = e0_ / e_u;
  return law_ == HardeningLaw::linear ? kappa_ * (1.0 - ratio) : 1.0 - std::pow(ratio, 1.0 - n_);
}

double IlyushinLaw::omega_derivative(double e_u) const {
  if (e_u <= e0_) return 0.0;
  const double ratio = e0_ / e_u;
  return law_ == HardeningLaw::linear ? kappa_ * ratio / e_u : (1.0 - n_) * std::pow(ratio, 1.0 - n_) / e_u;
}

SecantResponse IlyushinLaw::respond(const VoigtVector& strain) const {
  SecantResponse r;
  const double mu = lame_.mu;
  const double e_u = strain_intensity(strain);
  const double omega_value = omega(e_u);
  r.strain_intensity = e_u;
  r.omega = omega_value;
  r.plastic = e_u > e0_;

  // Secant: lambda~ = lambda + (2/3) mu omega, mu~ = mu (1 - omega).
  const LameConstants secant{lame_.lambda + 2.0 / 3.0 * mu * omega_value, mu * (1.0 - omega_value)};
  r.secant = plane_strain_stiffness(secant);
  r.stress = r.secant * strain;
  r.stress33 = secant.lambda * (strain[0] + strain[1]);

  // Consistent tangent C = K I(x)I + 2 mu (1-omega) I_dev - (4 mu / 3)(omega'/e_u) e(x)e, restricted
  // to (11, 22, 12) with the engineering shear column (MODEL.md).  Below the limit omega' = 0
  // and C = D_elastic.
  r.tangent = r.secant;
  if (r.plastic) {
    const double trace = strain[0] + strain[1];
    const Eigen::Vector3d deviator(strain[0] - trace / 3.0, strain[1] - trace / 3.0, 0.5 * strain[2]);
    const double c = 4.0 * mu / 3.0 * omega_derivative(e_u) / e_u;
    r.tangent -= c * deviator * deviator.transpose();
  }
  return r;
}

std::optional<std::string> IlyushinLaw::admissibility_violation() const {
  if (law_ == HardeningLaw::linear && kappa_ == 0.0) return std::nullopt;  // omega = 0: elastic
  for (int k = 1; k <= 400; ++k) {
    const double e_u = e0_ * std::pow(1e4, k / 400.0);
    const double w = omega(e_u);
    const double d = w + e_u * omega_derivative(e_u);  // d(e_u omega)/d e_u
    if (!(w > 0.0 && w < d && d < 1.0))
      return fmt::format("at e_u = {:.4g}: omega = {:.6g}, d(e_u omega)/de_u = {:.6g}; Ilyushin's theory needs "
                         "0 < omega < d(e_u omega)/de_u < 1",
                         e_u, w, d);
  }
  return std::nullopt;
}

}  // namespace indentsim
