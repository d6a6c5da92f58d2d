#include "indentsim/materials/finite_strain_law.hpp"

#include <stdexcept>

namespace indentsim {

HenckyPointLaw::HenckyPointLaw(const ElasticMaterial& elastic, std::unique_ptr<PointLaw> law,
                               ElasticStressMeasure measure)
    : elastic_(elastic.stiffness()), law_(std::move(law)), measure_(measure) {}

FiniteStrainResponse HenckyPointLaw::respond(std::size_t point, const Deformation& F) const {
  const LogarithmicStrain e = logarithmic_strain(F, identity_tensor());
  FiniteStrainResponse r;
  ConstitutiveMatrix d = elastic_;
  if (law_) {
    const PointResponse small = law_->respond(point, e.strain);
    r.kirchhoff = small.stress;
    d = small.tangent;
    r.plastic = small.plastic;
  } else {
    r.kirchhoff = elastic_ * e.strain;
  }
  express_in_kirchhoff_stress(measure_, e.strain, r.kirchhoff, d);
  const NominalResponse p = nominal_response(F.F(), r.kirchhoff, d, e.derivative);
  r.nominal = p.stress;
  r.tangent = p.tangent;
  return r;
}

NominalTangent HenckyPointLaw::unloading_tangent(std::size_t point, const Deformation& F) const {
  const LogarithmicStrain e = logarithmic_strain(F, identity_tensor());
  VoigtVector tau = law_ ? law_->respond(point, e.strain).stress : VoigtVector(elastic_ * e.strain);
  ConstitutiveMatrix d = elastic_;
  express_in_kirchhoff_stress(measure_, e.strain, tau, d);
  return nominal_response(F.F(), tau, d, e.derivative).tangent;
}

void HenckyPointLaw::commit(std::size_t point, const Deformation& F) {
  if (law_) law_->commit(point, logarithmic_strain(F, identity_tensor()).strain);
}

void HenckyPointLaw::restore(const std::vector<double>& history) {
  if (law_) law_->restore(history);
  else if (!history.empty()) throw std::invalid_argument("an elastic Hencky law carries no history");
}

// ---------------------------------------------------------------------------------------------
J2LogStrainPointLaw::J2LogStrainPointLaw(const J2Law& law, std::size_t points, ElasticStressMeasure measure)
    : law_(law), state_(points), measure_(measure) {}

FiniteStrainResponse J2LogStrainPointLaw::respond(const Deformation& F, const J2FiniteState& old,
                                                  J2FiniteState* updated) const {
  const LogarithmicStrain trial = logarithmic_strain(F, old.inverse_plastic_metric);
  // The small-strain return from a state without plastic strain: its trial deviator is
  // 2 mu dev(e_e^tr), its pressure K tr(e_e^tr) = K ln J (plastic flow keeps the volume).
  J2State small;
  small.equivalent_plastic_strain = old.equivalent_plastic_strain;
  const J2Response j = law_.respond(trial.strain, small, time_step_);
  FiniteStrainResponse r;
  r.kirchhoff = j.stress;
  r.plastic = j.plastic;
  // J = e^{tr e^tr} = det F (det C_p = 1): the return map is the measure's, tau follows.
  ConstitutiveMatrix d = j.tangent;
  express_in_kirchhoff_stress(measure_, trial.strain, r.kirchhoff, d);
  const NominalResponse p = nominal_response(F.F(), r.kirchhoff, d, trial.derivative);
  r.nominal = p.stress;
  r.tangent = p.tangent;
  if (updated) {
    // e_e = e_e^tr - d eps_p (tensor components 11, 22, 33, 12 of the return's plastic strain).
    const Eigen::Vector4d& dp = j.state.plastic_strain;
    const VoigtVector elastic(trial.strain[0] - dp[0], trial.strain[1] - dp[1], trial.strain[2] - 2.0 * dp[3],
                              trial.strain[3] - dp[2]);
    updated->inverse_plastic_metric = pull_back(F.F(), exponential_of_twice(elastic));
    updated->equivalent_plastic_strain = j.state.equivalent_plastic_strain;
  }
  return r;
}

FiniteStrainResponse J2LogStrainPointLaw::respond(std::size_t point, const Deformation& F) const {
  return respond(F, state_[point], nullptr);
}

NominalTangent J2LogStrainPointLaw::unloading_tangent(std::size_t point, const Deformation& F) const {
  const LogarithmicStrain trial = logarithmic_strain(F, state_[point].inverse_plastic_metric);
  J2State small;
  small.equivalent_plastic_strain = state_[point].equivalent_plastic_strain;
  VoigtVector tau = law_.respond(trial.strain, small).stress;  // instantaneous: no flow
  ConstitutiveMatrix d = law_.elastic_stiffness();
  express_in_kirchhoff_stress(measure_, trial.strain, tau, d);
  return nominal_response(F.F(), tau, d, trial.derivative).tangent;
}

void J2LogStrainPointLaw::commit(std::size_t point, const Deformation& F) {
  J2FiniteState updated;
  respond(F, state_[point], &updated);
  // An elastic step leaves C_p^-1 as it was (exp(2 e_e^tr) pulled back is C_p^-1 to round-off).
  if (updated.equivalent_plastic_strain > state_[point].equivalent_plastic_strain) state_[point] = updated;
}

std::vector<double> J2LogStrainPointLaw::history() const {
  std::vector<double> h;
  h.reserve(5 * state_.size());
  for (const J2FiniteState& s : state_) {
    const SymmetricTensor& g = s.inverse_plastic_metric;
    h.insert(h.end(), {g[0], g[1], g[2], g[3], s.equivalent_plastic_strain});
  }
  return h;
}

void J2LogStrainPointLaw::restore(const std::vector<double>& h) {
  if (h.size() != 5 * state_.size()) throw std::invalid_argument("J2 history of the wrong size for this mesh");
  for (std::size_t p = 0; p < state_.size(); ++p) {
    state_[p].inverse_plastic_metric = SymmetricTensor(h[5 * p], h[5 * p + 1], h[5 * p + 2], h[5 * p + 3]);
    state_[p].equivalent_plastic_strain = h[5 * p + 4];
  }
}

}  // namespace indentsim
