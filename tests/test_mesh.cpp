// The graded tensor mesh: exact extents, a uniform fine zone, bounded growth, and refinement
// that reaches the far field.
#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "indentsim/geometry/mesh.hpp"
#include "test_support.hpp"

using namespace indentsim;

namespace {
double largest_element(const std::vector<double>& x) {
  double largest = 0;
  for (std::size_t i = 0; i + 1 < x.size(); ++i) largest = std::max(largest, x[i + 1] - x[i]);
  return largest;
}
}  // namespace

TEST(Mesh, GradedAxisIsUniformThenGrowsAndClosesExactly) {
  const double length = 15e-3, fine = 3e-4, h = 1e-5, growth = 1.15;
  const auto x = graded_axis(length, fine, h, growth);
  EXPECT_EQ(static_cast<std::int64_t>(x.size()), graded_axis_count(length, fine, h, growth));
  EXPECT_EQ(x.front(), 0.0);
  EXPECT_EQ(x.back(), length);
  for (std::size_t i = 0; i + 1 < x.size(); ++i) {
    const double size = x[i + 1] - x[i];
    ASSERT_GT(size, 0.0);
    if (x[i + 1] <= fine * (1 + 1e-12)) {
      EXPECT_NEAR(size, h, 1e-9 * h);
    }
    if (i > 0) {
      EXPECT_LE(size / (x[i] - x[i - 1]), growth * (1 + 1e-9));
    }
  }
}

TEST(Mesh, DoublingContactNodesRefinesEveryRegion) {
  const LoadCase coarse = indentsim::testing::shipped_case("elastic.toml", {"mesh.contact_nodes=10"});
  const LoadCase fine = indentsim::testing::shipped_case("elastic.toml", {"mesh.contact_nodes=20"});
  const Mesh a = Mesh::from_plan(coarse, plan_mesh(coarse)), b = Mesh::from_plan(fine, plan_mesh(fine));
  // The far field refines too (MODEL.md): the largest element shrinks markedly, not only the fine zone.
  EXPECT_LT(largest_element(b.x()), 0.7 * largest_element(a.x()));
  EXPECT_LT(largest_element(b.y()), 0.7 * largest_element(a.y()));
}

TEST(Mesh, BoundaryConditionsFixBaseAndAxis) {
  const Mesh mesh(graded_axis(1.0, 0.2, 0.1, 1.3), graded_axis(1.0, 0.2, 0.1, 1.3));
  int fixed = 0;
  for (int i = 0; i < mesh.nodes_x(); ++i)
    for (int j = 0; j < mesh.nodes_y(); ++j) {
      const int n = mesh.node(i, j);
      EXPECT_EQ(mesh.equation(Mesh::dof_u(n)) < 0, i == 0 || j == 0);
      EXPECT_EQ(mesh.equation(Mesh::dof_v(n)) < 0, j == 0);
      fixed += (mesh.equation(Mesh::dof_u(n)) < 0) + (mesh.equation(Mesh::dof_v(n)) < 0);
    }
  EXPECT_EQ(mesh.equations() + fixed, 2 * mesh.nodes());
}

TEST(Mesh, PlanFollowsTheEstimatedContactHalfWidth) {
  const LoadCase lc = indentsim::testing::shipped_case("elastic.toml");
  const MeshPlan plan = plan_mesh(lc);
  EXPECT_NEAR(plan.fine_spacing * lc.mesh.contact_nodes, plan.contact_half_width_estimate, 1e-15);
  EXPECT_GE(plan.fine_width, plan.contact_half_width_estimate);
  // The estimate can never exceed the geometric chord of the punch at the final depth.
  const double chord = std::sqrt(2 * lc.punch.radius * lc.max_depth());
  EXPECT_LE(plan.contact_half_width_estimate, chord);
}
