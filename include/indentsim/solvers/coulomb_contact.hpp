#pragma once
// Coulomb friction between the specimen and the rigid punch (docs/MODEL.md §3.3).
//
// The normal rows are node-to-rigid's (contact.hpp).  The horizontal unknown of a candidate, where
// the mesh leaves it free, gets Alart and Curnier's semi-smooth equation
//   F^t_k = q_k - proj_[-mu l_k, mu l_k](q_k - c^t_k ds_k),
// q_k = r^t_k the tangential force the punch exerts along +x (it balances the node's horizontal
// internal force), l_k = max(0, c_k pen_k - r_k) Alart and Curnier's augmented normal force (-r_k
// at a solution, 0 where the normal row opens), ds_k = u_k - u^n_k the slip over the increment
// from the committed state u^n, c^t_k = K_tt.  Its branches: stick, row c^t e_k; slip with
// s = sign(q - c^t ds), row dr^t + mu s (dr - c_k e_v) -- the tangential stiffness row plus
// mu s times the normal one, unsymmetric; open (l = 0), the stiffness row.  F^t is continuous
// across all three.  mu = infinity ("sticking"): a node in contact keeps its
// committed horizontal displacement, row c^t e_k (pinned, symmetric once eliminated: CHOLMOD may
// take it).
#include <memory>
#include <vector>

#include "indentsim/geometry/mesh.hpp"
#include "indentsim/solvers/contact.hpp"
#include "indentsim/solvers/contact_discretization.hpp"

namespace indentsim {

class CoulombNodeToRigidContact final : public ContactDiscretization {
public:
  /// mu > 0, or +infinity for sticking contact.
  CoulombNodeToRigidContact(const Mesh& mesh, std::shared_ptr<const PunchShape> punch, const StiffnessPattern& pattern,
                            const std::vector<double>& stiffness_values, double mu);
  /// Given candidates (a subset renumbered onto a condensed system) and their committed
  /// horizontal displacements (per candidate, 0 where the unknown is fixed).
  CoulombNodeToRigidContact(std::shared_ptr<const PunchShape> punch, double symmetry_factor,
                            std::vector<ContactCandidate> candidates, double mu, std::vector<double> committed);

  double friction_coefficient() const { return mu_; }
  bool sticking() const;

  /// The tangential row's branch at u.
  enum class Branch { open, stick, slip_positive, slip_negative };
  Branch branch(std::size_t candidate, const double* u, double alpha, double normal_force_row,
                double tangential_force_row) const;

  std::unique_ptr<ContactDiscretization> on_candidates(std::vector<ContactCandidate> candidates) const override;
  void write_residual_rows(const double* u, double alpha, const double* row_force, double* f) const override;
  std::uint64_t write_jacobian_rows(const double* u, double alpha, const double* row_force,
                                    const StiffnessPattern& pattern,
                                    const std::vector<std::vector<std::int64_t>>& row_positions,
                                    double* values) const override;
  /// At fixed u and fixed committed state: the normal rows as node-to-rigid's, a slip row
  /// d r^t - mu s d l, a stick row's c^t ds scaled with the stiffness.
  void write_parameter_derivative_rows(const double* u, double alpha, const double* row_force,
                                       const double* d_row_force, double d_log_stiffness,
                                       double* df) const override;
  /// The normal rows' c_k on active rows; a slip row's -s mu c_k (its cone's radius moves with
  /// the penetration), the other tangential rows 0.
  void write_depth_derivative_rows(const double* u, double alpha, const double* row_force, double* df) const override;
  /// Sticking rows pin unknowns; sliding ones combine two stiffness rows.
  bool rows_pin_unknowns() const override { return sticking(); }
  bool rows_keep_symmetry() const override { return sticking(); }

  void hold_committed_state(const double* u_committed) override;
  bool carries_history() const override { return true; }
  /// The same rows with u as the committed state: an increment that unloads from u.
  std::unique_ptr<ContactDiscretization> at_load_reversal(const double* u) const override;

  /// Node-to-rigid's contact state, with each contact node's tangential force and whether it slips.
  ContactResult evaluate(const double* u, const double* internal_force, double alpha) const override;
  double half_width(const double* u, double alpha, const ContactResult& contact) const override;
  bool touches(const double* u, double alpha) const override;
  std::vector<double> admissibility_violation(const double* u, double alpha) const override;

private:
  NodeToRigidContact normal_;          ///< the normal rows' discretization, on the same candidates
  double mu_;
  std::vector<double> committed_;     ///< u^n_k per candidate (0 where the unknown is fixed)
  std::vector<int> tangential_row_;   ///< per candidate: its index in row_equations(), or -1
};

}  // namespace indentsim
