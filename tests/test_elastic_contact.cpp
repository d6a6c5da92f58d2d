// Elastic Signorini indentation against theory: Hertz line contact (P-a and pressure profile,
// converging under refinement), layer-by-layer equilibrium, and the basic shape of P(alpha).
#include <cmath>
#include <numbers>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "indentsim/geometry/hertz.hpp"
#include "indentsim/simulation/simulation.hpp"
#include "test_support.hpp"

using namespace indentsim;

namespace {

struct HertzErrors {
  double force_vs_half_width = 0.0;  ///< max |P - P_hertz(a)| / P over the checked increments
  double pressure = 0.0;             ///< max RMS (p - p_hertz) / p0 over the checked increments
};

// Runs the thick-block case at `contact_nodes` and compares every increment from the second
// half of the path (where the contact spans most of the fine zone) with Hertz.
HertzErrors hertz_errors(int contact_nodes) {
  const LoadCase lc = indentsim::testing::shipped_case(
      "hertz_thick_block.toml", {"mesh.contact_nodes=" + std::to_string(contact_nodes), "load.increments=6"});
  Simulation sim(lc);
  const double e_star = lc.material.E / (1 - lc.material.nu * lc.material.nu);
  const double radius = lc.punch.radius;
  HertzErrors errors;
  sim.run([&](const IncrementRecord& r) {
    if (r.step < 3) return;
    EXPECT_LT(r.half_width / radius, 0.03);  // the parabolic approximation holds
    const double p_hertz = hertz::force(r.half_width, radius, e_star);
    errors.force_vs_half_width = std::max(errors.force_vs_half_width, std::abs(r.force - p_hertz) / r.force);

    // Pressure: nodal reaction over tributary width, against Hertz for the same total force.
    const ContactResult c = sim.contact();
    const double a_hertz = hertz::half_width(c.force, radius, e_star);
    const double p0 = 2 * c.force / (std::numbers::pi * a_hertz);
    double sum = 0;
    int count = 0;
    const auto& cs = sim.contact_boundary().candidates();
    for (int k = 0; k + 1 < c.outermost; ++k) {  // the outermost node's strip is partly open
      const double p = c.nodal_force[k] / cs[k].tributary_measure;
      sum += std::pow((p - hertz::pressure(cs[k].x, a_hertz, c.force)) / p0, 2);
      ++count;
    }
    errors.pressure = std::max(errors.pressure, std::sqrt(sum / count));
  });
  return errors;
}

}  // namespace

TEST(Hertz, ForceAndPressureConvergeToHertzLineContact) {
  const HertzErrors coarse = hertz_errors(10), standard = hertz_errors(20), fine = hertz_errors(40);
  RecordProperty("p_a_error_10_20_40", fmt::format("{:.4f} {:.4f} {:.4f}", coarse.force_vs_half_width,
                                                   standard.force_vs_half_width, fine.force_vs_half_width));
  // At the default contact_nodes (20) the P-a relation is within 1% of Hertz ...
  EXPECT_LT(standard.force_vs_half_width, 0.01);
  EXPECT_LT(standard.pressure, 0.01);
  // ... and the error drops under refinement.
  EXPECT_LT(standard.force_vs_half_width, coarse.force_vs_half_width);
  EXPECT_LT(fine.force_vs_half_width, standard.force_vs_half_width);
  EXPECT_LT(fine.pressure, coarse.pressure);
}

TEST(ElasticContact, EveryMeshLineCarriesThePunchForce) {
  const LoadCase lc = indentsim::testing::shipped_case("elastic.toml", {"load.increments=3"});
  Simulation sim(lc);
  sim.run();
  const double force = sim.contact().force;
  ASSERT_GT(force, 0.0);
  const auto layers = sim.line_forces();
  ASSERT_EQ(static_cast<int>(layers.size()), sim.mesh().nodes_y());
  for (std::size_t j = 0; j < layers.size(); ++j) {
    if (j > 0) {
      EXPECT_NEAR(layers[j].below, force, 1e-8 * force) << "line " << j << " y = " << layers[j].y;
    }
    if (j + 1 < layers.size()) {
      EXPECT_NEAR(layers[j].above, force, 1e-8 * force) << "line " << j;
    }
  }
}

TEST(ElasticContact, ZeroDepthGivesZeroForceAndTheCurveGrowsMonotonically) {
  const LoadCase lc = indentsim::testing::shipped_case("elastic.toml", {"load.increments=6"});
  Simulation sim(lc);
  std::vector<IncrementRecord> curve;
  sim.run([&](const IncrementRecord& r) { curve.push_back(r); });
  ASSERT_EQ(curve.size(), 7u);
  EXPECT_EQ(curve[0].alpha, 0.0);
  EXPECT_EQ(curve[0].force, 0.0);
  EXPECT_EQ(curve[0].half_width, 0.0);
  for (std::size_t k = 1; k < curve.size(); ++k) {
    EXPECT_GT(curve[k].alpha, curve[k - 1].alpha);
    EXPECT_GT(curve[k].force, curve[k - 1].force);
    EXPECT_GT(curve[k].half_width, curve[k - 1].half_width);
    EXPECT_GE(curve[k].contact_nodes, curve[k - 1].contact_nodes);
  }
  // The whole run analyses the (fixed) sparsity pattern once.
  EXPECT_EQ(sim.symbolic_analyses(), 1);
}

TEST(ElasticContact, NoPenetrationAndNoTensileContactForce) {
  const LoadCase lc = indentsim::testing::shipped_case("elastic.toml", {"load.increments=2"});
  Simulation sim(lc);
  sim.run();
  const ContactResult c = sim.contact();
  const auto& cs = sim.contact_boundary().candidates();
  const auto& u = sim.displacement();
  const double alpha = sim.alpha();
  for (std::size_t k = 0; k < cs.size(); ++k) {
    const double gap = cs[k].surface_height - alpha - u[cs[k].equation];
    EXPECT_GE(gap, -1e-12 * alpha) << "node " << k;
    EXPECT_GE(c.nodal_force[k], 0.0) << "node " << k;
    if (c.in_contact[k]) {
      EXPECT_NEAR(gap, 0.0, 1e-12 * alpha);
    }
  }
  // Contact is one connected zone from the axis.
  for (int k = 0; k <= c.outermost; ++k) EXPECT_TRUE(c.in_contact[k]) << k;
}

TEST(ElasticContact, SmallerIncrementsGiveTheSameElasticSolution) {
  // Elasticity has no history: the end state must not depend on the increments taken.
  Simulation one(indentsim::testing::shipped_case("elastic.toml", {"load.increments=1"}));
  Simulation many(indentsim::testing::shipped_case("elastic.toml", {"load.increments=7"}));
  one.run();
  many.run();
  EXPECT_NEAR(one.contact().force, many.contact().force, 1e-9 * many.contact().force);
}

TEST(ElasticContact, ObservedConvergenceOrderOfTheForceIsAtLeastOne) {
  // P at the final depth for contact_nodes 8, 16, 32 (the far field refines with them):
  // order = log2((P8 - P16) / (P16 - P32)).
  std::vector<double> force;
  for (int n : {8, 16, 32}) {
    Simulation sim(indentsim::testing::shipped_case(
        "elastic.toml", {"mesh.contact_nodes=" + std::to_string(n), "load.increments=1", "solver.linear=auto"}));
    sim.run();
    force.push_back(sim.contact().force);
  }
  const double order = std::log2((force[0] - force[1]) / (force[1] - force[2]));
  RecordProperty("observed_order", fmt::format("{:.3f}", order));
  EXPECT_GE(order, 1.0) << force[0] << " " << force[1] << " " << force[2];
}

// A rigid wedge on an elastic half-plane: a pressure bounded at the edges of the contact carries
// P = a E* cot(theta) per unit thickness (the 2-D punch problem; the force needs no depth of the
// block, unlike the approach).  And the mesh planner's estimate of the contact half-width
// (PunchShape::contact_estimate) must put that contact inside the fine zone with about the
// contact_nodes asked for: the rule of Hertz's cylinder applied to a wedge put it pi/2 too narrow.
TEST(ElasticContact, WedgeForceFollowsTheHalfPlaneSolutionInsideItsPlannedFineZone) {
  LoadCase lc = indentsim::testing::shipped_case("hertz_thick_block.toml", {"mesh.error_estimate=off"});
  lc.punch.shape = PunchShapeKind::cone;
  lc.punch.half_angle = 80.0;
  validate(lc);
  Simulation sim(lc);
  const double cot = 1.0 / std::tan(80.0 * std::numbers::pi / 180.0);
  IncrementRecord last;
  sim.run([&](const IncrementRecord& r) {
    if (r.step < 4) return;  // a contact of several nodes
    const double p_wedge = r.half_width * indentsim::testing::contact_modulus(lc) * cot;
    EXPECT_NEAR(r.force / p_wedge, 1.0, 0.01) << "alpha = " << r.alpha;
    last = r;
  });
  for (const std::string& w : sim.warnings()) EXPECT_EQ(w.find("left the fine mesh zone"), std::string::npos) << w;
  EXPECT_GE(last.contact_nodes, 0.8 * lc.mesh.contact_nodes);
  EXPECT_LE(last.contact_nodes, 1.25 * lc.mesh.contact_nodes);
  EXPECT_NEAR(last.half_width / sim.plan().contact_half_width_estimate, 1.0, 0.15);
}
