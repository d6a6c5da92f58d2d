// The paper's finite-difference view: the layer equations hold at every interior node, the top
// layer force is the contact reaction, and the layer pressure converges to Hertz.
#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include <gtest/gtest.h>

#include "indentsim/output/fields.hpp"
#include "indentsim/geometry/hertz.hpp"
#include "indentsim/simulation/simulation.hpp"
#include "test_support.hpp"

using namespace indentsim;
using indentsim::testing::shipped_case;

namespace {

void expect_finite_difference_equations_hold(const Simulation& sim) {
  const Mesh& mesh = sim.mesh();
  const auto layer = nodal_line_forces(mesh, sim.bulk());
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
  // The layer view's force on each surface node (rows of the elements below it), checked against
  // the contact conditions themselves rather than against the contact solver's own account: where
  // it presses, the node lies on the punch (u2 = -alpha + g(x)); where the node is off the punch,
  // it vanishes; it never pulls; there is no tangential surface force (frictionless); and twice
  // its sum is the force P of the increment.  A layer view built from the wrong rows or elements,
  // or a contact solution off the punch, fails here.
  for (const char* name : {"deep_plastic.toml", "elastic.toml"}) {
    SCOPED_TRACE(name);
    Simulation sim(shipped_case(name, {"load.increments=3", "mesh.contact_nodes=8"}));
    IncrementRecord last;
    sim.run([&](const IncrementRecord& r) { last = r; });
    const auto layer = nodal_line_forces(sim.mesh(), sim.bulk());
    const auto& u = sim.displacement();
    const double alpha = sim.alpha(), P = last.force;
    ASSERT_GT(P, 0.0);
    double total = 0.0;
    int pressing = 0;
    for (const auto& c : sim.contact_boundary().candidates()) {
      const double force = -layer[c.node].normal_below;  // the punch's push on the node
      // How far the node is below the punch surface y = -alpha + g(x): >= 0, 0 in contact.
      const double separation = -alpha + c.surface_height - u[c.equation];
      EXPECT_GE(force, -1e-9 * P) << "tensile contact at node " << c.node;
      EXPECT_GE(separation, -1e-9 * alpha) << "penetration at node " << c.node;
      if (force > 1e-9 * P) {
        EXPECT_NEAR(separation, 0.0, 1e-9 * alpha) << "a pressed node off the punch: " << c.node;
        ++pressing;
      } else if (separation > 1e-6 * alpha) {
        EXPECT_NEAR(force, 0.0, 1e-9 * P) << "a node off the punch carries force: " << c.node;
      }
      if (c.node != sim.mesh().node(0, sim.mesh().top_row())) {
        EXPECT_NEAR(layer[c.node].tangential_below, 0.0, 1e-9 * P) << "friction at node " << c.node;
      }
      total += force;
    }
    EXPECT_GE(pressing, 2);
    EXPECT_NEAR(2.0 * total, P, 1e-9 * P);
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
  const auto layer = nodal_line_forces(sim.mesh(), sim.bulk());
  const ContactResult c = sim.contact();
  const double a = hertz::half_width(c.force, lc.punch.radius, e_star);
  const double p0 = 2 * c.force / (std::numbers::pi * a);
  double sum = 0;
  int count = 0;
  for (int i = 0; i < c.outermost; ++i) {
    const int node = sim.mesh().node(i, sim.mesh().top_row());
    const double p = -layer[node].normal_below / tributary_measure(sim.mesh(), i);
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
