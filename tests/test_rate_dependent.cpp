// Rate-dependent J2 (docs/MODEL.md §13.3): Perzyna's overstress and Norton's power-law creep,
// integrated by backward Euler as a radial return.  At a material point: a creep test at constant
// stress flows at the law's rate, a relaxation test at fixed strain follows its closed form as the
// time step shrinks, the consistent tangent agrees with central differences, and the rate-
// independent and elastic responses are the limits of a vanishing rate.  In indentation: a flat
// punch held at constant force on a linear viscous half-space creeps at the rate Sneddon's
// incompressible solution gives, a vanishing rate gives the rate-independent curves in both
// scenes, and a creeping force-controlled run killed in its hold resumes bit for bit.
#include <cmath>
#include <csignal>
#include <functional>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <Eigen/LU>
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "indentsim/base/error.hpp"
#include "indentsim/fitting/forward_model.hpp"
#include "indentsim/materials/flow_rule.hpp"
#include "indentsim/materials/hardening.hpp"
#include "indentsim/materials/material.hpp"
#include "indentsim/simulation/load_stepping.hpp"
#include "indentsim/simulation/run_configuration.hpp"
#include "indentsim/simulation/simulation.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using namespace indentsim;
using indentsim::testing::refused_key;

namespace {

const ElasticMaterial steel{200e9, 0.3};

/// A material point under mixed control: the components `held` keep the strain they have in
/// `strain`, the others are solved (Newton with the law's consistent tangent) so that their stress
/// is `target`'s.  Returns the response; `strain` becomes the solution.
J2Response drive(const J2Law& law, const J2State& old, double time_step, const VoigtVector& target,
                 const std::array<bool, 4>& held, VoigtVector& strain, int* iterations = nullptr) {
  std::vector<int> free;
  for (int i = 0; i < 4; ++i)
    if (!held[i]) free.push_back(i);
  const auto n = static_cast<Eigen::Index>(free.size());
  J2Response r = law.respond(strain, old, time_step);
  for (int k = 0; k < 50; ++k) {
    Eigen::VectorXd residual(n);
    Eigen::MatrixXd jacobian(n, n);
    for (Eigen::Index a = 0; a < n; ++a) {
      residual[a] = r.stress[free[a]] - target[free[a]];
      for (Eigen::Index b = 0; b < n; ++b) jacobian(a, b) = r.tangent(free[a], free[b]);
    }
    if (residual.norm() <= 1e-13 * std::max(target.norm(), r.stress.norm())) {
      if (iterations) *iterations = k;
      return r;
    }
    const Eigen::VectorXd change = jacobian.lu().solve(residual);
    for (Eigen::Index a = 0; a < n; ++a) strain[free[a]] -= change[a];
    r = law.respond(strain, old, time_step);
  }
  ADD_FAILURE() << "the mixed-control Newton did not converge";
  return r;
}

// Uniaxial stress along 2: s22 given, s11 = s33 = s12 = 0.
constexpr std::array<bool, 4> stress_controlled{false, false, false, false};
// Uniaxial relaxation: e22 held, the other stresses zero.
constexpr std::array<bool, 4> axial_strain_held{false, true, false, false};

std::shared_ptr<const HardeningCurve> perfectly_plastic(double yield) {
  return std::make_shared<PowerLawHardening>(yield, steel.E, 0.0);
}

/// A creep test: the stress put on at once (the instantaneous, elastic response), then held over
/// `steps` steps of `dt`; the equivalent plastic strain and the axial strain after each step.
struct CreepStep {
  double plastic_strain_change = 0.0, axial_strain_change = 0.0, yield_after = 0.0;
  int newton_iterations = 0;
};
std::vector<CreepStep> creep_test(const J2Law& law, double stress, double dt, int steps) {
  const VoigtVector target(0.0, stress, 0.0, 0.0);
  VoigtVector strain(0.0, stress / steel.E, 0.0, 0.0);
  J2State state = drive(law, J2State{}, 0.0, target, stress_controlled, strain).state;
  std::vector<CreepStep> out;
  for (int k = 0; k < steps; ++k) {
    CreepStep s;
    const VoigtVector before = strain;
    const J2Response r = drive(law, state, dt, target, stress_controlled, strain, &s.newton_iterations);
    s.plastic_strain_change = r.state.equivalent_plastic_strain - state.equivalent_plastic_strain;
    s.axial_strain_change = strain[1] - before[1];
    state = r.state;
    out.push_back(s);
  }
  return out;
}

}  // namespace

// Backward Euler at constant stress is exact: each step flows dt A (sigma / sigma_ref)^m, seen in
// the equivalent plastic strain and in the axial strain alike (the elastic strain stays), and the
// consistent tangent makes the stress-controlled Newton converge in a few iterations.
TEST(RateDependentJ2, AUniaxialCreepTestAtConstantStressFlowsAtNortonsRate) {
  const double A = 1e-4, reference = 100e6, stress = 150e6, dt = 0.5;
  for (const double m : {1.0, 3.0, 5.0}) {
    SCOPED_TRACE(m);
    const J2Law law(steel, std::make_shared<NortonFlow>(A, reference, m));
    const double rate = A * std::pow(stress / reference, m);
    for (const CreepStep& s : creep_test(law, stress, dt, 10)) {
      EXPECT_NEAR(s.plastic_strain_change / dt, rate, 1e-8 * rate);
      EXPECT_NEAR(s.axial_strain_change / dt, rate, 1e-8 * rate);
      EXPECT_LE(s.newton_iterations, 6);
    }
  }
}

// Perzyna's rate depends on the overstress over the current yield stress: on a perfectly plastic
// curve it is constant, eps_p' = rate0 (sigma / sigma_y - 1)^m; on a hardening curve every step
// satisfies backward Euler's dgamma = dt rate0 (sigma / sigma_y(eps_p,n+1) - 1)^m, and the flow
// slows as the yield stress rises towards the applied stress.
TEST(RateDependentJ2, AUniaxialCreepTestAtConstantStressFlowsAtPerzynasRate) {
  const double rate0 = 1e-3, yield = 100e6, stress = 130e6, dt = 0.5;
  for (const double m : {1.0, 4.0}) {
    SCOPED_TRACE(m);
    const J2Law flat(steel, std::make_shared<PerzynaFlow>(perfectly_plastic(yield), rate0, m));
    const double rate = rate0 * std::pow(stress / yield - 1.0, m);
    for (const CreepStep& s : creep_test(flat, stress, dt, 10)) {
      EXPECT_NEAR(s.plastic_strain_change / dt, rate, 1e-8 * rate);
      EXPECT_NEAR(s.axial_strain_change / dt, rate, 1e-8 * rate);
    }
    const auto voce = std::make_shared<VoceHardening>(yield, 50e6, 20.0);
    const J2Law hardening(steel, std::make_shared<PerzynaFlow>(voce, rate0, m));
    double eps_p = 0.0, previous_rate = std::numeric_limits<double>::infinity();
    for (const CreepStep& s : creep_test(hardening, stress, dt, 20)) {
      eps_p += s.plastic_strain_change;
      const double implicit = dt * rate0 * std::pow(stress / voce->flow_stress(eps_p) - 1.0, m);
      EXPECT_NEAR(s.plastic_strain_change, implicit, 1e-8 * implicit);
      EXPECT_LT(s.plastic_strain_change / dt, previous_rate);
      previous_rate = s.plastic_strain_change / dt;
    }
  }
}

// Held at a fixed axial strain, the uniaxial stress relaxes as sigma' = -E A (sigma /
// sigma_ref)^m: sigma = sigma0 exp(-E A t / sigma_ref) for m = 1, sigma^(1-m) = sigma0^(1-m) +
// (m - 1) E A t / sigma_ref^m otherwise.  Backward Euler converges to it at first order: halving
// the step halves the error.
TEST(RateDependentJ2, AStressRelaxationAtFixedStrainFollowsItsClosedFormAtFirstOrder) {
  const double A = 1e-4, reference = 100e6, sigma0 = 200e6;
  for (const double m : {1.0, 3.0}) {
    SCOPED_TRACE(m);
    const J2Law law(steel, std::make_shared<NortonFlow>(A, reference, m));
    const double duration = m == 1.0 ? 5.0 : 1.0;
    const double closed = m == 1.0 ? sigma0 * std::exp(-steel.E * A * duration / reference)
                                   : std::pow(std::pow(sigma0, 1.0 - m) + (m - 1.0) * steel.E * A * duration /
                                                                              std::pow(reference, m),
                                              1.0 / (1.0 - m));
    std::vector<double> error;
    for (const int steps : {1000, 2000, 4000}) {
      VoigtVector strain(0.0, sigma0 / steel.E, 0.0, 0.0);
      J2State state = drive(law, J2State{}, 0.0, VoigtVector(0.0, sigma0, 0.0, 0.0), stress_controlled, strain).state;
      double sigma = 0.0;
      for (int k = 0; k < steps; ++k) {
        const J2Response r = drive(law, state, duration / steps, VoigtVector::Zero(), axial_strain_held, strain);
        state = r.state;
        sigma = r.stress[1];
      }
      error.push_back(sigma / closed - 1.0);
    }
    EXPECT_LT(std::abs(error[2]), 2e-4) << error[2];
    EXPECT_NEAR(error[0] / error[1], 2.0, 0.05);
    EXPECT_NEAR(error[1] / error[2], 2.0, 0.05);
  }
}

TEST(RateDependentJ2, TheConsistentTangentMatchesCentralDifferences) {
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> component(-1.0, 1.0);
  const auto voce = std::make_shared<VoceHardening>(300e6, 200e6, 10.0);
  const std::vector<std::shared_ptr<const FlowRule>> rules{
      std::make_shared<PerzynaFlow>(voce, 1e-2, 1.0), std::make_shared<PerzynaFlow>(voce, 1e-2, 4.0),
      std::make_shared<NortonFlow>(1e-4, 300e6, 1.0), std::make_shared<NortonFlow>(1e-4, 300e6, 5.0)};
  const double yield_strain = 300e6 / steel.E;
  for (const auto& rule : rules) {
    const J2Law law(steel, rule);
    int plastic = 0;
    for (int trial = 0; trial < 30; ++trial) {
      const auto random_strain = [&](double size) {
        VoigtVector e(component(rng), component(rng), component(rng), component(rng));
        return VoigtVector(e * size / e.norm());
      };
      const J2State old = law.respond(random_strain(4 * yield_strain), J2State{}, 1.0).state;
      for (const double dt : {0.01, 1.0, 100.0}) {
        const VoigtVector strain = random_strain(4 * yield_strain) + random_strain(2 * yield_strain);
        const J2Response r = law.respond(strain, old, dt);
        plastic += r.plastic ? 1 : 0;
        const ConstitutiveMatrix fd = indentsim::testing::finite_difference_tangent(
            [&](const VoigtVector& e) { return law.respond(e, old, dt).stress; }, strain);
        EXPECT_LE((r.tangent - fd).cwiseAbs().maxCoeff(), 1e-6 * r.tangent.cwiseAbs().maxCoeff())
            << "dt " << dt << " plastic " << r.plastic << "\n" << r.tangent << "\n" << fd;
      }
    }
    // Norton's creep flows at any stress; Perzyna's beyond the yield surface, most of these steps.
    EXPECT_GE(plastic, rule->initial_yield() > 0.0 ? 45 : 90);
  }
}

// Perzyna with rate0 -> infinity is the rate-independent return on its curve; Norton with A -> 0
// is elasticity; and a step of no duration (the instantaneous response) flows nothing.
TEST(RateDependentJ2, AVanishingRateGivesTheRateIndependentOrTheElasticResponse) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> component(-1.0, 1.0);
  const auto voce = std::make_shared<VoceHardening>(300e6, 200e6, 10.0);
  const J2Law rate_independent(steel, voce);
  const J2Law fast(steel, std::make_shared<PerzynaFlow>(voce, 1e12, 1.0));
  const J2Law slow(steel, std::make_shared<NortonFlow>(1e-30, 300e6, 3.0));
  const J2Law elastic(steel, perfectly_plastic(1e30));
  for (int trial = 0; trial < 20; ++trial) {
    const VoigtVector strain = VoigtVector(component(rng), component(rng), component(rng), component(rng)) * 5e-3;
    const J2Response a = fast.respond(strain, J2State{}, 1.0), b = rate_independent.respond(strain, J2State{});
    ASSERT_TRUE(b.plastic);
    EXPECT_LE((a.stress - b.stress).norm(), 1e-9 * b.stress.norm());
    const J2Response c = slow.respond(strain, J2State{}, 1.0), d = elastic.respond(strain, J2State{});
    EXPECT_LE((c.stress - d.stress).norm(), 1e-12 * d.stress.norm());
    for (const J2Law* law : {&fast, &slow}) EXPECT_FALSE(law->respond(strain, J2State{}, 0.0).plastic);
  }
}

// ---------------------------------------------------------------------------------------------
namespace {

/// The shipped flat punch (R = 50 um, E = 70 GPa, nu = 0.2, a 5 mm cylinder) on a Norton
/// specimen, pressed to `force` in 0.1 s under force control and held to `hold_end`.
LoadCase creeping_flat_punch(double A, double reference, double m, double force, double hold_end,
                             const std::vector<std::string>& more = {}) {
  std::vector<std::string> overrides{"material.model=\"j2\"",
                                     "material.rate=\"norton\"",
                                     fmt::format("material.creep_coefficient={}", A),
                                     fmt::format("material.reference_stress={}", reference),
                                     fmt::format("material.rate_exponent={}", m),
                                     "load.control=\"force\"",
                                     fmt::format("load.path=[0, {}, {}]", force, force),
                                     fmt::format("load.times=[0, 0.1, {}]", hold_end),
                                     fmt::format("load.increments=[4, {}]", static_cast<int>(hold_end))};
  overrides.insert(overrides.end(), more.begin(), more.end());
  return indentsim::testing::shipped_case("axisymmetric/flat_punch.toml", overrides);
}

struct TimedRow {
  double time, alpha, force;
};
std::vector<TimedRow> run_timed(const LoadCase& lc) {
  const std::vector<double> times = plan_times(lc.load);
  std::vector<TimedRow> rows;
  Simulation sim(lc);
  sim.run([&](const IncrementRecord& r) { rows.push_back({times.at(static_cast<std::size_t>(r.step)), r.alpha, r.force}); });
  return rows;
}

double peak_force(const std::vector<TimedRow>& rows) {
  double peak = 0.0;
  for (const TimedRow& r : rows) peak = std::max(peak, r.force);
  return peak;
}

/// The depth rate over the last quarter of the hold.
double final_creep_rate(const std::vector<TimedRow>& rows) {
  const TimedRow& end = rows.back();
  const TimedRow& quarter = rows[rows.size() - 1 - (rows.size() - 5) / 4];
  return (end.alpha - quarter.alpha) / (end.time - quarter.time);
}

}  // namespace

// A flat punch of radius a held at force P on a Norton half-space with m = 1: the viscous flow is
// Stokes flow of viscosity eta = sigma_ref / (3 A), the incompressible elastic problem with shear
// modulus eta (the correspondence principle), so Sneddon's P = 8 G a h gives the steady rate
// h' = P / (8 eta a) = 3 A P / (8 a sigma_ref) (Hill 1992; Bower, Fleck, Needleman and Ogbonna
// 1993, m = 1).  The elastic, compressible part settles within a few relaxation times
// sigma_ref / (3 A G) ~ 1 s.  On the same mesh the correspondence is exact but for nu = 0.4999 in
// place of 1/2: the rate is P / (S eta / G) with S the incompressible elastic stiffness the mesh
// gives, to 1e-3.  Against Sneddon the rate carries that mesh's own error (the rim singularity, 20
// contact nodes, a 5 mm cylinder: 1.7% stiff).  Under finite strain the small depth changes nothing.
TEST(RateDependentIndentation, AFlatPunchHeldOnALinearViscousHalfSpaceCreepsAtSneddonsRate) {
  const double A = 0.01, reference = 1e9, force = 2.0, a = 50e-6, eta = reference / (3.0 * A);
  const double sneddon_rate = force / (8.0 * eta * a);
  const std::vector<TimedRow> rows = run_timed(creeping_flat_punch(A, reference, 1.0, force, 16.0));
  for (std::size_t k = 1; k < rows.size(); ++k) EXPECT_NEAR(rows[k].force, k >= 4 ? force : force * k / 4.0, 1e-9 * force);
  for (std::size_t k = 5; k < rows.size(); ++k) EXPECT_GT(rows[k].alpha, rows[k - 1].alpha) << k;  // creeps
  const double rate = final_creep_rate(rows);
  // The incompressible elastic stiffness of the same mesh (B-bar, as the creeping run's).
  const LoadCase elastic =
      indentsim::testing::shipped_case("axisymmetric/flat_punch.toml", {"material.nu=0.4999", "mesh.element=\"bbar\""});
  Simulation sim(elastic);
  std::vector<IncrementRecord> elastic_rows;
  sim.run([&](const IncrementRecord& r) { elastic_rows.push_back(r); });
  const double S = elastic_rows.back().force / elastic_rows.back().alpha;
  const double G = elastic.material.E / (2.0 * (1.0 + elastic.material.nu));
  const double mesh_rate = force / (S * eta / G);
  EXPECT_NEAR(rate / mesh_rate, 1.0, 1e-3) << "rate " << rate << " on the mesh " << mesh_rate;
  const double mesh_error = S / (2.0 * indentsim::testing::contact_modulus(elastic) * a) - 1.0;
  EXPECT_NEAR(rate / sneddon_rate, 1.0, std::abs(mesh_error) + 2e-3)
      << "rate " << rate << " Sneddon " << sneddon_rate << " mesh error " << mesh_error;
  // The same hold in finite strain (h / a < 5%): the rate moves by less than a percent.
  const std::vector<TimedRow> finite =
      run_timed(creeping_flat_punch(A, reference, 1.0, force, 16.0, {"geometry.strain=\"finite\""}));
  EXPECT_NEAR(final_creep_rate(finite) / rate, 1.0, 0.01);
}

// The similarity solution of a flat punch on a power-law creeping half-space (Hill 1992; Bower,
// Fleck, Needleman and Ogbonna 1993): the contact radius a is fixed, so the steady state is
// h' / (a eps0') = f(m) (P / (pi a^2 sigma_ref))^m -- the steady punching rate goes as the m-th power
// of the load.  It holds on the mesh as well: at steady state the elastic strain is constant,
// equilibrium is linear in the stress and the creep rate homogeneous of degree m in it, so the
// discrete velocities scale as P^m exactly; what is measured is how far the holds have reached the
// steady state (A = 100 /s: the far field relaxes within the 10 s hold).  f(1) = 3 pi / 8 is
// Sneddon's (the test above); f(m) for m > 1 is the paper's table, not checked here.
TEST(RateDependentIndentation, AFlatPunchsSteadyCreepRateGoesAsTheMthPowerOfTheLoad) {
  const double A = 100.0, reference = 1e9, m = 3.0, a = 50e-6;
  const auto steady_rate = [&](double force) {
    LoadCase lc = creeping_flat_punch(A, reference, m, force, 10.0);
    lc.load.times = {0.0, 0.001, 10.0};
    lc.load.segment_increments = {4, 30};
    lc.load.increments = lc.load.total_increments();
    const std::vector<TimedRow> rows = run_timed(lc);
    const std::size_t n = rows.size();
    return (rows[n - 1].alpha - rows[n - 2].alpha) / (rows[n - 1].time - rows[n - 2].time);
  };
  const double low = steady_rate(2.0), high = steady_rate(3.0);
  const double exponent = std::log(high / low) / std::log(1.5);
  EXPECT_NEAR(exponent / m, 1.0, 2e-3) << "d ln h' / d ln P = " << exponent;
  const double f = low / (a * A) / std::pow(2.0 / (M_PI * a * a * reference), m);
  RecordProperty("f_of_m3", fmt::format("{:.4g}", f));
  std::printf("flat punch, m = 3: d ln h'/d ln P = %.5f, f(3) = %.4g on this mesh\n", exponent, f);
}

// Under force control a creeping specimen is deepest at the end of the hold, not where the force is
// first reached: the depth pilot follows the hold (MODEL.md §13.1), so the mesh planned from its
// estimate holds the contact to the end.  Without the creep pilot the estimate was the depth at the
// start of the hold, 57% of the final one here.
TEST(RateDependentIndentation, TheDepthPilotOfACreepingHoldReachesTheEndOfTheHold) {
  const LoadCase lc = indentsim::testing::shipped_case(
      "axisymmetric/berkovich_creep_hold.toml",
      {"material.rate_exponent=3", "load.path=[0, 5e-3, 5e-3]", "load.times=[0, 1, 21]", "load.increments=[6, 10]",
       "mesh.contact_nodes=12"});
  const LoadCase estimated = with_depth_estimate(lc);
  ASSERT_TRUE(estimated.load.depth_estimate);
  Simulation sim(estimated);
  double start_of_hold = 0.0, deepest = 0.0;
  sim.run([&](const IncrementRecord& r) {
    if (r.step == 6) start_of_hold = r.alpha;
    deepest = std::max(deepest, r.alpha);
  });
  EXPECT_GT(deepest, 1.5 * start_of_hold);  // the hold creeps
  EXPECT_NEAR(*estimated.load.depth_estimate / deepest, 1.0, 0.05)
      << "estimate " << *estimated.load.depth_estimate << " deepest " << deepest;
}

// Held at a fixed depth instead, the same specimen relaxes: the force falls through the hold.
TEST(RateDependentIndentation, AHoldAtFixedDepthRelaxesTheForce) {
  const LoadCase lc = indentsim::testing::shipped_case(
      "axisymmetric/flat_punch.toml",
      {"material.model=\"j2\"", "material.rate=\"norton\"", "material.creep_coefficient=0.01",
       "material.reference_stress=1e9", "material.rate_exponent=1", "load.path=[0, 0.5e-6, 0.5e-6]",
       "load.times=[0, 0.1, 5]", "load.increments=[4, 10]"});
  const std::vector<TimedRow> rows = run_timed(lc);
  ASSERT_EQ(rows.size(), 15u);
  for (std::size_t k = 5; k < rows.size(); ++k) {
    EXPECT_EQ(rows[k].alpha, 0.5e-6);
    EXPECT_LT(rows[k].force, rows[k - 1].force) << k;
  }
  EXPECT_LT(rows.back().force, 0.9 * rows[4].force);
}

// rate0 -> infinity: Perzyna's curves are the rate-independent J2 ones, in both scenes; A -> 0:
// Norton's are the elastic ones.
TEST(RateDependentIndentation, AVanishingRateGivesTheRateIndependentCurvesInBothScenes) {
  for (const SceneKind scene : {SceneKind::plane_strain, SceneKind::axisymmetric}) {
    SCOPED_TRACE(to_string(scene));
    LoadCase j2 = indentsim::testing::small_sphere_case(scene, MaterialModel::j2, HardeningLaw::linear);
    j2.load.path = {0.0, 20e-6, 10e-6};
    j2.load.times = {0.0, 1.0, 1.5};
    j2.load.increments = 6;
    LoadCase fast = j2;
    fast.material.rate = RateLaw::perzyna;
    fast.material.reference_strain_rate = 1e12;
    fast.material.rate_exponent = 1.0;
    validate(fast);
    const std::vector<TimedRow> a = run_timed(j2), b = run_timed(fast);
    ASSERT_EQ(a.size(), b.size());
    // (The unloading may leave the imprint: forces relative to the peak's.)
    for (std::size_t k = 1; k < a.size(); ++k) EXPECT_NEAR(b[k].force, a[k].force, 1e-7 * peak_force(a)) << k;

    LoadCase elastic = indentsim::testing::small_sphere_case(scene, MaterialModel::elastic, HardeningLaw::linear);
    elastic.load = j2.load;
    LoadCase slow = j2;
    slow.material.rate = RateLaw::norton;
    slow.material.creep_coefficient = 1e-30;
    slow.material.reference_stress = 1e9;
    slow.material.rate_exponent = 2.0;
    validate(slow);
    const std::vector<TimedRow> c = run_timed(elastic), d = run_timed(slow);
    ASSERT_EQ(c.size(), d.size());
    for (std::size_t k = 1; k < c.size(); ++k) EXPECT_NEAR(d[k].force, c[k].force, 1e-7 * peak_force(c)) << k;
  }
}

TEST(RateDependentIndentation, RateKeysAreRefusedByNameWhereTheyCannotApply) {
  const std::string sphere = "axisymmetric/elastic_sphere.toml";
  const std::vector<std::string> timed{"load.path=[0, 1e-6, 1e-6]", "load.times=[0, 1, 2]"};
  const auto with = [&](std::vector<std::string> more) {
    more.insert(more.begin(), timed.begin(), timed.end());
    return more;
  };
  const std::vector<std::string> norton{"material.model=\"j2\"", "material.rate=\"norton\"",
                                        "material.creep_coefficient=1e-3", "material.reference_stress=1e8",
                                        "material.rate_exponent=3"};
  EXPECT_EQ(refused_key(sphere, with(norton)), "");
  EXPECT_EQ(refused_key(sphere, with({"material.rate=\"norton\"", "material.creep_coefficient=1e-3",
                                      "material.reference_stress=1e8", "material.rate_exponent=3"})),
            "material.rate");  // an elastic model
  EXPECT_EQ(refused_key(sphere, with({"material.model=\"j2\"", "material.rate=\"norton\"",
                                      "material.reference_stress=1e8", "material.rate_exponent=3"})),
            "material.creep_coefficient");
  EXPECT_EQ(refused_key(sphere, with({"material.model=\"j2\"", "material.rate=\"perzyna\"",
                                      "material.rate_exponent=3"})),
            "material.reference_strain_rate");
  std::vector<std::string> untimed = norton;
  untimed.push_back("load.path=[0, 1e-6]");
  EXPECT_EQ(refused_key(sphere, untimed), "material.rate");  // no load.times
  std::vector<std::string> odd = with(norton);
  odd.push_back("material.yield_stress=1e8");  // Norton has no yield surface
  EXPECT_EQ(refused_key(sphere, odd), "material.yield_stress");
  odd = with(norton);
  odd.push_back("material.reference_strain_rate=1");  // Perzyna's key
  EXPECT_EQ(refused_key(sphere, odd), "material.reference_strain_rate");
  odd = with(norton);
  odd.push_back("solver.far_field=\"condense\"");
  EXPECT_EQ(refused_key(sphere, odd), "solver.far_field");
  odd = with(norton);
  odd.push_back("material.rate_exponent=0.5");
  EXPECT_EQ(refused_key(sphere, odd), "material.rate_exponent");
  // The fit follows a creeping material in time only: a curve without time, or an imprint, is refused.
  for (const FitDataKind kind : {FitDataKind::force_depth_curve, FitDataKind::imprint_profile})
    try {
      refuse_unfittable_load(indentsim::testing::shipped_case(sphere, with(norton)), kind);
      FAIL() << "the fit took a rate-dependent material without its time history";
    } catch (const InputError& e) {
      EXPECT_EQ(e.key(), "material.rate");
    }
}

class RateDependentCli : public indentsim::testing::CliTest {};

// A flat punch on a Norton-creeping specimen (A = 0.01 /s, sigma_ref = 1 GPa, m = 3), loaded to 2 N
// in 0.1 s, held 9.9 s and unloaded to 0.2 N in 0.1 s under force control, on a coarse mesh.
const std::string creeping_flat_punch_flags =
      " --set mesh.contact_nodes=8 --set material.model=j2 --set material.rate=norton "
      "--set material.creep_coefficient=0.01 --set material.reference_stress=1e9 --set material.rate_exponent=3 "
      "--set load.control=force --set load.path=[0,2,2,0.2] --set load.times=[0,0.1,10,10.1] "
      "--set load.increments=[4,8,6]";

// A force-controlled creeping run killed in its hold resumes to the same curve, bit for bit: the
// history (plastic strain, equivalent plastic strain) is the checkpoint's, and each row's time
// and duration follow from the plan.  Its analysis finds the unloading where the force starts to
// fall (the run's branches are found in its controlled quantity) and the hold before it, with the
// creep depth the curve shows.
TEST_F(RateDependentCli, ACreepingForceControlledRunKilledInItsHoldResumesBitForBit) {
  const std::string source = indentsim::testing::source_path("loadcases/axisymmetric/flat_punch.toml");
  const std::string args = creeping_flat_punch_flags + " --set output.checkpoint_every=2";
  ASSERT_EQ(cli("run " + source + args + " --quiet --out " + (dir_ / "full").string()), 0) << err();
  EXPECT_EQ(err().find("only labels the increments"), std::string::npos) << err();
  const std::vector<std::vector<double>> rows = indentsim::testing::read_curve(dir_ / "full" / "curve.csv");
  ASSERT_EQ(rows.size(), 19u);
  EXPECT_GT(rows[12][2], rows[4][2]);  // the hold crept (column 2: alpha)
  ASSERT_EQ(cli("analyze " + (dir_ / "full").string()), 0) << err();
  const auto json = nlohmann::json::parse(indentsim::testing::slurp(dir_ / "full" / "analysis.json"));
  ASSERT_EQ(json["branches"].size(), 1u);
  const auto& hold = json["branches"][0]["hold"];
  ASSERT_TRUE(hold.is_object()) << json["branches"][0].dump();
  EXPECT_NEAR(hold["duration_s"].get<double>(), 9.9, 1e-9);
  EXPECT_NEAR(hold["creep_depth"].get<double>(), rows[12][2] - rows[4][2], 1e-12 * rows[12][2]);
  EXPECT_GT(hold["depth_rate_at_end"].get<double>(), 0.0);
  const std::string expected = indentsim::testing::curve_without_timing(dir_ / "full" / "curve.csv");
  const fs::path out = dir_ / "killed";
  EXPECT_EQ(cli("run " + source + args + " --quiet --out " + out.string(), "INDENTSIM_FAULT=increment:9"),
            128 + SIGKILL);
  ASSERT_EQ(cli("resume " + (out / "checkpoints").string() + " --quiet"), 0) << err();
  EXPECT_EQ(indentsim::testing::curve_without_timing(out / "curve.csv"), expected);
}

// The fit follows a load-controlled instrument's protocol in time (docs/MODEL.md §13.4): the depth
// a force-controlled creeping run reached at each time is fitted for the creep coefficient that
// produced it.  On the data's own mesh (no refinement) the forward model is the run itself, so the
// coefficient comes back to the optimiser's tolerance; as an instrument writes the file (time in
// ms, depth in nm, load in mN, semicolons, named columns) through a fit file, the same.
TEST_F(RateDependentCli, AForceControlledCreepHistoryIsFittedForTheCreepCoefficientThatMadeIt) {
  const std::string source = indentsim::testing::source_path("loadcases/axisymmetric/flat_punch.toml");
  const std::string args = creeping_flat_punch_flags;
  ASSERT_EQ(cli("run " + source + args + " --quiet --out " + (dir_ / "truth").string()), 0) << err();
  const fs::path truth_case = dir_ / "truth" / "case.toml", truth_curve = dir_ / "truth" / "curve.csv";
  const std::string quick = " --starts 1 --mesh-refinements 0 --single-level --no-design --no-profile --no-plot --quiet";
  const auto fitted = [&](const fs::path& folder) {
    const auto json = nlohmann::json::parse(indentsim::testing::slurp(folder / "fit.json"));
    EXPECT_EQ(json["data"][0]["kind"], "time_history");
    EXPECT_EQ(json["data"][0]["response"], "depth");
    return json["parameters"]["material.creep_coefficient"]["value"].get<double>();
  };
  ASSERT_EQ(cli("fit " + truth_case.string() + " --set material.creep_coefficient=0.003 --data " +
                truth_curve.string() + " --free material.creep_coefficient" + quick + " --out " +
                (dir_ / "fit").string()),
            0)
      << err();
  EXPECT_NEAR(fitted(dir_ / "fit"), 0.01, 1e-6);

  // The instrument's export of the same curve.
  const std::vector<std::vector<double>> rows = indentsim::testing::read_curve(truth_curve);
  std::string text = "Time (ms);Depth (nm);Load (mN)\r\n";
  for (const auto& r : rows) text += fmt::format("{:.17g};{:.17g};{:.17g}\r\n", 1e3 * r[1], 1e9 * r[2], 1e3 * r[3]);
  indentsim::testing::write_text(dir_ / "instrument.csv", text);
  std::string start = indentsim::testing::slurp(truth_case);
  const auto at = start.find("creep_coefficient = ");
  ASSERT_NE(at, std::string::npos);
  start.replace(at, start.find('\n', at) - at, "creep_coefficient = 0.003");
  indentsim::testing::write_text(dir_ / "start.toml", start);
  indentsim::testing::write_text(dir_ / "fit.toml", "[fit]\nfree = [\"material.creep_coefficient\"]\n\n[[data]]\n"
                                                    "case = \"start.toml\"\ncurve = \"instrument.csv\"\n"
                                                    "time_column = \"Time\"\ndepth_column = \"Depth\"\n"
                                                    "force_column = \"Load\"\n");
  ASSERT_EQ(cli("fit " + (dir_ / "fit.toml").string() + quick + " --out " + (dir_ / "instrument").string()), 0)
      << err();
  EXPECT_NEAR(fitted(dir_ / "instrument"), 0.01, 1e-6);

  // Refused before any run, naming what is wrong: the curve without its time column (the fit
  // cannot follow a creeping, force-controlled protocol along depths), a time beyond the protocol's.
  std::string untimed = "alpha,P\n";
  for (const auto& r : rows) untimed += fmt::format("{:.17g},{:.17g}\n", r[2], r[3]);
  indentsim::testing::write_text(dir_ / "untimed.csv", untimed);
  expect_refused("fit " + (dir_ / "start.toml").string() + " --data " + (dir_ / "untimed.csv").string() +
                     " --free material.creep_coefficient",
                 "--time-column");
  std::string late = text + "20000;300;2\r\n";
  indentsim::testing::write_text(dir_ / "late.csv", late);
  expect_refused("fit " + (dir_ / "start.toml").string() + " --data " + (dir_ / "late.csv").string() +
                     " --time-column Time --depth-column Depth --force-column Load --free material.creep_coefficient",
                 "outside the protocol's times");
  // A flow rule's parameter the case's rule does not have.
  expect_refused("fit " + (dir_ / "start.toml").string() + " --data " + truth_curve.string() +
                     " --free material.reference_strain_rate",
                 "material.reference_strain_rate");
}
