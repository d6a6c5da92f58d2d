#include "indentsim/analysis/coating_analysis.hpp"

#include <cmath>

namespace indentsim {

std::optional<CoatingContext> coating_of(const LoadCase& lc) {
  if (lc.layers.empty()) return std::nullopt;
  const MaterialInput& film = lc.layers.front().material;
  const MaterialInput& below = lc.region_material(lc.layers.size() > 1 ? 2 : 0);
  return CoatingContext{lc.layers.front().thickness, film.E, film.nu, below.E, below.nu};
}

GaoWeights gao_weights(double x, double nu) {
  const double pi = std::acos(-1.0);
  // x ln((1 + x^2)/x^2) -> 0 as x -> 0 (and ln -> 1/x^2 as x -> infinity): written with log1p.
  const double x_log = x > 0.0 ? x * std::log1p(1.0 / (x * x)) : 0.0;
  GaoWeights w;
  w.I0 = 2.0 / pi * std::atan(x) + ((1.0 - 2.0 * nu) * x_log - x / (1.0 + x * x)) / (2.0 * pi * (1.0 - nu));
  w.I1 = 2.0 / pi * std::atan(x) + x_log / pi;
  return w;
}

double gao_contact_modulus(double film_E, double film_nu, double substrate_E, double substrate_nu, double x) {
  const GaoWeights w = gao_weights(x, substrate_nu);
  const double mu_f = film_E / (2.0 * (1.0 + film_nu)), mu_s = substrate_E / (2.0 * (1.0 + substrate_nu));
  const double mu = mu_s + (mu_f - mu_s) * w.I0, nu = substrate_nu + (film_nu - substrate_nu) * w.I1;
  return 2.0 * mu / (1.0 - nu);
}

std::optional<double> gao_film_modulus(double contact_modulus, double film_nu, double substrate_E, double substrate_nu,
                                       double x) {
  const GaoWeights w = gao_weights(x, substrate_nu);
  if (!(w.I0 >= 1e-3)) return std::nullopt;
  const double nu = substrate_nu + (film_nu - substrate_nu) * w.I1;
  const double mu = 0.5 * contact_modulus * (1.0 - nu), mu_s = substrate_E / (2.0 * (1.0 + substrate_nu));
  const double mu_f = mu_s + (mu - mu_s) / w.I0;
  if (!(mu_f > 0.0) || !std::isfinite(mu_f)) return std::nullopt;
  return 2.0 * mu_f * (1.0 + film_nu);
}

}  // namespace indentsim
