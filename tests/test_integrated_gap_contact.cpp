// The integrated-gap contact discretization (include/indentsim/solvers/integrated_gap_contact.hpp,
// docs/MODEL.md §3.2): its Jacobian rows are its residual's derivative (the contact pieces' ends
// found to round-off make F continuously differentiable), Hertz's force and radius hold as for the
// node-to-rigid rows, the unloading stiffness is the derivative of P(alpha), and the condensed
// near field solves the same equations as the whole mesh.
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "indentsim/geometry/hertz.hpp"
#include "indentsim/geometry/mesh.hpp"
#include "indentsim/geometry/punch.hpp"
#include "indentsim/simulation/simulation.hpp"
#include "indentsim/solvers/assembly.hpp"
#include "indentsim/solvers/integrated_gap_contact.hpp"
#include "indentsim/solvers/solver.hpp"
#include "test_support.hpp"

namespace indentsim {
namespace {

using testing::shipped_case;

LoadCase integrated(LoadCase lc) {
  lc.contact.discretization = ContactDiscretizationChoice::integrated_gap;
  return lc;
}

// A surface pressed onto the punch with some nodes past it and some short of it, so that
// segments touch wholly, partly (a root inside) and not at all.
TEST(IntegratedGapContact, TheJacobianRowsAreTheResidualsDerivative) {
  for (const char* name : {"elastic.toml", "axisymmetric/elastic_sphere.toml", "axisymmetric/berkovich_cone.toml"}) {
    SCOPED_TRACE(name);
    const LoadCase lc = shipped_case(name, {"mesh.contact_nodes=8", "material.model=\"elastic\""});
    const Mesh mesh = Mesh::from_plan(lc, plan_mesh(lc));
    const StiffnessPattern pattern(mesh);
    ElasticStiffness k(mesh, ElasticMaterial{lc.material.E, lc.material.nu}, pattern);
    const IntegratedGapContact contact(mesh, make_punch(lc.punch), pattern, k.values(), 100.0);
    ContactEquations equations(pattern, k, k, contact);
    const auto& cs = contact.candidates();
    ASSERT_GE(cs.size(), 12u);
    const double alpha = 0.5 * lc.max_depth();
    std::mt19937 random(11);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    std::vector<double> u(static_cast<std::size_t>(mesh.equations()), 0.0);
    // On the punch over the first nodes, within +-5% of the depth of it; open further out.
    for (std::size_t i = 0; i < cs.size(); ++i)
      u[cs[i].equation] = cs[i].surface_height - alpha + (i < 8 ? 0.05 : 0.2 * static_cast<double>(i - 6)) * alpha * (i < 8 ? unit(random) : 1.0);
    const auto n = static_cast<std::size_t>(mesh.equations());
    std::vector<double> values(static_cast<std::size_t>(pattern.nonzeros())), f(n), f_plus(n), f_minus(n), jd(n);
    equations.residual(u.data(), alpha, f.data());
    equations.jacobian(u.data(), alpha, values.data());
    // A touching candidate on both sides of the test: the rows must hold contact force.
    double contact_force = 0.0;
    std::vector<double> bulk(n);
    k.internal_force(u.data(), bulk.data());
    for (const auto& c : cs) contact_force += f[c.equation] - bulk[c.equation];
    ASSERT_GT(contact_force, 0.0);

    std::vector<double> direction(n, 0.0);
    for (const auto& c : cs) direction[c.equation] = 1e-3 * alpha * unit(random);
    pattern.multiply(values, direction.data(), jd.data());
    const double step = 1e-4;
    std::vector<double> plus = u, minus = u;
    for (std::size_t i = 0; i < n; ++i) {
      plus[i] += step * direction[i];
      minus[i] -= step * direction[i];
    }
    equations.residual(plus.data(), alpha, f_plus.data());
    equations.residual(minus.data(), alpha, f_minus.data());
    double scale = 0.0;
    for (const auto& c : cs) scale = std::max(scale, std::abs(jd[c.equation]));
    for (const auto& c : cs)
      EXPECT_NEAR((f_plus[c.equation] - f_minus[c.equation]) / (2.0 * step), jd[c.equation], 1e-6 * scale)
          << "candidate at x = " << c.x;

    // dF/dalpha at fixed u.
    std::vector<double> d_alpha(n, 0.0), row_force;
    for (const auto& c : cs) row_force.push_back(bulk[c.equation]);
    contact.write_depth_derivative_rows(u.data(), alpha, row_force.data(), d_alpha.data());
    const double delta = 1e-7 * alpha;
    equations.residual(u.data(), alpha + delta, f_plus.data());
    equations.residual(u.data(), alpha - delta, f_minus.data());
    double d_scale = 0.0;
    for (const auto& c : cs) d_scale = std::max(d_scale, std::abs(d_alpha[c.equation]));
    ASSERT_GT(d_scale, 0.0);
    for (const auto& c : cs)
      EXPECT_NEAR((f_plus[c.equation] - f_minus[c.equation]) / (2.0 * delta), d_alpha[c.equation], 1e-6 * d_scale)
          << "candidate at x = " << c.x;
  }
}

// Hertz (1882) for the sphere on the shipped elastic specimen: P = (4/3) E* R^1/2 alpha^3/2 and
// a = (R alpha)^1/2, held by the node-to-rigid rows to the finite specimen's offset (+0.3% on P,
// docs/verification.md); the penalty's penetration p h / (kappa E*) adds about 1e-4 of alpha.
TEST(IntegratedGapContact, HertzsForceAndRadiusHoldOnTheElasticSphere) {
  const LoadCase node = shipped_case("axisymmetric/elastic_sphere.toml");
  const LoadCase gap = integrated(node);
  Simulation a(node), b(gap);
  a.run();
  b.run();
  const double alpha = node.max_depth(), R = node.punch.radius, E_star = testing::contact_modulus(node);
  const double hertz_force = 4.0 / 3.0 * E_star * std::sqrt(R) * std::pow(alpha, 1.5);
  const double hertz_radius = std::sqrt(R * alpha);
  EXPECT_NEAR(b.contact().force / hertz_force, 1.0, 0.006);
  EXPECT_NEAR(b.contact_half_width() / hertz_radius, 1.0, 0.005);
  EXPECT_NEAR(b.contact().force / a.contact().force, 1.0, 5e-4);
}

// The elastic unloading stiffness is dP/dalpha (frictionless elastic contact is path
// independent): against a central difference of whole runs on the same mesh.
TEST(IntegratedGapContact, TheUnloadingStiffnessIsTheSlopeOfTheElasticCurve) {
  const LoadCase lc = integrated(shipped_case("axisymmetric/elastic_sphere.toml"));
  const double alpha = lc.max_depth(), delta = 1e-4 * alpha;
  Simulation at(lc);
  at.run();
  double sides[2];
  for (int s = 0; s < 2; ++s) {
    LoadCase shifted = lc;
    shifted.load.path.back() = alpha + (s == 0 ? delta : -delta);
    shifted.mesh.contact_half_width = at.plan().contact_half_width_estimate;  // the same mesh
    Simulation sim(shifted);
    sim.run();
    sides[s] = sim.contact().force;
  }
  LoadCase pinned = lc;
  pinned.mesh.contact_half_width = at.plan().contact_half_width_estimate;
  Simulation same_mesh(pinned);
  same_mesh.run();
  const double S = same_mesh.unloading_stiffness();
  EXPECT_NEAR(S / ((sides[0] - sides[1]) / (2.0 * delta)), 1.0, 1e-3);
}

// The condensed near field and the whole mesh solve the same equations (the penalty is the whole
// mesh's in both), through plasticity and unloading.
TEST(IntegratedGapContact, TheCondensedNearFieldGivesTheWholeMeshsCurve) {
  for (const char* name : {"deep_plastic.toml", "axisymmetric/steel_sphere.toml"}) {
    SCOPED_TRACE(name);
    std::vector<double> forces[2];
    for (int whole = 0; whole < 2; ++whole) {
      const LoadCase lc = integrated(shipped_case(
          name, {"mesh.contact_nodes=8", whole ? "solver.far_field=\"full\"" : "solver.far_field=\"condense\""}));
      Simulation sim(lc);
      sim.run([&](const IncrementRecord& r) { forces[whole].push_back(r.force); });
    }
    ASSERT_EQ(forces[0].size(), forces[1].size());
    const double peak = *std::max_element(forces[1].begin(), forces[1].end());
    for (std::size_t k = 0; k < forces[0].size(); ++k) EXPECT_NEAR(forces[0][k], forces[1][k], 1e-8 * peak) << "row " << k;
  }
}

// A run restored from a state taken mid-path continues bit for bit.
TEST(IntegratedGapContact, ARestoredStateContinuesBitForBit) {
  const LoadCase lc = integrated(shipped_case("axisymmetric/steel_sphere.toml", {"mesh.contact_nodes=8"}));
  Simulation run(lc);
  std::vector<IncrementRecord> rows;
  std::vector<SimulationState> states;
  run.run([&](const IncrementRecord& r) {
    rows.push_back(r);
    states.push_back(run.state());
  });
  const std::size_t from = rows.size() / 2;
  Simulation resumed(lc, run.plan().contact_half_width_estimate, states[from].near_field);
  resumed.restore(states[from]);
  std::vector<IncrementRecord> rest;
  resumed.run([&](const IncrementRecord& r) { rest.push_back(r); });
  ASSERT_EQ(rest.size() + from + 1, rows.size());
  for (std::size_t k = 0; k < rest.size(); ++k) {
    EXPECT_EQ(rest[k].force, rows[from + 1 + k].force) << "row " << from + 1 + k;
    EXPECT_EQ(rest[k].half_width, rows[from + 1 + k].half_width) << "row " << from + 1 + k;
  }
  EXPECT_EQ(resumed.displacement(), run.displacement());
}

}  // namespace
}  // namespace indentsim
