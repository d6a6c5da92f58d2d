#include "indentsim/materials/hardening.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "indentsim/materials/material.hpp"

namespace indentsim {

std::optional<PlasticCorrection> HardeningCurve::correct(double trial_equivalent, double eps_p_old, double mu) const {
  const double three_mu = 3.0 * mu;
  const double start_stress = flow_stress(eps_p_old);
  const double excess = trial_equivalent - start_stress;
  if (!(excess > 1e-14 * start_stress)) return std::nullopt;
  // f(dgamma) = trial - 3 mu dgamma - sigma_y(eps_p_old + dgamma) falls strictly: f(0) = excess > 0,
  // f(excess / 3 mu) = sigma_y(eps_p_old) - sigma_y(eps_p_old + excess / 3 mu) <= 0.
  double low = 0.0, high = excess / three_mu;
  // The first guess is the perfectly plastic return; with hardening the root lies below it.
  double dgamma = high;
  const double tolerance = 1e-15 * trial_equivalent;
  for (int iteration = 0; iteration < 200; ++iteration) {
    const double f = trial_equivalent - three_mu * dgamma - flow_stress(eps_p_old + dgamma);
    if (std::abs(f) <= tolerance) break;
    if (f > 0.0) low = dgamma;
    else high = dgamma;
    const double slope = three_mu + hardening_modulus(eps_p_old + dgamma);
    double next = dgamma + f / slope;
    // Keep Newton inside the bracket; where it leaves (a kink of a table, the infinite slope of
    // Ludwik's law at eps_p = 0), bisect.
    if (!(next > low && next < high)) next = 0.5 * (low + high);
    if (next == dgamma || high - low <= 4.0 * std::numeric_limits<double>::epsilon() * high) {
      dgamma = next;
      break;
    }
    dgamma = next;
  }
  return PlasticCorrection{dgamma, hardening_modulus(eps_p_old + dgamma)};
}

// ---------------------------------------------------------------------------------------------
IlyushinHardening::IlyushinHardening(const IlyushinLaw& law) : law_(std::make_unique<IlyushinLaw>(law)) {}
IlyushinHardening::~IlyushinHardening() = default;

double IlyushinHardening::intensity_of_plastic_strain(double eps_p) const {
  const double e0 = law_->elastic_limit();
  if (eps_p <= 0.0) return e0;
  // g(e_u) = e_u omega(e_u) - eps_p rises with slope d = omega + e_u omega' in (0, 1) (Ilyushin's
  // conditions), so Newton from e_u = e0 + eps_p (where g >= 0, as d < 1) descends monotonically.
  double e_u = e0 + eps_p;
  for (int iteration = 0; iteration < 100; ++iteration) {
    const double g = e_u * law_->omega(e_u) - eps_p;
    const double d = law_->omega(e_u) + e_u * law_->omega_derivative(e_u);
    const double next = std::max(e0, e_u - g / d);
    if (std::abs(next - e_u) <= 1e-15 * e_u) return next;
    e_u = next;
  }
  return e_u;
}

double IlyushinHardening::flow_stress(double eps_p) const {
  return law_->stress_intensity(intensity_of_plastic_strain(eps_p));
}

double IlyushinHardening::hardening_modulus(double eps_p) const {
  const double e_u = intensity_of_plastic_strain(eps_p);
  const double d = law_->omega(e_u) + e_u * law_->omega_derivative(e_u);
  return 3.0 * law_->lame().mu * (1.0 - d) / d;
}

std::optional<PlasticCorrection> IlyushinHardening::correct(double trial_equivalent, double eps_p_old,
                                                            double mu) const {
  // Radial return, sigma_eq_trial - 3 mu dgamma = sigma_y(eps_p + dgamma), in closed form.  The
  // hardening curve is Ilyushin's sigma_u(e_u) = 3 mu e_u (1 - omega(e_u)) with the plastic strain
  // eps_p(e_u) = e_u omega(e_u) (the total intensity less the elastic part sigma_u / 3 mu), so with
  // e_u the intensity at the end of the step, sigma_y = 3 mu (e_u - eps_p_old - dgamma) and the
  // return equation becomes linear in e_u: e_u = sigma_eq_trial / (3 mu) + eps_p_old.  (Iterating
  // on dgamma instead needs eps_p -> e_u inverted at every iterate: a nested Newton, whose pow()
  // calls under a power law were a fifth of a J2 cone run.)  The point yields when that e_u carries
  // more plastic strain than the history: e_u omega(e_u) > eps_p_old.
  const double e_u = trial_equivalent / (3.0 * mu) + eps_p_old;
  const double omega = e_u > law_->elastic_limit() ? law_->omega(e_u) : 0.0;
  const double dgamma = e_u * omega - eps_p_old;
  if (!(dgamma > 1e-14 * e_u)) return std::nullopt;
  // H = (d sigma_u / d e_u) / (d eps_p / d e_u) = 3 mu (1 - d) / d with d = d(e_u omega)/de_u.
  const double d = omega + e_u * law_->omega_derivative(e_u);
  return PlasticCorrection{dgamma, 3.0 * mu * (1.0 - d) / d};
}

// ---------------------------------------------------------------------------------------------
double PowerLawHardening::flow_stress(double eps_p) const {
  return sigma_y_ * std::pow(1.0 + E_ * eps_p / sigma_y_, n_);
}
double PowerLawHardening::hardening_modulus(double eps_p) const {
  if (n_ == 0.0) return 0.0;
  return n_ * E_ * std::pow(1.0 + E_ * eps_p / sigma_y_, n_ - 1.0);
}

double LudwikHardening::flow_stress(double eps_p) const {
  return sigma_y_ + (eps_p > 0.0 ? K_ * std::pow(eps_p, n_) : 0.0);
}
double LudwikHardening::hardening_modulus(double eps_p) const {
  // K n eps_p^(n-1): infinite at eps_p = 0 for n < 1 (the corrector bisects there).
  if (eps_p <= 0.0) return n_ < 1.0 ? std::numeric_limits<double>::infinity() : K_;
  return K_ * n_ * std::pow(eps_p, n_ - 1.0);
}

double SwiftHardening::flow_stress(double eps_p) const { return K_ * std::pow(eps0_ + eps_p, n_); }
double SwiftHardening::hardening_modulus(double eps_p) const {
  if (n_ == 0.0) return 0.0;
  return K_ * n_ * std::pow(eps0_ + eps_p, n_ - 1.0);
}

double VoceHardening::flow_stress(double eps_p) const { return sigma_y_ + Q_ * (1.0 - std::exp(-b_ * eps_p)); }
double VoceHardening::hardening_modulus(double eps_p) const { return Q_ * b_ * std::exp(-b_ * eps_p); }

TableHardening::TableHardening(std::vector<std::pair<double, double>> points, TableExtension extension)
    : points_(std::move(points)), extension_(extension) {}

std::size_t TableHardening::segment(double eps_p) const {
  // The last point with eps_p(k) <= eps_p, kept below the last point so that [k, k+1] exists.
  const auto after = std::upper_bound(points_.begin(), points_.end(), eps_p,
                                      [](double x, const std::pair<double, double>& p) { return x < p.first; });
  const std::size_t k = after == points_.begin() ? 0 : static_cast<std::size_t>(after - points_.begin()) - 1;
  return std::min(k, points_.size() - 2);
}

double TableHardening::flow_stress(double eps_p) const {
  const auto& last = points_.back();
  if (eps_p >= last.first && extension_ == TableExtension::flat) return last.second;
  const std::size_t k = segment(eps_p);
  const auto& [x0, y0] = points_[k];
  const auto& [x1, y1] = points_[k + 1];
  return y0 + (y1 - y0) * (eps_p - x0) / (x1 - x0);
}

double TableHardening::hardening_modulus(double eps_p) const {
  if (eps_p >= points_.back().first && extension_ == TableExtension::flat) return 0.0;
  const std::size_t k = segment(eps_p);
  return (points_[k + 1].second - points_[k].second) / (points_[k + 1].first - points_[k].first);
}

// ---------------------------------------------------------------------------------------------
std::shared_ptr<const HardeningCurve> make_hardening_curve(const MaterialInput& m) {
  const double yield_stress = m.yield_stress.value_or(yield_stress_of_e0(m.e0, m.E, m.nu));
  switch (m.hardening) {
    case HardeningLaw::linear:
    case HardeningLaw::power:
      return std::make_shared<IlyushinHardening>(IlyushinLaw({m.E, m.nu}, m.e0, m.hardening, m.kappa, m.n));
    case HardeningLaw::power_law: return std::make_shared<PowerLawHardening>(yield_stress, m.E, m.n);
    // The load case requires each law's parameters (check_hardening_keys); value_or(0) is never taken.
    case HardeningLaw::ludwik: return std::make_shared<LudwikHardening>(yield_stress, m.K.value_or(0.0), m.n);
    case HardeningLaw::swift:
      return std::make_shared<SwiftHardening>(m.K.value_or(0.0), m.prestrain.value_or(0.0), m.n);
    case HardeningLaw::voce: return std::make_shared<VoceHardening>(yield_stress, m.Q.value_or(0.0), m.b.value_or(0.0));
    case HardeningLaw::table: return std::make_shared<TableHardening>(m.hardening_points, m.table_extension);
  }
  return nullptr;
}

}  // namespace indentsim
