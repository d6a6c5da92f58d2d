#pragma once
// Frictionless Signorini contact with the rigid punch (docs/MODEL.md §3).
//
// The punch surface is y = -alpha + g(x), g the shape's profile (include/indentsim/geometry/punch.hpp).  At
// a candidate node k of the top surface (where g is finite) with vertical displacement v_k and vertical internal force r_k
// (= (K u)_k, so the contact force the punch exerts is lambda_k = -r_k), the conditions
//   gap d_k = g_k - alpha - v_k >= 0,  lambda_k >= 0,  lambda_k d_k = 0
// are written as one semi-smooth equation (the "max" complementarity function)
//   F_k = max(r_k, c_k (v_k + alpha - g_k)) = 0,   c_k = K_kk,
// whose generalized Newton derivative is the primal-dual active set method: an active node
// (c_k (v_k + alpha - g_k) >= r_k) gets the row c_k e_k, an inactive one its stiffness row.
// Scaling by the diagonal stiffness makes both branches force-sized and the choice of active
// set independent of units (docs/DESIGN.md explains the choice).
#include <memory>
#include <vector>

#include "indentsim/solvers/assembly.hpp"
#include "indentsim/solvers/contact_discretization.hpp"
#include "indentsim/geometry/mesh.hpp"
#include "indentsim/geometry/punch.hpp"

namespace indentsim {

/// The seed paper's discretization (docs/MODEL.md §3): one complementarity row per candidate
/// node, on its vertical unknown, against the rigid punch's profile at the node's abscissa.
class NodeToRigidContact final : public ContactDiscretization {
public:
  NodeToRigidContact(const Mesh& mesh, std::shared_ptr<const PunchShape> punch, const StiffnessPattern& pattern,
                     const std::vector<double>& stiffness_values);
  /// Given candidates (a subset renumbered onto a condensed system, say).
  NodeToRigidContact(std::shared_ptr<const PunchShape> punch, double symmetry_factor,
                     std::vector<ContactCandidate> candidates);

  /// The active branch of the complementarity function (ties count as contact).
  static bool active(const ContactCandidate& c, double internal_force, double v, double alpha) {
    return c.scale * penetration(c, v, alpha) >= internal_force;
  }
  static double complementarity(const ContactCandidate& c, double internal_force, double v, double alpha) {
    const double scaled = c.scale * penetration(c, v, alpha);
    return scaled >= internal_force ? scaled : internal_force;
  }

  std::unique_ptr<ContactDiscretization> on_candidates(std::vector<ContactCandidate> candidates) const override;
  /// F_k = max(r_k, c_k (v_k + alpha - g_k)).
  void write_residual_rows(const double* u, double alpha, const double* row_force, double* f) const override;
  /// An active node's row is c_k e_k, an inactive one keeps its stiffness row (the primal-dual
  /// active set method); the signature is FNV-1a over the candidates' flags.
  std::uint64_t write_jacobian_rows(const double* u, double alpha, const double* row_force,
                                    const StiffnessPattern& pattern,
                                    const std::vector<std::vector<std::int64_t>>& row_positions,
                                    double* values) const override;
  /// An active row c (v + alpha - g) vanishes at the solution whatever c is: its derivative is 0;
  /// an open one is the bulk's.
  void write_parameter_derivative_rows(const double* u, double alpha, const double* row_force,
                                       const double* d_row_force, double d_log_stiffness,
                                       double* df) const override;
  /// c_k on an active row, 0 on an open one.
  void write_depth_derivative_rows(const double* u, double alpha, const double* row_force, double* df) const override;
  bool rows_pin_unknowns() const override { return true; }
  bool rows_keep_symmetry() const override { return true; }

  ContactResult evaluate(const double* u, const double* internal_force, double alpha) const override;
  /// contact_edge_from_open_side (contact_discretization.hpp) past the outermost contact node.
  double half_width(const double* u, double alpha, const ContactResult& contact) const override;
  /// A candidate at or past the punch's surface.
  bool touches(const double* u, double alpha) const override;
  /// max(0, c_k (v_k + alpha - g_k)): a node past the punch.
  std::vector<double> admissibility_violation(const double* u, double alpha) const override;
};

}  // namespace indentsim
