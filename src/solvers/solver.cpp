#include "indentsim/solvers/solver.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <type_traits>

#include <sunlinsol/sunlinsol_spgmr.h>

#include "indentsim/base/error.hpp"
#include "indentsim/base/interruption.hpp"

#include "cholmod_solver.hpp"
#include "klu_solver.hpp"
#include "sundials_handles.hpp"

namespace indentsim {

static_assert(std::is_same_v<sunindextype, std::int64_t>,
              "SUNDIALS on Debian uses 64-bit indices; the stiffness pattern stores int64_t");

// ---------------------------------------------------------------------------------------------
// The residual and Jacobian of the bulk with contact.

ContactEquations::ContactEquations(const StiffnessPattern& pattern, BulkOperator& bulk, BulkOperator& elastic,
                                   const ContactDiscretization& contact)
    : pattern_(pattern), bulk_(&bulk), elastic_(elastic), contact_(contact), internal_force_(pattern.size()) {
  for (int equation : contact.row_equations()) contact_rows_.push_back(pattern.row_positions(equation));
}

void ContactEquations::residual(const double* u, double alpha, double* f) {
  bulk_->internal_force(u, f);
  const auto& rows = contact_.row_equations();
  residual_u_.assign(u, u + pattern_.size());
  residual_contact_force_.resize(rows.size());
  residual_bulk_ = bulk_;
  for (std::size_t i = 0; i < rows.size(); ++i) residual_contact_force_[i] = f[rows[i]];
  contact_.write_residual_rows(u, alpha, residual_contact_force_.data(), f);
}

// Coming back to an earlier contact set counts as a cycle unless the residual has at least halved
// since that visit.  Semi-smooth Newton often overshoots once at the contact edge on its way
// (A, B, A at a quarter of the first residual, deep_plastic.toml's early increments); stopping
// there repeated the whole solve with the line search, and a true cycle repeats its residual.
constexpr double cycle_contraction = 0.5;

bool ActiveSetHistory::record(std::uint64_t signature, double residual) {
  bool cycle = false;
  if (!seen_.empty() && seen_.back().first != signature)
    for (std::size_t k = 0; k + 1 < seen_.size(); ++k)
      if (seen_[k].first == signature && residual > cycle_contraction * seen_[k].second) cycle = true;
  seen_.emplace_back(signature, residual);
  return cycle;
}

void ContactEquations::jacobian(const double* u, double alpha, double* values) {
  bulk_->tangent(u, values);
  const auto& rows = contact_.row_equations();
  const bool cached = residual_bulk_ == bulk_ && residual_u_.size() == static_cast<std::size_t>(pattern_.size()) &&
                      std::equal(residual_u_.begin(), residual_u_.end(), u);
  if (!cached) {
    bulk_->internal_force(u, internal_force_.data());
    residual_contact_force_.resize(rows.size());
    for (std::size_t i = 0; i < rows.size(); ++i) residual_contact_force_[i] = internal_force_[rows[i]];
  }
  if (keep_bulk_rows_) {
    const std::size_t vertical = contact_.candidates().size();
    bulk_rows_.resize(vertical);
    for (std::size_t i = 0; i < vertical; ++i) {
      bulk_rows_[i].resize(contact_rows_[i].size());
      for (std::size_t p = 0; p < contact_rows_[i].size(); ++p) bulk_rows_[i][p] = values[contact_rows_[i][p]];
    }
  }
  signature_ = contact_.write_jacobian_rows(u, alpha, residual_contact_force_.data(), pattern_, contact_rows_, values);
}

bool ContactEquations::pivot_reference(double* values) {
  // The linear elastic stiffness (its tangent does not depend on u), no contact row replaced.
  const std::vector<double> zero(static_cast<std::size_t>(pattern_.size()), 0.0);
  elastic_.tangent(zero.data(), values);
  return true;
}

// ---------------------------------------------------------------------------------------------

// A chord step needs the previous step to have cut the residual by this factor (see below).
constexpr double chord_contraction = 1e-2;
// Residual norms kept per solve (diagnostics and the convergence tests need the first few).
constexpr std::size_t max_residual_history = 10000;
// The step tolerance as a share of the residual tolerance (see Impl's constructor).
constexpr double step_tolerance_share = 1e-3;
// GMRES's Krylov space per Newton iteration (no restarts): with a preconditioner from the same
// solve it converges in a few iterations; one that needs more is stale and is refreshed.
constexpr int krylov_dimension = 15;

struct NewtonSolver::Impl {
  IncrementEquations& equations;
  NewtonSettings settings;
  sundials::Context context;
  sundials::Vector u, u_scale, f_scale;
  sundials::Matrix jacobian;                  // the matrix the direct solver factors (CSC)
  std::unique_ptr<SparseDirectSolver> direct;  // KLU or CHOLMOD
  sundials::LinearSolver gmres;               // Krylov solves only
  sundials::KinsolMemory kinsol;
  double alpha = 0.0;
  std::string last_message;
  sundials::ErrorRoute error_route{[](const std::string& message, void* impl) {
                                     static_cast<Impl*>(impl)->last_message = message;
                                   },
                                   this};
  std::vector<double> residual_history;
  double best_residual = 0.0;
  std::vector<double> best_point;
  ActiveSetHistory active_sets;
  bool cycling = false;
  bool stop_on_cycling = true;
  // Chord steps (see jacobian_callback): the active set and residual at the last factorization.
  bool chord_allowed = false, factored = false;
  std::uint64_t factored_signature = 0;
  double previous_norm = 0.0;
  // Krylov solves: the Jacobian at the current iterate (for J v), and the preconditioner's age.
  std::vector<double> jacobian_values, jacobian_point;
  int preconditioner_setups = 0;  // calls of psetup in this solve

  Impl(IncrementEquations& eq, const NewtonSettings& s)
      : equations(eq),
        settings(s),
        u(sundials::make_serial_vector(eq.size(), context)),
        u_scale(sundials::make_serial_vector(eq.size(), context)),
        f_scale(sundials::make_serial_vector(eq.size(), context)),
        jacobian(SUNSparseMatrix(eq.size(), eq.size(), eq.pattern().nonzeros(), CSC_MAT, context)),
        kinsol(context) {
    if (!jacobian) throw std::runtime_error("SUNSparseMatrix failed");
    if (settings.linear == LinearSolverKind::cholmod) {
      // CHOLMOD eliminates pinned unknowns and factors the symmetric rest: exact only for such rows.
      if (!eq.symmetric_but_pinned_rows())
        throw std::logic_error("CHOLMOD cannot solve these Newton systems: their rows are not symmetric but for "
                               "pinned unknowns (choose KLU for this contact discretization)");
      direct = std::make_unique<CholmodSolver>(context, eq.pattern().dense_block());
    } else {
      auto klu = std::make_unique<KluSolver>(context);
      std::vector<double> reference(static_cast<std::size_t>(eq.pattern().nonzeros()));
      if (equations.pivot_reference(reference.data()))
        klu->analyse(eq.pattern(), std::move(reference));
      direct = std::move(klu);
    }

    N_VConst(1.0 / settings.displacement_scale, u_scale.get());
    N_VConst(1.0 / settings.force_scale, f_scale.get());

    sundials::check(KINInit(kinsol, residual_callback, u.get()), "KINInit");
    sundials::check(KINSetUserData(kinsol, this), "KINSetUserData");
    sundials::route_errors(kinsol, context, &error_route);
    if (settings.newton_linear == NewtonLinearSolve::krylov) {
      gmres.reset(SUNLinSol_SPGMR(u.get(), SUN_PREC_RIGHT, krylov_dimension, context));
      if (!gmres) throw std::runtime_error("SUNLinSol_SPGMR failed");
      sundials::check(KINSetLinearSolver(kinsol, gmres.get(), nullptr), "KINSetLinearSolver");
      sundials::check(KINSetPreconditioner(kinsol, preconditioner_setup, preconditioner_solve), "KINSetPreconditioner");
      sundials::check(KINSetJacTimesVecFn(kinsol, jacobian_times_vector), "KINSetJacTimesVecFn");
      // psetup is offered every iteration; it decides itself whether to factor.
      sundials::check(KINSetMaxSetupCalls(kinsol, 1), "KINSetMaxSetupCalls");
    } else {
      sundials::check(KINSetLinearSolver(kinsol, direct->get(), jacobian.get()), "KINSetLinearSolver");
      sundials::check(KINSetJacFn(kinsol, jacobian_callback), "KINSetJacFn");
      // Exact (semi-smooth) Newton: a fresh Jacobian every iteration.  The active set can change
      // at any iteration, and a stale Jacobian would carry the wrong contact rows.
      sundials::check(KINSetMaxSetupCalls(kinsol, 1), "KINSetMaxSetupCalls");
    }
    sundials::check(KINSetNumMaxIters(kinsol, settings.max_iterations), "KINSetNumMaxIters");
    sundials::check(KINSetFuncNormTol(kinsol, settings.tolerance), "KINSetFuncNormTol");
    // Convergence is judged on the residual only (solve() re-checks it: a tiny step is not
    // success), but a step below step_tolerance_share of the residual tolerance (in displacement
    // over its scale) cannot change a scaled residual by more than about that share of its
    // tolerance: the iteration has stagnated.  The same bound is the line search's shortest
    // step, lambda >= steptol / |p|: without it a search at a kink of the contact set halves
    // lambda down to 1e-300, about a thousand residuals for one Newton iteration.
    sundials::check(KINSetScaledStepTol(kinsol, step_tolerance_share * settings.tolerance), "KINSetScaledStepTol");
    // The predictor can be far from the solution in scaled units (first increment from u = 0):
    // KINSOL's default step bound would stop it (docs/DESIGN.md §15), so allow any step.
    sundials::check(KINSetMaxNewtonStep(kinsol, 1e30), "KINSetMaxNewtonStep");
  }

  static double max_norm(N_Vector v) {
    const double* x = N_VGetArrayPointer(v);
    double norm = 0.0;
    for (sunindextype i = 0; i < N_VGetLength(v); ++i) norm = std::max(norm, std::abs(x[i]));
    return norm;
  }

  static int residual_callback(N_Vector u, N_Vector f, void* data) {
    // A stop requested from outside (SIGINT/SIGTERM) ends this solve at once (unrecoverable for
    // KINSOL); the simulation then returns to its last converged increment.
    if (interruption_requested()) return -1;
    auto* me = static_cast<Impl*>(data);
    const double* point = N_VGetArrayPointer(u);
    me->equations.residual(point, me->alpha, N_VGetArrayPointer(f));
    const double norm = max_norm(f) / me->settings.force_scale;
    // A trial point where the residual is not finite (finite strain: an element turned inside
    // out, det F <= 0) is a recoverable failure: KINSOL shortens the step.
    const double* values = N_VGetArrayPointer(f);
    if (!std::all_of(values, values + N_VGetLength(f), [](double v) { return std::isfinite(v); })) return 1;
    // Bounded: a solve that never converges must not grow memory without end.
    if (me->residual_history.size() < max_residual_history) me->residual_history.push_back(norm);
    me->remember_if_best(point, norm);
    return 0;
  }

  // The iterate of lowest residual so far in this solve: what a failed solve hands back (a
  // plain attempt that ran out of iterations or diverged has usually passed closer to the
  // solution than the predictor it started from).  KINSOL evaluates F at line-search trial
  // points too; any point it evaluated is a point of the iteration.
  void remember_if_best(const double* point, double norm) {
    if (norm >= best_residual) return;
    best_residual = norm;
    best_point.assign(point, point + equations.size());
  }

  // The fixed pattern and the Jacobian's values at u into the matrix the direct solver factors.
  // KINSOL zeroes the whole matrix it hands to jacobian_callback, index arrays included, before
  // each call (docs/DESIGN.md §15): the pattern is written back every time.
  void write_pattern(SUNMatrix j) const {
    const auto& pattern = equations.pattern();
    std::copy(pattern.column_start().begin(), pattern.column_start().end(), SUNSparseMatrix_IndexPointers(j));
    std::copy(pattern.row_index().begin(), pattern.row_index().end(), SUNSparseMatrix_IndexValues(j));
  }

  // A cycling active set stops the plain attempt (recoverable): the caller repeats the trial with
  // KINSOL's line search, whose damped steps break the cycle, and cuts the increment back only if
  // that fails too.  True when the solve must stop.
  bool cycles(double norm) {
    if (active_sets.record(equations.active_set_signature(), norm) && stop_on_cycling) {
      cycling = true;
      return true;
    }
    return false;
  }

  static int jacobian_callback(N_Vector u, N_Vector fu, SUNMatrix j, void* data, N_Vector, N_Vector) {
    auto* me = static_cast<Impl*>(data);
    me->write_pattern(j);
    me->equations.jacobian(N_VGetArrayPointer(u), me->alpha, SUNSparseMatrix_Data(j));
    const double norm = max_norm(fu);
    if (me->cycles(norm)) return 1;
    // Chord step: keep the last factor (KINSOL still gets the fresh Jacobian, for its line search
    // and norms) when the active set is the one factored and the last step cut the residual by
    // chord_contraction or better -- the iteration is then in Newton's quadratic range, where the
    // Jacobian has changed by O(|du|) and the old factor contracts almost as well.  A chord step
    // that contracts less is followed by a fresh factorization.  Only this solve's history
    // decides, so a resumed run repeats the same steps.
    const std::uint64_t signature = me->equations.active_set_signature();
    const bool chord = me->chord_allowed && me->factored && signature == me->factored_signature &&
                       norm <= chord_contraction * me->previous_norm;
    me->previous_norm = norm;
    if (chord) {
      me->direct->keep_factor_once();
    } else {
      me->factored = true;
      me->factored_signature = signature;
    }
    return 0;
  }

  // Krylov solves.  The Jacobian at `point`, kept for J v until the iterate moves.
  void jacobian_at(const double* point) {
    const std::size_t n = static_cast<std::size_t>(equations.size());
    if (jacobian_point.size() == n && std::equal(jacobian_point.begin(), jacobian_point.end(), point)) return;
    jacobian_values.resize(static_cast<std::size_t>(equations.pattern().nonzeros()));
    equations.jacobian(point, alpha, jacobian_values.data());
    jacobian_point.assign(point, point + n);
  }

  // KINSOL offers a preconditioner setup at every iteration.  The solve's first iterate is always
  // factored -- so each increment's arithmetic depends on its own state alone, and a resumed run
  // repeats the uninterrupted one bit for bit -- and so is the second: the first step, from the
  // predictor, moves the contact set and the yield front, after which the Jacobian changes little.
  // Later iterates are factored only when the last GMRES solve stopped short of its tolerance
  // (the Krylov space of krylov_dimension was not enough: the preconditioner has gone stale).
  static int preconditioner_setup(N_Vector uu, N_Vector, N_Vector fu, N_Vector, void* data) {
    auto* me = static_cast<Impl*>(data);
    me->jacobian_at(N_VGetArrayPointer(uu));
    if (me->cycles(max_norm(fu))) return 1;
    const int call = me->preconditioner_setups++;
    const bool stale = SUNLinSolLastFlag(me->gmres.get()) == SUNLS_RES_REDUCED;
    if (call >= 2 && !stale) return 0;
    SUNMatrix j = me->jacobian.get();
    me->write_pattern(j);
    std::copy(me->jacobian_values.begin(), me->jacobian_values.end(), SUNSparseMatrix_Data(j));
    return SUNLinSolSetup(me->direct->get(), j) == SUNLS_SUCCESS ? 0 : 1;
  }

  static int preconditioner_solve(N_Vector, N_Vector, N_Vector, N_Vector, N_Vector v, void* data) {
    auto* me = static_cast<Impl*>(data);
    return SUNLinSolSolve(me->direct->get(), me->jacobian.get(), v, v, 0.0) == SUNLS_SUCCESS ? 0 : 1;
  }

  static int jacobian_times_vector(N_Vector v, N_Vector jv, N_Vector uu, sundials::Boolean*, void* data) {
    auto* me = static_cast<Impl*>(data);
    me->jacobian_at(N_VGetArrayPointer(uu));
    me->equations.pattern().multiply(me->jacobian_values, N_VGetArrayPointer(v), N_VGetArrayPointer(jv));
    return 0;
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
  m.direct->clear_keep_factor();
  m.direct->estimate_condition_at_next_setup();
  m.preconditioner_setups = 0;
  m.jacobian_point.clear();  // the depth changed: so does the Jacobian at the same u
  const long factorizations_before = total_factorizations();
  const long analyses_before = total_symbolic_analyses();

  NewtonReport report;
  // A predictor that already satisfies the tolerance is the solution (an unloaded specimen off
  // the punch, a step along an elastic unloading that the extrapolation got exactly).  KINSOL
  // would accept it only below 1% of the tolerance and otherwise factor a Jacobian for a step
  // of nothing.
  const double initial = m.scaled_residual(data);
  m.residual_history.push_back(initial);
  m.best_residual = initial;
  m.best_point = u;
  if (initial <= m.settings.tolerance) {
    report.converged = true;
    report.residual = initial;
    report.residual_history = m.residual_history;
    return report;
  }
  m.residual_history.clear();  // KINSOL's own first evaluation records it again
  const int strategy = globalization == Globalization::line_search ? KIN_LINESEARCH : KIN_NONE;
  report.kinsol_flag = KINSol(m.kinsol, m.u.get(), strategy, m.u_scale.get(), m.f_scale.get());
  long iterations = 0;
  KINGetNumNonlinSolvIters(m.kinsol, &iterations);
  report.iterations = iterations;
  if (m.gmres) {
    long linear = 0;
    KINGetNumLinIters(m.kinsol, &linear);
    report.linear_iterations = linear;
  }
  report.factorizations = total_factorizations() - factorizations_before;
  report.symbolic_analyses = total_symbolic_analyses() - analyses_before;
  report.residual = m.scaled_residual(data);
  report.condition_estimate = m.direct->condition_estimate();
  // Trust the residual, not the return code alone: KIN_STEP_LT_STPTOL and friends are not
  // convergence, and a success must really satisfy the tolerance.
  report.converged = report.kinsol_flag >= 0 && report.residual <= m.settings.tolerance;
  report.cycling = m.cycling;
  report.message = m.cycling ? "active-set cycling between contact sets detected" : m.last_message;
  report.residual_history = m.residual_history;
  report.stopped_while_converging = !report.converged && report.kinsol_flag == KIN_MAXITER_REACHED &&
                                    report.residual <= m.best_residual;
  // Converged: the solution.  Not converged: the best iterate, with its residual.
  if (report.converged || m.best_residual >= report.residual) {
    std::copy(data, data + u.size(), u.begin());
  } else {
    u = m.best_point;
    report.residual = m.best_residual;
  }
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
  m.write_pattern(j);
  m.equations.jacobian(u.data(), alpha, SUNSparseMatrix_Data(j));
  // A chord step's request to keep the factor may be pending from the converged solve: this
  // matrix must be factored.
  m.direct->clear_keep_factor();
  SUNLinearSolver solver = m.direct->get();
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

long NewtonSolver::total_factorizations() const { return impl_->direct->numeric_factorizations(); }
long NewtonSolver::total_symbolic_analyses() const { return impl_->direct->symbolic_analyses(); }
long NewtonSolver::factor_nonzeros() const { return impl_->direct->factor_nonzeros(); }

}  // namespace indentsim
