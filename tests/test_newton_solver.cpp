// What NewtonSolver hands back to the increment that called it (src/simulation/simulation.cpp
// tries a plain attempt, then one with the line search): a predictor that is already the
// solution, an attempt that ran out of iterations while still converging, and one that diverged.
// The equations are linear (K u = f on a graded block) with a Jacobian c K handed to Newton, so
// that each full step multiplies the error by exactly 1 - 1/c: c = 2 converges linearly (the
// residual halves), c = 0.4 diverges (it grows by 1.5).
#include <cmath>
#include <stdexcept>

#include <gtest/gtest.h>

#include "indentsim/solvers/assembly.hpp"
#include "indentsim/geometry/mesh.hpp"
#include "indentsim/solvers/solver.hpp"
#include "test_support.hpp"

using namespace indentsim;

namespace {

class ScaledJacobianEquations : public IncrementEquations {
public:
  ScaledJacobianEquations(const StiffnessPattern& p, ElasticStiffness& k, std::vector<double> f, double c)
      : pattern_(p), stiffness_(k), load_(std::move(f)), c_(c) {}
  const StiffnessPattern& pattern() const override { return pattern_; }
  void residual(const double* u, double, double* f) override {
    stiffness_.multiply(u, f);
    for (std::size_t i = 0; i < load_.size(); ++i) f[i] -= load_[i];
  }
  void jacobian(const double*, double, double* values) override {
    for (std::size_t i = 0; i < stiffness_.values().size(); ++i) values[i] = c_ * stiffness_.values()[i];
  }
  void set_jacobian_factor(double c) { c_ = c; }
  /// Pretend rows that couple unknowns (a mortar or frictional contact discretization would).
  void declare_coupling_rows() { pinned_rows_only_ = false; }
  bool symmetric_but_pinned_rows() const override { return pinned_rows_only_; }

private:
  const StiffnessPattern& pattern_;
  ElasticStiffness& stiffness_;
  std::vector<double> load_;
  double c_;
  bool pinned_rows_only_ = true;
};

class NewtonAttempts : public ::testing::Test {
protected:
  NewtonAttempts()
      : mesh_(indentsim::testing::graded_block(15e-3, 10e-3, ElementKind::q1)),
        pattern_(mesh_),
        stiffness_(mesh_, ElasticMaterial{210e9, 0.3}, pattern_) {
    // A load on the top surface's first node: any f with a nonzero solution does.
    std::vector<double> f(static_cast<std::size_t>(mesh_.equations()), 0.0);
    f[static_cast<std::size_t>(mesh_.equation(Mesh::dof_v(mesh_.node(0, mesh_.top_row()))))] = -1e3;
    equations_ = std::make_unique<ScaledJacobianEquations>(pattern_, stiffness_, f, 1.0);
    settings_.displacement_scale = 1e-6;
    settings_.force_scale = 1e3;
    settings_.tolerance = 1e-12;
    settings_.max_iterations = 200;
  }
  std::vector<double> zero() const { return std::vector<double>(static_cast<std::size_t>(mesh_.equations()), 0.0); }

  Mesh mesh_;
  StiffnessPattern pattern_;
  ElasticStiffness stiffness_;
  std::unique_ptr<ScaledJacobianEquations> equations_;
  NewtonSettings settings_;
};

}  // namespace

TEST_F(NewtonAttempts, APredictorWithinTheToleranceComesBackAsItIsWithoutAFactorization) {
  NewtonSolver solver(*equations_, settings_);
  std::vector<double> u = zero();
  const NewtonReport exact = solver.solve(0.0, u);
  ASSERT_TRUE(exact.converged) << exact.message;
  ASSERT_GE(exact.iterations, 1);

  const std::vector<double> solution = u;
  const NewtonReport again = solver.solve(0.0, u);
  EXPECT_TRUE(again.converged);
  EXPECT_EQ(again.iterations, 0);
  EXPECT_EQ(again.factorizations, 0);
  EXPECT_LE(again.residual, settings_.tolerance);
  EXPECT_EQ(u, solution);  // bit for bit: nothing was stepped
}

TEST_F(NewtonAttempts, AnAttemptOutOfIterationsWhileConvergingHandsBackWhereItStopped) {
  equations_->set_jacobian_factor(2.0);  // the error halves at every step
  NewtonSolver solver(*equations_, settings_);
  std::vector<double> u = zero();
  const NewtonReport first = solver.solve(0.0, u, Globalization::none, 4);
  ASSERT_FALSE(first.converged);
  EXPECT_EQ(first.iterations, 4);
  EXPECT_TRUE(first.stopped_while_converging);
  // Four halvings of the predictor's residual, and u the fourth iterate.
  ASSERT_GE(first.residual_history.size(), 5u);
  EXPECT_NEAR(first.residual, first.residual_history.front() / 16.0, 1e-9 * first.residual_history.front());

  // The next attempt starts from that iterate: its first residual is the one handed back.
  const NewtonReport second = solver.solve(0.0, u, Globalization::line_search);
  ASSERT_TRUE(second.converged) << second.message;
  ASSERT_FALSE(second.residual_history.empty());
  EXPECT_DOUBLE_EQ(second.residual_history.front(), first.residual);
}

TEST_F(NewtonAttempts, ADivergingAttemptHandsBackItsBestIterateAndSaysItWasNotConverging) {
  equations_->set_jacobian_factor(0.4);  // every step overshoots: the error grows by 1.5
  NewtonSolver solver(*equations_, settings_);
  const std::vector<double> predictor = zero();
  std::vector<double> u = predictor;
  const NewtonReport report = solver.solve(0.0, u, Globalization::none, 4);
  ASSERT_FALSE(report.converged);
  EXPECT_FALSE(report.stopped_while_converging);
  ASSERT_GE(report.residual_history.size(), 2u);
  EXPECT_GT(report.residual_history.back(), report.residual_history.front());
  // The best iterate is the predictor itself.
  EXPECT_EQ(u, predictor);
  EXPECT_DOUBLE_EQ(report.residual, report.residual_history.front());
}

// CHOLMOD's solve eliminates pinned unknowns and factors a symmetric rest: equations whose rows
// are not of that shape are refused before any solve, and KLU takes them.
TEST_F(NewtonAttempts, CholmodRefusesRowsThatAreNotSymmetricButForPinnedUnknownsAndKluTakesThem) {
  settings_.linear = LinearSolverKind::cholmod;
  EXPECT_NO_THROW((NewtonSolver{*equations_, settings_}));
  equations_->declare_coupling_rows();
  EXPECT_THROW((NewtonSolver{*equations_, settings_}), std::logic_error);
  settings_.linear = LinearSolverKind::klu;
  NewtonSolver solver(*equations_, settings_);
  std::vector<double> u = zero();
  EXPECT_TRUE(solver.solve(0.0, u).converged);
}
