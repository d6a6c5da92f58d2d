#pragma once
// The sparse direct solvers the Newton systems are factored with, behind one face (private to the
// library): SuiteSparse KLU (klu_solver.hpp, the default) and CHOLMOD's supernodal Cholesky
// (cholmod_solver.hpp).  Each is a SUNLinearSolver of our own, so KINSOL can drive it directly
// (one factorization per Newton iteration, or a kept one for a chord step) or NewtonSolver can
// call it as the preconditioner of a Krylov solve (src/solvers/solver.cpp).
#include <memory>

#include "sundials_handles.hpp"

namespace indentsim {

class SparseDirectSolver {
public:
  virtual ~SparseDirectSolver() = default;
  /// The SUNDIALS face of the solver (owned by this object): SUNLinSolSetup factors a
  /// SUNSparseMatrix (CSC), SUNLinSolSolve solves with the factor.
  virtual SUNLinearSolver get() const = 0;
  virtual long numeric_factorizations() const = 0;
  virtual long symbolic_analyses() const = 0;
  /// Entries of the factors of the current symbolic analysis (KLU: L and U; CHOLMOD: L), 0
  /// before the first: the fill the ordering left, what each factorization and solve works on.
  virtual long factor_nonzeros() const = 0;
  /// The next setup keeps the current factor instead of factoring its matrix (a chord step).
  virtual void keep_factor_once() = 0;
  /// Withdraws a pending keep_factor_once (the next setup factors its matrix).
  virtual void clear_keep_factor() = 0;
  /// The next setup also estimates the condition number of its factor, where that costs extra
  /// work (KLU's condest: a few solves); CHOLMOD's estimate is always at hand.
  virtual void estimate_condition_at_next_setup() {}
  /// Condition estimate of the factor it was last asked for (KLU's condest, or 1/rcond of
  /// CHOLMOD's factor).
  virtual double condition_estimate() const = 0;
};

/// The SUNDIALS face of a direct solver of ours: a direct SUNLinearSolver whose `content` belongs
/// to the C++ object (freeing the shell frees only the shell) and whose `initialize`, which KINSOL
/// calls at every KINSol call, keeps what the solver has analysed.
sundials::LinearSolver make_direct_solver_shell(SUNContext context, void* content,
                                                SUNLinearSolver_ID (*id)(SUNLinearSolver),
                                                int (*setup)(SUNLinearSolver, SUNMatrix),
                                                int (*solve)(SUNLinearSolver, SUNMatrix, N_Vector, N_Vector, sundials::Real),
                                                sunindextype (*last_flag)(SUNLinearSolver));

}  // namespace indentsim
