#include "indentsim/contact.hpp"

#include "indentsim/layer_forces.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace indentsim {

ContactBoundary::ContactBoundary(const Mesh& mesh, std::shared_ptr<const PunchShape> punch,
                                 const StiffnessPattern& pattern, const std::vector<double>& stiffness_values)
    : punch_(std::move(punch)), symmetry_factor_(mesh.kinematics().symmetry_factor()) {
  const int j = mesh.top_row();
  for (int i = 0; i < mesh.nodes_x(); ++i) {
    const double x = mesh.x(i);
    const double g = punch_->surface_height(x);
    if (!std::isfinite(g)) break;  // beyond the punch's rim: never touched
    ContactCandidate c;
    c.node = mesh.node(i, j);
    c.equation = mesh.equation(Mesh::dof_v(c.node));
    c.x = x;
    c.surface_height = g;
    c.scale = stiffness_values[pattern.diagonal_position(c.equation)];
    c.tributary_measure = tributary_measure(mesh, i);
    candidates_.push_back(c);
  }
}

ContactResult evaluate_contact(const ContactBoundary& boundary, const double* u, const double* internal_force,
                               double alpha) {
  const auto& cs = boundary.candidates();
  ContactResult r;
  r.nodal_force.assign(cs.size(), 0.0);
  r.in_contact.assign(cs.size(), 0);
  double half_model_force = 0.0;
  for (std::size_t k = 0; k < cs.size(); ++k) {
    const double fk = internal_force[cs[k].equation];
    const bool on = ContactBoundary::active(cs[k], fk, u[cs[k].equation], alpha);
    r.in_contact[k] = on;
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
  r.force = boundary.symmetry_factor() * half_model_force;
  return r;
}

double contact_half_width(const ContactBoundary& boundary, const ContactResult& contact) {
  const auto& cs = boundary.candidates();
  const int n = contact.outermost;
  // No force, no contact zone: at alpha = 0 the punch touches the axis node only.
  if (n < 0 || !(contact.force > 0.0)) return 0.0;
  const double x_n = cs[n].x;
  if (n + 1 >= static_cast<int>(cs.size())) return x_n;  // the rim node of a flat punch touches
  const double x_open = cs[n + 1].x;

  // Least squares of p^2 = A + B x^2 over the contact nodes just inside the edge.  The pressure
  // is taken relative to the largest of them and x relative to x_open, so that the fit is the same
  // in any units (p^2 of a pressure in pascals overflows for E near 1e160 and underflows for small E).
  double p_scale = 0.0;
  for (int k = std::max(0, n - 5); k < n; ++k)
    if (contact.in_contact[k] && cs[k].tributary_measure > 0.0)
      p_scale = std::max(p_scale, std::abs(contact.nodal_force[k] / cs[k].tributary_measure));
  double s1 = 0, sx = 0, sxx = 0, sy = 0, sxy = 0;
  int used = 0;
  for (int k = std::max(0, n - 5); k < n; ++k) {
    if (!contact.in_contact[k] || !(cs[k].tributary_measure > 0.0) || !(p_scale > 0.0)) continue;
    const double p = contact.nodal_force[k] / cs[k].tributary_measure / p_scale;
    const double x2 = cs[k].x * cs[k].x, p2 = p * p;
    s1 += 1;
    sx += x2;
    sxx += x2 * x2;
    sy += p2;
    sxy += x2 * p2;
    ++used;
  }
  const double midpoint = 0.5 * (x_n + x_open);
  if (used < 2) return midpoint;
  const double det = s1 * sxx - sx * sx;
  if (!(det > 0.0)) return midpoint;
  const double slope = (s1 * sxy - sx * sy) / det;
  const double intercept = (sy - slope * sx) / s1;
  if (!(slope < 0.0) || !(intercept > 0.0)) return midpoint;
  // The discrete edge may also fall just inside x_n: an outermost node carrying a sliver of
  // force is on the active set although the continuous edge has not quite reached it.
  const double x_inner = n > 0 ? cs[n - 1].x : 0.0;
  return std::clamp(std::sqrt(-intercept / slope), x_inner, x_open);
}

}  // namespace indentsim
