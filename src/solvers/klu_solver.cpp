#include "klu_solver.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>
#include <klu.h>
#include <nvector/nvector_serial.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include "cholmod_common.hpp"

namespace indentsim {

static_assert(sizeof(SuiteSparse_long) == sizeof(sunindextype),
              "KLU's long interface and SUNDIALS' indices must agree (64-bit on Debian)");

// A refactorization whose reciprocal condition estimate falls below this lost the accuracy of its
// pivots: eps^(2/3), the threshold SUNLinSol_KLU applies after klu_refactor.
static const double refactor_rcond_limit = std::pow(std::numeric_limits<double>::epsilon(), 2.0 / 3.0);

namespace {

// A fill-reducing order of a structurally symmetric pattern: CHOLMOD's nested dissection (METIS
// bisections, constrained minimum degree on the parts), postordered.  On the near fields of
// plastic runs it leaves less fill than AMD as the mesh is refined -- nnz(L+U) 0.78 M against
// 0.86 M and 17% fewer flops at 11 000 unknowns (deep_plastic.toml, contact_nodes 30); refactor
// and solves take 7% less of the whole run there and 14% at contact_nodes 48 -- because a 2-D
// mesh's separators are what nested dissection is made for.  Empty if CHOLMOD fails (then AMD).
std::vector<SuiteSparse_long> nested_dissection_order(std::vector<SuiteSparse_long>& column_start,
                                                      std::vector<SuiteSparse_long>& row_index) {
  const auto n = static_cast<std::size_t>(column_start.size() - 1);
  CholmodCommon cholmod;
  cholmod_common* cm = &cholmod.common;
  cm->nmethods = 1;
  cm->method[0].ordering = CHOLMOD_NESDIS;
  cm->postorder = 1;
  cholmod_sparse pattern{};
  pattern.nrow = pattern.ncol = n;
  pattern.nzmax = static_cast<std::size_t>(column_start[n]);
  pattern.p = column_start.data();
  pattern.i = row_index.data();
  pattern.stype = 1;  // the upper triangle stands for the whole (symmetric) pattern
  pattern.itype = CHOLMOD_LONG;
  pattern.xtype = CHOLMOD_PATTERN;
  pattern.dtype = CHOLMOD_DOUBLE;
  pattern.sorted = 1;
  pattern.packed = 1;
  cholmod_factor* symbolic = analyze_serialized(&pattern, cm);
  if (!symbolic) return {};
  const auto* perm = static_cast<const SuiteSparse_long*>(symbolic->Perm);
  std::vector<SuiteSparse_long> order(perm, perm + n);
  cholmod_l_free_factor(&symbolic, cm);
  return order;
}

}  // namespace

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
    common.ordering = 0;  // AMD (../shared/STACK.md), when no nested-dissection order is given
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
  bool analyse(std::vector<SuiteSparse_long> columns, std::vector<SuiteSparse_long> rows, double* values) {
    column_start = std::move(columns);
    row_index = std::move(rows);
    const auto n = static_cast<SuiteSparse_long>(column_start.size() - 1);
    std::vector<SuiteSparse_long> order = nested_dissection_order(column_start, row_index);
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
    if (!k.analyse({colptr, colptr + n + 1}, {rowind, rowind + colptr[n]}, SUNSparseMatrix_Data(a)))
      return k.last_flag = SUNLS_PACKAGE_FAIL_UNREC;
    ++k.numeric_factorizations;
    k.estimate_condition_of(a);
    return k.last_flag = SUNLS_SUCCESS;
  }
  return k.last_flag = k.factor(a);
}

int solve(SUNLinearSolver s, SUNMatrix, N_Vector x, N_Vector b, realtype) {
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

void KluSolver::analyse(const std::vector<std::int64_t>& column_start, const std::vector<std::int64_t>& row_index,
                        std::vector<double> reference_values) {
  if (!state_->analyse({column_start.begin(), column_start.end()}, {row_index.begin(), row_index.end()},
                       reference_values.data()))
    throw std::runtime_error(fmt::format("KLU could not factor the elastic stiffness of the Newton system (status {})",
                                         state_->common.status));
}
long KluSolver::numeric_factorizations() const { return state_->numeric_factorizations; }
long KluSolver::symbolic_analyses() const { return state_->symbolic_analyses; }
void KluSolver::keep_factor_once() { state_->keep_factor = true; }
void KluSolver::clear_keep_factor() { state_->keep_factor = false; }
void KluSolver::estimate_condition_at_next_setup() { state_->estimate_condition = true; }
double KluSolver::condition_estimate() const { return state_->condition_estimate; }

}  // namespace indentsim
