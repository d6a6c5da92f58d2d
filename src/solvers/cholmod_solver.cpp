#include "cholmod_solver.hpp"
#include "cholmod_common.hpp"
#include "fill_reducing_order.hpp"

#include <cstring>
#include <stdexcept>
#include <vector>

#include <cholmod.h>
#include <nvector/nvector_serial.h>
#include <sunmatrix/sunmatrix_sparse.h>

namespace indentsim {

struct CholmodSolver::State : CholmodCommon {
  cholmod_sparse* matrix = nullptr;  // symmetric (lower triangle read), same pattern as the Jacobian
  cholmod_factor* factor = nullptr;
  cholmod_dense* rhs = nullptr;
  std::vector<char> pinned;          // per unknown: its row holds only the diagonal
  std::vector<double> original;      // the Jacobian's values, for the right-hand side correction
  std::vector<sunindextype> column_start, row_index;
  std::vector<std::int64_t> dense_block;  // unknowns coupled all to all: ordered last
  long numeric_factorizations = 0, symbolic_analyses = 0;
  int last_flag = 0;
  bool keep_factor = false;

  State() = default;
  ~State() {
    if (factor) cholmod_l_free_factor(&factor, &common);
    if (matrix) cholmod_l_free_sparse(&matrix, &common);
    if (rhs) cholmod_l_free_dense(&rhs, &common);
  }
};

namespace {

using Cholmod = CholmodSolver::State;
Cholmod* self(SUNLinearSolver s) { return static_cast<Cholmod*>(s->content); }

SUNLinearSolver_ID id(SUNLinearSolver) { return SUNLINEARSOLVER_CUSTOM; }

// The symbolic analysis of the pattern just copied into c.matrix.  With a dense block, in the
// order that dissects the rest and factors the block last (fill_reducing_order.hpp: CHOLMOD's own
// choice on a condensed near field of 27 559 unknowns was AMD, with 40% more flops); else in
// CHOLMOD's own choice between AMD and METIS.
cholmod_factor* analyze(Cholmod& c) {
  if (!c.dense_block.empty()) {
    std::vector<std::int64_t> order = fill_reducing_order(c.column_start, c.row_index, c.dense_block);
    if (!order.empty()) {
      c.common.nmethods = 1;
      c.common.method[0].ordering = CHOLMOD_GIVEN;
      c.common.postorder = 1;
      return cholmod_l_analyze_p(c.matrix, order.data(), nullptr, 0, &c.common);
    }
  }
  return analyze_serialized(c.matrix, &c.common);
}

int setup(SUNLinearSolver s, SUNMatrix a) {
  Cholmod& c = *self(s);
  const auto n = static_cast<std::size_t>(SUNSparseMatrix_Columns(a));
  const sunindextype* colptr = SUNSparseMatrix_IndexPointers(a);
  const sunindextype* rowind = SUNSparseMatrix_IndexValues(a);
  const double* values = SUNSparseMatrix_Data(a);
  const auto nnz = static_cast<std::size_t>(colptr[n]);

  if (c.keep_factor && c.factor && c.numeric_factorizations > 0) {
    c.keep_factor = false;
    return c.last_flag = SUNLS_SUCCESS;
  }
  c.keep_factor = false;
  if (!c.matrix) {  // first setup: the pattern, the dense right-hand side, the symbolic analysis
    c.matrix = cholmod_l_allocate_sparse(n, n, nnz, /*sorted*/ 1, /*packed*/ 1, /*stype*/ -1, CHOLMOD_REAL, &c.common);
    c.rhs = cholmod_l_allocate_dense(n, 1, n, CHOLMOD_REAL, &c.common);
    if (!c.matrix || !c.rhs) return c.last_flag = SUNLS_MEM_FAIL;
    std::memcpy(c.matrix->p, colptr, (n + 1) * sizeof(SuiteSparse_long));
    std::memcpy(c.matrix->i, rowind, nnz * sizeof(SuiteSparse_long));
    c.column_start.assign(colptr, colptr + n + 1);
    c.row_index.assign(rowind, rowind + nnz);
    c.pinned.assign(n, 0);
    c.original.assign(nnz, 0.0);
    c.factor = analyze(c);
    if (!c.factor) return c.last_flag = SUNLS_PACKAGE_FAIL_UNREC;
    ++c.symbolic_analyses;
  }

  std::memcpy(c.original.data(), values, nnz * sizeof(double));
  std::fill(c.pinned.begin(), c.pinned.end(), 1);
  for (std::size_t j = 0; j < n; ++j)
    for (auto p = colptr[j]; p < colptr[j + 1]; ++p)
      if (static_cast<std::size_t>(rowind[p]) != j && values[p] != 0.0) c.pinned[rowind[p]] = 0;
  auto* x = static_cast<double*>(c.matrix->x);
  for (std::size_t j = 0; j < n; ++j)
    for (auto p = colptr[j]; p < colptr[j + 1]; ++p) {
      const auto i = static_cast<std::size_t>(rowind[p]);
      x[p] = (i != j && (c.pinned[i] || c.pinned[j])) ? 0.0 : values[p];
    }
  ++c.numeric_factorizations;
  if (!cholmod_l_factorize(c.matrix, c.factor, &c.common) || c.common.status != CHOLMOD_OK)
    return c.last_flag = SUNLS_PACKAGE_FAIL_REC;  // not positive definite: let Newton cut back
  return c.last_flag = SUNLS_SUCCESS;
}

int solve(SUNLinearSolver s, SUNMatrix, N_Vector x, N_Vector b, sundials::Real) {
  Cholmod& c = *self(s);
  const std::size_t n = c.pinned.size();
  const double* bb = N_VGetArrayPointer(b);
  auto* r = static_cast<double*>(c.rhs->x);
  std::memcpy(r, bb, n * sizeof(double));
  // Pinned unknowns are known; their columns move to the right-hand side.
  for (std::size_t k = 0; k < n; ++k) {
    if (!c.pinned[k]) continue;
    double diagonal = 0.0;
    for (auto p = c.column_start[k]; p < c.column_start[k + 1]; ++p)
      if (static_cast<std::size_t>(c.row_index[p]) == k) diagonal = c.original[p];
    const double known = bb[k] / diagonal;
    for (auto p = c.column_start[k]; p < c.column_start[k + 1]; ++p) {
      const auto i = static_cast<std::size_t>(c.row_index[p]);
      if (i != k && !c.pinned[i]) r[i] -= c.original[p] * known;
    }
  }
  cholmod_dense* solution = cholmod_l_solve(CHOLMOD_A, c.factor, c.rhs, &c.common);
  if (!solution) return c.last_flag = SUNLS_PACKAGE_FAIL_REC;
  std::memcpy(N_VGetArrayPointer(x), solution->x, n * sizeof(double));
  cholmod_l_free_dense(&solution, &c.common);
  return c.last_flag = SUNLS_SUCCESS;
}

sunindextype last_flag(SUNLinearSolver s) { return self(s)->last_flag; }

}  // namespace

CholmodSolver::CholmodSolver(SUNContext context, std::vector<std::int64_t> dense_block)
    : state_(std::make_unique<State>()),
      shell_(make_direct_solver_shell(context, state_.get(), id, setup, solve, last_flag)) {
  state_->dense_block = std::move(dense_block);
}

CholmodSolver::~CholmodSolver() = default;

long CholmodSolver::numeric_factorizations() const { return state_->numeric_factorizations; }
void CholmodSolver::keep_factor_once() { state_->keep_factor = true; }
void CholmodSolver::clear_keep_factor() { state_->keep_factor = false; }
long CholmodSolver::symbolic_analyses() const { return state_->symbolic_analyses; }
long CholmodSolver::factor_nonzeros() const {
  return state_->factor ? static_cast<long>(state_->common.lnz) : 0;  // nnz(L) of the last analysis
}
double CholmodSolver::condition_estimate() const {
  if (!state_->factor) return 0.0;
  const double rcond = cholmod_l_rcond(state_->factor, &state_->common);
  return rcond > 0.0 ? 1.0 / rcond : 0.0;
}

}  // namespace indentsim
