#pragma once
// SuiteSparse KLU behind a SUNLinearSolver of our own (private to the library): the default
// sparse direct solver of the Newton systems.
//
// Why not SUNLinSol_KLU as it is: KINSOL calls a linear solver's `initialize` at every KINSol call
// (every increment), and SUNLinSol_KLU's forces a new symbolic analysis and a full factorization
// there (docs/DESIGN.md §15).  The pattern of a Newton system never changes, so this solver
// analyses it once, in CHOLMOD's nested-dissection order (less fill than AMD on a refined mesh;
// AMD leaves 2-3x less than KLU's default COLAMD on these matrices), with a condensed system's
// dense interface block last.
//
// Pivots chosen once, on a matrix of the mesh alone.  KLU's factorization with partial pivoting
// (klu_factor) chooses a pivot sequence; klu_refactor computes the factors of another matrix of the
// same pattern with that sequence, about twice as fast (measured: 0.12 s against 0.25 s for a
// plastic near field of 11 000 unknowns).  The sequence is chosen on the *pivot reference*, the
// Newton system's elastic stiffness, which depends on the mesh only: every Jacobian is then
// refactored with it, so no factorization depends on the matrices factored before it, and a run
// resumed from a checkpoint repeats the uninterrupted run bit for bit.  The Jacobians are
// symmetric positive definite (consistent tangents of hardening laws) except for the active
// contact rows, which hold only their diagonal (docs/DESIGN.md §1); the reference's pivots (its
// diagonal, in KLU's fill-reducing order) are stable for all of them.  Should a refactorization
// lose accuracy anyway (KLU's rcond below eps^(2/3), the test SUNLinSol_KLU uses), that matrix is
// factored afresh with pivots of its own, into a second factor that does not replace the reference.
#include <cstdint>
#include <memory>
#include <vector>

#include "indentsim/solvers/assembly.hpp"
#include "sparse_direct_solver.hpp"

namespace indentsim {

class KluSolver final : public SparseDirectSolver {
public:
  explicit KluSolver(SUNContext context);
  ~KluSolver() override;
  KluSolver(const KluSolver&) = delete;
  KluSolver& operator=(const KluSolver&) = delete;

  /// Analyses the pattern (the pattern of every matrix to come; its dense block is ordered last)
  /// and factors the reference matrix whose pivots every later factorization reuses: part of
  /// building a Newton system, not counted among numeric_factorizations().  Without it, the first
  /// matrix set up is analysed and becomes the reference.  Throws std::runtime_error when KLU
  /// cannot factor the reference.
  void analyse(const StiffnessPattern& pattern, std::vector<double> reference_values);

  SUNLinearSolver get() const override { return shell_.get(); }
  long numeric_factorizations() const override;
  long symbolic_analyses() const override;
  long factor_nonzeros() const override;
  void keep_factor_once() override;
  void clear_keep_factor() override;
  void estimate_condition_at_next_setup() override;
  double condition_estimate() const override;

  struct State;  // KLU's common block, symbolic analysis and factors

private:
  std::unique_ptr<State> state_;
  sundials::LinearSolver shell_;
};

}  // namespace indentsim
