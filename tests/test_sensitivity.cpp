// Forward sensitivities dP/d(theta) and du/d(theta) through the converged Newton system
// (Simulation::sensitivities) against central finite differences of whole runs, for every
// parameter the fit differentiates this way, in both scenes, elastic and plastic, loading and
// Ilyushin's unloading branch, with contact, on the condensed and on the whole-mesh system.  The mesh is pinned (mesh.contact_half_width,
// mesh.element) so that the finite differences see the same discretization.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "indentsim/input/load_case.hpp"
#include "indentsim/simulation/load_stepping.hpp"
#include "indentsim/materials/material_parameter.hpp"
#include "indentsim/simulation/simulation.hpp"
#include "test_support.hpp"

namespace indentsim {
namespace {

struct ForceAndSensitivities {
  double force = 0.0;
  std::optional<std::vector<double>> sensitivities;
};

ForceAndSensitivities final_force(const LoadCase& lc, const std::vector<MaterialParameter>& parameters) {
  Simulation sim(lc);
  sim.run();
  ForceAndSensitivities r;
  r.force = sim.contact().force;
  r.sensitivities = sim.force_sensitivities(parameters);
  return r;
}

/// Central difference of the final P in each parameter with relative step `h`.
std::vector<double> finite_differences(const LoadCase& lc, const std::vector<MaterialParameter>& parameters, double h) {
  std::vector<double> d;
  for (MaterialParameter p : parameters) {
    const double value = value_of(lc.material, p);
    double sides[2];
    for (int s = 0; s < 2; ++s) {
      LoadCase perturbed = lc;
      set_value(perturbed.material, p, value * (1.0 + (s == 0 ? h : -h)));
      sides[s] = final_force(perturbed, {}).force;
    }
    d.push_back((sides[0] - sides[1]) / (2.0 * h * value));
  }
  return d;
}

void expect_sensitivities_match(const LoadCase& lc, const std::vector<MaterialParameter>& parameters, double tolerance,
                                double step = 2e-5) {
  const ForceAndSensitivities base = final_force(lc, parameters);
  ASSERT_TRUE(base.sensitivities.has_value());
  // A step of 2e-5: small enough that no Gauss point crosses the elastic limit inside it (at
  // 1e-4 one does on the plane-strain linear-hardening case, a kink of 1e-5 in d ln P / d ln kappa).
  const std::vector<double> fd = finite_differences(lc, parameters, step);
  for (std::size_t i = 0; i < parameters.size(); ++i) {
    const double value = value_of(lc.material, parameters[i]);
    // Compared as d ln P / d ln theta: the relative change of P per relative change of theta.
    const double exact = (*base.sensitivities)[i] * value / base.force;
    const double numeric = fd[i] * value / base.force;
    EXPECT_NEAR(exact, numeric, tolerance * std::max(1.0, std::abs(numeric))) << key_of(parameters[i]);
    EXPECT_GT(std::abs(numeric), 1e-3) << key_of(parameters[i]) << ": a parameter the test should feel";
  }
}

LoadCase sphere_case(SceneKind scene, MaterialModel model, HardeningLaw law) {
  return testing::small_sphere_case(scene, model, law);
}

TEST(ForceSensitivity, ElasticSphereInBothScenesMatchesFiniteDifferences) {
  for (SceneKind scene : {SceneKind::plane_strain, SceneKind::axisymmetric}) {
    LoadCase lc = sphere_case(scene, MaterialModel::elastic, HardeningLaw::linear);
    expect_sensitivities_match(lc, {MaterialParameter::E}, 1e-5);
  }
}

// The integrated gap's contact rows are the bulk's rows plus a penalty force that scales with the
// elastic stiffness (with E, not with the plastic law), and P sums the reactions of every
// candidate carrying contact force.  The residual is C^1 but its second derivative jumps where a
// contact piece's end crosses a node, so the central difference needs a smaller step than the
// node-to-rigid rows' 2e-5 to reach its truncation error: at 4e-5, 2e-5, 1e-5 and 5e-6 on
// plane-strain Ilyushin's e0 it differs from the exact derivative by 6e-5, 5e-5, <1e-5, <1e-5.
TEST(ForceSensitivity, TheIntegratedGapsRowsCarryTheBulksDerivative) {
  for (SceneKind scene : {SceneKind::plane_strain, SceneKind::axisymmetric}) {
    SCOPED_TRACE(scene == SceneKind::axisymmetric ? "axisymmetric" : "plane strain");
    LoadCase elastic = sphere_case(scene, MaterialModel::elastic, HardeningLaw::linear);
    elastic.contact.discretization = ContactDiscretizationChoice::integrated_gap;
    expect_sensitivities_match(elastic, {MaterialParameter::E}, 1e-5, 5e-6);
    LoadCase plastic = sphere_case(scene, MaterialModel::ilyushin, HardeningLaw::linear);
    plastic.contact.discretization = ContactDiscretizationChoice::integrated_gap;
    expect_sensitivities_match(plastic, {MaterialParameter::E, MaterialParameter::e0, MaterialParameter::kappa}, 1e-5, 5e-6);
  }
}

TEST(ForceSensitivity, IlyushinLinearHardeningMatchesFiniteDifferences) {
  for (SceneKind scene : {SceneKind::plane_strain, SceneKind::axisymmetric}) {
    LoadCase lc = sphere_case(scene, MaterialModel::ilyushin, HardeningLaw::linear);
    expect_sensitivities_match(lc, {MaterialParameter::E, MaterialParameter::e0, MaterialParameter::kappa}, 1e-5);
  }
}

TEST(ForceSensitivity, IlyushinPowerLawWithYieldStressMatchesFiniteDifferences) {
  for (SceneKind scene : {SceneKind::plane_strain, SceneKind::axisymmetric}) {
    LoadCase lc = sphere_case(scene, MaterialModel::ilyushin, HardeningLaw::power);
    set_value(lc.material, MaterialParameter::yield_stress, value_of(lc.material, MaterialParameter::yield_stress));
    const std::vector<MaterialParameter> ps{MaterialParameter::E, MaterialParameter::yield_stress, MaterialParameter::n};
    expect_sensitivities_match(lc, ps, 1e-5);
    // At fixed nu and n every stress scales with (E, sigma_y) together, so P is homogeneous of
    // degree one in them and Euler's theorem gives d ln P / d ln E + d ln P / d ln sigma_y = 1.
    const ForceAndSensitivities s = final_force(lc, ps);
    const double sum = ((*s.sensitivities)[0] * lc.material.E + (*s.sensitivities)[1] * *lc.material.yield_stress) / s.force;
    EXPECT_NEAR(sum, 1.0, 1e-9);
  }
}

TEST(ForceSensitivity, WholeMeshAndCondensedSystemsAgree) {
  LoadCase lc = sphere_case(SceneKind::axisymmetric, MaterialModel::ilyushin, HardeningLaw::power);
  const std::vector<MaterialParameter> ps{MaterialParameter::E, MaterialParameter::e0, MaterialParameter::n};
  lc.solver.far_field = FarFieldChoice::condense;
  const auto condensed = final_force(lc, ps);
  lc.solver.far_field = FarFieldChoice::full;
  const auto full = final_force(lc, ps);
  ASSERT_TRUE(condensed.sensitivities && full.sensitivities);
  for (std::size_t i = 0; i < ps.size(); ++i)
    EXPECT_NEAR((*condensed.sensitivities)[i], (*full.sensitivities)[i], 1e-7 * std::abs((*full.sensitivities)[i]));
}

TEST(ForceSensitivity, ConeUnderBbarMatchesFiniteDifferences) {
  LoadCase lc = sphere_case(SceneKind::axisymmetric, MaterialModel::ilyushin, HardeningLaw::power);
  lc.punch.shape = PunchShapeKind::cone;
  lc.punch.half_angle = 70.3;
  lc.geometry.lx = lc.geometry.ly = 0.2e-3;
  lc.load.path = {0.0, 1e-6};
  lc.mesh.contact_half_width = 3.2e-6;
  lc.mesh.element = ElementChoice::bbar;
  validate(lc);
  expect_sensitivities_match(lc, {MaterialParameter::E, MaterialParameter::e0, MaterialParameter::n}, 1e-5);
}

/// The final state of a load path that unloads, with its sensitivities: as the fit runs it, the
/// sensitivities are taken at each reversal of the path too (they record the peak's d eps*/d theta).
struct UnloadedState {
  double force = 0.0, axis_depth = 0.0;  ///< P, and the surface's depth -v at the axis
  std::optional<Simulation::Sensitivities> sensitivities;
};

UnloadedState unloaded_state(const LoadCase& lc, const std::vector<MaterialParameter>& parameters) {
  Simulation sim(lc);
  const std::vector<int> descents = descent_starts(plan_increments(lc.load));
  sim.run([&](const IncrementRecord& r) {
    if (!parameters.empty() && std::count(descents.begin(), descents.end(), r.step)) {
      ASSERT_TRUE(sim.sensitivities(parameters).has_value());
    }
  });
  UnloadedState s;
  s.force = sim.contact().force;
  const auto& axis = sim.contact_boundary().candidates().front();
  s.axis_depth = -sim.displacement()[static_cast<std::size_t>(axis.equation)];
  if (!parameters.empty()) s.sensitivities = sim.sensitivities(parameters, true);
  if (s.sensitivities) {
    for (auto& d : s.sensitivities->displacement) d = {-d[static_cast<std::size_t>(axis.equation)]};
  }
  return s;
}

/// Ilyushin's unloading branch: sigma = sigma_L(eps*) + D (eps - eps*) moves with theta through the
/// peak strain as well; part way down (force) and after leaving the surface (the imprint's depth).
TEST(ForceSensitivity, IlyushinUnloadingBranchAndImprintMatchFiniteDifferences) {
  for (SceneKind scene : {SceneKind::plane_strain, SceneKind::axisymmetric}) {
    LoadCase lc = sphere_case(scene, MaterialModel::ilyushin, HardeningLaw::power);
    set_value(lc.material, MaterialParameter::yield_stress, value_of(lc.material, MaterialParameter::yield_stress));
    const std::vector<MaterialParameter> ps{MaterialParameter::E, MaterialParameter::yield_stress, MaterialParameter::n};
    // Part way down; down to 0 (the imprint); and, axisymmetric, a hold at the first peak, a
    // partial unloading and a reload past it before the imprint (the peak moves: the record must too).
    std::vector<std::vector<double>> paths{{0.0, 20e-6, 17e-6}, {0.0, 20e-6, 0.0}};
    if (scene == SceneKind::axisymmetric) paths.push_back({0.0, 20e-6, 20e-6, 12e-6, 22e-6, 0.0});
    for (const std::vector<double>& path : paths) {
      lc.load.path = path;
      lc.load.increments = 8;
      lc.load.segment_increments.clear();
      if (path.size() == 6) lc.load.segment_increments = {5, 2, 3, 4, 8};
      validate(lc);
      const bool imprint = path.back() == 0.0;
      const UnloadedState base = unloaded_state(lc, ps);
      ASSERT_TRUE(base.sensitivities.has_value());
      const double measured = imprint ? base.axis_depth : base.force;
      ASSERT_GT(measured, 0.0);
      for (std::size_t i = 0; i < ps.size(); ++i) {
        const double value = value_of(lc.material, ps[i]), h = 2e-5;
        double sides[2];
        for (int side = 0; side < 2; ++side) {
          LoadCase perturbed = lc;
          set_value(perturbed.material, ps[i], value * (1.0 + (side == 0 ? h : -h)));
          const UnloadedState s = unloaded_state(perturbed, {});
          sides[side] = imprint ? s.axis_depth : s.force;
        }
        const double numeric = (sides[0] - sides[1]) / (2.0 * h * measured);
        const double exact =
            (imprint ? base.sensitivities->displacement[i][0] : base.sensitivities->force[i]) * value / measured;
        EXPECT_NEAR(exact, numeric, 1e-5 * std::max(1.0, std::abs(numeric)))
            << key_of(ps[i]) << (imprint ? " (imprint depth)" : " (force, unloading)");
        if (ps[i] != MaterialParameter::E || !imprint) {
          EXPECT_GT(std::abs(numeric), 1e-3) << key_of(ps[i]) << ": a parameter the test should feel";
        }
      }
    }
  }
}

TEST(ForceSensitivity, HistoryDependentStatesSayTheyNeedFiniteDifferences) {
  LoadCase j2 = sphere_case(SceneKind::axisymmetric, MaterialModel::j2, HardeningLaw::power);
  EXPECT_FALSE(final_force(j2, {MaterialParameter::e0}).sensitivities.has_value());
  // An unloading state whose peak's sensitivities were never taken (a run without the fit's
  // calls at the reversals, or one restored from a checkpoint).
  LoadCase unloaded = sphere_case(SceneKind::axisymmetric, MaterialModel::ilyushin, HardeningLaw::power);
  unloaded.load.path = {0.0, 20e-6, 15e-6};
  EXPECT_FALSE(final_force(unloaded, {MaterialParameter::e0}).sensitivities.has_value());
  LoadCase elastic = sphere_case(SceneKind::axisymmetric, MaterialModel::elastic, HardeningLaw::power);
  EXPECT_FALSE(final_force(elastic, {MaterialParameter::nu}).sensitivities.has_value());
}

}  // namespace
}  // namespace indentsim
