#include "indentsim/solver.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <type_traits>

#include "indentsim/error.hpp"
#include "indentsim/interruption.hpp"

#include "cholmod_solver.hpp"
#include "sundials_handles.hpp"

namespace indentsim {

static_assert(std::is_same_v<sunindextype, std::int64_t>,
              "SUNDIALS on Debian uses 64-bit indices; the stiffness pattern stores int64_t");

// ---------------------------------------------------------------------------------------------
// The residual and Jacobian of elastic contact.

ContactEquations::ContactEquations(const StiffnessPattern& pattern, BulkOperator& bulk, const ContactBoundary& contact)
    : pattern_(pattern), bulk_(&bulk), contact_(contact), internal_force_(pattern.size()) {
  for (const auto& c : contact.candidates()) contact_rows_.push_back(pattern.row_positions(c.equation));
}

void ContactEquations::residual(const double* u, double alpha, double* f) {
  bulk_->internal_force(u, f);
  const auto& cs = contact_.candidates();
  residual_u_.assign(u, u + pattern_.size());
  residual_contact_force_.resize(cs.size());
  residual_bulk_ = bulk_;
  for (std::size_t i = 0; i < cs.size(); ++i) {
    const auto& c = cs[i];
    residual_contact_force_[i] = f[c.equation];
    f[c.equation] = ContactBoundary::complementarity(c, f[c.equation], u[c.equation], alpha);
  }
}

bool ActiveSetHistory::record(std::uint64_t signature, double residual) {
  bool cycle = false;
  if (!seen_.empty() && seen_.back().first != signature)
    for (std::size_t k = 0; k + 1 < seen_.size(); ++k)
      if (seen_[k].first == signature && residual > 0.1 * seen_[k].second) cycle = true;
  seen_.emplace_back(signature, residual);
  return cycle;
}

void ContactEquations::jacobian(const double* u, double alpha, double* values) {
  bulk_->tangent(u, values);
  const auto& cs = contact_.candidates();
  const bool cached = residual_bulk_ == bulk_ && residual_u_.size() == static_cast<std::size_t>(pattern_.size()) &&
                      std::equal(residual_u_.begin(), residual_u_.end(), u);
  if (!cached) {
    bulk_->internal_force(u, internal_force_.data());
    residual_contact_force_.resize(cs.size());
    for (std::size_t i = 0; i < cs.size(); ++i) residual_contact_force_[i] = internal_force_[cs[i].equation];
  }
  std::uint64_t signature = 0xcbf29ce484222325ull;  // FNV-1a over the active flags
  for (std::size_t i = 0; i < cs.size(); ++i) {
    const auto& c = cs[i];
    const bool active = ContactBoundary::active(c, residual_contact_force_[i], u[c.equation], alpha);
    signature = (signature ^ (active ? 1u : 2u)) * 0x100000001b3ull;
    if (!active) continue;
    // Active node: the row of c (v + alpha - g) is c e_k.
    for (std::int64_t p : contact_rows_[i]) values[p] = 0.0;
    values[pattern_.diagonal_position(c.equation)] = c.scale;
  }
  signature_ = signature;
}

// ---------------------------------------------------------------------------------------------
// A SUNLinearSolver around SUNLinSol_KLU that keeps KLU's symbolic analysis across KINSol calls.
//
// KINSOL calls the linear solver's `initialize` at the start of every KINSol call, and
// SUNLinSol_KLU's initialize forces a new symbolic analysis and a full factorization
// (../shared/STACK.md).  The sparsity pattern of this problem never changes, so this wrapper
// forwards `initialize` only until the first analysis exists; afterwards every setup is a KLU
// refactorization reusing the symbolic analysis and the previous pivot sequence.  If a
// refactorization fails (a pivot that was fine became zero) the wrapper analyses and factors
// afresh, so reuse never costs robustness.  SUNLinSol_KLU itself checks KLU's rcond after a
// refactorization and factors again when the old pivots have become poor.

namespace {

struct KluWithReuse {
  sundials::LinearSolver klu;
  long numeric_factorizations = 0;
  long symbolic_analyses = 0;
  bool fresh_numeric = false;  // the next setup factors afresh (new pivots), keeping the analysis
  bool keep_factor = false;    // the next setup keeps the current factor (a chord step)
  double condition_estimate = 0.0;  // of the increment's first (fresh) factorization

  static KluWithReuse* self(SUNLinearSolver s) { return static_cast<KluWithReuse*>(s->content); }
  static SUNLinearSolverContent_KLU klu_content(SUNLinearSolver klu) {
    return static_cast<SUNLinearSolverContent_KLU>(klu->content);
  }

  static SUNLinearSolver_Type type(SUNLinearSolver) { return SUNLINEARSOLVER_DIRECT; }
  static SUNLinearSolver_ID id(SUNLinearSolver) { return SUNLINEARSOLVER_KLU; }
  // Called by KINSOL at the start of every KINSol call (every increment).  The symbolic analysis
  // is kept; the first factorization of the increment is a full numeric one with fresh pivoting,
  // later ones refactor with its pivots.  So an increment's arithmetic depends only on its own
  // matrices, not on what the previous increment left in KLU: a run resumed from a checkpoint
  // repeats an uninterrupted run bit for bit.
  static int initialize(SUNLinearSolver s) {
    KluWithReuse* me = self(s);
    if (me->symbolic_analyses == 0) return SUNLinSolInitialize_KLU(me->klu.get());
    me->fresh_numeric = true;
    return SUNLS_SUCCESS;
  }
  static int setup(SUNLinearSolver s, SUNMatrix a) {
    KluWithReuse* me = self(s);
    SUNLinearSolver klu = me->klu.get();
    SUNLinearSolverContent_KLU content = klu_content(klu);
    if (me->keep_factor && content->numeric) {
      me->keep_factor = false;
      return SUNLS_SUCCESS;
    }
    ++me->numeric_factorizations;
    if (me->fresh_numeric && content->symbolic) {
      me->fresh_numeric = false;
      if (content->numeric) sun_klu_free_numeric(&content->numeric, &content->common);
      content->numeric = sun_klu_factor(SUNSparseMatrix_IndexPointers(a), SUNSparseMatrix_IndexValues(a),
                                        SUNSparseMatrix_Data(a), content->symbolic, &content->common);
      content->last_flag = content->numeric ? SUNLS_SUCCESS : SUNLS_PACKAGE_FAIL_REC;
      if (content->numeric &&
          sun_klu_condest(SUNSparseMatrix_IndexPointers(a), SUNSparseMatrix_Data(a), content->symbolic,
                          content->numeric, &content->common))
        me->condition_estimate = content->common.condest;
      return content->last_flag;
    }
    const bool analyse = content->first_factorize != 0;
    int flag = SUNLinSolSetup_KLU(klu, a);
    if (flag != SUNLS_SUCCESS && !analyse) {
      // A refactorization failed (a pivot that was fine became zero): analyse and factor afresh.
      content->first_factorize = 1;
      flag = SUNLinSolSetup_KLU(klu, a);
      ++me->symbolic_analyses;
    } else if (analyse) {
      ++me->symbolic_analyses;
    }
    return flag;
  }
  static int solve(SUNLinearSolver s, SUNMatrix a, N_Vector x, N_Vector b, realtype tol) {
    return SUNLinSolSolve_KLU(self(s)->klu.get(), a, x, b, tol);
  }
  static sunindextype last_flag(SUNLinearSolver s) { return SUNLinSolLastFlag_KLU(self(s)->klu.get()); }
  static int free(SUNLinearSolver s) {
    // The KLU solver is owned by the C++ object; only the shell belongs to SUNDIALS.
    SUNLinSolFreeEmpty(s);
    return SUNLS_SUCCESS;
  }
};

}  // namespace

// ---------------------------------------------------------------------------------------------

// A chord step needs the previous step to have cut the residual by this factor (see above).
constexpr double chord_contraction = 1e-2;
// Residual norms kept per solve (diagnostics and the convergence tests need the first few).
constexpr std::size_t max_residual_history = 10000;

struct NewtonSolver::Impl {
  IncrementEquations& equations;
  NewtonSettings settings;
  sundials::Context context;
  sundials::Vector u, u_scale, f_scale;
  sundials::Matrix jacobian;
  KluWithReuse klu;
  sundials::LinearSolver klu_shell;       // our SUNLinearSolver around SUNLinSol_KLU
  std::unique_ptr<CholmodSolver> cholmod;  // or CHOLMOD's supernodal Cholesky
  sundials::KinsolMemory kinsol;
  double alpha = 0.0;
  std::string last_message;
  std::vector<double> residual_history;
  ActiveSetHistory active_sets;
  bool cycling = false;
  bool stop_on_cycling = true;
  // Chord steps (see jacobian_callback): the active set and residual at the last factorization.
  bool chord_allowed = false, factored = false;
  std::uint64_t factored_signature = 0;
  double previous_norm = 0.0;

  Impl(IncrementEquations& eq, const NewtonSettings& s)
      : equations(eq),
        settings(s),
        u(sundials::make_serial_vector(eq.size(), context)),
        u_scale(sundials::make_serial_vector(eq.size(), context)),
        f_scale(sundials::make_serial_vector(eq.size(), context)),
        jacobian(SUNSparseMatrix(eq.size(), eq.size(), eq.pattern().nonzeros(), CSC_MAT, context)),
        kinsol(context) {
    if (!jacobian) throw std::runtime_error("SUNSparseMatrix failed");
    SUNLinearSolver linear_solver = nullptr;
    if (settings.linear == LinearSolverKind::cholmod) {
      cholmod = std::make_unique<CholmodSolver>(context);
      linear_solver = cholmod->get();
    } else {
      klu.klu.reset(SUNLinSol_KLU(u.get(), jacobian.get(), context));
      if (!klu.klu) throw std::runtime_error("SUNLinSol_KLU failed");
      // AMD fill-reducing ordering: 2-3x faster with less fill than KLU's default COLAMD on
      // finite-element matrices (../shared/STACK.md).
      sundials::check(SUNLinSol_KLUSetOrdering(klu.klu.get(), 0), "SUNLinSol_KLUSetOrdering");
      klu_shell.reset(SUNLinSolNewEmpty(context));
      if (!klu_shell) throw std::runtime_error("SUNLinSolNewEmpty failed");
      linear_solver = klu_shell.get();
      linear_solver->content = &klu;
      linear_solver->ops->gettype = KluWithReuse::type;
      linear_solver->ops->getid = KluWithReuse::id;
      linear_solver->ops->initialize = KluWithReuse::initialize;
      linear_solver->ops->setup = KluWithReuse::setup;
      linear_solver->ops->solve = KluWithReuse::solve;
      linear_solver->ops->lastflag = KluWithReuse::last_flag;
      linear_solver->ops->free = KluWithReuse::free;
    }

    N_VConst(1.0 / settings.displacement_scale, u_scale.get());
    N_VConst(1.0 / settings.force_scale, f_scale.get());

    sundials::check(KINInit(kinsol, residual_callback, u.get()), "KINInit");
    sundials::check(KINSetUserData(kinsol, this), "KINSetUserData");
    sundials::check(KINSetErrHandlerFn(kinsol, error_callback, this), "KINSetErrHandlerFn");
    sundials::check(KINSetLinearSolver(kinsol, linear_solver, jacobian.get()), "KINSetLinearSolver");
    sundials::check(KINSetJacFn(kinsol, jacobian_callback), "KINSetJacFn");
    // Exact (semi-smooth) Newton: a fresh Jacobian every iteration.  The active set can change
    // at any iteration, and a stale Jacobian would carry the wrong contact rows.
    sundials::check(KINSetMaxSetupCalls(kinsol, 1), "KINSetMaxSetupCalls");
    sundials::check(KINSetNumMaxIters(kinsol, settings.max_iterations), "KINSetNumMaxIters");
    sundials::check(KINSetFuncNormTol(kinsol, settings.tolerance), "KINSetFuncNormTol");
    // Convergence is judged on the residual only: a tiny step is not success.
    sundials::check(KINSetScaledStepTol(kinsol, 1e-300), "KINSetScaledStepTol");
    // The predictor can be far from the solution in scaled units (first increment from u = 0):
    // KINSOL's default step bound would stop it (STACK.md), so allow any step.
    sundials::check(KINSetMaxNewtonStep(kinsol, 1e30), "KINSetMaxNewtonStep");
  }

  static int residual_callback(N_Vector u, N_Vector f, void* data) {
    // A stop requested from outside (SIGINT/SIGTERM) ends this solve at once (unrecoverable for
    // KINSOL); the simulation then returns to its last converged increment.
    if (interruption_requested()) return -1;
    auto* me = static_cast<Impl*>(data);
    double* values = N_VGetArrayPointer(f);
    me->equations.residual(N_VGetArrayPointer(u), me->alpha, values);
    double norm = 0.0;
    for (sunindextype i = 0; i < N_VGetLength(f); ++i) norm = std::max(norm, std::abs(values[i]));
    // Bounded: a solve that never converges must not grow memory without end.
    if (me->residual_history.size() < max_residual_history) me->residual_history.push_back(norm / me->settings.force_scale);
    return 0;
  }

  static int jacobian_callback(N_Vector u, N_Vector fu, SUNMatrix j, void* data, N_Vector, N_Vector) {
    auto* me = static_cast<Impl*>(data);
    // KINSOL zeroes the whole matrix, index arrays included, before each call (STACK.md):
    // write the fixed pattern back every time.
    const auto& pattern = me->equations.pattern();
    std::copy(pattern.column_start().begin(), pattern.column_start().end(), SUNSparseMatrix_IndexPointers(j));
    std::copy(pattern.row_index().begin(), pattern.row_index().end(), SUNSparseMatrix_IndexValues(j));
    me->equations.jacobian(N_VGetArrayPointer(u), me->alpha, SUNSparseMatrix_Data(j));
    // A cycling active set stops the plain attempt (recoverable): the caller repeats the trial
    // with KINSOL's line search, whose damped steps break the cycle, and cuts the increment back
    // only if that fails too.
    const double* f = N_VGetArrayPointer(fu);
    double norm = 0.0;
    for (sunindextype i = 0; i < N_VGetLength(fu); ++i) norm = std::max(norm, std::abs(f[i]));
    const std::uint64_t signature = me->equations.active_set_signature();
    if (me->active_sets.record(signature, norm) && me->stop_on_cycling) {
      me->cycling = true;
      return 1;
    }
    // Chord step: keep the last factor (KINSOL still gets the fresh Jacobian, for its line search
    // and norms) when the active set is the one factored and the last step cut the residual by
    // chord_contraction or better -- the iteration is then in Newton's quadratic range, where the
    // Jacobian has changed by O(|du|) and the old factor contracts almost as well.  A chord step
    // that contracts less is followed by a fresh factorization.  Only this solve's history
    // decides, so a resumed run repeats the same steps.
    const bool chord = me->chord_allowed && me->factored && signature == me->factored_signature &&
                       norm <= chord_contraction * me->previous_norm;
    me->previous_norm = norm;
    if (chord) {
      if (me->cholmod) me->cholmod->keep_factor_once();
      else me->klu.keep_factor = true;
    } else {
      me->factored = true;
      me->factored_signature = signature;
    }
    return 0;
  }

  static void error_callback(int, const char* module, const char* function, char* msg, void* data) {
    static_cast<Impl*>(data)->last_message = std::string(module) + "/" + function + ": " + msg;
  }

  double scaled_residual(const double* u_data) {
    std::vector<double> f(static_cast<std::size_t>(equations.size()));
    equations.residual(u_data, alpha, f.data());
    double norm = 0.0;
    for (double v : f) norm = std::max(norm, std::abs(v));
    return norm / settings.force_scale;
  }
};

NewtonSolver::NewtonSolver(IncrementEquations& equations, const NewtonSettings& settings)
    : impl_(std::make_unique<Impl>(equations, settings)) {}

NewtonSolver::~NewtonSolver() = default;

NewtonReport NewtonSolver::solve(double alpha, std::vector<double>& u, Globalization globalization,
                                 int max_iterations) {
  Impl& m = *impl_;
  const int limit = max_iterations > 0 ? std::min(max_iterations, m.settings.max_iterations) : m.settings.max_iterations;
  sundials::check(KINSetNumMaxIters(m.kinsol, limit), "KINSetNumMaxIters");
  m.alpha = alpha;
  m.last_message.clear();
  m.residual_history.clear();
  double* data = N_VGetArrayPointer(m.u.get());
  std::copy(u.begin(), u.end(), data);
  m.active_sets.clear();
  m.cycling = false;
  m.stop_on_cycling = globalization == Globalization::none;
  m.chord_allowed = m.settings.chord_steps && globalization == Globalization::none;
  m.factored = false;
  m.previous_norm = 0.0;
  m.klu.keep_factor = false;
  const long factorizations_before = total_factorizations();
  const long analyses_before = total_symbolic_analyses();

  NewtonReport report;
  const int strategy = globalization == Globalization::line_search ? KIN_LINESEARCH : KIN_NONE;
  report.kinsol_flag = KINSol(m.kinsol, m.u.get(), strategy, m.u_scale.get(), m.f_scale.get());
  long iterations = 0;
  KINGetNumNonlinSolvIters(m.kinsol, &iterations);
  report.iterations = iterations;
  report.factorizations = total_factorizations() - factorizations_before;
  report.symbolic_analyses = total_symbolic_analyses() - analyses_before;
  report.residual = m.scaled_residual(data);
  report.condition_estimate = m.cholmod ? m.cholmod->condition_estimate() : m.klu.condition_estimate;
  // Trust the residual, not the return code alone: KIN_STEP_LT_STPTOL and friends are not
  // convergence, and a success must really satisfy the tolerance.
  report.converged = report.kinsol_flag >= 0 && report.residual <= m.settings.tolerance;
  report.message = m.cycling ? "active-set cycling between contact sets detected" : m.last_message;
  report.residual_history = m.residual_history;
  std::copy(data, data + u.size(), u.begin());
  return report;
}

void NewtonSolver::solve_linearized(const std::vector<double>& u, double alpha,
                                    std::vector<std::vector<double>>& right_hand_sides) {
  Impl& m = *impl_;
  const std::size_t n = static_cast<std::size_t>(m.equations.size());
  if (u.size() != n) throw std::invalid_argument("solve_linearized: u does not fit the system");
  m.alpha = alpha;
  // The residual first: the contact rows' branch is chosen from the internal force at u.
  std::vector<double> f(n);
  m.equations.residual(u.data(), alpha, f.data());
  SUNMatrix j = m.jacobian.get();
  const auto& pattern = m.equations.pattern();
  std::copy(pattern.column_start().begin(), pattern.column_start().end(), SUNSparseMatrix_IndexPointers(j));
  std::copy(pattern.row_index().begin(), pattern.row_index().end(), SUNSparseMatrix_IndexValues(j));
  m.equations.jacobian(u.data(), alpha, SUNSparseMatrix_Data(j));
  // A chord step's request to keep the factor may be pending from the converged solve: this
  // matrix must be factored.
  m.klu.keep_factor = false;
  if (m.cholmod) m.cholmod->clear_keep_factor();
  SUNLinearSolver solver = m.cholmod ? m.cholmod->get() : m.klu_shell.get();
  if (SUNLinSolSetup(solver, j) != SUNLS_SUCCESS) throw SolverError("the sensitivity system could not be factored");
  sundials::Vector x = sundials::make_serial_vector(static_cast<sunindextype>(n), m.context);
  sundials::Vector b = sundials::make_serial_vector(static_cast<sunindextype>(n), m.context);
  for (auto& rhs : right_hand_sides) {
    if (rhs.size() != n) throw std::invalid_argument("solve_linearized: a right-hand side does not fit the system");
    std::copy(rhs.begin(), rhs.end(), N_VGetArrayPointer(b.get()));
    if (SUNLinSolSolve(solver, j, x.get(), b.get(), 0.0) != SUNLS_SUCCESS)
      throw SolverError("the sensitivity system could not be solved");
    const double* xs = N_VGetArrayPointer(x.get());
    std::copy(xs, xs + n, rhs.begin());
  }
}

long NewtonSolver::total_factorizations() const {
  return impl_->cholmod ? impl_->cholmod->numeric_factorizations() : impl_->klu.numeric_factorizations;
}
long NewtonSolver::total_symbolic_analyses() const {
  return impl_->cholmod ? impl_->cholmod->symbolic_analyses() : impl_->klu.symbolic_analyses;
}

}  // namespace indentsim
