#include "indentsim/solvers/finite_strain_bulk.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace indentsim {

FiniteStrainBulk::FiniteStrainBulk(const ElasticStiffness& elastic, std::unique_ptr<FiniteStrainPointLaw> law)
    : elastic_(elastic),
      mesh_(elastic.mesh()),
      law_(std::move(law)),
      slots_(whole_mesh_slots(elastic.mesh(), elastic.pattern())),
      committed_u_(static_cast<std::size_t>(elastic.mesh().equations()), 0.0) {
  // One quadrature per (column class, height class), as ElasticStiffness tabulates its matrices.
  for (const Rectangle& rect : mesh_.class_rectangles())
    quadrature_by_class_.push_back(mesh_.kinematics().finite_strain_quadrature(rect, mesh_.element_kind()));
}

bool FiniteStrainBulk::symmetric_tangent() const {
  return mesh_.element_kind() != ElementKind::bbar && law_->symmetric_tangent();
}

FiniteStrainBulk::KeptResponse FiniteStrainBulk::respond(int ei, int ej, const ElementVector& ue) const {
  KeptResponse r;
  r.ue = ue;
  const auto F = quadrature(ei, ej).law_gradients(ue);
  const std::size_t first = 4 * static_cast<std::size_t>(mesh_.element(ei, ej));
  for (std::size_t g = 0; g < 4; ++g) {
    const FiniteStrainResponse p = law_->respond(first + g, F[g]);
    r.stress[g] = p.nominal;
    r.tangent[g] = p.tangent;
  }
  return r;
}

void FiniteStrainBulk::add_force_corrections(const std::vector<ElementSlot>& slots, const double* u, double* f) const {
  kept_.clear();
  ElementVector ue;
  for (const ElementSlot& slot : slots) {
    for (int a = 0; a < 8; ++a) ue[a] = slot.unknowns[a] < 0 ? 0.0 : u[slot.unknowns[a]];
    KeptResponse& kept = kept_[mesh_.element(slot.ei, slot.ej)];
    kept = respond(slot.ei, slot.ej, ue);
    const ElementVector correction = quadrature(slot.ei, slot.ej).internal_force(ue, kept.stress) -
                                     elastic_.cached_matrix(slot.ei, slot.ej) * ue;
    for (int a = 0; a < 8; ++a)
      if (slot.unknowns[a] >= 0) f[slot.unknowns[a]] += correction[a];
  }
}

void FiniteStrainBulk::add_tangent_corrections(const std::vector<ElementSlot>& slots, const double* u,
                                               double* values) const {
  ElementVector ue;
  for (const ElementSlot& slot : slots) {
    for (int a = 0; a < 8; ++a) ue[a] = slot.unknowns[a] < 0 ? 0.0 : u[slot.unknowns[a]];
    const auto found = kept_.find(mesh_.element(slot.ei, slot.ej));
    const KeptResponse r = found != kept_.end() && found->second.ue == ue ? found->second : respond(slot.ei, slot.ej, ue);
    const ElementMatrix correction =
        quadrature(slot.ei, slot.ej).stiffness(ue, r.stress, r.tangent) - elastic_.cached_matrix(slot.ei, slot.ej);
    for (int p = 0; p < 64; ++p)
      if (slot.positions[p] >= 0) values[slot.positions[p]] += correction(p / 8, p % 8);
  }
}

std::optional<std::vector<double>> FiniteStrainBulk::unloading_tangent(const double* u) const {
  std::vector<double> values = elastic_.values();
  for (const ElementSlot& slot : slots_) {
    const ElementVector ue = gather(mesh_, slot.ei, slot.ej, u);
    const FiniteStrainQuadrature& q = quadrature(slot.ei, slot.ej);
    KeptResponse r = respond(slot.ei, slot.ej, ue);
    const auto F = q.law_gradients(ue);
    const std::size_t first = 4 * static_cast<std::size_t>(mesh_.element(slot.ei, slot.ej));
    for (std::size_t g = 0; g < 4; ++g) r.tangent[g] = law_->unloading_tangent(first + g, F[g]);
    const ElementMatrix correction = q.stiffness(ue, r.stress, r.tangent) - elastic_.cached_matrix(slot.ei, slot.ej);
    for (int p = 0; p < 64; ++p)
      if (slot.positions[p] >= 0) values[static_cast<std::size_t>(slot.positions[p])] += correction(p / 8, p % 8);
  }
  return values;
}

bool FiniteStrainBulk::departs_at(int ei, int ej, const double* u) const {
  const ElementVector ue = gather(mesh_, ei, ej, u);
  const FiniteStrainQuadrature& q = quadrature(ei, ej);
  const auto F = q.gradients(ue);
  for (const Deformation& f : F)
    if (f.H().cwiseAbs().maxCoeff() > small_strain_limit) return true;
  const std::size_t first = 4 * static_cast<std::size_t>(mesh_.element(ei, ej));
  const auto law_F = q.law_gradients(ue);
  for (std::size_t g = 0; g < 4; ++g)
    if (law_->respond(first + g, law_F[g]).plastic) return true;
  return false;
}

double FiniteStrainBulk::largest_gradient_outside(const std::vector<ElementSlot>& near) const {
  std::vector<char> inside(static_cast<std::size_t>(mesh_.elements()), 0);
  for (const ElementSlot& slot : near) inside[static_cast<std::size_t>(mesh_.element(slot.ei, slot.ej))] = 1;
  double largest = 0.0;
  for (int ei = 0; ei < mesh_.elements_x(); ++ei)
    for (int ej = 0; ej < mesh_.elements_y(); ++ej) {
      if (inside[static_cast<std::size_t>(mesh_.element(ei, ej))]) continue;
      for (const Deformation& f : quadrature(ei, ej).gradients(gather(mesh_, ei, ej, committed_u_.data())))
        largest = std::max(largest, f.H().cwiseAbs().maxCoeff());
    }
  return largest;
}

void FiniteStrainBulk::internal_force(const double* u, double* f) {
  elastic_.multiply(u, f);
  add_force_corrections(slots_, u, f);
}

void FiniteStrainBulk::tangent(const double* u, double* values) {
  const auto& k = elastic_.values();
  std::copy(k.begin(), k.end(), values);
  add_tangent_corrections(slots_, u, values);
}

void FiniteStrainBulk::commit(const double* u) {
  kept_.clear();
  std::copy(u, u + committed_u_.size(), committed_u_.begin());
  plastic_points_ = 0;
  max_strain_intensity_ = 0.0;
  for (int ei = 0; ei < mesh_.elements_x(); ++ei)
    for (int ej = 0; ej < mesh_.elements_y(); ++ej) {
      const auto F = quadrature(ei, ej).law_gradients(gather(mesh_, ei, ej, u));
      const std::size_t first = 4 * static_cast<std::size_t>(mesh_.element(ei, ej));
      for (std::size_t g = 0; g < 4; ++g) {
        // e_u of the logarithmic strain 1/2 ln(F F^T).
        max_strain_intensity_ =
            std::max(max_strain_intensity_, strain_intensity(logarithmic_strain(F[g], identity_tensor()).strain));
        law_->commit(first + g, F[g]);
        if (law_->has_yielded(first + g)) ++plastic_points_;
      }
    }
}

std::array<GaussPointState, 4> FiniteStrainBulk::gauss_point_states(int ei, int ej) const {
  const auto F = quadrature(ei, ej).law_gradients(gather(mesh_, ei, ej, committed_u_.data()));
  const std::size_t first = 4 * static_cast<std::size_t>(mesh_.element(ei, ej));
  std::array<GaussPointState, 4> states;
  for (std::size_t g = 0; g < 4; ++g) {
    const FiniteStrainResponse r = law_->respond(first + g, F[g]);
    // Cauchy stress sigma = tau / J on the current configuration.
    states[g] = {r.kirchhoff / jacobian(F[g].F()), strain_intensity(logarithmic_strain(F[g], identity_tensor()).strain), 0.0,
                 law_->has_yielded(first + g)};
  }
  return states;
}

ElementVector FiniteStrainBulk::element_force(int ei, int ej) const {
  const ElementVector ue = gather(mesh_, ei, ej, committed_u_.data());
  return quadrature(ei, ej).internal_force(ue, respond(ei, ej, ue).stress);
}

std::vector<double> FiniteStrainBulk::history() const {
  std::vector<double> h{static_cast<double>(plastic_points_), max_strain_intensity_, far_field_gradient_};
  const std::vector<double> law = law_->history();
  h.insert(h.end(), law.begin(), law.end());
  return h;
}

void FiniteStrainBulk::restore(const std::vector<double>& h, const double* u) {
  if (h.size() < 3) throw std::invalid_argument("finite-strain history too short");
  kept_.clear();
  plastic_points_ = static_cast<long>(h[0]);
  max_strain_intensity_ = h[1];
  far_field_gradient_ = h[2];
  law_->restore(std::vector<double>(h.begin() + 3, h.end()));
  std::copy(u, u + committed_u_.size(), committed_u_.begin());
}

}  // namespace indentsim
