// The paper's finite-difference view: the layer equations hold at every interior node, the top
// layer force is the contact reaction, and the layer pressure converges to Hertz.
#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include <gtest/gtest.h>

#include "indentsim/fields.hpp"
#include "indentsim/hertz.hpp"
#include "indentsim/simulation.hpp"
#include "test_support.hpp"

using namespace indentsim;
using indentsim::testing::shipped_case;

namespace {

void expect_finite_difference_equations_hold(const Simulation& sim) {
  const Mesh& mesh = sim.mesh();
  const auto layer = nodal_layer_forces(mesh, sim.bulk());
  // Scale: the largest nodal layer force anywhere.
  double scale = 0;
  for (const auto& l : layer) scale = std::max({scale, std::abs(l.normal_below), std::abs(l.tangential_below)});
  ASSERT_GT(scale, 0);
  int checked = 0;
  for (int i = 0; i < mesh.nodes_x(); ++i)
    for (int j = 1; j < mesh.top_row(); ++j) {
      const auto& l = layer[mesh.node(i, j)];
      EXPECT_NEAR(l.normal_below + l.normal_above, 0.0, 1e-9 * scale) << "node " << i << "," << j;
      // On the axis the u row is the symmetry condition (its sum is the reaction).
      if (i > 0) {
        EXPECT_NEAR(l.tangential_below + l.tangential_above, 0.0, 1e-9 * scale) << "node " << i << "," << j;
      }
      ++checked;
    }
  EXPECT_GT(checked, 100);
}

}  // namespace

TEST(FiniteDifferenceView, LayerEquationsVanishAtInteriorNodesElastic) {
  Simulation sim(shipped_case("elastic.toml", {"load.increments=2", "mesh.contact_nodes=10"}));
  sim.run();
  expect_finite_difference_equations_hold(sim);
}

TEST(FiniteDifferenceView, LayerEquationsVanishAtInteriorNodesPlastic) {
  Simulation sim(shipped_case("deep_plastic.toml", {"load.increments=3", "mesh.contact_nodes=8"}));
  sim.run();
  ASSERT_GT(sim.bulk().plastic_points(), 0);
  expect_finite_difference_equations_hold(sim);
}

TEST(FiniteDifferenceView, TopLayerForceIsTheContactReaction) {
  Simulation sim(shipped_case("deep_plastic.toml", {"load.increments=3", "mesh.contact_nodes=8"}));
  sim.run();
  const auto layer = nodal_layer_forces(sim.mesh(), sim.bulk());
  const ContactResult c = sim.contact();
  const auto& cs = sim.contact_boundary().candidates();
  for (std::size_t k = 0; k < cs.size(); ++k) {
    // sigma_N^- at a top node is minus the punch's force on it.
    EXPECT_NEAR(-layer[cs[k].node].normal_below, c.nodal_force[k], 1e-9 * c.force) << "node " << k;
    // Frictionless: no tangential force on the surface (the axis node carries the symmetry reaction).
    if (k > 0) {
      EXPECT_NEAR(layer[cs[k].node].tangential_below, 0.0, 1e-9 * c.force) << "node " << k;
    }
  }
}

namespace {
// RMS of the layer pressure -sigma_N^-/w on the surface against Hertz for the same force, over
// the contact nodes but the outermost, at the final depth of the thick-block case.
double layer_pressure_error(int contact_nodes) {
  Simulation sim(shipped_case("hertz_thick_block.toml",
                              {"load.increments=2", "mesh.contact_nodes=" + std::to_string(contact_nodes)}));
  sim.run();
  const auto& lc = sim.load_case();
  const double e_star = lc.material.E / (1 - lc.material.nu * lc.material.nu);
  const auto layer = nodal_layer_forces(sim.mesh(), sim.bulk());
  const ContactResult c = sim.contact();
  const double a = hertz::half_width(c.force, lc.punch.radius, e_star);
  const double p0 = 2 * c.force / (std::numbers::pi * a);
  double sum = 0;
  int count = 0;
  for (int i = 0; i < c.outermost; ++i) {
    const int node = sim.mesh().node(i, sim.mesh().top_row());
    const double p = -layer[node].normal_below / tributary_width(sim.mesh(), i);
    sum += std::pow((p - hertz::pressure(sim.mesh().x(i), a, c.force)) / p0, 2);
    ++count;
  }
  return std::sqrt(sum / count);
}
}  // namespace

TEST(FiniteDifferenceView, SurfaceLayerPressureConvergesToHertz) {
  const double coarse = layer_pressure_error(8), fine = layer_pressure_error(16);
  RecordProperty("rms_8_16", fmt::format("{:.5f} {:.5f}", coarse, fine));
  EXPECT_LT(fine, 0.01);
  EXPECT_LT(fine, coarse);
}
