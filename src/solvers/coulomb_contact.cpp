#include "indentsim/solvers/coulomb_contact.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "indentsim/solvers/contact.hpp"

namespace indentsim {

namespace {

// Slipping is reported where |q| reaches the cone to this relative tolerance (the Newton solve
// converges the rows to solver.tolerance, far below it).
constexpr double slip_report_tolerance = 1e-6;

// Alart and Curnier's augmented normal force max(0, c_k (v_k + alpha - g_k) - r_k): the punch's
// force -r_k at every solution (where a contact node's penetration vanishes), and 0 exactly where
// node-to-rigid's normal row opens (c_k pen_k = r_k), so the cone's radius, and with it F^t, is
// continuous across the normal switch as well.
double augmented_normal_force(const ContactCandidate& c, double normal_force_row, double v, double alpha) {
  return std::max(0.0, c.scale * penetration(c, v, alpha) - normal_force_row);
}

}  // namespace

CoulombNodeToRigidContact::CoulombNodeToRigidContact(const Mesh& mesh, std::shared_ptr<const PunchShape> punch,
                                                     const StiffnessPattern& pattern,
                                                     const std::vector<double>& stiffness_values, double mu)
    : CoulombNodeToRigidContact(punch, mesh.kinematics().symmetry_factor(),
                                contact_candidates(mesh, *punch, pattern, stiffness_values), mu, {}) {}

CoulombNodeToRigidContact::CoulombNodeToRigidContact(std::shared_ptr<const PunchShape> punch, double symmetry_factor,
                                                     std::vector<ContactCandidate> candidates, double mu,
                                                     std::vector<double> committed)
    : ContactDiscretization(std::move(punch), symmetry_factor, std::move(candidates), true),
      normal_(punch_shape(), symmetry_factor, this->candidates()),
      mu_(mu),
      committed_(std::move(committed)),
      tangential_row_(tangential_row_indices(this->candidates())) {
  if (!(mu_ > 0.0)) throw std::invalid_argument("Coulomb friction needs a coefficient > 0 (0 is node-to-rigid contact)");
  committed_.resize(this->candidates().size(), 0.0);
}

bool CoulombNodeToRigidContact::sticking() const { return std::isinf(mu_); }

CoulombNodeToRigidContact::Branch CoulombNodeToRigidContact::branch(std::size_t k, const double* u, double alpha,
                                                                    double normal_force_row,
                                                                    double tangential_force_row) const {
  const ContactCandidate& c = candidates()[k];
  const double l = augmented_normal_force(c, normal_force_row, u[c.equation], alpha);
  if (!(l > 0.0)) return Branch::open;
  if (sticking()) return Branch::stick;
  // z = q - c^t ds, q = r^t (the punch's force along +x balances the internal force); the
  // cone's radius mu l.
  const double z = tangential_force_row - c.tangential_scale * (u[c.tangential_equation] - committed_[k]);
  const double radius = mu_ * l;
  if (std::abs(z) <= radius) return Branch::stick;
  return z > 0.0 ? Branch::slip_positive : Branch::slip_negative;
}

std::unique_ptr<ContactDiscretization> CoulombNodeToRigidContact::on_candidates(
    std::vector<ContactCandidate> candidates) const {
  std::vector<double> committed(committed_.begin(),
                                committed_.begin() + static_cast<std::ptrdiff_t>(std::min(candidates.size(), committed_.size())));
  return std::make_unique<CoulombNodeToRigidContact>(punch_shape(), symmetry_factor(), std::move(candidates), mu_,
                                                     std::move(committed));
}

void CoulombNodeToRigidContact::hold_committed_state(const double* u_committed) {
  const auto& cs = candidates();
  for (std::size_t k = 0; k < cs.size(); ++k)
    committed_[k] = cs[k].tangential_equation >= 0 ? u_committed[cs[k].tangential_equation] : 0.0;
}

std::unique_ptr<ContactDiscretization> CoulombNodeToRigidContact::at_load_reversal(const double* u) const {
  auto reversed = std::make_unique<CoulombNodeToRigidContact>(punch_shape(), symmetry_factor(), candidates(), mu_,
                                                              std::vector<double>{});
  reversed->hold_committed_state(u);
  return reversed;
}

void CoulombNodeToRigidContact::write_residual_rows(const double* u, double alpha, const double* row_force,
                                                    double* f) const {
  const auto& cs = candidates();
  // The tangential rows first: they read the normal rows' internal force.
  for (std::size_t k = 0; k < cs.size(); ++k) {
    const int row = tangential_row_[k];
    if (row < 0) continue;
    const ContactCandidate& c = cs[k];
    const double r_n = row_force[k], r_t = row_force[row];
    const double slip = u[c.tangential_equation] - committed_[k];
    const double l = augmented_normal_force(c, r_n, u[c.equation], alpha);
    double& value = f[c.tangential_equation];
    switch (branch(k, u, alpha, r_n, r_t)) {
      case Branch::open: value = r_t; break;
      case Branch::stick: value = c.tangential_scale * slip; break;
      case Branch::slip_positive: value = r_t - mu_ * l; break;
      case Branch::slip_negative: value = r_t + mu_ * l; break;
    }
  }
  for (std::size_t k = 0; k < cs.size(); ++k)
    f[cs[k].equation] = NodeToRigidContact::complementarity(cs[k], row_force[k], u[cs[k].equation], alpha);
}

std::uint64_t CoulombNodeToRigidContact::write_jacobian_rows(const double* u, double alpha, const double* row_force,
                                                             const StiffnessPattern& pattern,
                                                             const std::vector<std::vector<std::int64_t>>& row_positions,
                                                             double* values) const {
  std::uint64_t signature = 0xcbf29ce484222325ull;  // FNV-1a over the branches
  const auto mix = [&signature](unsigned flag) { signature = (signature ^ flag) * 0x100000001b3ull; };
  const auto& cs = candidates();
  const auto& start = pattern.column_start();
  const auto& index = pattern.row_index();
  // The tangential rows first: a slip row reads the normal row's stiffness before it is replaced.
  for (std::size_t k = 0; k < cs.size(); ++k) {
    const int row = tangential_row_[k];
    if (row < 0) continue;
    const ContactCandidate& c = cs[k];
    const double r_n = row_force[k];
    const Branch b = branch(k, u, alpha, r_n, row_force[row]);
    mix(static_cast<unsigned>(b) + 1u);
    const auto& tangential = row_positions[static_cast<std::size_t>(row)];
    if (b == Branch::open) continue;
    if (b == Branch::stick) {
      for (std::int64_t p : tangential) values[p] = 0.0;
      values[pattern.diagonal_position(c.tangential_equation)] = c.tangential_scale;
      continue;
    }
    // d(r^t - mu s l) = dr^t + mu s (dr - c e_v), l > 0 on a sliding node.  Both rows of one node
    // couple to the same unknowns (an element couples all of its nodes' unknowns), so their
    // positions pair up column by column.
    const auto& normal = row_positions[k];
    const auto t = static_cast<std::size_t>(c.tangential_equation), n = static_cast<std::size_t>(c.equation);
    if (normal.size() != tangential.size() ||
        !std::equal(index.begin() + start[t], index.begin() + start[t + 1], index.begin() + start[n]))
      throw std::logic_error("a surface node's two unknowns couple to different unknowns: the slip row cannot be formed");
    const double s = b == Branch::slip_positive ? 1.0 : -1.0;
    for (std::size_t j = 0; j < tangential.size(); ++j) values[tangential[j]] += mu_ * s * values[normal[j]];
    // The (t, v) entry: the column c.equation among row t's.
    const auto first = index.begin() + start[t], last = index.begin() + start[t + 1];
    const auto at = std::lower_bound(first, last, static_cast<std::int64_t>(c.equation));
    values[tangential[static_cast<std::size_t>(at - first)]] -= mu_ * s * c.scale;
  }
  for (std::size_t k = 0; k < cs.size(); ++k) {
    const auto& c = cs[k];
    const bool on = NodeToRigidContact::active(c, row_force[k], u[c.equation], alpha);
    mix(on ? 1u : 2u);
    if (!on) continue;
    for (std::int64_t p : row_positions[k]) values[p] = 0.0;
    values[pattern.diagonal_position(c.equation)] = c.scale;
  }
  return signature;
}

void CoulombNodeToRigidContact::write_parameter_derivative_rows(const double* u, double alpha, const double* row_force,
                                                                const double* d_row_force, double d_log_stiffness,
                                                                double* df) const {
  const auto& cs = candidates();
  for (std::size_t k = 0; k < cs.size(); ++k) {
    const int row = tangential_row_[k];
    if (row < 0) continue;
    const ContactCandidate& c = cs[k];
    const double r_n = row_force[k], dr_n = d_row_force[k], dr_t = d_row_force[row];
    const double slip = u[c.tangential_equation] - committed_[k];
    double& value = df[c.tangential_equation];
    // l = c pen - r_n where it is positive; c moves with the stiffness.
    const double dl = augmented_normal_force(c, r_n, u[c.equation], alpha) > 0.0
                          ? c.scale * d_log_stiffness * penetration(c, u[c.equation], alpha) - dr_n
                          : 0.0;
    switch (branch(k, u, alpha, r_n, row_force[row])) {
      case Branch::open: value = dr_t; break;
      case Branch::stick: value = c.tangential_scale * d_log_stiffness * slip; break;
      case Branch::slip_positive: value = dr_t - mu_ * dl; break;
      case Branch::slip_negative: value = dr_t + mu_ * dl; break;
    }
  }
  for (std::size_t k = 0; k < cs.size(); ++k)
    df[cs[k].equation] =
        NodeToRigidContact::active(cs[k], row_force[k], u[cs[k].equation], alpha) ? 0.0 : d_row_force[k];
}

void CoulombNodeToRigidContact::write_depth_derivative_rows(const double* u, double alpha, const double* row_force,
                                                            double* df) const {
  const auto& cs = candidates();
  for (std::size_t k = 0; k < cs.size(); ++k) {
    df[cs[k].equation] = NodeToRigidContact::active(cs[k], row_force[k], u[cs[k].equation], alpha) ? cs[k].scale : 0.0;
    const int row = tangential_row_[k];
    if (row < 0) continue;
    // A slip row's l = c pen - r moves with alpha through pen.
    switch (branch(k, u, alpha, row_force[k], row_force[row])) {
      case Branch::slip_positive: df[cs[k].tangential_equation] = -mu_ * cs[k].scale; break;
      case Branch::slip_negative: df[cs[k].tangential_equation] = mu_ * cs[k].scale; break;
      default: df[cs[k].tangential_equation] = 0.0; break;
    }
  }
}

ContactResult CoulombNodeToRigidContact::evaluate(const double* u, const double* internal_force, double alpha) const {
  ContactResult r = normal_.evaluate(u, internal_force, alpha);
  const auto& cs = candidates();
  for (std::size_t k = 0; k < cs.size(); ++k) {
    if (!r.in_contact[k] || cs[k].tangential_equation < 0) continue;
    const double q = internal_force[cs[k].tangential_equation];
    r.tangential_force[k] = q;
    r.sliding[k] = !sticking() && std::abs(q) >= (1.0 - slip_report_tolerance) * mu_ * r.nodal_force[k];
  }
  return r;
}

double CoulombNodeToRigidContact::half_width(const double* u, double alpha, const ContactResult& contact) const {
  return normal_.half_width(u, alpha, contact);
}

bool CoulombNodeToRigidContact::touches(const double* u, double alpha) const { return normal_.touches(u, alpha); }

std::vector<double> CoulombNodeToRigidContact::admissibility_violation(const double* u, double alpha) const {
  return normal_.admissibility_violation(u, alpha);
}

}  // namespace indentsim
