#include "indentsim/materials/material.hpp"

#include <cmath>

#include <fmt/format.h>

namespace indentsim {

LameConstants ElasticMaterial::lame() const {
  return {E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), E / (2.0 * (1.0 + nu))};
}

ConstitutiveMatrix ElasticMaterial::stiffness() const { return isotropic_stiffness(lame()); }

ConstitutiveMatrix isotropic_stiffness(const LameConstants& l) {
  const double l2m = l.lambda + 2.0 * l.mu;
  ConstitutiveMatrix d;
  d << l2m, l.lambda, 0.0, l.lambda,  //
      l.lambda, l2m, 0.0, l.lambda,   //
      0.0, 0.0, l.mu, 0.0,            //
      l.lambda, l.lambda, 0.0, l2m;
  return d;
}

double strain_intensity(const VoigtVector& s) {
  const double e11 = s[0], e22 = s[1], e12 = 0.5 * s[2], e33 = s[3];
  const double sum =
      (e11 - e22) * (e11 - e22) + (e22 - e33) * (e22 - e33) + (e33 - e11) * (e33 - e11) + 6.0 * e12 * e12;
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

double IlyushinLaw::omega_parameter_derivative(double e_u, MaterialParameter parameter) const {
  if (e_u <= e0_) return 0.0;
  const double ratio = e0_ / e_u;
  if (law_ == HardeningLaw::linear) {
    // omega = kappa (1 - e0 / e_u)
    if (parameter == MaterialParameter::kappa) return 1.0 - ratio;
    if (parameter == MaterialParameter::e0) return -kappa_ / e_u;
    return 0.0;
  }
  // omega = 1 - (e0 / e_u)^(1 - n)
  if (parameter == MaterialParameter::e0) return -(1.0 - n_) * std::pow(ratio, -n_) / e_u;
  if (parameter == MaterialParameter::n) return std::pow(ratio, 1.0 - n_) * std::log(ratio);
  return 0.0;
}

VoigtVector IlyushinLaw::stress_parameter_derivative(const VoigtVector& strain, MaterialParameter parameter) const {
  const double d_omega = omega_parameter_derivative(strain_intensity(strain), parameter);
  if (d_omega == 0.0) return VoigtVector::Zero();
  const double trace = strain[0] + strain[1] + strain[3];
  const VoigtVector deviator(strain[0] - trace / 3.0, strain[1] - trace / 3.0, 0.5 * strain[2], strain[3] - trace / 3.0);
  return -2.0 * lame_.mu * d_omega * deviator;
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
  r.secant = isotropic_stiffness(secant);
  r.stress = r.secant * strain;

  // Consistent tangent C = K I(x)I + 2 mu (1-omega) I_dev - (4 mu / 3)(omega'/e_u) e(x)e on
  // (11, 22, 12, 33) with the engineering shear column (docs/MODEL.md §4).  Below the limit
  // omega' = 0 and C = D_elastic.
  r.tangent = r.secant;
  if (r.plastic) {
    const double trace = strain[0] + strain[1] + strain[3];
    const VoigtVector deviator(strain[0] - trace / 3.0, strain[1] - trace / 3.0, 0.5 * strain[2],
                               strain[3] - trace / 3.0);
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

J2Law::J2Law(const IlyushinLaw& curve) : J2Law(curve.elastic(), std::make_shared<IlyushinHardening>(curve)) {}

J2Law::J2Law(const ElasticMaterial& elastic, std::shared_ptr<const HardeningCurve> hardening)
    : J2Law(elastic, std::make_shared<RateIndependentFlow>(std::move(hardening))) {}

J2Law::J2Law(const ElasticMaterial& elastic, std::shared_ptr<const FlowRule> flow)
    : flow_(std::move(flow)),
      bulk_(elastic.lame().lambda + 2.0 * elastic.lame().mu / 3.0),
      mu_(elastic.lame().mu),
      initial_yield_(flow_->initial_yield()) {}

J2Response J2Law::respond(const VoigtVector& strain, const J2State& old, double time_step) const {
  J2Response r;
  r.state = old;
  const double trace = strain[0] + strain[1] + strain[3];
  // Deviatoric total strain as a tensor (11, 22, 33, 12).
  const Eigen::Vector4d e(strain[0] - trace / 3.0, strain[1] - trace / 3.0, strain[3] - trace / 3.0,
                          0.5 * strain[2]);
  const auto tensor_norm = [](const Eigen::Vector4d& t) {
    return std::sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2] + 2.0 * t[3] * t[3]);
  };
  const Eigen::Vector4d trial = 2.0 * mu_ * (e - old.plastic_strain);
  const double trial_norm = tensor_norm(trial);
  const double trial_equivalent = std::sqrt(1.5) * trial_norm;
  const std::optional<PlasticCorrection> correction =
      flow_->correct(trial_equivalent, old.equivalent_plastic_strain, mu_, time_step);

  Eigen::Vector4d deviator = trial;
  double theta = 1.0, theta_bar = 0.0;
  Eigen::Vector4d n = Eigen::Vector4d::Zero();
  if (correction) {
    const double dgamma = correction->dgamma, hardening = correction->hardening_modulus;
    n = trial / trial_norm;
    deviator = trial - 2.0 * mu_ * std::sqrt(1.5) * dgamma * n;
    r.state.plastic_strain += std::sqrt(1.5) * dgamma * n;
    r.state.equivalent_plastic_strain += dgamma;
    r.plastic = true;
    theta = 1.0 - 3.0 * mu_ * dgamma / trial_equivalent;
    theta_bar = 1.0 / (1.0 + hardening / (3.0 * mu_)) - (1.0 - theta);
  }
  const double pressure = bulk_ * trace;
  r.stress = VoigtVector(pressure + deviator[0], pressure + deviator[1], deviator[3], pressure + deviator[2]);
  r.equivalent_stress = std::sqrt(1.5) * tensor_norm(deviator);

  // C = K I(x)I + 2 mu theta I_dev - 2 mu theta_bar n(x)n on (11, 22, gamma12, 33).
  const double m = mu_ * theta;
  const double diagonal = bulk_ + 4.0 / 3.0 * m, off = bulk_ - 2.0 / 3.0 * m;
  r.tangent << diagonal, off, 0.0, off,  //
      off, diagonal, 0.0, off,           //
      0.0, 0.0, m, 0.0,                  //
      off, off, 0.0, diagonal;
  if (r.plastic) {
    const VoigtVector nv(n[0], n[1], n[3], n[2]);
    r.tangent -= 2.0 * mu_ * theta_bar * nv * nv.transpose();
  }
  return r;
}

}  // namespace indentsim
