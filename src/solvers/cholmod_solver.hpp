#pragma once
// A SUNLinearSolver of our own around CHOLMOD's supernodal Cholesky, so KINSOL still drives
// every solve (private to the library; selected by [solver] linear = "cholmod" or "auto").
//
// The Newton matrices of this problem are symmetric except for the active contact rows, which
// hold only a diagonal entry c_k (their columns still hold stiffness entries).  Such a "pinned"
// unknown is known as soon as the right-hand side is: x_k = b_k / c_k.  The solver therefore
// moves the pinned columns to the right-hand side, b_i -= A_ik x_k, and factors the remaining
// symmetric positive definite matrix (pinned rows and columns reduced to their diagonal).  This is
// exact for any matrix of that shape; which rows are pinned is read off the matrix at each setup.
// The symbolic analysis (fill-reducing ordering, supernodes) is done once per pattern.
#include <memory>

#include "sundials_handles.hpp"

namespace indentsim {

class CholmodSolver {
public:
  explicit CholmodSolver(SUNContext context);
  ~CholmodSolver();
  CholmodSolver(const CholmodSolver&) = delete;
  CholmodSolver& operator=(const CholmodSolver&) = delete;

  /// The SUNDIALS face of the solver (owned by this object) to hand to KINSetLinearSolver.
  SUNLinearSolver get() const { return shell_.get(); }
  long numeric_factorizations() const;
  /// The next setup keeps the current factor instead of factoring its matrix (a chord step).
  void keep_factor_once();
  /// Withdraws a pending keep_factor_once (the next setup factors its matrix).
  void clear_keep_factor();
  long symbolic_analyses() const;
  /// 1 / rcond of the last factor (CHOLMOD's cheap estimate from the diagonal of L).
  double condition_estimate() const;

  struct State;  // CHOLMOD's common block, matrix, factor and workspace

private:
  std::unique_ptr<State> state_;
  sundials::LinearSolver shell_;
};

}  // namespace indentsim
