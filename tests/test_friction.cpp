// Coulomb friction between specimen and punch (include/indentsim/solvers/coulomb_contact.hpp,
// docs/MODEL.md §3.3): the rows' Jacobian is their residual's derivative; a sticking flat punch
// carries Mossakovskii's force; friction raises the force monotonically between the frictionless
// and the sticking punch; the stick zone of an elastic sphere is self-similar (Spence); the
// unloading stiffness the run reports is the slope of its own unloading; the condensed near
// field, a restored state and both linear solvers solve the same equations.
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "indentsim/base/error.hpp"
#include "indentsim/geometry/mesh.hpp"
#include "indentsim/geometry/punch.hpp"
#include "indentsim/simulation/simulation.hpp"
#include "indentsim/solvers/assembly.hpp"
#include "indentsim/solvers/coulomb_contact.hpp"
#include "indentsim/solvers/solver.hpp"
#include "test_support.hpp"

namespace indentsim {
namespace {

using testing::shipped_case;
constexpr double sticking = std::numeric_limits<double>::infinity();

LoadCase with_friction(LoadCase lc, double mu) {
  lc.contact.friction = mu;
  validate(lc);
  return lc;
}

// Expects `check` to throw an InputError naming `key` (what was accepted otherwise: `what`).
template <class Check>
void expect_refused(Check check, const std::string& key, const char* what) {
  try {
    check();
    ADD_FAILURE() << what << " was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), key);
  }
}

double final_force(const LoadCase& lc) {
  Simulation sim(lc);
  sim.run();
  return sim.contact().force;
}

// A surface pressed onto the punch (some candidates past it, some short of it) with horizontal
// displacements and a committed state chosen so that contact nodes both stick and slip, in both
// directions: the Jacobian's rows against central differences of the residual, on every branch.
TEST(CoulombFriction, TheJacobianRowsAreTheResidualsDerivative) {
  for (const char* name : {"elastic.toml", "axisymmetric/elastic_sphere.toml"}) {
    SCOPED_TRACE(name);
    const LoadCase lc = shipped_case(name, {"mesh.contact_nodes=8"});
    const Mesh mesh = Mesh::from_plan(lc, plan_mesh(lc));
    const StiffnessPattern pattern(mesh);
    ElasticStiffness k(mesh, ElasticMaterial{lc.material.E, lc.material.nu}, pattern);
    CoulombNodeToRigidContact contact(mesh, make_punch(lc.punch), pattern, k.values(), 0.3);
    ContactEquations equations(pattern, k, k, contact);
    const auto& cs = contact.candidates();
    ASSERT_GE(cs.size(), 12u);
    const double alpha = 0.5 * lc.max_depth();
    const auto n = static_cast<std::size_t>(mesh.equations());
    std::mt19937 random(7);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    std::vector<double> u(n, 0.0), committed(n, 0.0);
    for (std::size_t i = 0; i < cs.size(); ++i) {
      // Past the punch (by up to 4% of the depth) over the first nodes, open further out.
      u[cs[i].equation] = cs[i].surface_height - alpha - (i < 8 ? 0.02 * (1.0 + unit(random)) : -0.2 * double(i - 6)) * alpha;
      if (cs[i].tangential_equation < 0) continue;
      u[cs[i].tangential_equation] = 0.02 * alpha * unit(random);
      // Every third node starts where it is (a small slip, stick); the others far from it (slip).
      committed[cs[i].tangential_equation] = u[cs[i].tangential_equation] - (i % 3 == 0 ? 1e-6 : 0.5) * alpha * unit(random);
    }
    contact.hold_committed_state(committed.data());
    std::vector<double> values(static_cast<std::size_t>(pattern.nonzeros())), f(n), f_plus(n), f_minus(n), jd(n), bulk(n);
    equations.residual(u.data(), alpha, f.data());
    equations.jacobian(u.data(), alpha, values.data());
    k.internal_force(u.data(), bulk.data());
    int branches[4] = {0, 0, 0, 0};
    for (std::size_t i = 0; i < cs.size(); ++i)
      if (cs[i].tangential_equation >= 0)
        ++branches[static_cast<int>(contact.branch(i, u.data(), alpha, bulk[cs[i].equation], bulk[cs[i].tangential_equation]))];
    EXPECT_GT(branches[1], 0) << "no node sticks";
    EXPECT_GT(branches[2] + branches[3], 0) << "no node slips";
    EXPECT_GT(branches[0], 0) << "no node is open";

    std::vector<double> direction(n, 0.0);
    for (std::size_t i = 0; i < n; ++i) direction[i] = 1e-6 * alpha * unit(random);
    pattern.multiply(values, direction.data(), jd.data());
    const double step = 1e-3;
    std::vector<double> plus = u, minus = u;
    for (std::size_t i = 0; i < n; ++i) {
      plus[i] += step * direction[i];
      minus[i] -= step * direction[i];
    }
    equations.residual(plus.data(), alpha, f_plus.data());
    equations.residual(minus.data(), alpha, f_minus.data());
    double scale = 0.0;
    for (std::size_t i = 0; i < n; ++i) scale = std::max(scale, std::abs(jd[i]));
    for (const auto& c : cs)
      for (int equation : {c.equation, c.tangential_equation}) {
        if (equation < 0) continue;
        EXPECT_NEAR((f_plus[equation] - f_minus[equation]) / (2.0 * step), jd[equation], 1e-6 * scale)
            << "candidate at x = " << c.x << (equation == c.equation ? ", vertical row" : ", horizontal row");
      }
    // The rows' derivative in the depth at fixed u (a slip row's cone moves with the penetration)
    // against central differences.
    std::vector<double> row_force, at_plus = bulk, at_minus = bulk, d_alpha(n, 0.0);
    for (int row : contact.row_equations()) row_force.push_back(bulk[static_cast<std::size_t>(row)]);
    const double h = 1e-6 * alpha;
    contact.write_residual_rows(u.data(), alpha + h, row_force.data(), at_plus.data());
    contact.write_residual_rows(u.data(), alpha - h, row_force.data(), at_minus.data());
    contact.write_depth_derivative_rows(u.data(), alpha, row_force.data(), d_alpha.data());
    for (int row : contact.row_equations()) {
      const auto i = static_cast<std::size_t>(row);
      EXPECT_NEAR((at_plus[i] - at_minus[i]) / (2.0 * h), d_alpha[i], 1e-6 * std::abs(d_alpha[i]) + 1e-9 * cs.back().scale)
          << "depth row " << row;
    }
  }
}

// F^t is continuous across stick, slip and the normal switch (Alart and Curnier's augmented normal
// force vanishes where node-to-rigid's normal row opens): along a line through states on every
// branch, the largest change of a row between neighbouring samples halves with the spacing, as
// it does for a continuous function and does not for a jump.
TEST(CoulombFriction, TheTangentialRowsAreContinuousAcrossEveryBranch) {
  const LoadCase lc = shipped_case("axisymmetric/elastic_sphere.toml", {"mesh.contact_nodes=8"});
  const Mesh mesh = Mesh::from_plan(lc, plan_mesh(lc));
  const StiffnessPattern pattern(mesh);
  ElasticStiffness k(mesh, ElasticMaterial{lc.material.E, lc.material.nu}, pattern);
  CoulombNodeToRigidContact contact(mesh, make_punch(lc.punch), pattern, k.values(), 0.3);
  ContactEquations equations(pattern, k, k, contact);
  const auto& cs = contact.candidates();
  const double alpha = 0.5 * lc.max_depth();
  const auto n = static_cast<std::size_t>(mesh.equations());
  std::mt19937 random(3);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<double> u(n, 0.0), direction(n, 0.0), committed(n, 0.0);
  for (std::size_t i = 0; i < cs.size(); ++i) {
    u[cs[i].equation] = cs[i].surface_height - alpha;
    direction[cs[i].equation] = 0.3 * alpha * unit(random);
    if (cs[i].tangential_equation < 0) continue;
    direction[cs[i].tangential_equation] = 0.6 * alpha * unit(random);
  }
  contact.hold_committed_state(committed.data());
  std::vector<double> f(n), x(n);
  // Largest change of each tangential row between neighbouring samples of u + t d, t in [-1, 1].
  const auto largest_steps = [&](int samples, std::vector<std::uint64_t>& signatures) {
    std::vector<double> largest(cs.size(), 0.0), last(cs.size(), 0.0);
    std::vector<double> values(static_cast<std::size_t>(pattern.nonzeros()));
    for (int i = 0; i <= samples; ++i) {
      const double t = -1.0 + 2.0 * i / samples;
      for (std::size_t j = 0; j < n; ++j) x[j] = u[j] + t * direction[j];
      equations.residual(x.data(), alpha, f.data());
      equations.jacobian(x.data(), alpha, values.data());
      signatures.push_back(equations.active_set_signature());
      for (std::size_t c = 0; c < cs.size(); ++c) {
        if (cs[c].tangential_equation < 0) continue;
        const double value = f[cs[c].tangential_equation];
        if (i > 0) largest[c] = std::max(largest[c], std::abs(value - last[c]));
        last[c] = value;
      }
    }
    return largest;
  };
  std::vector<std::uint64_t> coarse_signatures, fine_signatures;
  const std::vector<double> coarse = largest_steps(1000, coarse_signatures), fine = largest_steps(2000, fine_signatures);
  std::sort(fine_signatures.begin(), fine_signatures.end());
  const auto branch_sets = std::unique(fine_signatures.begin(), fine_signatures.end()) - fine_signatures.begin();
  EXPECT_GE(branch_sets, 5) << "the line crosses too few branches to show anything";
  for (std::size_t c = 0; c < cs.size(); ++c)
    if (cs[c].tangential_equation >= 0 && coarse[c] > 0.0) {
      EXPECT_LT(fine[c] / coarse[c], 0.6) << "candidate at x = " << cs[c].x;
    }
}

// Mossakovskii (1954; Spence 1968) for a rigid flat punch bonded to an elastic half-space: at the
// same depth, P_sticking / P_frictionless = (1 - nu) ln(3 - 4 nu) / (1 - 2 nu) (Popov, Hess and
// Willert, Handbook of Contact Mechanics, 2019, eq. 2.141): 1.0986 at nu = 0, 1.0513 at 0.2,
// 1.0183 at 0.35.  On the same mesh both forces carry the same discretization error of the rim's
// singularity, which the ratio cancels to well under the 2-10% effect measured.
TEST(CoulombFriction, AStickingFlatPunchCarriesMossakovskiisForce) {
  for (double nu : {0.0, 0.2, 0.35}) {
    SCOPED_TRACE(nu);
    LoadCase lc = shipped_case("axisymmetric/flat_punch.toml");
    lc.material.nu = nu;
    const double ratio = final_force(with_friction(lc, sticking)) / final_force(lc);
    const double mossakovskii = (1.0 - nu) * std::log(3.0 - 4.0 * nu) / (1.0 - 2.0 * nu);
    std::printf("nu = %.2f: P_sticking / P_frictionless = %.5f, Mossakovskii %.5f\n", nu, ratio, mossakovskii);
    EXPECT_NEAR(ratio / mossakovskii, 1.0, 2e-3);
  }
}

// Friction opposes the inward slip of the surface under the punch: the force grows with mu from
// the frictionless punch's to the sticking one's, which a large enough mu reaches.
TEST(CoulombFriction, FrictionRaisesTheFlatPunchsForceMonotonicallyUpToSticking) {
  LoadCase lc = shipped_case("axisymmetric/flat_punch.toml");
  const double frictionless = final_force(lc), stuck = final_force(with_friction(lc, sticking));
  double previous = frictionless;
  for (double mu : {0.02, 0.05, 0.1, 0.2}) {
    const double p = final_force(with_friction(lc, mu));
    std::printf("mu = %.2f: P / P_frictionless = %.5f\n", mu, p / frictionless);
    EXPECT_GT(p, previous) << "mu = " << mu;
    EXPECT_LT(p, stuck) << "mu = " << mu;
    previous = p;
  }
  EXPECT_EQ(final_force(with_friction(lc, 5.0)), stuck);
}

// Spence (1975): under monotone loading of an elastic half-space by a sphere with finite friction
// the contact has a central stick zone c whose ratio to the contact radius a stays constant (the
// problem is self-similar).  Discretely c and a are known to a node: c/a at every increment past
// the first few lies within two node spacings of its value at the deepest point.
TEST(CoulombFriction, TheStickZoneOfAnElasticSphereIsSelfSimilar) {
  for (double mu : {0.1, 0.2, 0.3, 0.5}) {
    SCOPED_TRACE(mu);
    const LoadCase lc = with_friction(shipped_case("axisymmetric/elastic_sphere.toml", {"load.increments=20"}), mu);
    Simulation sim(lc);
    std::vector<double> ratios, spacings;
    sim.run([&](const IncrementRecord&) {
      const ContactResult c = sim.contact();
      const auto& cs = sim.contact_boundary().candidates();
      // The stick zone: contact nodes from the axis up to the first that slides.
      std::size_t k = 0;
      while (k < cs.size() && c.in_contact[k] && !c.sliding[k]) ++k;
      if (k < 2 || c.outermost < 4) return;
      ratios.push_back(cs[k - 1].x / c.half_width);
      spacings.push_back((cs[k].x - cs[k - 1].x) / c.half_width);
    });
    ASSERT_GE(ratios.size(), 10u);
    std::printf("mu = %.2f: c/a from %.3f to %.3f (deepest %.3f, node spacing %.3f a)\n", mu,
                *std::min_element(ratios.begin(), ratios.end()), *std::max_element(ratios.begin(), ratios.end()),
                ratios.back(), spacings.back());
    for (std::size_t i = ratios.size() / 2; i < ratios.size(); ++i)
      EXPECT_NEAR(ratios[i], ratios.back(), 2.0 * spacings[i]) << "increment " << i;
  }
}

// The unloading stiffness a frictional run reports is the slope of its own unloading.  Which
// nodes stick and which go on sliding as the punch withdraws is part of the solution (on the
// elastic sphere the inner slip zone goes on sliding inward while the edge sticks): the run's own
// first small unloading increment, on whatever branches it finds, has the reported slope.  A
// sticking flat punch unloads with Mossakovskii's stiffness.
TEST(CoulombFriction, TheUnloadingStiffnessIsTheSlopeOfTheRunsOwnUnloading) {
  for (double mu : {0.1, 0.3}) {
    SCOPED_TRACE(mu);
    LoadCase lc = with_friction(shipped_case("axisymmetric/elastic_sphere.toml"), mu);
    const double alpha = lc.max_depth(), delta = 1e-5 * alpha;
    lc.load.path = {0.0, alpha, alpha - delta};
    lc.load.segment_increments = {10, 1};
    lc.load.increments = 11;
    validate(lc);
    Simulation sim(lc);
    double peak_force = 0.0, S = 0.0;
    sim.run([&](const IncrementRecord& r) {
      if (r.step != 10) return;
      peak_force = r.force;
      S = sim.unloading_stiffness();
    });
    const double slope = (peak_force - sim.contact().force) / delta;
    std::printf("mu = %g: S = %.8g N/m, the first unloading increment's slope %.8g N/m\n", mu, S, slope);
    EXPECT_NEAR(S / slope, 1.0, 1e-5);
  }
  LoadCase flat = shipped_case("axisymmetric/flat_punch.toml");
  const double nu = flat.material.nu, mossakovskii = (1.0 - nu) * std::log(3.0 - 4.0 * nu) / (1.0 - 2.0 * nu);
  Simulation frictionless(flat), stuck(with_friction(flat, sticking));
  frictionless.run();
  stuck.run();
  EXPECT_NEAR(stuck.unloading_stiffness() / frictionless.unloading_stiffness() / mossakovskii, 1.0, 2e-3);
}

// The condensed near field keeps the candidates' horizontal unknowns and solves the whole mesh's
// frictional equations, through plasticity and unloading, in both kinematics.
TEST(CoulombFriction, TheCondensedNearFieldGivesTheWholeMeshsCurve) {
  for (const char* name : {"load_unload.toml", "axisymmetric/steel_sphere.toml", "axisymmetric/elastic_sphere.toml"}) {
    SCOPED_TRACE(name);
    std::vector<double> forces[2];
    for (int whole = 0; whole < 2; ++whole) {
      const LoadCase lc = with_friction(
          shipped_case(name, {"mesh.contact_nodes=8", whole ? "solver.far_field=\"full\"" : "solver.far_field=\"condense\""}),
          0.2);
      Simulation sim(lc);
      sim.run([&](const IncrementRecord& r) { forces[whole].push_back(r.force); });
    }
    ASSERT_EQ(forces[0].size(), forces[1].size());
    const double peak = *std::max_element(forces[1].begin(), forces[1].end());
    for (std::size_t k = 0; k < forces[0].size(); ++k) EXPECT_NEAR(forces[0][k], forces[1][k], 1e-8 * peak) << "row " << k;
  }
}

// A frictional run restored from a state taken mid-path (through the unloading) continues bit for
// bit: the slip history is the committed displacement the state holds.
TEST(CoulombFriction, ARestoredStateContinuesBitForBit) {
  const LoadCase lc = with_friction(shipped_case("axisymmetric/steel_sphere.toml", {"mesh.contact_nodes=8"}), 0.15);
  Simulation run(lc);
  std::vector<IncrementRecord> rows;
  std::vector<SimulationState> states;
  run.run([&](const IncrementRecord& r) {
    rows.push_back(r);
    states.push_back(run.state());
  });
  for (std::size_t from : {rows.size() / 2, rows.size() - 4}) {
    Simulation resumed(lc, run.plan().contact_half_width_estimate, states[from].near_field);
    resumed.restore(states[from]);
    EXPECT_LE(resumed.equilibrium_residual(), lc.solver.tolerance);
    std::vector<IncrementRecord> rest;
    resumed.run([&](const IncrementRecord& r) { rest.push_back(r); });
    ASSERT_EQ(rest.size() + from + 1, rows.size());
    for (std::size_t k = 0; k < rest.size(); ++k) EXPECT_EQ(rest[k].force, rows[from + 1 + k].force) << "row " << from + 1 + k;
    EXPECT_EQ(resumed.displacement(), run.displacement());
  }
}

// Friction in a plastic specimen, both kinematics and both laws: the runs converge through
// unloading, contact nodes slide, the force stays within 10% of the frictionless one, and the
// final state's equilibrium holds to the tolerance (what a resume checks).  (Within the model's
// vertical gap friction's effect on the force is small and of either sign: -1% on the J2
// Berkovich cone at its default mesh, docs/MODEL.md §3.3.)
TEST(CoulombFriction, PlasticSpecimensIndentWithFrictionInBothKinematics) {
  for (const char* name : {"load_unload.toml", "deep_plastic.toml", "axisymmetric/berkovich_cone.toml",
                           "axisymmetric/steel_sphere.toml"}) {
    SCOPED_TRACE(name);
    const LoadCase lc = shipped_case(name, {"mesh.contact_nodes=10"});
    Simulation frictionless(lc), frictional(with_friction(lc, 0.2));
    double peak[2] = {0.0, 0.0};
    frictionless.run([&](const IncrementRecord& r) { peak[0] = std::max(peak[0], r.force); });
    int slid = 0;
    frictional.run([&](const IncrementRecord& r) {
      peak[1] = std::max(peak[1], r.force);
      const ContactResult c = frictional.contact();
      slid += static_cast<int>(std::count(c.sliding.begin(), c.sliding.end(), char{1}));
    });
    std::printf("%s: peak P with mu = 0.2 over frictionless %.5f\n", name, peak[1] / peak[0]);
    EXPECT_NEAR(peak[1] / peak[0], 1.0, 0.1);
    EXPECT_LE(frictional.equilibrium_residual(), lc.solver.tolerance);
    // Friction acts where the contact slides: the run slid somewhere on the way.
    EXPECT_GT(slid, 0) << "no contact node slid";
  }
}

// Sticking rows pin unknowns, which CHOLMOD's elimination takes: both solvers give one curve.
// Sliding rows are unsymmetric: a case asking CHOLMOD for them is refused, naming the keys.  A
// sticking node cannot release its tangential force as it separates: unloading is refused.
TEST(CoulombFriction, StickingRunsOnBothSolversAndSlidingOnlyOnKlu) {
  LoadCase lc = shipped_case("axisymmetric/steel_sphere.toml", {"mesh.contact_nodes=8"});
  lc.contact.friction = sticking;
  expect_refused([&] { validate(lc); }, "contact.friction", "sticking friction on an unloading path");
  lc.load.path = {0.0, 10e-6};
  lc.load.segment_increments.clear();
  lc.load.increments = 20;
  validate(lc);
  std::vector<double> forces[2];
  for (int cholmod = 0; cholmod < 2; ++cholmod) {
    lc.solver.linear = cholmod ? LinearSolverChoice::cholmod : LinearSolverChoice::klu;
    Simulation sim(lc);
    sim.run([&](const IncrementRecord& r) { forces[cholmod].push_back(r.force); });
  }
  ASSERT_EQ(forces[0].size(), forces[1].size());
  for (std::size_t k = 0; k < forces[0].size(); ++k) EXPECT_NEAR(forces[0][k], forces[1][k], 1e-8 * forces[0][k] + 1e-12);
  lc.contact.friction = 0.3;
  expect_refused([&] { validate(lc); }, "solver.linear", "CHOLMOD with sliding friction");
  lc.solver.linear = LinearSolverChoice::automatic;
  lc.contact.discretization = ContactDiscretizationChoice::integrated_gap;
  expect_refused([&] { validate(lc); }, "contact.friction", "friction with the integrated gap");
}

// The key reads a coefficient or the word "sticking", and writes it back as read.
TEST(CoulombFriction, TheKeyReadsACoefficientOrSticking) {
  const auto read = [](const std::string& value) {
    return parse_load_case(testing::small_case_toml + "[contact]\nfriction = " + value + "\n", "case.toml");
  };
  EXPECT_EQ(read("0.25").contact.friction, 0.25);
  EXPECT_TRUE(std::isinf(read("\"sticking\"").contact.friction));
  EXPECT_EQ(parse_load_case(to_toml(read("\"sticking\"")), "case.toml").contact.friction, read("\"sticking\"").contact.friction);
  EXPECT_EQ(parse_load_case(to_toml(read("0.25")), "case.toml").contact.friction, 0.25);
  EXPECT_EQ(read("0").contact.friction, 0.0);
  for (const char* bad : {"-0.1", "\"stuck\"", "inf", "nan"}) {
    SCOPED_TRACE(bad);
    expect_refused([&] { read(bad); }, "contact.friction", bad);
  }
}

// Friction's slip history depends on the material parameters and its derivative is not carried:
// the forward sensitivities say so (the fit then differentiates by finite differences), where the
// same frictionless Ilyushin run has them.
TEST(CoulombFriction, ForwardSensitivitiesAreRefusedForAHistoryTheyDoNotCarry) {
  const LoadCase lc = testing::small_sphere_case(SceneKind::axisymmetric, MaterialModel::ilyushin, HardeningLaw::power);
  Simulation frictionless(lc), frictional(with_friction(lc, 0.2));
  frictionless.run();
  frictional.run();
  EXPECT_TRUE(frictionless.force_sensitivities({MaterialParameter::e0}).has_value());
  EXPECT_FALSE(frictional.force_sensitivities({MaterialParameter::e0}).has_value());
}

}  // namespace
}  // namespace indentsim
