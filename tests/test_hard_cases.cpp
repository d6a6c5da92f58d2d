// Numerical stability on hard cases (loadcases/hard/): each must converge and keep the physics
// (layer equilibrium, monotone force on loading, no tensile contact force) within a bound on
// Newton iterations, or say clearly what is wrong with it.
#include <cmath>

#include <fmt/format.h>

#include <gtest/gtest.h>

#include "indentsim/geometry/hertz.hpp"
#include "indentsim/simulation/simulation.hpp"
#include "test_support.hpp"

using namespace indentsim;

namespace {

struct HardRun {
  LoadCase load_case;  ///< as run
  std::vector<IncrementRecord> curve;
  std::vector<std::string> warnings;
  double most_tensile_force = 0.0;
  double worst_layer_mismatch = 0.0;  // relative to P, final state
  long max_newton = 0;
  ElementKind element = ElementKind::q1;
  double condition = 0.0;
};

HardRun run_hard(const std::string& name, std::vector<std::string> overrides = {}) {
  overrides.push_back("output.checkpoint_every=0");
  Simulation sim(indentsim::testing::shipped_case("hard/" + name, overrides));
  HardRun h;
  h.load_case = sim.load_case();
  h.element = sim.mesh().element_kind();
  sim.run([&](const IncrementRecord& r) {
    h.curve.push_back(r);
    h.max_newton = std::max(h.max_newton, r.newton_iterations);
    for (double f : sim.contact().nodal_force) h.most_tensile_force = std::min(h.most_tensile_force, f);
  });
  const double force = sim.contact().force;
  if (force > 0)
    for (const auto& l : sim.line_forces()) {
      if (!std::isnan(l.below)) h.worst_layer_mismatch = std::max(h.worst_layer_mismatch, std::abs(l.below - force) / force);
      if (!std::isnan(l.above)) h.worst_layer_mismatch = std::max(h.worst_layer_mismatch, std::abs(l.above - force) / force);
    }
  h.warnings = sim.warnings();
  h.condition = sim.largest_condition_estimate();
  return h;
}

void expect_physics(const HardRun& h, long newton_bound, int cutback_bound = 0) {
  double peak = 0;
  for (const auto& r : h.curve) peak = std::max(peak, r.force);
  for (std::size_t k = 1; k < h.curve.size(); ++k)
    if (h.curve[k].alpha > h.curve[k - 1].alpha && h.curve[k - 1].alpha >= 0) {
      // Monotone force on loading (first loading, and reloading beyond the contact point).
      if (h.curve[k - 1].force > 0) {
        EXPECT_GE(h.curve[k].force, h.curve[k - 1].force * (1 - 1e-12)) << "step " << h.curve[k].step;
      }
    }
  EXPECT_GE(h.most_tensile_force, -1e-9 * peak);
  EXPECT_LE(h.worst_layer_mismatch, 1e-8);
  EXPECT_LE(h.max_newton, newton_bound);
  for (const auto& r : h.curve) EXPECT_LE(r.cutbacks, cutback_bound) << "step " << r.step;
}

bool warned(const HardRun& h, const std::string& words) {
  for (const auto& w : h.warnings)
    if (w.find(words) != std::string::npos) return true;
  return false;
}

// |P - P_Hertz(a)| / P at the final increment, with E, nu and R of the load case as run.
double hertz_error(const HardRun& h) {
  const IncrementRecord& r = h.curve.back();
  const auto& m = h.load_case.material;
  const double e_star = m.E / (1 - m.nu * m.nu);
  return std::abs(r.force - hertz::force(r.half_width, h.load_case.punch.radius, e_star)) / r.force;
}

}  // namespace

TEST(HardCases, NearlyIncompressibleBbarConvergesWherePlainQ1Locks) {
  const auto run = [](const char* element, int n) {
    return run_hard("incompressible.toml", {std::string("mesh.element=") + element,
                                            "mesh.contact_nodes=" + std::to_string(n), "solver.linear=auto"});
  };
  // At half and at the default resolution (mesh.contact_nodes = 20).  P(a) also carries the
  // contact edge's own discretisation error (docs/DESIGN.md §4): 1.0% at 16 nodes, 0.5% at 20.
  const HardRun q1_10 = run("q1", 10), q1_20 = run("q1", 20), bbar_10 = run("bbar", 10), bbar_20 = run("bbar", 20);
  const double e_q1_10 = hertz_error(q1_10), e_q1_20 = hertz_error(q1_20);
  const double e_b_10 = hertz_error(bbar_10), e_b_20 = hertz_error(bbar_20);
  RecordProperty("hertz_error_q1_10_20_bbar_10_20",
                 fmt::format("{:.4f} {:.4f} {:.4f} {:.4f}", e_q1_10, e_q1_20, e_b_10, e_b_20));
  EXPECT_LT(e_b_20, 0.01);
  EXPECT_LT(e_b_20, e_b_10);
  EXPECT_GT(e_q1_20, 0.05);          // locked: still far off at the default mesh
  EXPECT_GT(e_q1_10, 5 * e_b_10);
  EXPECT_GT(e_q1_20, 5 * e_b_20);
  EXPECT_EQ(run_hard("incompressible.toml").element, ElementKind::bbar);  // "auto" picks it
  expect_physics(bbar_20, 8);
}

TEST(HardCases, NearlyIncompressibleAcrossPoissonRatios) {
  for (const char* nu : {"0.49", "0.4999"}) {
    SCOPED_TRACE(nu);
    const HardRun h = run_hard("incompressible.toml",
                               {std::string("material.nu=") + nu, "solver.linear=auto", "mesh.contact_nodes=20"});
    EXPECT_EQ(h.element, ElementKind::bbar);
    EXPECT_LT(hertz_error(h), 0.01);
    expect_physics(h, 8);
  }
}

TEST(HardCases, NearPerfectPlasticityConverges) {
  const struct {
    const char* file;
    std::vector<std::string> overrides;
  } cases[] = {{"near_perfect_linear.toml", {}},
               {"near_perfect_linear.toml", {"material.kappa=0.99"}},
               {"near_perfect_power.toml", {}}};
  for (const auto& c : cases) {
    SCOPED_TRACE(c.file);
    const HardRun h = run_hard(c.file, c.overrides);
    EXPECT_EQ(h.element, ElementKind::bbar);
    EXPECT_GT(h.curve.back().plastic_points, 100);
    // Line search and cutbacks are allowed here (the issue asks that they still converge).
    expect_physics(h, 60, 3);
  }
}

TEST(HardCases, WholeDepthInOneIncrement) {
  const HardRun h = run_hard("single_increment.toml");
  ASSERT_EQ(h.curve.size(), 2u);
  EXPECT_GT(h.curve.back().plastic_points, 100);
  expect_physics(h, 40);
}

TEST(HardCases, TinyFirstIncrementTouchesOnlyTheAxisNode) {
  const HardRun h = run_hard("tiny_first_increment.toml");
  ASSERT_GE(h.curve.size(), 3u);
  EXPECT_EQ(h.curve[1].contact_nodes, 1);
  EXPECT_GT(h.curve[1].force, 0.0);
  EXPECT_GT(h.curve.back().contact_nodes, 8);
  expect_physics(h, 10);
}

TEST(HardCases, CoarseMeshRunsAndWarns) {
  const HardRun h = run_hard("coarse_mesh.toml");
  EXPECT_TRUE(warned(h, "coarse")) << (h.warnings.empty() ? "" : h.warnings.front());
  expect_physics(h, 6);
}

TEST(HardCases, ExtremeGradingKeepsTheFactorizationAccurate) {
  const LoadCase lc = indentsim::testing::shipped_case("hard/extreme_grading.toml");
  Simulation probe(lc);
  double aspect = 0;
  for (int ei = 0; ei < probe.mesh().elements_x(); ++ei)
    for (int ej = 0; ej < probe.mesh().elements_y(); ++ej) {
      const Rectangle r = probe.mesh().rectangle(ei, ej);
      aspect = std::max(aspect, std::max(r.width / r.height, r.height / r.width));
    }
  EXPECT_GE(aspect, 100.0);
  const HardRun h = run_hard("extreme_grading.toml");
  // The converged residual is re-checked after every solve (NewtonReport::converged); the
  // condition estimate says how much the factorization could lose.
  RecordProperty("condition_estimate", fmt::format("{:.3g}", h.condition));
  EXPECT_GT(h.condition, 1.0);
  EXPECT_LT(h.condition, 1e12);
  expect_physics(h, 8);
}

TEST(HardCases, DeepIndentationRunsAndWarns) {
  const HardRun h = run_hard("deep_indentation.toml");
  EXPECT_TRUE(warned(h, "beyond its range"));
  expect_physics(h, 8);
}

TEST(HardCases, ContactOutgrowingTheFineZoneIsDetected) {
  const HardRun h = run_hard("outgrow_fine_zone.toml");
  EXPECT_TRUE(warned(h, "left the fine mesh zone"));
  expect_physics(h, 8);
}

TEST(HardCases, TenUnloadReloadCyclesDoNotDrift) {
  const HardRun h = run_hard("cycles.toml");
  std::vector<double> peaks;
  int separations = 0;
  for (const auto& r : h.curve) {
    if (r.alpha >= 5e-5 * (1 - 1e-12)) peaks.push_back(r.force);
    if (r.alpha == 0.0 && r.step > 0) {
      EXPECT_EQ(r.force, 0.0);
      ++separations;
    }
  }
  ASSERT_EQ(peaks.size(), 11u);
  EXPECT_EQ(separations, 10);
  // J2 shakes down after the first unloading: later peaks agree to 1e-5, and all within 0.1%.
  for (std::size_t k = 2; k < peaks.size(); ++k) EXPECT_NEAR(peaks[k], peaks[1], 1e-5 * peaks[1]) << "cycle " << k;
  EXPECT_NEAR(peaks.back(), peaks.front(), 1e-3 * peaks.front());
  expect_physics(h, 40);
}
