#pragma once
// Frictionless contact with the gap integrated over the surface (docs/MODEL.md §3.2).
//
// The specimen's top line between two candidate nodes is the segment of the bilinear elements:
// v(x) = v_i N_i(x) + v_{i+1} N_{i+1}(x).  Its penetration past the punch's exact profile,
//   pi(x) = v(x) + alpha - g(x),
// is resisted by a contact pressure proportional to it, p(x) = eps_e max(0, pi(x)) (a penalty),
// whose nodal forces enter the residual rows of the surface nodes' vertical unknowns:
//   F_k = r_k + lambda_k,   lambda_k = sum_e int_e eps_e max(0, pi) N_k s(x) dx,
// s(x) the surface density of the kinematics (1, or the ring 2 pi x).  The integral is taken
// over the part of each segment where pi > 0, its ends found to round-off (the roots of pi and
// its stationary points, from the punch's slope), so that F is continuously differentiable in u
// and alpha: the contact edge moves continuously inside the elements and a node entering contact
// takes up its load gradually -- what removes the node-to-rigid discretization's sawtooth in
// P(alpha) under a nearly uniform plastic pressure.  The Jacobian rows are
//   dF_k/dv_j = K_kj + sum_e int eps_e H(pi) N_k N_j s dx,
// symmetric (the boundary terms vanish where pi = 0).  eps_e = kappa (c_i + c_{i+1}) /
// (m_i + m_{i+1}), a node's elastic diagonal stiffness over its tributary surface: the
// penalty's nodal stiffness is kappa times the node's own, and the penetration under a pressure
// p about p h / (kappa E*), which converges with the mesh.
#include <memory>
#include <vector>

#include "indentsim/geometry/kinematics.hpp"
#include "indentsim/geometry/mesh.hpp"
#include "indentsim/solvers/contact_discretization.hpp"

namespace indentsim {

class IntegratedGapContact final : public ContactDiscretization {
public:
  /// kappa: the penalty over a surface node's elastic stiffness (contact.penalty).
  IntegratedGapContact(const Mesh& mesh, std::shared_ptr<const PunchShape> punch, const StiffnessPattern& pattern,
                       const std::vector<double>& stiffness_values, double kappa);

  /// The penalty eps_e of segment e = [x_e, x_{e+1}] [Pa/m].
  const std::vector<double>& penalty() const { return penalty_; }

  std::unique_ptr<ContactDiscretization> on_candidates(std::vector<ContactCandidate> candidates) const override;
  void write_residual_rows(const double* u, double alpha, const double* row_force, double* f) const override;
  /// The signature is FNV-1a over the candidates that carry contact force.
  std::uint64_t write_jacobian_rows(const double* u, double alpha, const double* row_force,
                                    const StiffnessPattern& pattern,
                                    const std::vector<std::vector<std::int64_t>>& row_positions,
                                    double* values) const override;
  /// The bulk's derivative plus the penalty forces' own: eps scales with the elastic stiffness,
  /// d lambda_k / d theta = lambda_k d ln K / d theta.
  void write_parameter_derivative_rows(const double* u, double alpha, const double* row_force,
                                       const double* d_row_force, double d_log_stiffness,
                                       double* df) const override;
  /// sum_e int eps_e H(pi) N_k s dx.
  void write_depth_derivative_rows(const double* u, double alpha, const double* row_force, double* df) const override;
  bool rows_pin_unknowns() const override { return false; }
  bool rows_keep_symmetry() const override { return true; }

  /// lambda_k = -r_k on the candidates whose segments touch, P = f sum lambda_k; the gap at a node
  /// is -pi(x_k), negative where the penalty lets the surface pass the punch.
  ContactResult evaluate(const double* u, const double* internal_force, double alpha) const override;
  /// From the open side's gap law past the outermost node at or beyond the punch's surface.
  double half_width(const double* u, double alpha, const ContactResult& contact) const override;
  bool touches(const double* u, double alpha) const override;
  /// The penalty admits a penetration of the punch: the contact conditions alone prove nothing
  /// without the bulk's forces (zeros).
  std::vector<double> admissibility_violation(const double* u, double alpha) const override;

  /// The contact pressure p(x) = eps max(0, pi(x)) at abscissa x of segment e [Pa].
  double pressure(const double* u, double alpha, int e, double x) const;

private:
  IntegratedGapContact(std::shared_ptr<const PunchShape> punch, double symmetry_factor,
                       std::vector<ContactCandidate> candidates, const Kinematics& kinematics,
                       std::vector<double> penalty);
  /// [l, r] pieces of segment e where pi > 0.
  struct Piece {
    double left, right;
  };
  void contact_pieces(const double* u, double alpha, int e, std::vector<Piece>& pieces) const;
  double penetration_at(const double* u, double alpha, int e, double x) const;
  double penetration_slope(const double* u, int e, double x, bool from_left) const;
  /// Integrates over the contact pieces of every segment: the nodal forces (into force, per
  /// candidate), and optionally the depth derivative and the segment's 2x2 tangent.
  template <class Visit>
  void integrate(const double* u, double alpha, Visit&& visit) const;

  const Kinematics* kinematics_;
  std::vector<double> penalty_;  ///< per segment
};

}  // namespace indentsim
