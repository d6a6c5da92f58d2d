#pragma once
// Frictionless Signorini contact with the rigid punch (docs/MODEL.md §3).
//
// The punch surface is y = -alpha + g(x), g the shape's profile (include/indentsim/punch.hpp).  At
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

#include "indentsim/assembly.hpp"
#include "indentsim/mesh.hpp"
#include "indentsim/punch.hpp"

namespace indentsim {

struct ContactCandidate {
  int node = 0;
  int equation = 0;            ///< equation of the node's vertical unknown
  double x = 0.0;              ///< abscissa [m]
  double surface_height = 0.0; ///< g(x) [m]
  double scale = 0.0;          ///< c_k = K_kk [N/m^2]
  double tributary_measure = 0.0;  ///< the node's strip of surface (tributary_measure of layer_forces.hpp) [m or m^2]
};

class ContactBoundary {
public:
  ContactBoundary(const Mesh& mesh, std::shared_ptr<const PunchShape> punch, const StiffnessPattern& pattern,
                  const std::vector<double>& stiffness_values);
  /// Given candidates (a subset renumbered onto a condensed system, say).
  ContactBoundary(std::shared_ptr<const PunchShape> punch, double symmetry_factor,
                  std::vector<ContactCandidate> candidates)
      : punch_(std::move(punch)), symmetry_factor_(symmetry_factor), candidates_(std::move(candidates)) {}

  const std::vector<ContactCandidate>& candidates() const { return candidates_; }
  const PunchShape& punch() const { return *punch_; }
  const std::shared_ptr<const PunchShape>& punch_shape() const { return punch_; }
  /// The body's force over the modelled part's nodal forces (Kinematics::symmetry_factor).
  double symmetry_factor() const { return symmetry_factor_; }

  /// The active branch of the complementarity function (ties count as contact).
  static bool active(const ContactCandidate& c, double internal_force, double v, double alpha) {
    return c.scale * (v + alpha - c.surface_height) >= internal_force;
  }
  static double complementarity(const ContactCandidate& c, double internal_force, double v, double alpha) {
    const double penetration = c.scale * (v + alpha - c.surface_height);
    return penetration >= internal_force ? penetration : internal_force;
  }

private:
  std::shared_ptr<const PunchShape> punch_;
  double symmetry_factor_ = 2.0;
  std::vector<ContactCandidate> candidates_;
};

/// The contact state of a converged solution.
struct ContactResult {
  double force = 0.0;          ///< P = f sum lambda_k: the whole body's force (f = 2, N/m; f = 1, N)
  double half_width = 0.0;     ///< a: contact half-width or radius [m]
  int contact_nodes = 0;       ///< nodes on the active set, the axis node included
  int outermost = -1;          ///< index (into candidates) of the outermost contact node
  std::vector<double> nodal_force;  ///< lambda_k >= 0 per candidate [N/m or N]
  std::vector<char> in_contact;     ///< per candidate
};

/// Evaluates the contact state from the free-equation displacement u and internal force K u.
ContactResult evaluate_contact(const ContactBoundary& boundary, const double* u, const double* internal_force,
                               double alpha);

/// Contact half-width (radius) from the discrete solution.  A flat punch's contact ends at its
/// rim once the outermost candidate (the rim node) touches.  For a smooth punch the edge lies between the outermost contact
/// node x_n and the first open node x_{n+1}; the nodal pressures p_k = lambda_k / w_k (w_k the
/// tributary width) next to it locate it.  Near the edge of a smooth punch the pressure has the
/// square-root form p^2 ~ C (a^2 - x^2) (exact for Hertz, first-order for any smooth edge, the
/// cone's arccosh(a/r) included), so a
/// least-squares line p^2 = A + B x^2 through the contact nodes n-5 .. n-1 gives a^2 = -A/B
/// (pressures taken relative to the largest of them, so the fit does not depend on units).
/// Node n itself is left out: its tributary strip is partly open.  The estimate is confined to
/// [x_{n-1}, x_{n+1}] (an outermost node may carry a sliver of force with the continuous edge
/// just inside it); with too few contact nodes it falls back to the middle of [x_n, x_{n+1}].
/// Consistent: the fitted nodes are within 6 elements of the edge, so it converges as h -> 0.
double contact_half_width(const ContactBoundary& boundary, const ContactResult& contact);

}  // namespace indentsim
