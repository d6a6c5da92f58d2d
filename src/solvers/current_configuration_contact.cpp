#include "indentsim/solvers/current_configuration_contact.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "indentsim/solvers/contact.hpp"

namespace indentsim {

double surface_curvature(const PunchShape& punch, double x, double scale) {
  const double h = 1e-6 * scale;
  const double plus = punch.slope(x + h), minus = punch.slope(std::max(0.0, x - h));
  if (!std::isfinite(plus) || !std::isfinite(minus)) return 0.0;
  return (plus - minus) / (x + h - std::max(0.0, x - h));
}

std::optional<std::string> rim_cycling_cause(const PunchShape& punch) {
  const std::optional<double> rim = punch.rim();
  if (!rim) return std::nullopt;
  return fmt::format(
      "the contact set cycles at the {} punch's rim (x = {:.6g} m), where finite strain's gap ends: a node that "
      "slides outwards past it opens and springs back under the face, and the punch's corner and side wall are "
      "not modelled (docs/MODEL.md §12.3); run the case with geometry.strain = \"small\" (or \"auto\"), or "
      "give the punch's edge a finite slope as punch.shape = \"profile\"",
      punch.name(), *rim);
}

CurrentConfigurationContact::CurrentConfigurationContact(const Mesh& mesh, std::shared_ptr<const PunchShape> punch,
                                                         const StiffnessPattern& pattern,
                                                         const std::vector<double>& stiffness_values)
    : CurrentConfigurationContact(punch, mesh.kinematics().symmetry_factor(),
                                  contact_candidates(mesh, *punch, pattern, stiffness_values)) {}

CurrentConfigurationContact::CurrentConfigurationContact(std::shared_ptr<const PunchShape> punch, double symmetry_factor,
                                                         std::vector<ContactCandidate> candidates)
    : ContactDiscretization(std::move(punch), symmetry_factor, std::move(candidates), true),
      tangential_row_(tangential_row_indices(this->candidates())) {}

std::unique_ptr<ContactDiscretization> CurrentConfigurationContact::on_candidates(
    std::vector<ContactCandidate> candidates) const {
  return std::make_unique<CurrentConfigurationContact>(punch_shape(), symmetry_factor(), std::move(candidates));
}

double CurrentConfigurationContact::current_abscissa(std::size_t k, const double* u) const {
  const ContactCandidate& c = candidates()[k];
  return c.tangential_equation >= 0 ? c.x + u[c.tangential_equation] : c.x;
}

double CurrentConfigurationContact::current_penetration(std::size_t k, const double* u, double alpha) const {
  const double g = punch_shape()->surface_height(std::max(0.0, current_abscissa(k, u)));
  if (!std::isfinite(g)) return -std::numeric_limits<double>::infinity();
  return u[candidates()[k].equation] + alpha - g;
}

bool CurrentConfigurationContact::active(std::size_t k, const double* u, double alpha, double vertical_row_force) const {
  return candidates()[k].scale * current_penetration(k, u, alpha) >= vertical_row_force;
}

void CurrentConfigurationContact::write_residual_rows(const double* u, double alpha, const double* row_force,
                                                      double* f) const {
  const auto& cs = candidates();
  for (std::size_t k = 0; k < cs.size(); ++k) {
    const double r_v = row_force[k];
    const bool on = active(k, u, alpha, r_v);
    if (tangential_row_[k] >= 0) {
      const double r_u = row_force[tangential_row_[k]];
      f[cs[k].tangential_equation] = on ? r_u + punch_shape()->slope(std::max(0.0, current_abscissa(k, u))) * r_v : r_u;
    }
    f[cs[k].equation] = on ? cs[k].scale * current_penetration(k, u, alpha) : r_v;
  }
}

std::uint64_t CurrentConfigurationContact::write_jacobian_rows(
    const double* u, double alpha, const double* row_force, const StiffnessPattern& pattern,
    const std::vector<std::vector<std::int64_t>>& row_positions, double* values) const {
  std::uint64_t signature = 0xcbf29ce484222325ull;  // FNV-1a over the active flags
  const auto& cs = candidates();
  const auto& start = pattern.column_start();
  const auto& index = pattern.row_index();
  const double scale = cs.empty() ? 1.0 : std::max(cs.back().x, 1e-300);
  // The horizontal rows first: they read the vertical rows' stiffness before it is replaced.
  std::vector<char> on(cs.size());
  for (std::size_t k = 0; k < cs.size(); ++k) {
    on[k] = active(k, u, alpha, row_force[k]);
    signature = (signature ^ (on[k] ? 1u : 2u)) * 0x100000001b3ull;
    const int row = tangential_row_[k];
    if (row < 0 || !on[k]) continue;
    const ContactCandidate& c = cs[k];
    const double x = std::max(0.0, current_abscissa(k, u));
    const double slope = punch_shape()->slope(x);
    const auto& horizontal = row_positions[static_cast<std::size_t>(row)];
    const auto& vertical = row_positions[k];
    const auto t = static_cast<std::size_t>(c.tangential_equation), n = static_cast<std::size_t>(c.equation);
    if (vertical.size() != horizontal.size() ||
        !std::equal(index.begin() + start[t], index.begin() + start[t + 1], index.begin() + start[n]))
      throw std::logic_error("a surface node's two unknowns couple to different unknowns: its contact rows cannot be formed");
    // d(r_u + g'(x) r_v) = dr_u + g' dr_v + g'' r_v du.
    for (std::size_t j = 0; j < horizontal.size(); ++j) values[horizontal[j]] += slope * values[vertical[j]];
    values[pattern.diagonal_position(c.tangential_equation)] += surface_curvature(*punch_shape(), x, scale) * row_force[k];
  }
  for (std::size_t k = 0; k < cs.size(); ++k) {
    if (!on[k]) continue;
    const ContactCandidate& c = cs[k];
    // d(c (v + alpha - g(X + u))) = c (dv - g'(x) du).
    for (std::int64_t p : row_positions[k]) values[p] = 0.0;
    values[pattern.diagonal_position(c.equation)] = c.scale;
    if (c.tangential_equation < 0) continue;
    const auto n = static_cast<std::size_t>(c.equation);
    const auto first = index.begin() + start[n], last = index.begin() + start[n + 1];
    const auto at = std::lower_bound(first, last, static_cast<std::int64_t>(c.tangential_equation));
    values[row_positions[k][static_cast<std::size_t>(at - first)]] =
        -c.scale * punch_shape()->slope(std::max(0.0, current_abscissa(k, u)));
  }
  return signature;
}

void CurrentConfigurationContact::write_parameter_derivative_rows(const double* u, double alpha, const double* row_force,
                                                                  const double* d_row_force, double,
                                                                  double* df) const {
  const auto& cs = candidates();
  for (std::size_t k = 0; k < cs.size(); ++k) {
    const bool on = active(k, u, alpha, row_force[k]);
    if (tangential_row_[k] >= 0) {
      const double dr_u = d_row_force[tangential_row_[k]];
      df[cs[k].tangential_equation] =
          on ? dr_u + punch_shape()->slope(std::max(0.0, current_abscissa(k, u))) * d_row_force[k] : dr_u;
    }
    df[cs[k].equation] = on ? 0.0 : d_row_force[k];
  }
}

void CurrentConfigurationContact::write_depth_derivative_rows(const double* u, double alpha, const double* row_force,
                                                              double* df) const {
  const auto& cs = candidates();
  for (std::size_t k = 0; k < cs.size(); ++k) {
    if (cs[k].tangential_equation >= 0) df[cs[k].tangential_equation] = 0.0;
    df[cs[k].equation] = active(k, u, alpha, row_force[k]) ? cs[k].scale : 0.0;
  }
}

bool CurrentConfigurationContact::touches(const double* u, double alpha) const {
  for (std::size_t k = 0; k < candidates().size(); ++k)
    if (current_penetration(k, u, alpha) >= 0.0) return true;
  return false;
}

std::vector<double> CurrentConfigurationContact::admissibility_violation(const double* u, double alpha) const {
  std::vector<double> f;
  for (std::size_t k = 0; k < candidates().size(); ++k)
    f.push_back(std::max(0.0, candidates()[k].scale * current_penetration(k, u, alpha)));
  return f;
}

ContactResult CurrentConfigurationContact::evaluate(const double* u, const double* internal_force, double alpha) const {
  const auto& cs = candidates();
  ContactResult r = ContactResult::open(cs.size());
  double half_model_force = 0.0;
  for (std::size_t k = 0; k < cs.size(); ++k) {
    const double r_v = internal_force[cs[k].equation];
    const bool on = active(k, u, alpha, r_v);
    r.in_contact[k] = on;
    const double p = current_penetration(k, u, alpha);
    r.gap[k] = on ? 0.0 : (std::isfinite(p) ? -p : 0.0);
    // P is the punch's vertical force: the vertical component lambda of each node's normal force.
    if (on) {
      r.nodal_force[k] = -r_v;
      half_model_force += -r_v;
      ++r.contact_nodes;
      r.outermost = static_cast<int>(k);
    }
  }
  r.force = symmetry_factor() * half_model_force;
  r.half_width = half_width(u, alpha, r);
  return r;
}

double CurrentConfigurationContact::half_width(const double* u, double, const ContactResult& contact) const {
  if (contact.outermost < 0 || !(contact.force > 0.0)) return 0.0;
  // The edge law of contact_edge_from_open_side on the current surface: the candidates at their
  // current abscissae (the surface stays ordered: elements do not invert).
  std::vector<ContactCandidate> current = candidates();
  for (std::size_t k = 0; k < current.size(); ++k) current[k].x = current_abscissa(k, u);
  return contact_edge_from_open_side(current, contact.gap, contact.outermost);
}

}  // namespace indentsim
