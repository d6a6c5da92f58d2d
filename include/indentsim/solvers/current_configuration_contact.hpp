#pragma once
// Frictionless node-to-rigid contact on the current configuration (docs/MODEL.md §12.2), for
// finite strain.  A candidate node at reference abscissa X with displacement (u, v) sits at
// x = X + u; the punch surface is y = -alpha + g(x), so its penetration is
//   p = v + alpha - g(X + u),
// and the punch pushes along the surface normal, the gradient (-g'(x), 1) of p: a force
// lambda (g'(x), -1) with lambda = -r_v >= 0 the vertical reaction.  The rows of a candidate:
//   vertical     F_v = max(r_v, c p)                   (node-to-rigid's complementarity, contact.hpp)
//   horizontal   F_u = r_u + g'(x) r_v  in contact      (no force along the punch's surface),
//                F_u = r_u              open,
// with their exact Jacobians: c (e_v - g'(x) e_u) on an active vertical row, and
// K_u + g' K_v + g''(x) r_v e_u on an active horizontal row -- unsymmetric, so KLU solves them.
// This is the geometric effect Hay, Bolshakov and Pharr (J. Mater. Res. 14, 1999) add to
// Sneddon's cone: the surface moves inward as it is pressed, and the contact is where it now is.
// Candidates are the top nodes whose reference abscissa lies under the punch (as node-to-rigid's).
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "indentsim/geometry/mesh.hpp"
#include "indentsim/solvers/contact_discretization.hpp"

namespace indentsim {

/// g''(x) by central differences of g' over 1e-6 `scale` (the profiles give g and g' in closed
/// form or as cubics; the second derivative only enters Jacobian rows); 0 beyond a rim.
double surface_curvature(const PunchShape& punch, double x, double scale);

/// A punch whose surface ends at a rim (the flat punch): its side wall and corner are no graph
/// y = g(x), so a node that slides outwards past the rim opens, springs back and closes again,
/// and the contact set cycles (docs/MODEL.md §12.3).  The cause and the ways out, worded for a
/// failed increment's message; nothing for punches without a rim.
std::optional<std::string> rim_cycling_cause(const PunchShape& punch);

class CurrentConfigurationContact final : public ContactDiscretization {
public:
  CurrentConfigurationContact(const Mesh& mesh, std::shared_ptr<const PunchShape> punch, const StiffnessPattern& pattern,
                              const std::vector<double>& stiffness_values);
  CurrentConfigurationContact(std::shared_ptr<const PunchShape> punch, double symmetry_factor,
                              std::vector<ContactCandidate> candidates);

  /// The candidate's current abscissa X + u and its penetration v + alpha - g(X + u) (-inf where
  /// the node has left the punch's surface, beyond a rim).
  double current_abscissa(std::size_t candidate, const double* u) const;
  double current_penetration(std::size_t candidate, const double* u, double alpha) const;

  std::unique_ptr<ContactDiscretization> on_candidates(std::vector<ContactCandidate> candidates) const override;
  void write_residual_rows(const double* u, double alpha, const double* row_force, double* f) const override;
  std::uint64_t write_jacobian_rows(const double* u, double alpha, const double* row_force,
                                    const StiffnessPattern& pattern,
                                    const std::vector<std::vector<std::int64_t>>& row_positions,
                                    double* values) const override;
  void write_parameter_derivative_rows(const double* u, double alpha, const double* row_force,
                                       const double* d_row_force, double d_log_stiffness, double* df) const override;
  void write_depth_derivative_rows(const double* u, double alpha, const double* row_force, double* df) const override;
  bool rows_pin_unknowns() const override { return false; }
  bool rows_keep_symmetry() const override { return false; }

  /// P, the contact nodes and the gaps at the current abscissae.
  ContactResult evaluate(const double* u, const double* internal_force, double alpha) const override;
  /// contact_edge_from_open_side over the candidates' current abscissae.
  double half_width(const double* u, double alpha, const ContactResult& contact) const override;
  bool touches(const double* u, double alpha) const override;
  std::vector<double> admissibility_violation(const double* u, double alpha) const override;
  std::optional<std::string> known_cycling_cause() const override { return rim_cycling_cause(*punch_shape()); }

private:
  bool active(std::size_t candidate, const double* u, double alpha, double vertical_row_force) const;
  std::vector<int> tangential_row_;  ///< per candidate, its horizontal row's index in row_equations(), or -1
};

}  // namespace indentsim
