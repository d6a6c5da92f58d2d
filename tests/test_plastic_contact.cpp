// Ilyushin plasticity with contact along the load path: quadratic Newton convergence, path
// independence of deformation theory, the elastic limit, and layer equilibrium.
#include <cmath>

#include <fmt/format.h>

#include <gtest/gtest.h>

#include "indentsim/simulation/simulation.hpp"
#include "test_support.hpp"

using namespace indentsim;
using indentsim::testing::shipped_case;

TEST(PlasticContact, NewtonConvergesQuadraticallyNearTheSolution) {
  // Exact Newton (every iteration factors its own Jacobian): chord steps converge linearly by design.
  Simulation sim(
      shipped_case("deep_plastic.toml", {"mesh.contact_nodes=10", "load.increments=6", "solver.jacobian=fresh"}));
  int checked = 0;
  sim.run([&](const IncrementRecord& r) {
    if (r.step < 2) return;
    // Residuals above round-off.  Quadratic convergence: r_{k+1} <= C r_k^2 with a bounded C once
    // r_k is small (linear convergence at rate q would need C = q / r_k, ~1e5 here).
    std::vector<double> h;
    for (double v : sim.last_newton_report().residual_history)
      if (v > 1e-13) h.push_back(v);
    std::string shown;
    for (double v : sim.last_newton_report().residual_history) shown += fmt::format(" {:.2e}", v);
    RecordProperty(fmt::format("residuals_step_{}", r.step), shown);
    ASSERT_GE(h.size(), 3u) << shown;
    // Semi-smooth Newton is quadratic once the contact and plastic sets are settled (Qi and Sun
    // 1993); on a coarse mesh one of them may still switch at a small residual.  Such a switch
    // costs one step: below 1e-4 at most one pair may miss the bound, and never the last.
    int pairs = 0, switches = 0;
    for (std::size_t k = 0; k + 1 < h.size(); ++k) {
      if (h[k] > 1e-4) continue;
      if (h[k + 1] > 1e3 * h[k] * h[k]) ++switches;
      ++pairs;
    }
    EXPECT_GE(pairs, 1) << shown;
    EXPECT_LE(switches, 1) << "residual history:" << shown;
    const std::size_t n = h.size();
    EXPECT_LE(h[n - 1], 1e3 * h[n - 2] * h[n - 2]) << "residual history:" << shown;
    ++checked;
  });
  EXPECT_EQ(checked, 5);
}

TEST(PlasticContact, TheFirstIncrementStartsFromTheElasticContactSolution) {
  // From the unloaded state there is nothing to extrapolate: the first increment starts from the
  // elastic contact solution at its depth (Simulation::predict), and the plastic Newton from there
  // converges in its first, undamped attempt.  Started from u = 0, the plain attempt ran out of
  // its 12 iterations and the line search began again (19-21 iterations in all here, against 9-10;
  // 30 at contact_nodes 30).
  for (const char* jacobian : {"krylov", "reuse"}) {
    SCOPED_TRACE(jacobian);
    Simulation sim(shipped_case("deep_plastic.toml", {"mesh.contact_nodes=20", std::string("solver.jacobian=") + jacobian}));
    sim.advance_to(0.0);
    const IncrementRecord first = sim.advance_to(sim.load_case().max_depth() / 12);
    ASSERT_GT(first.plastic_points, 0);
    EXPECT_EQ(first.cutbacks, 0);
    EXPECT_LE(first.newton_iterations, 14) << "the plain attempt did not converge";
  }
}

TEST(PlasticContact, DeformationTheoryIsPathIndependentOnMonotoneLoading) {
  Simulation few(shipped_case("power_law.toml", {"mesh.contact_nodes=8", "load.increments=5"}));
  Simulation many(shipped_case("power_law.toml", {"mesh.contact_nodes=8", "load.increments=50"}));
  few.run();
  many.run();
  ASSERT_GT(many.bulk().plastic_points(), 0);
  EXPECT_NEAR(few.contact().force, many.contact().force, 1e-6 * many.contact().force);
}

TEST(PlasticContact, BelowTheElasticLimitTheResultIsTheElasticModels) {
  // The paper case up to 40 um stays below e0 = 0.027 (e_u reaches about 0.025).  Both runs take
  // the same Newton steps (direct solves; a plastic scene would otherwise solve them with GMRES,
  // which converges to the same solution within the tolerance but not to the same rounding).
  const std::vector<std::string> common{"load.path=[0, 4e-5]", "load.increments=4", "mesh.contact_half_width=2e-4",
                                        "solver.jacobian=reuse"};
  std::vector<std::string> elastic_overrides = common;
  elastic_overrides.push_back("material.model=elastic");
  Simulation plastic(shipped_case("paper.toml", common));
  Simulation elastic(shipped_case("paper.toml", elastic_overrides));
  ASSERT_NE(plastic.plasticity(), nullptr);
  ASSERT_EQ(elastic.plasticity(), nullptr);  // an elastic case never enters the plasticity code
  std::vector<IncrementRecord> a, b;
  plastic.run([&](const IncrementRecord& r) { a.push_back(r); });
  elastic.run([&](const IncrementRecord& r) { b.push_back(r); });
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].plastic_points, 0);
    EXPECT_LT(a[k].max_strain_intensity, 0.027);
    EXPECT_NEAR(a[k].force, b[k].force, 1e-12 * std::max(1.0, b[k].force)) << "step " << k;
    EXPECT_EQ(a[k].contact_nodes, b[k].contact_nodes);
  }
}

TEST(PlasticContact, LayerEquilibriumHoldsWithSecantMatrices) {
  Simulation sim(shipped_case("deep_plastic.toml", {"mesh.contact_nodes=10", "load.increments=4"}));
  sim.run();
  ASSERT_GT(sim.bulk().plastic_points(), 100);
  const double force = sim.contact().force;
  const auto layers = sim.line_forces();
  for (std::size_t j = 0; j < layers.size(); ++j) {
    if (j > 0) {
      EXPECT_NEAR(layers[j].below, force, 1e-8 * force) << "line " << j;
    }
    if (j + 1 < layers.size()) {
      EXPECT_NEAR(layers[j].above, force, 1e-8 * force) << "line " << j;
    }
  }
}

TEST(PlasticContact, ShippedPlasticCasesYieldAndLoadMonotonically) {
  for (const char* name : {"paper.toml", "power_law.toml", "deep_plastic.toml"}) {
    SCOPED_TRACE(name);
    Simulation sim(shipped_case(name, {"mesh.contact_nodes=8", "load.increments=5"}));
    IncrementRecord last;
    sim.run([&](const IncrementRecord& r) {
      if (r.step > 0) {
        EXPECT_GT(r.force, last.force);
        EXPECT_GE(r.plastic_points, last.plastic_points);
        EXPECT_EQ(r.cutbacks, 0);
      }
      last = r;
    });
    EXPECT_GT(last.plastic_points, 0);
    // Softening: plasticity lowers the force below the elastic one at the same depth.
    Simulation elastic(shipped_case(name, {"mesh.contact_nodes=8", "load.increments=5", "material.model=elastic",
                                           fmt::format("mesh.contact_half_width={}", sim.plan().contact_half_width_estimate)}));
    elastic.run();
    EXPECT_LT(last.force, elastic.contact().force);
  }
}
