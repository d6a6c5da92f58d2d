#include "indentsim/solvers/coulomb_current_configuration_contact.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace indentsim {

namespace {

// Sliding is reported where |q| reaches the cone to this relative tolerance (the Newton solve
// converges the rows to solver.tolerance, far below it), as in coulomb_contact.cpp.
constexpr double slip_report_tolerance = 1e-6;

/// Where column `column` sits among the positions of row `row` (rows and columns of a symmetric
/// pattern pair up).
std::size_t position_in_row(const StiffnessPattern& pattern, int row, int column) {
  const auto& start = pattern.column_start();
  const auto& index = pattern.row_index();
  const auto first = index.begin() + start[static_cast<std::size_t>(row)];
  const auto last = index.begin() + start[static_cast<std::size_t>(row) + 1];
  return static_cast<std::size_t>(std::lower_bound(first, last, static_cast<std::int64_t>(column)) - first);
}

}  // namespace

CoulombCurrentConfigurationContact::CoulombCurrentConfigurationContact(const Mesh& mesh,
                                                                       std::shared_ptr<const PunchShape> punch,
                                                                       const StiffnessPattern& pattern,
                                                                       const std::vector<double>& stiffness_values,
                                                                       double mu)
    : CoulombCurrentConfigurationContact(punch, mesh.kinematics().symmetry_factor(),
                                         contact_candidates(mesh, *punch, pattern, stiffness_values), mu, {}) {}

CoulombCurrentConfigurationContact::CoulombCurrentConfigurationContact(std::shared_ptr<const PunchShape> punch,
                                                                       double symmetry_factor,
                                                                       std::vector<ContactCandidate> candidates,
                                                                       double mu, std::vector<double> committed)
    : ContactDiscretization(std::move(punch), symmetry_factor, std::move(candidates), true),
      geometry_(punch_shape(), symmetry_factor, this->candidates()),
      mu_(mu),
      committed_(std::move(committed)),
      tangential_row_(tangential_row_indices(this->candidates())) {
  if (!(mu_ > 0.0))
    throw std::invalid_argument("Coulomb friction needs a coefficient > 0 (0 is the frictionless contact)");
  committed_.resize(this->candidates().size(), 0.0);
}

bool CoulombCurrentConfigurationContact::sticking() const { return std::isinf(mu_); }

CoulombCurrentConfigurationContact::NodeState CoulombCurrentConfigurationContact::node_state(
    std::size_t k, const double* u, double alpha, const double* row_force) const {
  const ContactCandidate& c = candidates()[k];
  NodeState s;
  s.penetration = geometry_.current_penetration(k, u, alpha);
  const double r_v = row_force[k];
  const int row = tangential_row_[k];
  if (row < 0) {
    // The axis node: its horizontal force is the symmetry condition's, the vertical row is
    // node-to-rigid's.
    s.lambda = -r_v;
  } else {
    const double x = std::max(0.0, geometry_.current_abscissa(k, u));
    const double slope = punch().slope(x);
    if (std::isfinite(slope) && std::isfinite(s.penetration)) {
      s.slope = slope;
      s.curvature = surface_curvature(punch(), x, std::max(candidates().back().x, 1e-300));
    }
    s.weight = 1.0 + s.slope * s.slope;
    const double r_u = row_force[row];
    s.lambda = (s.slope * r_u - r_v) / s.weight;
    s.q = (r_u + s.slope * r_v) / s.weight;
  }
  s.normal_active = c.scale * s.penetration >= -s.lambda;
  s.augmented = std::max(0.0, c.scale * s.penetration + s.lambda);
  return s;
}

CoulombCurrentConfigurationContact::Branch CoulombCurrentConfigurationContact::branch(std::size_t k, const double* u,
                                                                                      double alpha,
                                                                                      const double* row_force) const {
  const NodeState s = node_state(k, u, alpha, row_force);
  if (!(s.augmented > 0.0)) return Branch::open;
  if (sticking()) return Branch::stick;
  const ContactCandidate& c = candidates()[k];
  const double z = s.q - c.tangential_scale * (u[c.tangential_equation] - committed_[k]);
  if (std::abs(z) <= mu_ * s.augmented) return Branch::stick;
  return z > 0.0 ? Branch::slip_positive : Branch::slip_negative;
}

std::unique_ptr<ContactDiscretization> CoulombCurrentConfigurationContact::on_candidates(
    std::vector<ContactCandidate> candidates) const {
  std::vector<double> committed(committed_.begin(),
                                committed_.begin() + static_cast<std::ptrdiff_t>(std::min(candidates.size(), committed_.size())));
  return std::make_unique<CoulombCurrentConfigurationContact>(punch_shape(), symmetry_factor(), std::move(candidates),
                                                              mu_, std::move(committed));
}

void CoulombCurrentConfigurationContact::hold_committed_state(const double* u_committed) {
  const auto& cs = candidates();
  for (std::size_t k = 0; k < cs.size(); ++k)
    committed_[k] = cs[k].tangential_equation >= 0 ? u_committed[cs[k].tangential_equation] : 0.0;
}

std::unique_ptr<ContactDiscretization> CoulombCurrentConfigurationContact::at_load_reversal(const double* u) const {
  auto reversed = std::make_unique<CoulombCurrentConfigurationContact>(punch_shape(), symmetry_factor(), candidates(),
                                                                       mu_, std::vector<double>{});
  reversed->hold_committed_state(u);
  return reversed;
}

void CoulombCurrentConfigurationContact::write_residual_rows(const double* u, double alpha, const double* row_force,
                                                             double* f) const {
  const auto& cs = candidates();
  for (std::size_t k = 0; k < cs.size(); ++k) {
    const ContactCandidate& c = cs[k];
    const NodeState s = node_state(k, u, alpha, row_force);
    f[c.equation] = s.normal_active ? c.scale * s.penetration : -s.lambda;
    if (tangential_row_[k] < 0) continue;
    double& value = f[c.tangential_equation];
    switch (branch(k, u, alpha, row_force)) {
      case Branch::open: value = s.q; break;
      case Branch::stick: value = c.tangential_scale * (u[c.tangential_equation] - committed_[k]); break;
      case Branch::slip_positive: value = s.q - mu_ * s.augmented; break;
      case Branch::slip_negative: value = s.q + mu_ * s.augmented; break;
    }
  }
}

std::uint64_t CoulombCurrentConfigurationContact::write_jacobian_rows(
    const double* u, double alpha, const double* row_force, const StiffnessPattern& pattern,
    const std::vector<std::vector<std::int64_t>>& row_positions, double* values) const {
  std::uint64_t signature = 0xcbf29ce484222325ull;  // FNV-1a over the normal rows' and the branches' flags
  const auto mix = [&signature](unsigned flag) { signature = (signature ^ flag) * 0x100000001b3ull; };
  const auto& cs = candidates();
  const auto& start = pattern.column_start();
  const auto& index = pattern.row_index();
  std::vector<double> k_t, k_n;
  for (std::size_t k = 0; k < cs.size(); ++k) {
    const ContactCandidate& c = cs[k];
    const NodeState s = node_state(k, u, alpha, row_force);
    mix(s.normal_active ? 1u : 2u);
    const auto& normal = row_positions[k];
    const int row = tangential_row_[k];
    if (row < 0) {
      if (!s.normal_active) continue;
      for (std::int64_t p : normal) values[p] = 0.0;
      values[pattern.diagonal_position(c.equation)] = c.scale;
      continue;
    }
    const Branch b = branch(k, u, alpha, row_force);
    mix(static_cast<unsigned>(b) + 3u);
    const auto& tangential = row_positions[static_cast<std::size_t>(row)];
    const auto t = static_cast<std::size_t>(c.tangential_equation), n = static_cast<std::size_t>(c.equation);
    if (normal.size() != tangential.size() ||
        !std::equal(index.begin() + start[t], index.begin() + start[t + 1], index.begin() + start[n]))
      throw std::logic_error("a surface node's two unknowns couple to different unknowns: its contact rows cannot be formed");
    k_t.resize(tangential.size());
    k_n.resize(normal.size());
    for (std::size_t j = 0; j < normal.size(); ++j) {
      k_t[j] = values[tangential[j]];
      k_n[j] = values[normal[j]];
    }
    const std::size_t at_t = position_in_row(pattern, c.equation, c.tangential_equation);
    const std::size_t at_n = position_in_row(pattern, c.equation, c.equation);
    // d lambda = (g' dr_u - dr_v + g'' r_u du) / w - lambda 2 g' g'' du / w, and
    // d q      = (dr_u + g' dr_v + g'' r_v du) / w - q      2 g' g'' du / w, from w = 1 + g'^2.
    const double g1 = s.slope, g2 = s.curvature, w = s.weight;
    const double r_u = row_force[row], r_v = row_force[k];
    const double lambda_t = g1 / w, lambda_n = -1.0 / w, lambda_du = (g2 * r_u - 2.0 * g1 * g2 * s.lambda) / w;
    const double q_t = 1.0 / w, q_n = g1 / w, q_du = (g2 * r_v - 2.0 * g1 * g2 * s.q) / w;
    // The normal row: c (dv - g' du) when active, else -d lambda.
    if (s.normal_active) {
      for (std::int64_t p : normal) values[p] = 0.0;
      values[normal[at_n]] = c.scale;
      values[normal[at_t]] = -c.scale * g1;
    } else {
      for (std::size_t j = 0; j < normal.size(); ++j) values[normal[j]] = -(lambda_t * k_t[j] + lambda_n * k_n[j]);
      values[normal[at_t]] -= lambda_du;
    }
    // The tangential row.
    switch (b) {
      case Branch::open:
        for (std::size_t j = 0; j < tangential.size(); ++j) values[tangential[j]] = q_t * k_t[j] + q_n * k_n[j];
        values[tangential[at_t]] += q_du;
        break;
      case Branch::stick:
        for (std::int64_t p : tangential) values[p] = 0.0;
        values[tangential[at_t]] = c.tangential_scale;
        break;
      case Branch::slip_positive:
      case Branch::slip_negative: {
        // d(q - s mu l) with l = c p + lambda > 0: dq - s mu (c (dv - g' du) + d lambda).
        const double m = (b == Branch::slip_positive ? 1.0 : -1.0) * mu_;
        for (std::size_t j = 0; j < tangential.size(); ++j)
          values[tangential[j]] = (q_t - m * lambda_t) * k_t[j] + (q_n - m * lambda_n) * k_n[j];
        values[tangential[at_t]] += q_du - m * lambda_du + m * c.scale * g1;
        values[tangential[at_n]] -= m * c.scale;
        break;
      }
    }
  }
  return signature;
}

void CoulombCurrentConfigurationContact::write_parameter_derivative_rows(const double* u, double alpha,
                                                                         const double* row_force,
                                                                         const double* d_row_force,
                                                                         double d_log_stiffness, double* df) const {
  const auto& cs = candidates();
  for (std::size_t k = 0; k < cs.size(); ++k) {
    const ContactCandidate& c = cs[k];
    const NodeState s = node_state(k, u, alpha, row_force);
    const int row = tangential_row_[k];
    const double dr_v = d_row_force[k], dr_u = row < 0 ? 0.0 : d_row_force[row];
    const double d_lambda = row < 0 ? -dr_v : (s.slope * dr_u - dr_v) / s.weight;
    // c moves with the stiffness: d(c p) = c p d ln K.
    const double d_cp = std::isfinite(s.penetration) ? c.scale * s.penetration * d_log_stiffness : 0.0;
    df[c.equation] = s.normal_active ? d_cp : -d_lambda;
    if (row < 0) continue;
    const double d_q = (dr_u + s.slope * dr_v) / s.weight;
    double& value = df[c.tangential_equation];
    switch (branch(k, u, alpha, row_force)) {
      case Branch::open: value = d_q; break;
      case Branch::stick:
        value = c.tangential_scale * d_log_stiffness * (u[c.tangential_equation] - committed_[k]);
        break;
      case Branch::slip_positive: value = d_q - mu_ * (d_cp + d_lambda); break;
      case Branch::slip_negative: value = d_q + mu_ * (d_cp + d_lambda); break;
    }
  }
}

void CoulombCurrentConfigurationContact::write_depth_derivative_rows(const double* u, double alpha,
                                                                     const double* row_force, double* df) const {
  const auto& cs = candidates();
  for (std::size_t k = 0; k < cs.size(); ++k) {
    const ContactCandidate& c = cs[k];
    const NodeState s = node_state(k, u, alpha, row_force);
    df[c.equation] = s.normal_active ? c.scale : 0.0;
    if (tangential_row_[k] < 0) continue;
    // The slip rows' l = c p + lambda moves with alpha through p.
    switch (branch(k, u, alpha, row_force)) {
      case Branch::slip_positive: df[c.tangential_equation] = -mu_ * c.scale; break;
      case Branch::slip_negative: df[c.tangential_equation] = mu_ * c.scale; break;
      default: df[c.tangential_equation] = 0.0; break;
    }
  }
}

ContactResult CoulombCurrentConfigurationContact::evaluate(const double* u, const double* internal_force,
                                                           double alpha) const {
  const auto& cs = candidates();
  const auto& rows = row_equations();
  std::vector<double> row_force(rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) row_force[i] = internal_force[rows[i]];
  ContactResult r = ContactResult::open(cs.size());
  double half_model_force = 0.0;
  for (std::size_t k = 0; k < cs.size(); ++k) {
    const NodeState s = node_state(k, u, alpha, row_force.data());
    r.in_contact[k] = s.normal_active;
    r.gap[k] = s.normal_active ? 0.0 : (std::isfinite(s.penetration) ? -s.penetration : 0.0);
    if (!s.normal_active) continue;
    // P is the punch's vertical force: the vertical components of the normal and the friction
    // force together, -r_v.
    const double r_v = row_force[k];
    r.nodal_force[k] = -r_v;
    half_model_force += -r_v;
    ++r.contact_nodes;
    r.outermost = static_cast<int>(k);
    if (tangential_row_[k] < 0) continue;
    r.tangential_force[k] = s.q * std::sqrt(s.weight);
    r.sliding[k] = !sticking() && s.lambda > 0.0 && std::abs(s.q) >= (1.0 - slip_report_tolerance) * mu_ * s.lambda;
  }
  r.force = symmetry_factor() * half_model_force;
  r.half_width = half_width(u, alpha, r);
  return r;
}

double CoulombCurrentConfigurationContact::half_width(const double* u, double alpha, const ContactResult& contact) const {
  return geometry_.half_width(u, alpha, contact);
}

bool CoulombCurrentConfigurationContact::touches(const double* u, double alpha) const {
  return geometry_.touches(u, alpha);
}

std::vector<double> CoulombCurrentConfigurationContact::admissibility_violation(const double* u, double alpha) const {
  return geometry_.admissibility_violation(u, alpha);
}

}  // namespace indentsim
