// Uniform-compression patch test on a graded mesh, solved through the same KINSOL + KLU
// path as the contact problem: the exact linear field must come back to round-off.
#include <cmath>

#include <gtest/gtest.h>

#include "indentsim/solvers/assembly.hpp"
#include "indentsim/geometry/mesh.hpp"
#include "test_support.hpp"
#include "indentsim/solvers/solver.hpp"

using namespace indentsim;

namespace {

// K u - f = 0 for given nodal loads f.
class LinearEquations : public IncrementEquations {
public:
  LinearEquations(const StiffnessPattern& p, ElasticStiffness& k, std::vector<double> f)
      : pattern_(p), stiffness_(k), load_(std::move(f)) {}
  const StiffnessPattern& pattern() const override { return pattern_; }
  void residual(const double* u, double, double* f) override {
    stiffness_.multiply(u, f);
    for (std::size_t i = 0; i < load_.size(); ++i) f[i] -= load_[i];
  }
  void jacobian(const double*, double, double* values) override {
    std::copy(stiffness_.values().begin(), stiffness_.values().end(), values);
  }

private:
  const StiffnessPattern& pattern_;
  ElasticStiffness& stiffness_;
  std::vector<double> load_;
};


}  // namespace

class PatchTest : public ::testing::TestWithParam<ElementKind> {};

TEST_P(PatchTest, UniformCompressionIsReproducedExactlyOnAGradedMesh) {
  // u1 = 0, u2 = -eps (y + ly): satisfies the base clamp and the axis symmetry condition.
  // Stresses: sigma22 = -(lambda + 2 mu) eps on top, sigma11 = -lambda eps on the side x = lx.
  const double lx = 15e-3, ly = 10e-3, eps = 1e-3;
  Mesh mesh = indentsim::testing::graded_block(lx, ly, GetParam());
  const ElasticMaterial material{210e9, 0.3};
  const LameConstants lame = material.lame();
  const StiffnessPattern pattern(mesh);
  ElasticStiffness stiffness(mesh, material, pattern);

  // Consistent nodal loads of the constant tractions: half an edge length to each end node.
  std::vector<double> f(static_cast<std::size_t>(mesh.equations()), 0.0);
  const double top_traction = -(lame.lambda + 2 * lame.mu) * eps;  // sigma22 n2 on y = 0
  const double side_traction = -lame.lambda * eps;                  // sigma11 n1 on x = lx
  for (int i = 0; i + 1 < mesh.nodes_x(); ++i) {
    const double half = 0.5 * (mesh.x(i + 1) - mesh.x(i)) * top_traction;
    for (int n : {mesh.node(i, mesh.top_row()), mesh.node(i + 1, mesh.top_row())}) {
      const int eq = mesh.equation(Mesh::dof_v(n));
      if (eq >= 0) f[eq] += half;
    }
  }
  for (int j = 0; j + 1 < mesh.nodes_y(); ++j) {
    const double half = 0.5 * (mesh.y(j + 1) - mesh.y(j)) * side_traction;
    for (int n : {mesh.node(mesh.nodes_x() - 1, j), mesh.node(mesh.nodes_x() - 1, j + 1)}) {
      const int eq = mesh.equation(Mesh::dof_u(n));
      if (eq >= 0) f[eq] += half;
    }
  }

  LinearEquations equations(pattern, stiffness, f);
  NewtonSettings settings;
  settings.displacement_scale = eps * ly;
  settings.force_scale = material.E * eps * 1e-3;
  settings.tolerance = 1e-12;
  NewtonSolver solver(equations, settings);
  std::vector<double> u(static_cast<std::size_t>(mesh.equations()), 0.0);
  const NewtonReport report = solver.solve(0.0, u);
  ASSERT_TRUE(report.converged) << report.message;
  EXPECT_LE(report.iterations, 2);  // linear: one Newton step

  double worst = 0;
  for (int i = 0; i < mesh.nodes_x(); ++i)
    for (int j = 0; j < mesh.nodes_y(); ++j) {
      const int n = mesh.node(i, j);
      const int eu = mesh.equation(Mesh::dof_u(n)), ev = mesh.equation(Mesh::dof_v(n));
      const double exact_v = -eps * (mesh.y(j) + ly);
      if (eu >= 0) worst = std::max(worst, std::abs(u[eu]));
      if (ev >= 0) worst = std::max(worst, std::abs(u[ev] - exact_v));
    }
  EXPECT_LE(worst, 1e-12 * eps * ly);
}

TEST_P(PatchTest, EveryConstantStrainStateIsExactOnAGradedMesh) {
  // The patch test in its discrete form, for each of the three constant-strain states (the
  // mesh's clamped base and symmetry axis admit only the first as a solved problem above): with
  // the nodes displaced by an exact linear field, every element's Gauss-point strain is the
  // constant strain, and the assembled element forces vanish at every interior node (constant
  // stress is in equilibrium) and equal the consistent tractions on the boundary.
  const double lx = 15e-3, ly = 10e-3, e = 1e-3;
  Mesh mesh = indentsim::testing::graded_block(lx, ly, GetParam());
  const ElasticMaterial material{210e9, 0.3};
  const StiffnessPattern pattern(mesh);
  ElasticStiffness stiffness(mesh, material, pattern);
  const ConstitutiveMatrix d = material.stiffness();
  const struct {
    const char* name;
    VoigtVector strain;  // (eps11, eps22, gamma12, eps33 = 0)
  } states[] = {{"uniaxial x", {e, 0, 0, 0}}, {"uniaxial y", {0, e, 0, 0}}, {"shear", {0, 0, e, 0}}};
  for (const auto& state : states) {
    SCOPED_TRACE(state.name);
    // u1 = eps11 x + gamma12 y / 2, u2 = eps22 y + gamma12 x / 2.
    const auto u1 = [&](double x, double y) { return state.strain[0] * x + 0.5 * state.strain[2] * y; };
    const auto u2 = [&](double x, double y) { return state.strain[1] * y + 0.5 * state.strain[2] * x; };
    const VoigtVector stress = d * state.strain;
    std::vector<double> fx(static_cast<std::size_t>(mesh.nodes()), 0.0), fy(fx);
    for (int ei = 0; ei < mesh.elements_x(); ++ei)
      for (int ej = 0; ej < mesh.elements_y(); ++ej) {
        // Paper vertex order: 1 = (x0, y0), 2 = (x0, y1), 3 = (x1, y0), 4 = (x1, y1).
        const double xs[4] = {mesh.x(ei), mesh.x(ei), mesh.x(ei + 1), mesh.x(ei + 1)};
        const double ys[4] = {mesh.y(ej), mesh.y(ej + 1), mesh.y(ej), mesh.y(ej + 1)};
        const int nodes[4] = {mesh.node(ei, ej), mesh.node(ei, ej + 1), mesh.node(ei + 1, ej), mesh.node(ei + 1, ej + 1)};
        ElementVector ue;
        for (int q = 0; q < 4; ++q) {
          ue[q] = u1(xs[q], ys[q]);
          ue[q + 4] = u2(xs[q], ys[q]);
        }
        for (const VoigtVector& strain : stiffness.quadrature(ei, ej).strains(ue))
          EXPECT_LE((strain - state.strain).norm(), 1e-12 * e);
        const ElementVector fe = stiffness.cached_matrix(ei, ej) * ue;
        for (int q = 0; q < 4; ++q) {
          fx[nodes[q]] += fe[q];
          fy[nodes[q]] += fe[q + 4];
        }
      }
    // Consistent tractions t = sigma n: half of each boundary edge's load to each of its nodes.
    std::vector<double> tx(fx.size(), 0.0), ty(fx.size(), 0.0);
    const auto edge = [&](int n1, int n2, double length, double nx, double ny) {
      const double t1 = stress[0] * nx + stress[2] * ny, t2 = stress[2] * nx + stress[1] * ny;
      for (int n : {n1, n2}) {
        tx[n] += 0.5 * length * t1;
        ty[n] += 0.5 * length * t2;
      }
    };
    const int top = mesh.top_row(), right = mesh.nodes_x() - 1;
    for (int i = 0; i < right; ++i) {
      edge(mesh.node(i, top), mesh.node(i + 1, top), mesh.x(i + 1) - mesh.x(i), 0, 1);
      edge(mesh.node(i, 0), mesh.node(i + 1, 0), mesh.x(i + 1) - mesh.x(i), 0, -1);
    }
    for (int j = 0; j < top; ++j) {
      edge(mesh.node(right, j), mesh.node(right, j + 1), mesh.y(j + 1) - mesh.y(j), 1, 0);
      edge(mesh.node(0, j), mesh.node(0, j + 1), mesh.y(j + 1) - mesh.y(j), -1, 0);
    }
    const double scale = material.E * e * lx;
    for (int n = 0; n < mesh.nodes(); ++n) {
      EXPECT_NEAR(fx[n], tx[n], 1e-10 * scale) << "node " << n;
      EXPECT_NEAR(fy[n], ty[n], 1e-10 * scale) << "node " << n;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Elements, PatchTest, ::testing::Values(ElementKind::q1, ElementKind::bbar),
                         [](const ::testing::TestParamInfo<ElementKind>& info) {
                           return std::string(info.param == ElementKind::q1 ? "q1" : "bbar");
                         });
