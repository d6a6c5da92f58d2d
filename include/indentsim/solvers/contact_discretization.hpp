#pragma once
// The contact discretization: how the contact conditions become rows of the Newton system
// (docs/DESIGN.md §16, docs/MODEL.md §3).  The increment's equations (ContactEquations,
// solver.hpp) evaluate the bulk's internal force and tangent on the whole system and hand the rows
// of the contact's unknowns to the discretization, which writes its own residual and Jacobian rows
// over them.  Two implementations:
//
//   NodeToRigidContact    (contact.hpp) the seed paper's: a complementarity row per surface node,
//                         its vertical gap to the punch at the node's abscissa.
//   IntegratedGapContact  (integrated_gap_contact.hpp) the gap integrated over the surface
//                         segments against the exact punch profile, the contact pressure a
//                         penalty on the penetration, so that the contact edge moves continuously
//                         inside the elements.
//
// Both act on the same candidates: the top-surface nodes the punch can reach, in order from the
// axis, each with its vertical unknown.  What a discretization promises the linear solver is
// stated, not assumed: CHOLMOD solves the Newton matrix by eliminating pinned unknowns (a row
// c_k e_k) and factoring the symmetric rest (cholmod_solver.hpp), which is exact only when the
// contact keeps the matrix symmetric; KLU takes any rows.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "indentsim/geometry/punch.hpp"
#include "indentsim/solvers/assembly.hpp"

namespace indentsim {

struct ContactCandidate {
  int node = 0;
  int equation = 0;            ///< equation of the node's vertical unknown
  double x = 0.0;              ///< abscissa [m]
  double surface_height = 0.0; ///< g(x) [m]
  double scale = 0.0;          ///< c_k = K_kk [N/m^2]
  double tributary_measure = 0.0;  ///< the node's strip of surface (tributary_measure of line_forces.hpp) [m or m^2]
  /// Equation of the node's horizontal (radial) unknown, -1 where a symmetry condition fixes it
  /// (the axis node); its diagonal stiffness.  Only frictional rows use them.
  int tangential_equation = -1;
  double tangential_scale = 0.0;  ///< c^t_k = K_tt [N/m^2]
};

/// v + alpha - g: how far a candidate is past the punch's surface (minus the gap d) [m].
inline double penetration(const ContactCandidate& c, double v, double alpha) { return v + alpha - c.surface_height; }

/// Per candidate, the index of its horizontal row in row_equations() of a discretization built
/// with tangential rows (after the candidates' vertical rows, in candidate order), or -1 where a
/// symmetry condition fixes the unknown.
std::vector<int> tangential_row_indices(const std::vector<ContactCandidate>& candidates);

/// How many surface nodes, from the axis, the punch can touch: those inside its rim (node i is
/// candidate i).
int contact_candidate_count(const Mesh& mesh, const PunchShape& punch);

/// The candidates of a mesh: its first contact_candidate_count top nodes, scaled by the diagonal
/// of the stiffness `stiffness_values` in `pattern`.
std::vector<ContactCandidate> contact_candidates(const Mesh& mesh, const PunchShape& punch,
                                                 const StiffnessPattern& pattern,
                                                 const std::vector<double>& stiffness_values);

/// The contact state of a converged solution.
struct ContactResult {
  double force = 0.0;          ///< P = f sum lambda_k: the whole body's force (f = 2, N/m; f = 1, N)
  double half_width = 0.0;     ///< a: contact half-width or radius [m] (set by half_width())
  int contact_nodes = 0;       ///< candidates carrying contact force, the axis node included
  int outermost = -1;          ///< index (into candidates) of the outermost of them
  std::vector<double> nodal_force;  ///< lambda_k >= 0 per candidate: its reaction -r_k [N/m or N]
  std::vector<char> in_contact;     ///< per candidate: carries contact force
  std::vector<double> gap;          ///< d_k = g_k - alpha - v_k per candidate [m] (0 on node-to-rigid contact)
  /// q_k per candidate: the tangential force the punch exerts, along +x [N/m or N] (0 without
  /// friction and on open nodes).
  std::vector<double> tangential_force;
  std::vector<char> sliding;  ///< per candidate: in contact with |q_k| = mu lambda_k (friction only)

  /// No node in contact, every per-candidate field sized for `candidates`: where evaluate() starts.
  static ContactResult open(std::size_t candidates);
};

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
/// `gap` holds d_k per candidate and `n` is the outermost touching candidate.
double contact_edge_from_open_side(const std::vector<ContactCandidate>& candidates, const std::vector<double>& gap,
                                   int n);

class ContactDiscretization {
public:
  ContactDiscretization(std::shared_ptr<const PunchShape> punch, double symmetry_factor,
                        std::vector<ContactCandidate> candidates);
  virtual ~ContactDiscretization() = default;

  const std::vector<ContactCandidate>& candidates() const { return candidates_; }
  const PunchShape& punch() const { return *punch_; }
  const std::shared_ptr<const PunchShape>& punch_shape() const { return punch_; }
  /// The body's force over the modelled part's nodal forces (Kinematics::symmetry_factor).
  double symmetry_factor() const { return symmetry_factor_; }
  /// The equations whose rows the discretization writes: row i < candidates().size() is candidate
  /// i's vertical unknown; a frictional discretization appends the free horizontal unknowns of
  /// its candidates, in their order.
  const std::vector<int>& row_equations() const { return row_equations_; }
  /// True when the rows include the candidates' horizontal unknowns (friction): a condensed near
  /// field must keep them.
  bool has_tangential_rows() const { return row_equations_.size() > candidates_.size(); }

  /// Rows that depend on the committed state the increment starts from (friction's slip), which
  /// they read from `u_committed` in this discretization's numbering: called before every Newton
  /// solve and residual check.  Nothing for rows without history.
  virtual void hold_committed_state(const double* /*u_committed*/) {}
  /// True when the rows carry a history whose derivative under a material parameter is not
  /// carried (friction): the forward sensitivities are then unavailable.
  virtual bool carries_history() const { return false; }
  /// Where the model itself has no answer between two contact sets, so that Newton cycles
  /// between them at every depth: what a failed increment's message should name, if known.
  virtual std::optional<std::string> known_cycling_cause() const { return std::nullopt; }
  /// The discretization of an increment that unloads from u (the exact unloading stiffness of
  /// rows that carry history: friction's, with u committed); nullptr for the rows as they are.
  virtual std::unique_ptr<ContactDiscretization> at_load_reversal(const double* /*u*/) const { return nullptr; }

  /// The same discretization on `candidates`, a leading part of this one's renumbered onto
  /// another system (a condensed near field, condensation.hpp); their `scale` is that system's.
  virtual std::unique_ptr<ContactDiscretization> on_candidates(std::vector<ContactCandidate> candidates) const = 0;

  /// Overwrites the contact rows of the residual F(u; alpha).  On entry f holds the bulk's
  /// internal force at u, and `row_force[i]` that force on row i (the caller keeps it: the
  /// Jacobian at the same u chooses its branches on it).
  virtual void write_residual_rows(const double* u, double alpha, const double* row_force, double* f) const = 0;

  /// Overwrites the contact rows of the Jacobian at u: on entry `values` holds the bulk's tangent
  /// in `pattern`, `row_positions[i]` the value positions of row i, and `row_force` the internal
  /// force of the residual at the same u.  Returns a signature of the rows' branches (the active
  /// set), which the Newton iterations compare to detect cycles and to reuse a factorization.
  virtual std::uint64_t write_jacobian_rows(const double* u, double alpha, const double* row_force,
                                            const StiffnessPattern& pattern,
                                            const std::vector<std::vector<std::int64_t>>& row_positions,
                                            double* values) const = 0;

  /// dF/dtheta on the contact rows for a material parameter theta at fixed u: `d_row_force[i]`
  /// is d r_i / d theta, and `d_log_stiffness` d ln K / d theta, how the elastic stiffness the
  /// rows are scaled by moves (1/E for Young's modulus, 0 for a parameter of the plastic law).
  /// Writes df[row_equations()[i]].
  virtual void write_parameter_derivative_rows(const double* u, double alpha, const double* row_force,
                                               const double* d_row_force, double d_log_stiffness,
                                               double* df) const = 0;
  /// dF/dalpha on the contact rows at fixed u (the bulk's rows do not depend on alpha).
  virtual void write_depth_derivative_rows(const double* u, double alpha, const double* row_force,
                                           double* df) const = 0;

  /// True when every row the discretization writes is either the bulk's own row or c_k e_k (an
  /// unknown pinned by the contact).
  virtual bool rows_pin_unknowns() const = 0;
  /// True when the Jacobian stays symmetric once the pinned unknowns are eliminated: what
  /// CHOLMOD's solve assumes.  Frictional rows answer false, and only KLU may factor them.
  virtual bool rows_keep_symmetry() const = 0;

  /// The contact state at u, `internal_force` the bulk's force r(u) on the system.
  virtual ContactResult evaluate(const double* u, const double* internal_force, double alpha) const = 0;
  /// The contact half-width (radius) a of a contact state evaluated at u.
  virtual double half_width(const double* u, double alpha, const ContactResult& contact) const = 0;
  /// Whether the punch's surface reaches the specimen's anywhere at u (ties count).
  virtual bool touches(const double* u, double alpha) const = 0;
  /// What the contact conditions alone prove of a state whose bulk history is not at hand (a
  /// checkpoint's previous increment): per candidate, the force-sized violation of them
  /// (0 where they hold).
  virtual std::vector<double> admissibility_violation(const double* u, double alpha) const = 0;

protected:
  /// With `tangential_rows`, the candidates' free horizontal unknowns are rows too.
  ContactDiscretization(std::shared_ptr<const PunchShape> punch, double symmetry_factor,
                        std::vector<ContactCandidate> candidates, bool tangential_rows);

private:
  std::shared_ptr<const PunchShape> punch_;
  double symmetry_factor_ = 2.0;
  std::vector<ContactCandidate> candidates_;
  std::vector<int> row_equations_;  ///< candidates_[i].equation, then the free tangential_equation
};

}  // namespace indentsim
