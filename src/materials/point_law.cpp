#include "indentsim/materials/point_law.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

namespace indentsim {

// ---------------------------------------------------------------------------------------------
IlyushinPointLaw::IlyushinPointLaw(const IlyushinLaw& law, bool unloading_rule, std::size_t points)
    : law_(law),
      unloading_rule_(unloading_rule),
      elastic_(law.elastic().stiffness()),
      peak_strain_(points, VoigtVector::Zero()),
      peak_intensity_(points, 0.0) {}

bool IlyushinPointLaw::elastic(std::size_t point, const VoigtVector& strain) const {
  // Loading: the secant law has no history.  Unloading: the branch sigma(eps*) + D (eps - eps*)
  // is D eps exactly when eps* itself was elastic.
  if (loading_) return strain_intensity(strain) <= law_.elastic_limit();
  return peak_intensity_[point] <= law_.elastic_limit();
}

PointResponse IlyushinPointLaw::respond(std::size_t point, const VoigtVector& strain) const {
  PointResponse r;
  if (loading_) {
    const SecantResponse s = law_.respond(strain);
    r = {s.stress, s.tangent, s.strain_intensity, s.omega, s.plastic};
    return r;
  }
  // Elastic unloading (or reloading) from the peak state.
  const VoigtVector& peak = peak_strain_[point];
  const SecantResponse at_peak = law_.respond(peak);
  const VoigtVector change = strain - peak;
  r.stress = at_peak.stress + elastic_ * change;
  r.tangent = elastic_;
  r.strain_intensity = strain_intensity(strain);
  r.omega = at_peak.omega;
  r.plastic = false;
  return r;
}

std::optional<VoigtVector> IlyushinPointLaw::stress_parameter_derivative(std::size_t point, const VoigtVector& strain,
                                                                         MaterialParameter parameter) const {
  if (loading_) return law_.stress_parameter_derivative(strain, parameter);
  const auto recorded = peak_strain_derivative_.find(parameter);
  if (recorded == peak_strain_derivative_.end()) return std::nullopt;
  // sigma = sigma_L(eps*) + D (eps - eps*): the law's own dependence at the peak strain, and the
  // peak strain's, weighted by how much the loading law and the elastic branch differ there.
  const VoigtVector& peak = peak_strain_[point];
  const ConstitutiveMatrix loading_tangent = law_.respond(peak).tangent;
  return VoigtVector(law_.stress_parameter_derivative(peak, parameter) +
                     (loading_tangent - elastic_) * recorded->second[point]);
}

void IlyushinPointLaw::record_strain_derivatives(MaterialParameter parameter, PointStrains d_strain) {
  if (!loading_ || d_strain.size() != peak_strain_.size()) return;
  peak_strain_derivative_[parameter] = std::move(d_strain);
}

void IlyushinPointLaw::commit(std::size_t point, const VoigtVector& strain) {
  if (!loading_) return;
  peak_strain_derivative_.clear();  // the peak moves
  peak_strain_[point] = strain;
  peak_intensity_[point] = strain_intensity(strain);
}

std::vector<double> IlyushinPointLaw::history() const {
  std::vector<double> h;
  h.reserve(1 + 5 * peak_intensity_.size());
  h.push_back(loading_ ? 1.0 : 0.0);
  for (std::size_t p = 0; p < peak_intensity_.size(); ++p) {
    h.insert(h.end(), {peak_strain_[p][0], peak_strain_[p][1], peak_strain_[p][2], peak_strain_[p][3],
                       peak_intensity_[p]});
  }
  return h;
}

void IlyushinPointLaw::restore(const std::vector<double>& h) {
  if (h.size() != 1 + 5 * peak_intensity_.size())
    throw std::invalid_argument("Ilyushin history of the wrong size for this mesh");
  loading_ = h[0] != 0.0;
  peak_strain_derivative_.clear();  // recorded for another peak (checkpoints do not carry them)
  for (std::size_t p = 0; p < peak_intensity_.size(); ++p) {
    peak_strain_[p] = VoigtVector(h[1 + 5 * p], h[2 + 5 * p], h[3 + 5 * p], h[4 + 5 * p]);
    peak_intensity_[p] = h[5 + 5 * p];
  }
}

std::optional<std::string> IlyushinPointLaw::history_violation(std::size_t point, const VoigtVector& strain) const {
  const VoigtVector& peak = peak_strain_[point];
  const double intensity = peak_intensity_[point];
  if (!(intensity >= 0.0) || !std::isfinite(intensity) || !peak.allFinite())
    return fmt::format("a peak strain intensity {:g} is no strain intensity", intensity);
  // Both are written by commit() from the same strain, so they agree to the last bit.
  if (intensity != strain_intensity(peak))
    return fmt::format("a peak strain intensity {:.17g} is not that of its peak strain ({:.17g})", intensity,
                       strain_intensity(peak));
  if (loading_ && peak != strain)
    return "a peak strain is not the committed strain although the load path is at its deepest point";
  return std::nullopt;
}

// ---------------------------------------------------------------------------------------------
J2PointLaw::J2PointLaw(const J2Law& law, std::size_t points)
    : law_(law), initial_yield_(law.initial_yield()), state_(points) {}

bool J2PointLaw::elastic(std::size_t point, const VoigtVector& strain) const {
  if (state_[point].equivalent_plastic_strain > 0.0) return false;
  // Virgin point: elastic while the von Mises stress of D eps stays below the initial yield
  // stress, i.e. while 3 mu e_u <= sigma_y(0).
  return 3.0 * law_.shear_modulus() * strain_intensity(strain) <= initial_yield_;
}

PointResponse J2PointLaw::respond(std::size_t point, const VoigtVector& strain) const {
  const J2Response j = law_.respond(strain, state_[point], time_step_);
  PointResponse r;
  r.stress = j.stress;
  r.tangent = j.tangent;
  r.strain_intensity = strain_intensity(strain);
  r.plastic = j.plastic;
  // The secant softening of the equivalent Ilyushin state, for display: 1 - sigma_eq / (3 mu e_u).
  r.omega = r.strain_intensity > 0 ? std::max(0.0, 1.0 - j.equivalent_stress / (3.0 * law_.shear_modulus() *
                                                                                  r.strain_intensity))
                                   : 0.0;
  return r;
}

void J2PointLaw::commit(std::size_t point, const VoigtVector& strain) {
  state_[point] = law_.respond(strain, state_[point], time_step_).state;
}

std::vector<double> J2PointLaw::history() const {
  std::vector<double> h;
  h.reserve(5 * state_.size());
  for (const J2State& s : state_) {
    h.insert(h.end(), {s.plastic_strain[0], s.plastic_strain[1], s.plastic_strain[2], s.plastic_strain[3],
                       s.equivalent_plastic_strain});
  }
  return h;
}

void J2PointLaw::restore(const std::vector<double>& h) {
  if (h.size() != 5 * state_.size()) throw std::invalid_argument("J2 history of the wrong size for this mesh");
  for (std::size_t p = 0; p < state_.size(); ++p) {
    state_[p].plastic_strain = Eigen::Vector4d(h[5 * p], h[5 * p + 1], h[5 * p + 2], h[5 * p + 3]);
    state_[p].equivalent_plastic_strain = h[5 * p + 4];
  }
}

namespace {
// Relative rounding a J2 history may carry: each return adds a deviator exact to ~1e-16 of its
// size, so 1e-9 leaves room for 10^7 returns and still refuses any edit a reader would notice.
constexpr double accumulated_rounding = 1e-9;
}  // namespace

std::optional<std::string> J2PointLaw::history_violation(std::size_t point, const VoigtVector& strain) const {
  const J2State& s = state_[point];
  const double path = s.equivalent_plastic_strain;
  if (!(path >= 0.0) || !std::isfinite(path) || !s.plastic_strain.allFinite())
    return fmt::format("an equivalent plastic strain {:g} is no accumulated plastic strain", path);
  const Eigen::Vector4d& p = s.plastic_strain;  // tensor components (11, 22, 33, 12)
  const double norm = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + 2.0 * p[3] * p[3]);
  if (std::abs(p[0] + p[1] + p[2]) > accumulated_rounding * path)
    return "a plastic strain is not a deviator (plastic flow keeps the volume)";
  if (norm > std::sqrt(1.5) * path * (1.0 + accumulated_rounding))
    return fmt::format("a plastic strain of norm {:g} is longer than the path its equivalent plastic strain {:g} "
                       "allows (|eps_p| <= sqrt(3/2) eps_p_bar)",
                       norm, path);
  // The instantaneous return: rate-independent rules' (a rate-dependent rule flows nothing in no time).
  const J2Response again = law_.respond(strain, s);
  if (again.state.equivalent_plastic_strain - path > accumulated_rounding * std::max(path, initial_yield_ / (3.0 * law_.shear_modulus())))
    return fmt::format("the committed strain lies outside the yield surface of its history (a converged state "
                       "would have returned {:g} more equivalent plastic strain)",
                       again.state.equivalent_plastic_strain - path);
  return std::nullopt;
}

}  // namespace indentsim
