#include "indentsim/plasticity.hpp"

#include <algorithm>

namespace indentsim {

IlyushinBulk::IlyushinBulk(const ElasticStiffness& elastic, const IlyushinLaw& law)
    : elastic_(elastic),
      mesh_(elastic.mesh()),
      pattern_(elastic.pattern()),
      law_(law),
      committed_u_(static_cast<std::size_t>(elastic.mesh().equations()), 0.0),
      strain_intensity_(4 * static_cast<std::size_t>(elastic.mesh().elements()), 0.0) {}

bool IlyushinBulk::yields(int ei, int ej, const double* u, std::array<VoigtVector, 4>& strains) const {
  strains = gauss_point_strains(mesh_, ei, ej, u);
  for (const VoigtVector& s : strains)
    if (strain_intensity(s) > law_.elastic_limit()) return true;
  return false;
}

void IlyushinBulk::internal_force(const double* u, double* f) {
  elastic_.multiply(u, f);
  const auto& points = gauss_points_2x2();
  std::array<VoigtVector, 4> strains;
  for (int ei = 0; ei < mesh_.elements_x(); ++ei)
    for (int ej = 0; ej < mesh_.elements_y(); ++ej) {
      if (!yields(ei, ej, u, strains)) continue;
      // Correction f_e(u) - K_e^elastic u_e, scattered onto the free equations.
      const Rectangle rect = mesh_.rectangle(ei, ej);
      ElementVector fe = -(elastic_.cached_matrix(ei, ej) * gather(mesh_, ei, ej, u));
      for (std::size_t g = 0; g < points.size(); ++g) {
        const StrainDisplacement b = strain_displacement(rect, points[g].xi, points[g].eta);
        fe.noalias() += (points[g].weight * rect.width * rect.height) * b.transpose() * law_.respond(strains[g]).stress;
      }
      const auto dofs = mesh_.element_dofs(ei, ej);
      for (int a = 0; a < 8; ++a) {
        const int eq = mesh_.equation(dofs[a]);
        if (eq >= 0) f[eq] += fe[a];
      }
    }
}

void IlyushinBulk::tangent(const double* u, double* values) {
  const auto& k = elastic_.values();
  std::copy(k.begin(), k.end(), values);
  const auto& points = gauss_points_2x2();
  std::array<VoigtVector, 4> strains;
  for (int ei = 0; ei < mesh_.elements_x(); ++ei)
    for (int ej = 0; ej < mesh_.elements_y(); ++ej) {
      if (!yields(ei, ej, u, strains)) continue;
      std::array<PlaneStrainMatrix, 4> d;
      for (std::size_t g = 0; g < points.size(); ++g) d[g] = law_.respond(strains[g]).tangent;
      const ElementMatrix correction = gauss_stiffness(mesh_.rectangle(ei, ej), d) - elastic_.cached_matrix(ei, ej);
      const std::int32_t* pos = pattern_.element_positions(mesh_.element(ei, ej));
      for (int a = 0; a < 8; ++a)
        for (int b = 0; b < 8; ++b)
          if (pos[8 * a + b] >= 0) values[pos[8 * a + b]] += correction(a, b);
    }
}

void IlyushinBulk::commit(const double* u) {
  std::copy(u, u + committed_u_.size(), committed_u_.begin());
  yielded_.clear();
  plastic_points_ = 0;
  max_strain_intensity_ = 0.0;
  for (int ei = 0; ei < mesh_.elements_x(); ++ei)
    for (int ej = 0; ej < mesh_.elements_y(); ++ej) {
      const auto strains = gauss_point_strains(mesh_, ei, ej, u);
      bool element_yielded = false;
      for (int g = 0; g < 4; ++g) {
        const double e_u = strain_intensity(strains[g]);
        strain_intensity_[4 * static_cast<std::size_t>(mesh_.element(ei, ej)) + g] = e_u;
        max_strain_intensity_ = std::max(max_strain_intensity_, e_u);
        if (e_u > law_.elastic_limit()) {
          ++plastic_points_;
          element_yielded = true;
        }
      }
      if (element_yielded) yielded_.push_back(mesh_.element(ei, ej));
    }
}

std::array<GaussPointState, 4> IlyushinBulk::gauss_point_states(int ei, int ej) const {
  const auto strains = gauss_point_strains(mesh_, ei, ej, committed_u_.data());
  std::array<GaussPointState, 4> states;
  for (int g = 0; g < 4; ++g) {
    const SecantResponse r = law_.respond(strains[g]);
    states[g] = {r.stress, r.stress33, r.strain_intensity, r.omega, r.plastic};
  }
  return states;
}

ElementMatrix IlyushinBulk::element_matrix(int ei, int ej) const {
  std::array<VoigtVector, 4> strains;
  if (!yields(ei, ej, committed_u_.data(), strains)) return elastic_.cached_matrix(ei, ej);
  std::array<PlaneStrainMatrix, 4> d;
  for (int g = 0; g < 4; ++g) d[g] = law_.respond(strains[g]).secant;
  return gauss_stiffness(mesh_.rectangle(ei, ej), d);
}

}  // namespace indentsim
