#include "indentsim/materials/flow_rule.hpp"

#include <cmath>
#include <limits>

namespace indentsim {

namespace {

/// The root of g, falling on [low, high] with g(low) > 0 >= g(high), by Newton's method from
/// `start` (one end) kept inside the bracket (bisection where a step leaves it or is not finite).
/// Each rule's g is concave or convex in its variable, and started from the end from which Newton
/// descends onto the root without overshooting; the bracket guards against the curvature a
/// hardening curve adds.
template <class Residual>
double falling_root(Residual residual_and_slope, double low, double high, double start, double tolerance) {
  double x = start;
  for (int iteration = 0; iteration < 200; ++iteration) {
    const auto [g, slope] = residual_and_slope(x);
    if (std::abs(g) <= tolerance) break;
    if (g > 0.0) low = x;
    else high = x;
    double next = x - g / slope;
    if (!(next > low && next < high)) next = 0.5 * (low + high);
    if (next == x || high - low <= 4.0 * std::numeric_limits<double>::epsilon() * high) return next;
    x = next;
  }
  return x;
}

}  // namespace

std::optional<PlasticCorrection> PerzynaFlow::correct(double trial_equivalent, double eps_p_old, double mu,
                                                      double time_step) const {
  const double start_stress = hardening_->flow_stress(eps_p_old);
  const double excess = trial_equivalent - start_stress;
  if (!(excess > 1e-14 * start_stress) || !(time_step > 0.0)) return std::nullopt;
  // Backward Euler: dgamma = dt rate0 (sigma_e / sigma_y - 1)^m at the end of the step.  In the
  // overstress ratio y = (dgamma / (dt rate0))^(1/m), dgamma = c y^m with c = dt rate0, and
  //   g(y) = sigma_e^trial - 3 mu c y^m - sigma_y(eps_p_old + c y^m) (1 + y)
  // falls from g(0) = excess > 0 with a finite slope (in dgamma the slope is infinite at 0 for
  // m > 1).  At the perfectly plastic return dgamma = excess / 3 mu, g <= 0: the bracket.
  const double c = time_step * rate0_, three_mu = 3.0 * mu;
  const double high = std::pow(excess / three_mu / c, 1.0 / m_);
  if (!(c > 0.0) || !std::isfinite(high)) return std::nullopt;  // a step too short to flow in double precision
  const auto g = [&](double y) {
    const double ym1 = std::pow(y, m_ - 1.0), dgamma = c * ym1 * y;
    const double sigma_y = hardening_->flow_stress(eps_p_old + dgamma);
    const double d_dgamma = c * m_ * ym1;  // d dgamma / dy
    const double H = hardening_->hardening_modulus(eps_p_old + dgamma);
    return std::pair{trial_equivalent - three_mu * dgamma - sigma_y * (1.0 + y),
                     -(three_mu + H * (1.0 + y)) * d_dgamma - sigma_y};
  };
  const double y = falling_root(g, 0.0, high, high, 1e-15 * trial_equivalent);
  const double dgamma = c * std::pow(y, m_);
  if (!(dgamma > 0.0)) return std::nullopt;
  // R(dgamma) = sigma_y(eps_p) (1 + y(dgamma)): R' = H (1 + y) + sigma_y y / (m dgamma).
  const double eps_p = eps_p_old + dgamma;
  const double slope = hardening_->hardening_modulus(eps_p) * (1.0 + y) + hardening_->flow_stress(eps_p) * y / (m_ * dgamma);
  return PlasticCorrection{dgamma, slope};
}

std::optional<PlasticCorrection> NortonFlow::correct(double trial_equivalent, double /*eps_p_old*/, double mu,
                                                     double time_step) const {
  if (!(trial_equivalent > 0.0) || !(time_step > 0.0)) return std::nullopt;
  // Backward Euler: dgamma = dt A (sigma_e / sigma_ref)^m at the end of the step, sigma_e =
  // sigma_e^trial - 3 mu dgamma.  In the share of the trial stress that relaxes, z = 3 mu dgamma /
  // sigma_e^trial in [0, 1) (so that a small creep step keeps its digits, which 1 - sigma_e /
  // sigma_e^trial would cancel),
  //   g(z) = dt A (ratio (1 - z))^m - z sigma_e^trial / (3 mu),   ratio = sigma_e^trial / sigma_ref,
  // falls from g(0) > 0 to g(1) < 0, convex for m >= 1: Newton from z = 0 rises onto the root.
  const double three_mu = 3.0 * mu, scale = trial_equivalent / three_mu;
  const double c = time_step * A_, ratio = trial_equivalent / sigma_ref_;
  if (!(c > 0.0)) return std::nullopt;  // a step too short to flow in double precision
  const auto g = [&](double z) {
    const double rest = 1.0 - z, rate_term = c * std::pow(ratio * rest, m_);
    return std::pair{rate_term - scale * z, -m_ * rate_term / rest - scale};
  };
  const double z = falling_root(g, 0.0, 1.0, 0.0, 1e-15 * scale);
  const double dgamma = scale * z;
  if (!(dgamma > 0.0)) return std::nullopt;
  // R(dgamma) = sigma_ref (dgamma / (dt A))^(1/m) = sigma_e: R' = sigma_e / (m dgamma).
  return PlasticCorrection{dgamma, (1.0 - z) * trial_equivalent / (m_ * dgamma)};
}

std::shared_ptr<const FlowRule> make_flow_rule(const MaterialInput& material) {
  // The load case requires each rule's parameters (validate_rate); value_or(1) is never taken.
  switch (material.rate) {
    case RateLaw::none: return std::make_shared<RateIndependentFlow>(make_hardening_curve(material));
    case RateLaw::perzyna:
      return std::make_shared<PerzynaFlow>(make_hardening_curve(material), material.reference_strain_rate.value_or(1.0),
                                           material.rate_exponent.value_or(1.0));
    case RateLaw::norton:
      return std::make_shared<NortonFlow>(material.creep_coefficient.value_or(1.0),
                                          material.reference_stress.value_or(1.0), material.rate_exponent.value_or(1.0));
  }
  return nullptr;
}

}  // namespace indentsim
