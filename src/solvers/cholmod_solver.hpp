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
#include <cstdint>
#include <memory>
#include <vector>

#include "sparse_direct_solver.hpp"

namespace indentsim {

class CholmodSolver final : public SparseDirectSolver {
public:
  /// `dense_block`: the unknowns of the pattern to come that are coupled all to all
  /// (StiffnessPattern::dense_block), which the fill-reducing order puts last.
  explicit CholmodSolver(SUNContext context, std::vector<std::int64_t> dense_block = {});
  ~CholmodSolver() override;
  CholmodSolver(const CholmodSolver&) = delete;
  CholmodSolver& operator=(const CholmodSolver&) = delete;

  SUNLinearSolver get() const override { return shell_.get(); }
  long numeric_factorizations() const override;
  void keep_factor_once() override;
  void clear_keep_factor() override;
  long symbolic_analyses() const override;
  long factor_nonzeros() const override;
  /// 1 / rcond of the last factor (CHOLMOD's cheap estimate from the diagonal of L).
  double condition_estimate() const override;

  struct State;  // CHOLMOD's common block, matrix, factor and workspace

private:
  std::unique_ptr<State> state_;
  sundials::LinearSolver shell_;
};

}  // namespace indentsim
