#include "indentsim/solvers/integrated_gap_contact.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

namespace indentsim {

namespace {

// Each segment is searched for roots of pi on this many equal parts: a part holds at most one
// stationary point of pi for any punch whose slope is monotone over it (every analytic shape;
// a measured profile's monotone cubic between its points).
constexpr int parts_per_segment = 4;
// Bisection to the segment's round-off: 2^-60 of a part.
constexpr int bisection_steps = 60;
// Three-point Gauss-Legendre on each contact piece: exact for the flat punch's cubic integrand,
// and for the curved profiles an error far below the penalty's.
constexpr std::array<double, 3> gauss_abscissa{-0.7745966692414834, 0.0, 0.7745966692414834};
constexpr std::array<double, 3> gauss_weight{5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0};

std::int64_t find_position(const StiffnessPattern& pattern, int row, int column) {
  const auto& start = pattern.column_start();
  const auto& rows = pattern.row_index();
  const auto first = rows.begin() + start[static_cast<std::size_t>(column)];
  const auto last = rows.begin() + start[static_cast<std::size_t>(column) + 1];
  const auto at = std::lower_bound(first, last, static_cast<std::int64_t>(row));
  if (at == last || *at != row) throw std::logic_error("the contact segment's unknowns are not coupled in the pattern");
  return at - rows.begin();
}

std::uint64_t fnv(std::uint64_t signature, bool on) { return (signature ^ (on ? 1u : 2u)) * 0x100000001b3ull; }

}  // namespace

IntegratedGapContact::IntegratedGapContact(const Mesh& mesh, std::shared_ptr<const PunchShape> punch,
                                           const StiffnessPattern& pattern,
                                           const std::vector<double>& stiffness_values, double kappa)
    : ContactDiscretization(punch, mesh.kinematics().symmetry_factor(),
                            contact_candidates(mesh, *punch, pattern, stiffness_values)),
      kinematics_(&mesh.kinematics()) {
  const auto& cs = candidates();
  for (std::size_t e = 0; e + 1 < cs.size(); ++e)
    penalty_.push_back(kappa * (cs[e].scale + cs[e + 1].scale) / (cs[e].tributary_measure + cs[e + 1].tributary_measure));
}

IntegratedGapContact::IntegratedGapContact(std::shared_ptr<const PunchShape> punch, double symmetry_factor,
                                           std::vector<ContactCandidate> candidates, const Kinematics& kinematics,
                                           std::vector<double> penalty)
    : ContactDiscretization(std::move(punch), symmetry_factor, std::move(candidates)),
      kinematics_(&kinematics),
      penalty_(std::move(penalty)) {}

std::unique_ptr<ContactDiscretization> IntegratedGapContact::on_candidates(std::vector<ContactCandidate> candidates) const {
  // The penalty is the whole mesh's (not the condensed diagonal's): the same equations on either system.
  const std::size_t segments = candidates.empty() ? 0 : candidates.size() - 1;
  if (segments > penalty_.size()) throw std::logic_error("more candidates than the contact has");
  std::vector<double> penalty(penalty_.begin(), penalty_.begin() + static_cast<std::ptrdiff_t>(segments));
  return std::unique_ptr<ContactDiscretization>(
      new IntegratedGapContact(punch_shape(), symmetry_factor(), std::move(candidates), *kinematics_, std::move(penalty)));
}

double IntegratedGapContact::penetration_at(const double* u, double alpha, int e, double x) const {
  const auto& a = candidates()[static_cast<std::size_t>(e)];
  const auto& b = candidates()[static_cast<std::size_t>(e) + 1];
  const double t = (x - a.x) / (b.x - a.x);
  const double v = (1.0 - t) * u[a.equation] + t * u[b.equation];
  const double g = x == a.x ? a.surface_height : x == b.x ? b.surface_height : punch().surface_height(x);
  return v + alpha - g;
}

double IntegratedGapContact::penetration_slope(const double* u, int e, double x, bool from_left) const {
  const auto& a = candidates()[static_cast<std::size_t>(e)];
  const auto& b = candidates()[static_cast<std::size_t>(e) + 1];
  // g' is one-sided at a kink (a cone's tip); the side inside the part is what its monotonicity needs.
  const double h = b.x - a.x;
  const double g_slope = punch().slope(from_left ? x : std::max(a.x, x - 1e-12 * h));
  return (u[b.equation] - u[a.equation]) / h - g_slope;
}

void IntegratedGapContact::contact_pieces(const double* u, double alpha, int e, std::vector<Piece>& pieces) const {
  pieces.clear();
  const auto& a = candidates()[static_cast<std::size_t>(e)];
  const auto& b = candidates()[static_cast<std::size_t>(e) + 1];
  const double h = b.x - a.x;
  const auto pi = [&](double x) { return penetration_at(u, alpha, e, x); };
  // Where pi > 0 on a part [l, r] on which pi is monotone: all of it, none, or up to its root.
  const auto monotone = [&](double l, double r, double pl, double pr) {
    if (pl > 0.0 && pr > 0.0) {
      pieces.push_back({l, r});
    } else if (pl > 0.0 || pr > 0.0) {
      double lo = l, hi = r;  // pi(lo) and pi(hi) of opposite signs
      const bool rising = pr > 0.0;
      for (int i = 0; i < bisection_steps && hi - lo > 0.0; ++i) {
        const double mid = 0.5 * (lo + hi);
        if (mid <= lo || mid >= hi) break;
        ((pi(mid) > 0.0) == rising ? hi : lo) = mid;
      }
      const double root = 0.5 * (lo + hi);
      if (rising) pieces.push_back({root, r});
      else pieces.push_back({l, root});
    }
  };
  for (int part = 0; part < parts_per_segment; ++part) {
    const double l = part == 0 ? a.x : a.x + h * part / parts_per_segment;
    const double r = part + 1 == parts_per_segment ? b.x : a.x + h * (part + 1) / parts_per_segment;
    const double pl = pi(l), pr = pi(r);
    const double dl = penetration_slope(u, e, l, true), dr = penetration_slope(u, e, r, false);
    // A stationary point inside matters when it may change the sign: a maximum between two ends
    // not both in contact, or a minimum between two ends not both open.
    const bool maximum = dl > 0.0 && dr < 0.0 && !(pl > 0.0 && pr > 0.0);
    const bool minimum = dl < 0.0 && dr > 0.0 && !(pl <= 0.0 && pr <= 0.0);
    if (!maximum && !minimum) {
      monotone(l, r, pl, pr);
      continue;
    }
    double lo = l, hi = r;
    for (int i = 0; i < bisection_steps; ++i) {
      const double mid = 0.5 * (lo + hi);
      if (mid <= lo || mid >= hi) break;
      ((penetration_slope(u, e, mid, true) > 0.0) == maximum ? lo : hi) = mid;
    }
    const double stationary = 0.5 * (lo + hi), ps = pi(stationary);
    monotone(l, stationary, pl, ps);
    monotone(stationary, r, ps, pr);
  }
}

template <class Visit>
void IntegratedGapContact::integrate(const double* u, double alpha, Visit&& visit) const {
  const auto& cs = candidates();
  std::vector<Piece> pieces;
  for (int e = 0; e + 1 < static_cast<int>(cs.size()); ++e) {
    contact_pieces(u, alpha, e, pieces);
    const double x0 = cs[static_cast<std::size_t>(e)].x, h = cs[static_cast<std::size_t>(e) + 1].x - x0;
    const double eps = penalty_[static_cast<std::size_t>(e)];
    for (const Piece& p : pieces) {
      const double half = 0.5 * (p.right - p.left), middle = 0.5 * (p.left + p.right);
      for (std::size_t g = 0; g < gauss_abscissa.size(); ++g) {
        const double x = middle + half * gauss_abscissa[g];
        const double n1 = (x - x0) / h, n0 = 1.0 - n1;
        const double weight = eps * gauss_weight[g] * half * kinematics_->surface_density(x);
        visit(e, n0, n1, std::max(0.0, penetration_at(u, alpha, e, x)), weight);
      }
    }
  }
}

void IntegratedGapContact::write_residual_rows(const double* u, double alpha, const double* row_force,
                                               double* f) const {
  const auto& cs = candidates();
  for (std::size_t i = 0; i < cs.size(); ++i) f[cs[i].equation] = row_force[i];
  integrate(u, alpha, [&](int e, double n0, double n1, double pi, double weight) {
    f[cs[static_cast<std::size_t>(e)].equation] += weight * pi * n0;
    f[cs[static_cast<std::size_t>(e) + 1].equation] += weight * pi * n1;
  });
}

std::uint64_t IntegratedGapContact::write_jacobian_rows(const double* u, double alpha, const double*,
                                                        const StiffnessPattern& pattern,
                                                        const std::vector<std::vector<std::int64_t>>&,
                                                        double* values) const {
  const auto& cs = candidates();
  std::vector<char> touching(cs.size(), 0);
  std::vector<std::array<double, 3>> segment(cs.size(), {0.0, 0.0, 0.0});  // (00, 01, 11) per segment
  integrate(u, alpha, [&](int e, double n0, double n1, double, double weight) {
    auto& k = segment[static_cast<std::size_t>(e)];
    k[0] += weight * n0 * n0;
    k[1] += weight * n0 * n1;
    k[2] += weight * n1 * n1;
  });
  std::uint64_t signature = 0xcbf29ce484222325ull;
  for (std::size_t e = 0; e + 1 < cs.size(); ++e) {
    const auto& k = segment[e];
    if (k[0] == 0.0 && k[1] == 0.0 && k[2] == 0.0) continue;
    touching[e] = touching[e + 1] = 1;
    const int i = cs[e].equation, j = cs[e + 1].equation;
    values[pattern.diagonal_position(i)] += k[0];
    values[find_position(pattern, i, j)] += k[1];
    values[find_position(pattern, j, i)] += k[1];
    values[pattern.diagonal_position(j)] += k[2];
  }
  for (char on : touching) signature = fnv(signature, on != 0);
  return signature;
}

void IntegratedGapContact::write_parameter_derivative_rows(const double* u, double alpha, const double*,
                                                           const double* d_row_force, double d_log_stiffness,
                                                           double* df) const {
  const auto& cs = candidates();
  for (std::size_t i = 0; i < cs.size(); ++i) df[cs[i].equation] = d_row_force[i];
  if (d_log_stiffness == 0.0) return;
  integrate(u, alpha, [&](int e, double n0, double n1, double pi, double weight) {
    df[cs[static_cast<std::size_t>(e)].equation] += d_log_stiffness * weight * pi * n0;
    df[cs[static_cast<std::size_t>(e) + 1].equation] += d_log_stiffness * weight * pi * n1;
  });
}

void IntegratedGapContact::write_depth_derivative_rows(const double* u, double alpha, const double*,
                                                       double* df) const {
  const auto& cs = candidates();
  for (const auto& c : cs) df[c.equation] = 0.0;
  integrate(u, alpha, [&](int e, double n0, double n1, double, double weight) {
    df[cs[static_cast<std::size_t>(e)].equation] += weight * n0;
    df[cs[static_cast<std::size_t>(e) + 1].equation] += weight * n1;
  });
}

ContactResult IntegratedGapContact::evaluate(const double* u, const double* internal_force, double alpha) const {
  const auto& cs = candidates();
  ContactResult r = ContactResult::open(cs.size());
  std::vector<double> penalty_force(cs.size(), 0.0);
  integrate(u, alpha, [&](int e, double n0, double n1, double pi, double weight) {
    penalty_force[static_cast<std::size_t>(e)] += weight * pi * n0;
    penalty_force[static_cast<std::size_t>(e) + 1] += weight * pi * n1;
  });
  double half_model_force = 0.0;
  for (std::size_t k = 0; k < cs.size(); ++k) {
    r.gap[k] = -penetration(cs[k], u[cs[k].equation], alpha);
    if (!(penalty_force[k] > 0.0)) continue;
    // The reaction -r_k, as the node-to-rigid contact reports it: at equilibrium it is the
    // penalty's nodal force, and sums to what a load cell measures.
    r.in_contact[k] = 1;
    r.nodal_force[k] = -internal_force[cs[k].equation];
    half_model_force += r.nodal_force[k];
    ++r.contact_nodes;
    r.outermost = static_cast<int>(k);
  }
  r.force = symmetry_factor() * half_model_force;
  r.half_width = half_width(u, alpha, r);
  return r;
}

double IntegratedGapContact::half_width(const double*, double, const ContactResult& contact) const {
  if (contact.outermost < 0 || !(contact.force > 0.0)) return 0.0;
  // The outermost segment that carries pressure, [x_{o-1}, x_o], holds the edge: the open side's
  // gap law from x_o on locates it as for node-to-rigid contact (the penalty's own edge, where
  // the discrete surface line crosses the punch, is only first-order accurate).
  const int n = std::max(0, contact.outermost - 1);
  return contact_edge_from_open_side(candidates(), contact.gap, n);
}

bool IntegratedGapContact::touches(const double* u, double alpha) const {
  for (const ContactCandidate& c : candidates())
    if (penetration(c, u[c.equation], alpha) >= 0.0) return true;
  std::vector<Piece> pieces;
  for (int e = 0; e + 1 < static_cast<int>(candidates().size()); ++e) {
    contact_pieces(u, alpha, e, pieces);
    if (!pieces.empty()) return true;
  }
  return false;
}

std::vector<double> IntegratedGapContact::admissibility_violation(const double*, double) const {
  return std::vector<double>(candidates().size(), 0.0);
}

double IntegratedGapContact::pressure(const double* u, double alpha, int e, double x) const {
  return penalty_[static_cast<std::size_t>(e)] * std::max(0.0, penetration_at(u, alpha, e, x));
}

}  // namespace indentsim
