#pragma once
// Coulomb friction on the current configuration (docs/MODEL.md §12.3), for finite strain.
//
// A candidate node at reference abscissa X sits at x = X + u; the punch surface is
// y = -alpha + g(x).  The punch's force on the node is a normal part lambda (g'(x), -1) and a
// tangential part q (1, g'(x)); the node's internal force r = (r_u, r_v) balances it, so with
// w = 1 + g'^2
//   lambda = (g' r_u - r_v) / w,   q = (r_u + g' r_v) / w,
// and Coulomb's bound |q| sqrt(w) <= mu lambda sqrt(w) is |q| <= mu lambda.  The punch moves
// vertically, so a node that sticks keeps its current abscissa: the slip over the increment is
// ds = u - u^n, as in the small-deformation rows (coulomb_contact.hpp).  The rows of a candidate
// whose horizontal unknown is free:
//   normal       F_n = max(-lambda, c p)     p = v + alpha - g(X + u) the penetration
//   tangential   F_t = q - proj_[-mu l, mu l](q - c^t ds),   l = max(0, c p + lambda)
// (Alart and Curnier, 1991: l is lambda at every solution, 0 exactly where the normal row opens,
// so F_t is continuous across the normal switch as well).  Branches of F_t: open (l = 0), q;
// stick, c^t ds; slip with s = sign(q - c^t ds), q - s mu l.  The axis node (its horizontal
// unknown fixed by symmetry) keeps node-to-rigid's vertical row max(r_v, c p).  With g' = 0 the
// rows are those of coulomb_contact.hpp.  mu = infinity ("sticking"): a node in contact keeps
// its abscissa.  All Jacobian rows are exact (g'' included), and unsymmetric: KLU solves them.
#include <memory>
#include <vector>

#include "indentsim/geometry/mesh.hpp"
#include "indentsim/solvers/contact_discretization.hpp"
#include "indentsim/solvers/current_configuration_contact.hpp"

namespace indentsim {

class CoulombCurrentConfigurationContact final : public ContactDiscretization {
public:
  /// mu > 0, or +infinity for sticking contact.
  CoulombCurrentConfigurationContact(const Mesh& mesh, std::shared_ptr<const PunchShape> punch,
                                     const StiffnessPattern& pattern, const std::vector<double>& stiffness_values,
                                     double mu);
  /// Given candidates (a subset renumbered onto a condensed system) and their committed
  /// horizontal displacements (per candidate, 0 where the unknown is fixed).
  CoulombCurrentConfigurationContact(std::shared_ptr<const PunchShape> punch, double symmetry_factor,
                                     std::vector<ContactCandidate> candidates, double mu,
                                     std::vector<double> committed);

  double friction_coefficient() const { return mu_; }
  bool sticking() const;

  /// The tangential row's branch at u.
  enum class Branch { open, stick, slip_positive, slip_negative };
  Branch branch(std::size_t candidate, const double* u, double alpha, const double* row_force) const;

  std::unique_ptr<ContactDiscretization> on_candidates(std::vector<ContactCandidate> candidates) const override;
  void write_residual_rows(const double* u, double alpha, const double* row_force, double* f) const override;
  std::uint64_t write_jacobian_rows(const double* u, double alpha, const double* row_force,
                                    const StiffnessPattern& pattern,
                                    const std::vector<std::vector<std::int64_t>>& row_positions,
                                    double* values) const override;
  void write_parameter_derivative_rows(const double* u, double alpha, const double* row_force,
                                       const double* d_row_force, double d_log_stiffness,
                                       double* df) const override;
  void write_depth_derivative_rows(const double* u, double alpha, const double* row_force, double* df) const override;
  bool rows_pin_unknowns() const override { return false; }
  bool rows_keep_symmetry() const override { return false; }

  void hold_committed_state(const double* u_committed) override;
  bool carries_history() const override { return true; }
  std::optional<std::string> known_cycling_cause() const override { return rim_cycling_cause(*punch_shape()); }
  std::unique_ptr<ContactDiscretization> at_load_reversal(const double* u) const override;

  /// The contact state: P the punch's vertical force, each contact node's tangential force along
  /// the surface (positive towards +x) and whether it slides.
  ContactResult evaluate(const double* u, const double* internal_force, double alpha) const override;
  double half_width(const double* u, double alpha, const ContactResult& contact) const override;
  bool touches(const double* u, double alpha) const override;
  std::vector<double> admissibility_violation(const double* u, double alpha) const override;

private:
  /// A candidate's state at u: the surface's slope and curvature at its current abscissa, the
  /// normal and tangential forces and the penetration.
  struct NodeState {
    double slope = 0.0, curvature = 0.0, weight = 1.0;  ///< g', g'', w = 1 + g'^2
    double lambda = 0.0, q = 0.0, penetration = 0.0;
    double augmented = 0.0;  ///< l = max(0, c p + lambda)
    bool normal_active = false;
  };
  NodeState node_state(std::size_t candidate, const double* u, double alpha, const double* row_force) const;

  CurrentConfigurationContact geometry_;  ///< the current surface: abscissae, penetrations, the edge
  double mu_;
  std::vector<double> committed_;    ///< u^n_k per candidate (0 where the unknown is fixed)
  std::vector<int> tangential_row_;  ///< per candidate: its index in row_equations(), or -1
};

}  // namespace indentsim
