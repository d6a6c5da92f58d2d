#include "klu_solver.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>
#include <klu.h>
#include <nvector/nvector_serial.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <algorithm>

#include "fill_reducing_order.hpp"

namespace indentsim {

static_assert(sizeof(SuiteSparse_long) == sizeof(sunindextype),
              "KLU's long interface and SUNDIALS' indices must agree (64-bit on Debian)");

// A refactorization whose reciprocal condition estimate falls below this lost the accuracy of its
// pivots: eps^(2/3), the threshold SUNLinSol_KLU applies after klu_refactor.
static const double refactor_rcond_limit = std::pow(std::numeric_limits<double>::epsilon(), 2.0 / 3.0);

struct KluSolver::State {
  klu_l_common common{};
  klu_l_symbolic* symbolic = nullptr;
  klu_l_numeric* reference = nullptr;  // pivots of the reference matrix; refactored in place
  klu_l_numeric* fresh = nullptr;      // a matrix's own pivots, when refactoring lost accuracy
  klu_l_numeric* current = nullptr;    // the factor the last setup left (reference or fresh)
  // The pattern, copied once: KLU's interface takes non-const pointers.
  std::vector<SuiteSparse_long> column_start, row_index;
  long numeric_factorizations = 0, symbolic_analyses = 0;
  bool keep_factor = false, estimate_condition = false;
  double condition_estimate = 0.0;
  int last_flag = SUNLS_SUCCESS;

  State() {
    klu_l_defaults(&common);
    common.ordering = 0;  // AMD (docs/DESIGN.md §15), when no nested-dissection order is given
    common.btf = 0;       // a connected mesh's matrix is irreducible: one block, nothing to find
  }
  ~State() {
    if (fresh) klu_l_free_numeric(&fresh, &common);
    if (reference) klu_l_free_numeric(&reference, &common);
    if (symbolic) klu_l_free_symbolic(&symbolic, &common);
  }
  State(const State&) = delete;
  State& operator=(const State&) = delete;

  // The pattern's symbolic analysis, and the reference factorization that fixes the pivots.
  bool analyse(std::vector<SuiteSparse_long> columns, std::vector<SuiteSparse_long> rows,
               const std::vector<std::int64_t>& dense_block, std::int64_t last, double* values) {
    column_start = std::move(columns);
    row_index = std::move(rows);
    const auto n = static_cast<SuiteSparse_long>(column_start.size() - 1);
    std::vector<std::int64_t> order = fill_reducing_order(column_start, row_index, dense_block);
    // An unknown whose pivot the reference cannot choose goes last: its pivot is then the Schur
    // complement of all the others (force control's depth).
    if (last >= 0 && !order.empty()) {
      order.erase(std::find(order.begin(), order.end(), last));
      order.push_back(last);
    }
    symbolic = order.empty()
                   ? klu_l_analyze(n, column_start.data(), row_index.data(), &common)
                   : klu_l_analyze_given(n, column_start.data(), row_index.data(), order.data(), order.data(), &common);
    if (!symbolic) return false;
    ++symbolic_analyses;
    reference = klu_l_factor(column_start.data(), row_index.data(), values, symbolic, &common);
    current = reference;
    return reference != nullptr;
  }

  void estimate_condition_of(SUNMatrix a) {
    if (!estimate_condition) return;
    estimate_condition = false;
    if (klu_l_condest(column_start.data(), SUNSparseMatrix_Data(a), symbolic, current, &common))
      condition_estimate = common.condest;
  }

  int factor(SUNMatrix a) {
    double* values = SUNSparseMatrix_Data(a);
    ++numeric_factorizations;
    current = reference;
    const bool refactored = klu_l_refactor(column_start.data(), row_index.data(), values, symbolic, reference, &common) &&
                            klu_l_rcond(symbolic, reference, &common) && common.rcond >= refactor_rcond_limit;
    if (!refactored) {
      // The reference's pivots do not suit this matrix: its own, in the second factor.
      if (fresh) klu_l_free_numeric(&fresh, &common);
      fresh = klu_l_factor(column_start.data(), row_index.data(), values, symbolic, &common);
      current = fresh;
      if (!fresh) return SUNLS_PACKAGE_FAIL_REC;  // singular: Newton cuts the increment back
    }
    estimate_condition_of(a);
    return SUNLS_SUCCESS;
  }
};

namespace {

using Klu = KluSolver::State;
Klu* self(SUNLinearSolver s) { return static_cast<Klu*>(s->content); }

SUNLinearSolver_ID id(SUNLinearSolver) { return SUNLINEARSOLVER_KLU; }

int setup(SUNLinearSolver s, SUNMatrix a) {
  Klu& k = *self(s);
  if (k.keep_factor && k.current) {
    k.keep_factor = false;
    return k.last_flag = SUNLS_SUCCESS;
  }
  k.keep_factor = false;
  if (!k.symbolic) {  // no reference given: `a` becomes it
    const auto n = static_cast<std::size_t>(SUNSparseMatrix_Columns(a));
    const sunindextype* colptr = SUNSparseMatrix_IndexPointers(a);
    const sunindextype* rowind = SUNSparseMatrix_IndexValues(a);
    if (!k.analyse({colptr, colptr + n + 1}, {rowind, rowind + colptr[n]}, {}, -1, SUNSparseMatrix_Data(a)))
      return k.last_flag = SUNLS_PACKAGE_FAIL_UNREC;
    ++k.numeric_factorizations;
    k.estimate_condition_of(a);
    return k.last_flag = SUNLS_SUCCESS;
  }
  return k.last_flag = k.factor(a);
}

int solve(SUNLinearSolver s, SUNMatrix, N_Vector x, N_Vector b, sundials::Real) {
  Klu& k = *self(s);
  if (!k.current) return k.last_flag = SUNLS_PACKAGE_FAIL_UNREC;
  N_VScale(1.0, b, x);
  const auto n = static_cast<SuiteSparse_long>(k.column_start.size() - 1);
  if (!klu_l_solve(k.symbolic, k.current, n, 1, N_VGetArrayPointer(x), &k.common))
    return k.last_flag = SUNLS_PACKAGE_FAIL_REC;
  return k.last_flag = SUNLS_SUCCESS;
}

sunindextype last_flag(SUNLinearSolver s) { return self(s)->last_flag; }

}  // namespace

KluSolver::KluSolver(SUNContext context)
    : state_(std::make_unique<State>()),
      shell_(make_direct_solver_shell(context, state_.get(), id, setup, solve, last_flag)) {}

KluSolver::~KluSolver() = default;

void KluSolver::analyse(const StiffnessPattern& pattern, std::vector<double> reference_values) {
  const auto& column_start = pattern.column_start();
  const auto& row_index = pattern.row_index();
  if (!state_->analyse({column_start.begin(), column_start.end()}, {row_index.begin(), row_index.end()},
                       pattern.dense_block(), pattern.eliminated_last(), reference_values.data()))
    throw std::runtime_error(fmt::format("KLU could not factor the elastic stiffness of the Newton system (status {})",
                                         state_->common.status));
}
long KluSolver::numeric_factorizations() const { return state_->numeric_factorizations; }
long KluSolver::symbolic_analyses() const { return state_->symbolic_analyses; }
long KluSolver::factor_nonzeros() const {
  const klu_l_numeric* reference = state_->reference;
  return reference ? static_cast<long>(reference->lnz + reference->unz) : 0;
}
void KluSolver::keep_factor_once() { state_->keep_factor = true; }
void KluSolver::clear_keep_factor() { state_->keep_factor = false; }
void KluSolver::estimate_condition_at_next_setup() { state_->estimate_condition = true; }
double KluSolver::condition_estimate() const { return state_->condition_estimate; }

}  // namespace indentsim
