#pragma once
// One increment of the load path: the semi-smooth Newton solve of F(u; alpha) = 0 driven by
// SUNDIALS KINSOL, its linear systems solved with the SuiteSparse KLU sparse direct solver (or
// CHOLMOD's), either directly at every iteration or as the preconditioner of GMRES (docs/DESIGN.md
// §8).
//
// The SUNDIALS, KLU and CHOLMOD objects (context, vectors, matrix, linear solvers, factors, KINSOL
// memory) are owned by RAII handles inside NewtonSolver (src/solvers/sundials_handles.hpp,
// klu_solver.hpp, cholmod_solver.hpp); this header does not expose them.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "indentsim/solvers/assembly.hpp"
#include "indentsim/solvers/contact_discretization.hpp"

namespace indentsim {

/// Active-set cycling guard of one Newton solve: the contact sets seen at successive Jacobians,
/// with the residual norm at each.  Staying on a set is convergence; coming back to a set left
/// earlier (A, B, A) while the residual has not fallen to half of what it was at the earlier
/// visit is a cycle, which semi-smooth Newton would repeat forever.  (Coupled with plasticity,
/// a node may flip back once on the way to convergence; then the residual has dropped.)
class ActiveSetHistory {
public:
  void clear() { seen_.clear(); }
  /// Records the current active set and residual norm; true if it closes a cycle.
  bool record(std::uint64_t signature, double residual);

private:
  std::vector<std::pair<std::uint64_t, double>> seen_;
};

/// The discrete equations of one increment and their generalized Jacobian.
class IncrementEquations {
public:
  virtual ~IncrementEquations() = default;
  /// A signature of the contact set the last Jacobian used (0 when there is no contact).
  virtual std::uint64_t active_set_signature() const { return 0; }
  virtual const StiffnessPattern& pattern() const = 0;
  std::int64_t size() const { return pattern().size(); }
  /// F(u; alpha).
  virtual void residual(const double* u, double alpha, double* f) = 0;
  /// Values of the Jacobian dF/du at u, in the fixed pattern.
  virtual void jacobian(const double* u, double alpha, double* values) = 0;
  /// Values (in the pattern) of a matrix that depends on the mesh alone, on which the sparse LU
  /// chooses its pivots once for all the Jacobians to come (src/solvers/klu_solver.hpp); false
  /// when there is none (the first Jacobian factored is the reference then).
  virtual bool pivot_reference(double* /*values*/) { return false; }
  /// True when every Jacobian is symmetric but for rows c_k e_k (pinned unknowns): what CHOLMOD's
  /// solve assumes (cholmod_solver.hpp).  NewtonSolver refuses CHOLMOD otherwise.
  virtual bool symmetric_but_pinned_rows() const { return true; }
};

/// The bulk model (elastic or plastic) with contact: F = f_int(u), with the contact rows written
/// by the contact discretization (contact_discretization.hpp).  One Newton iteration handles the
/// material nonlinearity and the contact together.
class ContactEquations : public IncrementEquations {
public:
  /// `elastic` is the linear elastic bulk of the same system (the same object for an elastic
  /// scene): its stiffness is the pivot reference.
  ContactEquations(const StiffnessPattern& pattern, BulkOperator& bulk, BulkOperator& elastic,
                   const ContactDiscretization& contact);
  const StiffnessPattern& pattern() const override { return pattern_; }
  /// Solve with another bulk model on the same pattern (the elastic predictor of a plastic run).
  void use_bulk(BulkOperator& bulk) { bulk_ = &bulk; }
  std::uint64_t active_set_signature() const override { return signature_; }
  void residual(const double* u, double alpha, double* f) override;
  void jacobian(const double* u, double alpha, double* values) override;
  bool pivot_reference(double* values) override;
  bool symmetric_but_pinned_rows() const override { return contact_.rows_keep_symmetry(); }

  /// The internal force on each contact row (row_equations() order) at the u of the last residual
  /// or Jacobian evaluated.
  const std::vector<double>& contact_row_forces() const { return residual_contact_force_; }
  /// With `keep`, every Jacobian evaluation first saves the bulk's tangent on the candidates'
  /// vertical rows (the values at row_positions(equation) of each, in its order), which the contact
  /// rows then overwrite: the force row of force control needs them (force_controlled_equations.hpp).
  void keep_bulk_rows(bool keep) { keep_bulk_rows_ = keep; }
  const std::vector<std::vector<double>>& bulk_rows() const { return bulk_rows_; }

private:
  const StiffnessPattern& pattern_;
  BulkOperator* bulk_;
  BulkOperator& elastic_;
  const ContactDiscretization& contact_;
  std::vector<std::vector<std::int64_t>> contact_rows_;  // value positions of each contact row
  std::vector<double> internal_force_;                    // scratch, sized once
  // The contact rows' internal forces of the last residual evaluation, and where it was taken:
  // KINSOL evaluates F(u) before J(u) at the same u, so the Jacobian reuses them instead of a
  // second pass over the elements.
  std::vector<double> residual_u_, residual_contact_force_;
  const BulkOperator* residual_bulk_ = nullptr;
  std::uint64_t signature_ = 0;
  bool keep_bulk_rows_ = false;
  std::vector<std::vector<double>> bulk_rows_;
};

/// The sparse direct solver that factors the Newton matrices: SuiteSparse KLU or CHOLMOD's
/// supernodal Cholesky (each through a SUNLinearSolver of our own).
enum class LinearSolverKind { klu, cholmod };

/// How a Newton iteration solves J du = -F (docs/DESIGN.md §8).
enum class NewtonLinearSolve {
  /// KINSOL's linear solver is the sparse direct solver: a factorization per iteration (a chord
  /// step may keep the last one).
  direct,
  /// GMRES (SUNDIALS SPGMR) on the exact Jacobian, inexact Newton with Eisenstat and Walker's
  /// forcing terms, right-preconditioned by the sparse factorization of a Jacobian of the same
  /// solve: the first iterate's, refreshed at the second (the first step moves the contact set and
  /// the yield front) and whenever GMRES stops short of its tolerance.
  krylov
};

struct NewtonSettings {
  LinearSolverKind linear = LinearSolverKind::klu;
  NewtonLinearSolve newton_linear = NewtonLinearSolve::direct;
  double displacement_scale = 1.0;  ///< typical |u| [m] (KINSOL's uscale = 1/this)
  double force_scale = 1.0;         ///< typical |F| [N/m or N] (KINSOL's fscale = 1/this)
  double tolerance = 1e-11;         ///< on max |F| / force_scale
  int max_iterations = 50;
  /// Direct solves only.  Chord steps: a converging iteration keeps the last factorization
  /// (NewtonSolver).  Off, every iteration factors its own Jacobian (exact semi-smooth Newton,
  /// quadratic near the solution).
  bool chord_steps = true;
};

enum class Globalization {
  none,        ///< full semi-smooth Newton steps (KIN_NONE)
  line_search  ///< KINSOL's backtracking line search on ||F||^2 (KIN_LINESEARCH)
};

struct NewtonReport {
  bool converged = false;
  long iterations = 0;
  long factorizations = 0;      ///< numeric factorizations (KLU or CHOLMOD)
  long linear_iterations = 0;   ///< GMRES iterations of Krylov solves (0 for direct solves)
  long symbolic_analyses = 0;   ///< KLU symbolic analyses (ideally one per mesh)
  double residual = 0.0;        ///< max |F| / force_scale at the returned u
  /// 1-norm condition estimate of the first Jacobian factored in the solve (KLU's condest, or
  /// 1/rcond of CHOLMOD's factor): how much accuracy the factorization may lose.
  double condition_estimate = 0.0;
  int kinsol_flag = 0;
  /// Not converged within its iterations, but its last iterate was its best: still converging
  /// (another attempt may go on from it) rather than wandering or diverging.
  bool stopped_while_converging = false;
  /// Stopped because the contact set returned to one it had left (ActiveSetHistory).
  bool cycling = false;
  std::string message;          ///< KINSOL's own words when it failed
  std::vector<double> residual_history;  ///< max |F| / force_scale at each residual evaluation (the first 10 000)
};

class NewtonSolver {
public:
  NewtonSolver(IncrementEquations& equations, const NewtonSettings& settings);
  ~NewtonSolver();
  NewtonSolver(const NewtonSolver&) = delete;
  NewtonSolver& operator=(const NewtonSolver&) = delete;

  /// Solves F(u; alpha) = 0 starting from u (the predictor).  Converged, u is the solution; not
  /// converged, u is the iterate of lowest residual (report.residual).  A predictor within the
  /// tolerance is returned as it is, with 0 iterations.
  /// `max_iterations` (when > 0) caps this attempt below the settings' limit.
  NewtonReport solve(double alpha, std::vector<double>& u, Globalization globalization = Globalization::none,
                     int max_iterations = 0);

  /// Solves J(u) x = b in place for each right-hand side, J the generalized Jacobian of the
  /// equations at u (with the contact set active at u): the forward sensitivities of a converged
  /// state.  One numeric factorization (counted), reusing the symbolic analysis; a direct solve
  /// whatever the settings' newton_linear.
  void solve_linearized(const std::vector<double>& u, double alpha, std::vector<std::vector<double>>& right_hand_sides);

  long total_factorizations() const;
  long total_symbolic_analyses() const;
  /// Entries of the direct solver's factors (KLU: L and U; CHOLMOD: L), 0 before the first
  /// factorization: the fill its fill-reducing order left.
  long factor_nonzeros() const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace indentsim
