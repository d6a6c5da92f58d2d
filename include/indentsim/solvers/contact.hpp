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

struct ContactCandidate {
  int node = 0;
  int equation = 0;            ///< equation of the node's vertical unknown
  double x = 0.0;              ///< abscissa [m]
  double surface_height = 0.0; ///< g(x) [m]
  double scale = 0.0;          ///< c_k = K_kk [N/m^2]
  double tributary_measure = 0.0;  ///< the node's strip of surface (tributary_measure of layer_forces.hpp) [m or m^2]
};

/// How many surface nodes, from the axis, the punch can touch: those inside its rim (node i is
/// candidate i).
int contact_candidate_count(const Mesh& mesh, const PunchShape& punch);

/// The seed paper's discretization (docs/MODEL.md §3): one complementarity row per candidate
/// node, on its vertical unknown, against the rigid punch's profile at the node's abscissa.
class NodeToRigidContact final : public ContactDiscretization {
public:
  NodeToRigidContact(const Mesh& mesh, std::shared_ptr<const PunchShape> punch, const StiffnessPattern& pattern,
                     const std::vector<double>& stiffness_values);
  /// Given candidates (a subset renumbered onto a condensed system, say).
  NodeToRigidContact(std::shared_ptr<const PunchShape> punch, double symmetry_factor,
                     std::vector<ContactCandidate> candidates);

  const std::vector<ContactCandidate>& candidates() const { return candidates_; }
  const PunchShape& punch() const { return *punch_; }
  const std::shared_ptr<const PunchShape>& punch_shape() const { return punch_; }
  /// The body's force over the modelled part's nodal forces (Kinematics::symmetry_factor).
  double symmetry_factor() const { return symmetry_factor_; }

  /// v + alpha - g: how far the node is past the punch's surface (minus the gap d) [m].
  static double penetration(const ContactCandidate& c, double v, double alpha) { return v + alpha - c.surface_height; }
  /// The active branch of the complementarity function (ties count as contact).
  static bool active(const ContactCandidate& c, double internal_force, double v, double alpha) {
    return c.scale * penetration(c, v, alpha) >= internal_force;
  }
  static double complementarity(const ContactCandidate& c, double internal_force, double v, double alpha) {
    const double scaled = c.scale * penetration(c, v, alpha);
    return scaled >= internal_force ? scaled : internal_force;
  }

  // The Newton rows (contact_discretization.hpp): row i is candidate i's vertical unknown.
  const std::vector<int>& row_equations() const override { return row_equations_; }
  /// F_k = max(r_k, c_k (v_k + alpha - g_k)).
  void write_residual_rows(const double* u, double alpha, const double* row_force, double* f) const override;
  /// An active node's row is c_k e_k, an inactive one keeps its stiffness row (the primal-dual
  /// active set method); the signature is FNV-1a over the candidates' flags.
  std::uint64_t write_jacobian_rows(const double* u, double alpha, const double* row_force,
                                    const StiffnessPattern& pattern,
                                    const std::vector<std::vector<std::int64_t>>& row_positions,
                                    double* values) const override;
  bool rows_pin_unknowns() const override { return true; }

private:
  std::shared_ptr<const PunchShape> punch_;
  double symmetry_factor_ = 2.0;
  std::vector<ContactCandidate> candidates_;
  std::vector<int> row_equations_;  ///< candidates_[i].equation
};

/// The contact state of a converged solution.
struct ContactResult {
  double force = 0.0;          ///< P = f sum lambda_k: the whole body's force (f = 2, N/m; f = 1, N)
  double half_width = 0.0;     ///< a: contact half-width or radius [m]
  int contact_nodes = 0;       ///< nodes on the active set, the axis node included
  int outermost = -1;          ///< index (into candidates) of the outermost contact node
  std::vector<double> nodal_force;  ///< lambda_k >= 0 per candidate [N/m or N]
  std::vector<char> in_contact;     ///< per candidate
  std::vector<double> gap;          ///< d_k = g_k - alpha - v_k per candidate (0 on contact) [m]
};

/// Evaluates the contact state from the free-equation displacement u and internal force K u.
ContactResult evaluate_contact(const NodeToRigidContact& boundary, const double* u, const double* internal_force,
                               double alpha);

/// Contact half-width (radius) a from the discrete solution, resolved inside the element where the
/// active set ends.  A flat punch's contact ends at its rim once the outermost candidate (the rim
/// node) touches.  For a smooth punch the edge lies between the outermost contact node x_n and
/// the first open node x_{n+1}, and the open side locates it: next to the edge of any frictionless
/// contact of a smooth punch the surface is locally that of a half-space under a square-root
/// pressure, p ~ K (a - x)^{1/2} inside, and the gap opens as d ~ (4K / 3E') (x - a)^{3/2} outside
/// (the half-plane under a square-root load: the contact edge as a crack tip; Hertz's line contact
/// expands to exactly this, d = (2 sqrt 2 / 3) (a^2 / R) ((x - a) / a)^{3/2}).  It holds for
/// Hertz and Sneddon's cone alike, and, unlike the interior pressure profile, for plastic contact, whose pressure is
/// nearly uniform inside: only the width of the square-root layer shrinks, not the gap's law.  So
/// y_k = d_k^{2/3} is linear in x, y = c (x - a), over the first open nodes n+1 .. n+3, and a
/// weighted least-squares line through them gives a where y = 0.  The residuals are weighted by y_k
/// itself: the discrete gap is least accurate next to the edge (its neighbour x_n is pinned to the
/// punch) and more accurate away from it.  Gaps are taken relative to the largest, x relative to
/// x_{n+1} in units of the element, so the fit is the same in any units.  No node position enters
/// the result as a bound: an extrapolation that contradicts the active set (outside
/// (x_{n-1}, x_{n+1})) or a fit without an opening gap falls back to the middle of [x_n, x_{n+1}].
/// Consistent: the fitted nodes are within 3 elements of the edge; measured convergence in
/// tests/test_contact_edge.cpp and docs/DESIGN.md §4.
double contact_half_width(const NodeToRigidContact& boundary, const ContactResult& contact);

}  // namespace indentsim
