#pragma once
// The contact discretization: how the contact conditions become rows of the Newton system
// (docs/DESIGN.md §16).  The increment's equations (ContactEquations, solver.hpp) evaluate the
// bulk's internal force and tangent on the whole system and hand the rows of the contact's
// unknowns to the discretization, which overwrites them with its own residual and Jacobian rows:
// today's vertical node-to-rigid gap (NodeToRigidContact, contact.hpp) is one implementation; a
// weighted-gap (mortar) discretization and Coulomb friction are others, behind the same calls.
//
// What a discretization promises the linear solver is stated, not assumed: CHOLMOD solves the
// Newton matrix by eliminating pinned unknowns (a row c_k e_k) and factoring the symmetric rest
// (cholmod_solver.hpp), which is exact only for rows of that shape; KLU takes any rows.
#include <cstdint>
#include <vector>

#include "indentsim/solvers/assembly.hpp"

namespace indentsim {

class ContactDiscretization {
public:
  virtual ~ContactDiscretization() = default;

  /// The equations whose rows the discretization writes, row i of it on equation
  /// row_equations()[i] of the system.
  virtual const std::vector<int>& row_equations() const = 0;

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

  /// True when every row the discretization writes is either the bulk's own row or c_k e_k (an
  /// unknown pinned by the contact), so that the matrix is the bulk's symmetric one with pinned
  /// unknowns eliminated: what CHOLMOD's solve assumes.  Rows coupling unknowns (a weighted gap,
  /// a frictional slip) answer false, and only KLU may factor them.
  virtual bool rows_pin_unknowns() const = 0;
};

}  // namespace indentsim
