#include "indentsim/solvers/inelastic_bulk.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

namespace indentsim {

// ---------------------------------------------------------------------------------------------
InelasticBulk::InelasticBulk(const ElasticStiffness& elastic, std::unique_ptr<PointLaw> law)
    : elastic_(elastic),
      mesh_(elastic.mesh()),
      pattern_(elastic.pattern()),
      law_(std::move(law)),
      slots_(whole_mesh_slots(elastic.mesh(), elastic.pattern())),
      committed_u_(static_cast<std::size_t>(elastic.mesh().equations()), 0.0) {}

bool InelasticBulk::inelastic(int ei, int ej, const double* u, std::array<VoigtVector, 4>& strains) const {
  return inelastic(ei, ej, gather(mesh_, ei, ej, u), strains);
}

bool InelasticBulk::inelastic(int ei, int ej, const ElementVector& ue, std::array<VoigtVector, 4>& strains) const {
  strains = elastic_.quadrature(ei, ej).strains(ue);
  const std::size_t first = 4 * static_cast<std::size_t>(mesh_.element(ei, ej));
  for (std::size_t g = 0; g < 4; ++g)
    if (!law_->elastic(first + g, strains[g])) return true;
  return false;
}

bool InelasticBulk::departs_at(int ei, int ej, const double* u) const {
  std::array<VoigtVector, 4> strains;
  return inelastic(ei, ej, u, strains);
}

ElementVector InelasticBulk::element_force(int ei, int ej, const std::array<VoigtVector, 4>& strains,
                                           std::array<ConstitutiveMatrix, 4>* tangents) const {
  const std::size_t first = 4 * static_cast<std::size_t>(mesh_.element(ei, ej));
  std::array<VoigtVector, 4> stresses;
  for (std::size_t g = 0; g < 4; ++g) {
    const PointResponse r = law_->respond(first + g, strains[g]);
    stresses[g] = r.stress;
    if (tangents) (*tangents)[g] = r.tangent;
  }
  return elastic_.quadrature(ei, ej).internal_force(stresses);
}

void InelasticBulk::add_force_corrections(const std::vector<ElementSlot>& slots, const double* u, double* f) const {
  kept_.clear();
  ElementVector ue;
  std::array<VoigtVector, 4> strains;
  for (const ElementSlot& slot : slots) {
    for (int a = 0; a < 8; ++a) ue[a] = slot.unknowns[a] < 0 ? 0.0 : u[slot.unknowns[a]];
    if (!inelastic(slot.ei, slot.ej, ue, strains)) continue;
    KeptResponse& kept = kept_[mesh_.element(slot.ei, slot.ej)];
    kept.ue = ue;
    const ElementVector correction =
        element_force(slot.ei, slot.ej, strains, &kept.tangents) - elastic_.cached_matrix(slot.ei, slot.ej) * ue;
    for (int a = 0; a < 8; ++a)
      if (slot.unknowns[a] >= 0) f[slot.unknowns[a]] += correction[a];
  }
}

void InelasticBulk::add_tangent_corrections(const std::vector<ElementSlot>& slots, const double* u,
                                            double* values) const {
  ElementVector ue;
  std::array<VoigtVector, 4> strains;
  std::array<ConstitutiveMatrix, 4> d;
  for (const ElementSlot& slot : slots) {
    for (int a = 0; a < 8; ++a) ue[a] = slot.unknowns[a] < 0 ? 0.0 : u[slot.unknowns[a]];
    const int element = mesh_.element(slot.ei, slot.ej);
    const auto kept = kept_.find(element);
    if (kept != kept_.end() && kept->second.ue == ue) {
      d = kept->second.tangents;  // the force pass at this u ran the return map already
    } else {
      if (!inelastic(slot.ei, slot.ej, ue, strains)) continue;
      const std::size_t first = 4 * static_cast<std::size_t>(element);
      for (std::size_t g = 0; g < 4; ++g) d[g] = law_->respond(first + g, strains[g]).tangent;
    }
    const ElementMatrix correction =
        elastic_.quadrature(slot.ei, slot.ej).stiffness(d) - elastic_.cached_matrix(slot.ei, slot.ej);
    for (int p = 0; p < 64; ++p)
      if (slot.positions[p] >= 0) values[slot.positions[p]] += correction(p / 8, p % 8);
  }
}

bool InelasticBulk::add_parameter_derivative(const std::vector<ElementSlot>& slots, const double* u,
                                             MaterialParameter parameter, double* df) const {
  ElementVector ue;
  std::array<VoigtVector, 4> strains, stress_derivatives;
  for (const ElementSlot& slot : slots) {
    for (int a = 0; a < 8; ++a) ue[a] = slot.unknowns[a] < 0 ? 0.0 : u[slot.unknowns[a]];
    // An element elastic at u has sigma = D eps at all four points: no dependence on e0, kappa, n.
    if (!inelastic(slot.ei, slot.ej, ue, strains)) continue;
    const std::size_t first = 4 * static_cast<std::size_t>(mesh_.element(slot.ei, slot.ej));
    for (std::size_t g = 0; g < 4; ++g) {
      const std::optional<VoigtVector> d = law_->stress_parameter_derivative(first + g, strains[g], parameter);
      if (!d) return false;
      stress_derivatives[g] = *d;
    }
    // f_e = int B^T sigma is linear in the stresses (B-bar included).
    const ElementVector d_force = elastic_.quadrature(slot.ei, slot.ej).internal_force(stress_derivatives);
    for (int a = 0; a < 8; ++a)
      if (slot.unknowns[a] >= 0) df[slot.unknowns[a]] += d_force[a];
  }
  return true;
}

void InelasticBulk::record_strain_derivatives(const std::vector<ElementSlot>& slots, const double* du,
                                              MaterialParameter parameter) {
  // The strains are linear in the displacements (B-bar included): d eps = B du.  Points outside
  // the slots (a condensed far field, elastic by construction) keep d eps = 0; their stress on
  // either branch is D eps and does not depend on eps*.
  PointStrains d_strain(4 * static_cast<std::size_t>(mesh_.elements()), VoigtVector::Zero());
  ElementVector due;
  for (const ElementSlot& slot : slots) {
    for (int a = 0; a < 8; ++a) due[a] = slot.unknowns[a] < 0 ? 0.0 : du[slot.unknowns[a]];
    const std::array<VoigtVector, 4> strains = elastic_.quadrature(slot.ei, slot.ej).strains(due);
    const std::size_t first = 4 * static_cast<std::size_t>(mesh_.element(slot.ei, slot.ej));
    for (std::size_t g = 0; g < 4; ++g) d_strain[first + g] = strains[g];
  }
  law_->record_strain_derivatives(parameter, std::move(d_strain));
}

void InelasticBulk::internal_force(const double* u, double* f) {
  elastic_.multiply(u, f);
  add_force_corrections(slots_, u, f);
}

void InelasticBulk::tangent(const double* u, double* values) {
  const auto& k = elastic_.values();
  std::copy(k.begin(), k.end(), values);
  add_tangent_corrections(slots_, u, values);
}

void InelasticBulk::commit(const double* u) {
  kept_.clear();  // the history moves: responses at the old history are stale
  std::copy(u, u + committed_u_.size(), committed_u_.begin());
  plastic_points_ = 0;
  max_strain_intensity_ = 0.0;
  visit_points(u, [&](std::size_t point, const VoigtVector& strain, int, int, std::size_t) {
    max_strain_intensity_ = std::max(max_strain_intensity_, strain_intensity(strain));
    law_->commit(point, strain);
    if (law_->has_yielded(point)) ++plastic_points_;
  });
}

std::vector<double> InelasticBulk::history() const {
  std::vector<double> h{static_cast<double>(plastic_points_), max_strain_intensity_};
  const std::vector<double> law = law_->history();
  h.insert(h.end(), law.begin(), law.end());
  return h;
}

void InelasticBulk::restore(const std::vector<double>& h, const double* u) {
  if (h.size() < 2) throw std::invalid_argument("inelastic history too short");
  kept_.clear();
  plastic_points_ = static_cast<long>(h[0]);
  max_strain_intensity_ = h[1];
  law_->restore(std::vector<double>(h.begin() + 2, h.end()));
  std::copy(u, u + committed_u_.size(), committed_u_.begin());
}

std::optional<std::string> InelasticBulk::history_violation() const {
  long yielded = 0;
  double largest = 0.0;
  std::optional<std::string> violation;
  visit_points(committed_u_.data(), [&](std::size_t point, const VoigtVector& strain, int ei, int ej, std::size_t g) {
    largest = std::max(largest, strain_intensity(strain));
    if (law_->has_yielded(point)) ++yielded;
    if (violation) return;
    if (const auto wrong = law_->history_violation(point, strain))
      violation = fmt::format("Gauss point {} of element ({}, {}): {}", g, ei, ej, *wrong);
  });
  if (violation) return violation;
  // commit() counts both from the same points and strains: equal to the last bit.
  if (plastic_points_ != yielded || max_strain_intensity_ != largest)
    return fmt::format("it counts {} yielded Gauss points and a largest strain intensity {:.17g}, where its points "
                       "and the displacement give {} and {:.17g}",
                       plastic_points_, max_strain_intensity_, yielded, largest);
  return std::nullopt;
}

std::array<GaussPointState, 4> InelasticBulk::gauss_point_states(int ei, int ej) const {
  const auto strains = elastic_.quadrature(ei, ej).strains(gather(mesh_, ei, ej, committed_u_.data()));
  const std::size_t first = 4 * static_cast<std::size_t>(mesh_.element(ei, ej));
  std::array<GaussPointState, 4> states;
  for (std::size_t g = 0; g < 4; ++g) {
    const PointResponse r = law_->respond(first + g, strains[g]);
    states[g] = {r.stress, r.strain_intensity, r.omega, law_->has_yielded(first + g)};
  }
  return states;
}

ElementVector InelasticBulk::element_force(int ei, int ej) const {
  std::array<VoigtVector, 4> strains;
  if (!inelastic(ei, ej, committed_u_.data(), strains))
    return elastic_.cached_matrix(ei, ej) * gather(mesh_, ei, ej, committed_u_.data());
  return element_force(ei, ej, strains);
}

}  // namespace indentsim
