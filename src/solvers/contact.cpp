#include "indentsim/solvers/contact.hpp"

#include "indentsim/solvers/line_forces.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace indentsim {

int contact_candidate_count(const Mesh& mesh, const PunchShape& punch) {
  int count = 0;
  while (count < mesh.nodes_x() && std::isfinite(punch.surface_height(mesh.x(count)))) ++count;
  return count;  // beyond the punch's rim: never touched
}

ContactResult ContactResult::open(std::size_t candidates) {
  ContactResult r;
  r.nodal_force.assign(candidates, 0.0);
  r.in_contact.assign(candidates, 0);
  r.gap.assign(candidates, 0.0);
  r.tangential_force.assign(candidates, 0.0);
  r.sliding.assign(candidates, 0);
  return r;
}

std::vector<int> tangential_row_indices(const std::vector<ContactCandidate>& candidates) {
  std::vector<int> rows(candidates.size(), -1);
  int next = static_cast<int>(candidates.size());
  for (std::size_t k = 0; k < candidates.size(); ++k)
    if (candidates[k].tangential_equation >= 0) rows[k] = next++;
  return rows;
}

std::vector<ContactCandidate> contact_candidates(const Mesh& mesh, const PunchShape& punch,
                                                 const StiffnessPattern& pattern,
                                                 const std::vector<double>& stiffness_values) {
  std::vector<ContactCandidate> candidates;
  const int j = mesh.top_row();
  const int count = contact_candidate_count(mesh, punch);
  for (int i = 0; i < count; ++i) {
    const double x = mesh.x(i);
    ContactCandidate c;
    c.node = mesh.node(i, j);
    c.equation = mesh.equation(Mesh::dof_v(c.node));
    c.x = x;
    c.surface_height = punch.surface_height(x);
    c.scale = stiffness_values[pattern.diagonal_position(c.equation)];
    c.tributary_measure = tributary_measure(mesh, i);
    c.tangential_equation = mesh.equation(Mesh::dof_u(c.node));
    if (c.tangential_equation >= 0) c.tangential_scale = stiffness_values[pattern.diagonal_position(c.tangential_equation)];
    candidates.push_back(c);
  }
  return candidates;
}

ContactDiscretization::ContactDiscretization(std::shared_ptr<const PunchShape> punch, double symmetry_factor,
                                             std::vector<ContactCandidate> candidates)
    : ContactDiscretization(std::move(punch), symmetry_factor, std::move(candidates), false) {}

ContactDiscretization::ContactDiscretization(std::shared_ptr<const PunchShape> punch, double symmetry_factor,
                                             std::vector<ContactCandidate> candidates, bool tangential_rows)
    : punch_(std::move(punch)), symmetry_factor_(symmetry_factor), candidates_(std::move(candidates)) {
  for (const auto& c : candidates_) row_equations_.push_back(c.equation);
  if (tangential_rows)
    for (const auto& c : candidates_)
      if (c.tangential_equation >= 0) row_equations_.push_back(c.tangential_equation);
}

NodeToRigidContact::NodeToRigidContact(const Mesh& mesh, std::shared_ptr<const PunchShape> punch,
                                       const StiffnessPattern& pattern, const std::vector<double>& stiffness_values)
    : ContactDiscretization(punch, mesh.kinematics().symmetry_factor(),
                            contact_candidates(mesh, *punch, pattern, stiffness_values)) {}

NodeToRigidContact::NodeToRigidContact(std::shared_ptr<const PunchShape> punch, double symmetry_factor,
                                       std::vector<ContactCandidate> candidates)
    : ContactDiscretization(std::move(punch), symmetry_factor, std::move(candidates)) {}

std::unique_ptr<ContactDiscretization> NodeToRigidContact::on_candidates(std::vector<ContactCandidate> candidates) const {
  return std::make_unique<NodeToRigidContact>(punch_shape(), symmetry_factor(), std::move(candidates));
}

void NodeToRigidContact::write_residual_rows(const double* u, double alpha, const double* row_force,
                                             double* f) const {
  const auto& cs = candidates();
  for (std::size_t i = 0; i < cs.size(); ++i) {
    const auto& c = cs[i];
    f[c.equation] = complementarity(c, row_force[i], u[c.equation], alpha);
  }
}

std::uint64_t NodeToRigidContact::write_jacobian_rows(const double* u, double alpha, const double* row_force,
                                                      const StiffnessPattern& pattern,
                                                      const std::vector<std::vector<std::int64_t>>& row_positions,
                                                      double* values) const {
  std::uint64_t signature = 0xcbf29ce484222325ull;  // FNV-1a over the active flags
  const auto& cs = candidates();
  for (std::size_t i = 0; i < cs.size(); ++i) {
    const auto& c = cs[i];
    const bool on = active(c, row_force[i], u[c.equation], alpha);
    signature = (signature ^ (on ? 1u : 2u)) * 0x100000001b3ull;
    if (!on) continue;
    // Active node: the row of c (v + alpha - g) is c e_k.
    for (std::int64_t p : row_positions[i]) values[p] = 0.0;
    values[pattern.diagonal_position(c.equation)] = c.scale;
  }
  return signature;
}

void NodeToRigidContact::write_parameter_derivative_rows(const double* u, double alpha, const double* row_force,
                                                         const double* d_row_force, double,
                                                         double* df) const {
  const auto& cs = candidates();
  for (std::size_t i = 0; i < cs.size(); ++i)
    df[cs[i].equation] = active(cs[i], row_force[i], u[cs[i].equation], alpha) ? 0.0 : d_row_force[i];
}

void NodeToRigidContact::write_depth_derivative_rows(const double* u, double alpha, const double* row_force,
                                                     double* df) const {
  const auto& cs = candidates();
  for (std::size_t i = 0; i < cs.size(); ++i)
    df[cs[i].equation] = active(cs[i], row_force[i], u[cs[i].equation], alpha) ? cs[i].scale : 0.0;
}

bool NodeToRigidContact::touches(const double* u, double alpha) const {
  for (const ContactCandidate& c : candidates())
    if (penetration(c, u[c.equation], alpha) >= 0.0) return true;
  return false;
}

std::vector<double> NodeToRigidContact::admissibility_violation(const double* u, double alpha) const {
  std::vector<double> f;
  for (const auto& c : candidates()) f.push_back(std::max(0.0, c.scale * penetration(c, u[c.equation], alpha)));
  return f;
}

ContactResult NodeToRigidContact::evaluate(const double* u, const double* internal_force, double alpha) const {
  const auto& cs = candidates();
  ContactResult r = ContactResult::open(cs.size());
  double half_model_force = 0.0;
  for (std::size_t k = 0; k < cs.size(); ++k) {
    const double fk = internal_force[cs[k].equation];
    const bool on = active(cs[k], fk, u[cs[k].equation], alpha);
    r.in_contact[k] = on;
    r.gap[k] = on ? 0.0 : -penetration(cs[k], u[cs[k].equation], alpha);
    // docs/MODEL.md §3: P is the sum of the vertical reactions of all contact nodes, the axis node
    // included, times the symmetry factor (twice, for the half model of plane strain).  Open nodes carry no force (their residual is the
    // equilibrium residual itself), so summing -r_k over contact nodes is the reaction.
    if (on) {
      r.nodal_force[k] = -fk;
      half_model_force += -fk;
      ++r.contact_nodes;
      r.outermost = static_cast<int>(k);
    }
  }
  r.force = symmetry_factor() * half_model_force;
  r.half_width = half_width(u, alpha, r);
  return r;
}

double NodeToRigidContact::half_width(const double*, double, const ContactResult& contact) const {
  // No force, no contact zone: at alpha = 0 the punch touches the axis node only.
  if (contact.outermost < 0 || !(contact.force > 0.0)) return 0.0;
  return contact_edge_from_open_side(candidates(), contact.gap, contact.outermost);
}

double contact_edge_from_open_side(const std::vector<ContactCandidate>& cs, const std::vector<double>& gap, int n) {
  const int candidates = static_cast<int>(cs.size());
  const double x_n = cs[n].x;
  if (n + 1 >= candidates) return x_n;  // the rim node of a flat punch touches
  const double x_open = cs[n + 1].x;
  const double midpoint = 0.5 * (x_n + x_open);

  // The first open nodes (up to three; fewer where the punch's surface ends).
  const int last = std::min(candidates - 1, n + 3);
  if (last < n + 2) return midpoint;
  double gap_scale = 0.0;
  for (int k = n + 1; k <= last; ++k) gap_scale = std::max(gap_scale, gap[k]);
  if (!(gap_scale > 0.0)) return midpoint;
  const double element = cs[n + 2].x - x_open;

  // Weighted least squares of y = c (xi - xi_a), xi = (x - x_{n+1}) / element, weights y_k on the
  // residuals (w_k = y_k^2 on their squares).
  double sw = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (int k = n + 1; k <= last; ++k) {
    const double relative_gap = std::max(gap[k], 0.0) / gap_scale;
    const double y = std::cbrt(relative_gap * relative_gap);
    const double xi = (cs[k].x - x_open) / element, w = y * y;
    sw += w;
    sx += w * xi;
    sy += w * y;
    sxx += w * xi * xi;
    sxy += w * xi * y;
  }
  const double det = sw * sxx - sx * sx;
  if (!(det > 0.0)) return midpoint;
  const double slope = (sw * sxy - sx * sy) / det;
  const double intercept = (sy - slope * sx) / sw;
  if (!(slope > 0.0)) return midpoint;  // the gap does not open outward: no edge law to follow
  const double a = x_open - intercept / slope * element;
  // The active set says the edge is beyond x_{n-1} (node n carries force) and before x_{n+1}.
  const double x_inner = n > 0 ? cs[n - 1].x : 0.0;
  if (!(a > x_inner && a < x_open)) return midpoint;
  return a;
}

}  // namespace indentsim
