#pragma once
// The increment's equations under force control (docs/MODEL.md §13.1): the depth alpha joins the
// unknowns and one equation closes it,
//
//     F(u, alpha) = 0,      (P(u, alpha) - P_target) / P_ref * s_F = 0,
//
// with P the force the contact reports (ContactDiscretization::evaluate: the reactions of the
// candidates in contact, times the symmetry factor), P_ref = max(P_target, P_max / 100) and s_F
// the Newton system's force scale, so that Newton's tolerance on max |F| / s_F lands P on its
// target to that tolerance relative to the target (to 1 % of the path's largest force).  The
// Jacobian is the depth-controlled one bordered by a column and a row:
//
//     [ dF/du          dF/dalpha ]     dF/dalpha: the contact rows' depth derivative
//     [ s dP/du        0         ]     dP/du = -f sum_{k in contact} K_t(k, :)
//
// (s = s_F / P_ref), factored by the same KLU as a matrix of one more unknown, ordered last
// (StiffnessPattern's dense block): its pivot is the Schur complement -s dP/du J^-1 dF/dalpha,
// the force's stiffness dP/dalpha at fixed contact set, which is positive wherever the punch
// carries load.  The unknown vector is (u, alpha); the solver's parameter is P_target.
#include <cstdint>
#include <vector>

#include "indentsim/solvers/solver.hpp"

namespace indentsim {

/// The force P_ref against which force control's equation is scaled: the target, and no less than
/// 1 % of the path's largest force (so that a target near zero is not asked for to a tolerance
/// relative to itself).  Newton lands P within its tolerance times this.
double force_control_reference(double target, double largest_force);

class ForceControlledEquations : public IncrementEquations {
public:
  /// `depth_controlled` are the equations at fixed depth (their contact discretization `contact`),
  /// `force_scale` the Newton system's and `largest_force` the path's largest target force.
  ForceControlledEquations(ContactEquations& depth_controlled, const ContactDiscretization& contact,
                           double force_scale, double largest_force);
  const StiffnessPattern& pattern() const override { return pattern_; }
  std::uint64_t active_set_signature() const override { return depth_controlled_.active_set_signature(); }
  /// x = (u, alpha), `target` the force P_target.
  void residual(const double* x, double target, double* f) override;
  void jacobian(const double* x, double target, double* values) override;
  bool pivot_reference(double* values) override;
  bool symmetric_but_pinned_rows() const override { return false; }

private:
  /// Copies values of the depth-controlled pattern into this one's positions (border zeroed).
  void embed(const std::vector<double>& inner, double* values) const;

  ContactEquations& depth_controlled_;
  const ContactDiscretization& contact_;
  double force_scale_ = 1.0, largest_force_ = 1.0;
  StiffnessPattern pattern_;
  std::vector<std::int64_t> inner_position_;  // per inner value, its position here
  std::vector<std::int64_t> border_column_;   // per contact row (row_equations order): position of (row, n)
  std::int64_t corner_ = 0;                   // position of (n, n)
  // The force row: per vertical candidate, the positions here of (n, j) for the columns j of its
  // row, and the inner positions of (k, j) that hold K_t(k, j).
  std::vector<std::vector<std::pair<std::int64_t, std::int64_t>>> force_row_;
  std::vector<double> inner_values_, internal_force_;
  // The candidates in contact at the last residual, and the x it was evaluated at: KINSOL evaluates
  // F(x) before J(x), so the force row reuses them instead of a second contact evaluation.
  std::vector<double> residual_x_;
  std::vector<char> residual_in_contact_;
};

}  // namespace indentsim
