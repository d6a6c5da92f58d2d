// The inverse problem (fit.hpp): parameters back from curves the model itself made for known
// parameters with noise, from starts a factor 2 away; non-uniqueness reported where dimensional
// analysis says it must be (a sharp cone's loading curve, P = C alpha^2, holds one number), and
// resolved by a second data set; bad problems refused with the key named.
#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "indentsim/base/error.hpp"
#include "indentsim/fitting/fit.hpp"
#include "indentsim/input/load_case.hpp"
#include "test_support.hpp"

namespace indentsim {
namespace {

std::vector<double> depths(double deepest, int n) {
  std::vector<double> a;
  for (int k = 1; k <= n; ++k) a.push_back(deepest * k / n);
  return a;
}

/// `n` depths on loading to `deepest`, then `m` on unloading down to `lowest`.
std::vector<double> load_unload_depths(double deepest, int n, double lowest, int m) {
  std::vector<double> a = depths(deepest, n);
  for (int k = 1; k <= m; ++k) a.push_back(deepest + (lowest - deepest) * k / m);
  return a;
}

/// The small sphere scene with a power law given by its yield stress (400 MPa, n 0.2), pressed
/// 50 um on a mesh pinned for that depth (the element left to the fit).
LoadCase sphere(SceneKind scene) {
  LoadCase lc = testing::small_sphere_case(scene, MaterialModel::ilyushin, HardeningLaw::power);
  set_value(lc.material, MaterialParameter::yield_stress, 400e6);
  lc.load.path = {0.0, 50e-6};
  lc.load.increments = 20;
  lc.mesh.contact_half_width = 330e-6;
  lc.mesh.element = ElementChoice::automatic;
  validate(lc);
  return lc;
}

/// The truth's case with every free parameter moved a factor `factor` (n: towards the bounds' middle).
LoadCase started_away(LoadCase lc, const std::vector<FreeParameter>& free, double factor) {
  for (const auto& f : free) set_value(lc.material, f.parameter, value_of(lc.material, f.parameter) * factor);
  validate(lc);
  return lc;
}

void expect_round_trip(const FitResult& r, const LoadCase& truth, const std::vector<FreeParameter>& free) {
  ASSERT_TRUE(r.identifiable) << r.poorly_determined;
  for (std::size_t j = 0; j < free.size(); ++j) {
    const double exact = value_of(truth.material, free[j].parameter);
    const std::string key = key_of(free[j].parameter);
    EXPECT_LT(std::abs(r.values[j] - exact), 2.0 * r.std_errors[j]) << key << " = " << r.values[j] << " +- " << r.std_errors[j];
    EXPECT_LT(std::abs(r.values[j] / exact - 1.0), 0.03) << key;
  }
}

LoadCase cone(SceneKind scene) {
  LoadCase lc = sphere(scene);
  lc.punch.shape = PunchShapeKind::cone;
  lc.punch.half_angle = 70.3;
  lc.geometry.lx = lc.geometry.ly = 0.2e-3;
  lc.load.path = {0.0, 1e-6};
  lc.mesh.contact_half_width = 3.2e-6;
  validate(lc);
  return lc;
}

void print(const FitResult& r, const std::vector<FreeParameter>& free) {
  std::printf("forward runs %d, iterations %d, %.2f s, condition %.4g\n", r.forward_runs, r.iterations, r.wall_seconds,
              r.condition_number);
  for (std::size_t j = 0; j < free.size(); ++j)
    std::printf("  %s = %.6g +- %.3g\n", key_of(free[j].parameter).c_str(), r.values[j], r.std_errors[j]);
  if (!r.poorly_determined.empty()) std::printf("  %s\n", r.poorly_determined.c_str());
}

const std::vector<FreeParameter> yield_and_hardening{{MaterialParameter::yield_stress, 40e6, 4e9},
                                                     {MaterialParameter::n, 0.01, 0.6}};

/// A sphere (cylinder) and a cone (wedge) loading curve of one material, 20 points each, 0.5% noise,
/// started a factor 2 away (sigma_y 800 MPa, n 0.4 for the truth's 400 MPa, 0.2).
FitProblem sphere_and_cone(SceneKind scene, bool with_sphere, bool with_cone, int cone_points = 20) {
  FitProblem problem;
  problem.free = yield_and_hardening;
  if (with_sphere) {
    const LoadCase truth = sphere(scene);
    FitData d = synthetic_data(truth, FitDataKind::force_depth_curve, depths(20e-6, 20), problem.free, 0.005, 1);
    d.load_case = started_away(truth, problem.free, 2.0);
    problem.data.push_back(d);
  }
  if (with_cone) {
    const LoadCase truth = cone(scene);
    FitData d = synthetic_data(truth, FitDataKind::force_depth_curve, depths(1e-6, cone_points), problem.free, 0.005, 2);
    d.load_case = started_away(truth, problem.free, 2.0);
    problem.data.push_back(d);
  }
  return problem;
}

TEST(Fit, AxisymmetricSphereAndConeGiveYieldStressAndHardeningBack) {
  const FitProblem problem = sphere_and_cone(SceneKind::axisymmetric, true, true);
  const FitResult r = fit(problem);
  print(r, problem.free);
  expect_round_trip(r, sphere(SceneKind::axisymmetric), problem.free);
  EXPECT_EQ(r.data[0].gradients, "forward sensitivities");
}

TEST(Fit, PlaneStrainCylinderAndWedgeGiveYieldStressAndHardeningBack) {
  const FitProblem problem = sphere_and_cone(SceneKind::plane_strain, true, true);
  const FitResult r = fit(problem);
  print(r, problem.free);
  expect_round_trip(r, sphere(SceneKind::plane_strain), problem.free);
}

TEST(Fit, ConeLoadingCurveAloneCannotSeparateYieldStressFromHardening) {
  // Kick's law: under a sharp cone P = C alpha^2 with C(E, nu, sigma_y, n), one number.
  FitProblem problem = sphere_and_cone(SceneKind::axisymmetric, false, true, 10);
  problem.settings.max_iterations = 10;  // the valley is flat: the optimiser crawls along it
  const FitResult r = fit(problem);
  print(r, problem.free);
  EXPECT_FALSE(r.identifiable);
  EXPECT_GT(r.condition_number, identifiability_condition_limit);
  EXPECT_NE(r.poorly_determined.find("material.yield_stress"), std::string::npos);
  EXPECT_NE(r.poorly_determined.find("material.n"), std::string::npos);
  // The weak combination is the one Kick's constant does not feel: both move together or against.
  EXPECT_GT(std::abs(r.weakest_direction[0]) * std::abs(r.weakest_direction[1]), 0.05);
}

TEST(Fit, LoadUnloadCurveGivesModulusAndYieldStressWithFewerRunsThanFiniteDifferences) {
  // E from the unloading (through Ilyushin's unloading branch), sigma_y from the loading (with n
  // free too, a sphere's single curve holds sigma_y and n only to 5-10% at this noise: docs/verification.md);
  // 12 contact nodes, so the coarse phase runs on 6.  Sensitivities give every run its Jacobian:
  // one run per Levenberg-Marquardt step; finite differences need p + 1.
  LoadCase truth = sphere(SceneKind::axisymmetric);
  truth.mesh.contact_nodes = 12;
  validate(truth);
  const std::vector<FreeParameter> free{{MaterialParameter::E, 50e9, 800e9}, yield_and_hardening[0]};
  FitData d = synthetic_data(truth, FitDataKind::force_depth_curve, load_unload_depths(50e-6, 14, 40e-6, 6), free, 0.005, 4);
  d.load_case = started_away(truth, free, 1.5);
  FitProblem problem;
  problem.free = free;
  problem.data.push_back(d);
  const FitResult with_sensitivities = fit(problem);
  print(with_sensitivities, free);
  expect_round_trip(with_sensitivities, truth, free);
  EXPECT_EQ(with_sensitivities.data[0].gradients, "forward sensitivities");
  EXPECT_GT(with_sensitivities.coarse_runs, 0);
  EXPECT_EQ(with_sensitivities.starts.back().phase, "polish");
  problem.settings.finite_differences = true;
  const FitResult with_differences = fit(problem);
  print(with_differences, free);
  std::printf("forward runs (coarse): sensitivities %d (%d), finite differences %d (%d)\n", with_sensitivities.forward_runs,
              with_sensitivities.coarse_runs, with_differences.forward_runs, with_differences.coarse_runs);
  EXPECT_LT(with_sensitivities.forward_runs, with_differences.forward_runs);
  EXPECT_LT(with_sensitivities.coarse_runs, with_differences.coarse_runs);
  // Both reach the same optimum, to a small fraction of its standard errors.
  for (std::size_t j = 0; j < free.size(); ++j)
    EXPECT_LT(std::abs(with_sensitivities.values[j] - with_differences.values[j]), 0.2 * with_sensitivities.std_errors[j])
        << key_of(free[j].parameter);
}

TEST(Fit, ConeBecomesIdentifiableWithItsImprint) {
  // The residual imprint after unloading (Bolzon et al. 2004) holds what the loading curve does
  // not: the same pair as above, with the imprint's profile added, is determined.
  FitProblem problem = sphere_and_cone(SceneKind::axisymmetric, false, true, 10);
  LoadCase truth = cone(SceneKind::axisymmetric);
  truth.load.path = {0.0, 1e-6, 0.0};
  truth.load.increments = 30;
  validate(truth);
  std::vector<double> radii;
  for (int k = 0; k < 12; ++k) radii.push_back(0.3e-6 * k);
  FitData imprint = synthetic_data(truth, FitDataKind::imprint_profile, radii, problem.free, 0.005, 3);
  imprint.load_case = started_away(truth, problem.free, 2.0);
  problem.data.push_back(imprint);
  const FitResult r = fit(problem);
  print(r, problem.free);
  expect_round_trip(r, truth, problem.free);
  EXPECT_EQ(r.data[1].gradients, "forward sensitivities");  // through Ilyushin's unloading branch
}

class FitCli : public testing::CliTest {
protected:
  void SetUp() override {
    CliTest::SetUp();
    std::ofstream(dir_ / "case.toml") << to_toml(sphere(SceneKind::axisymmetric));
    std::ofstream curve(dir_ / "curve.csv");
    curve << "alpha,P\n";
    for (int k = 1; k <= 5; ++k) curve << 4e-6 * k << "," << 10.0 * k * std::sqrt(k) << "\n";
  }
  std::string fit_args(const std::string& extra) const {
    return "fit " + (dir_ / "case.toml").string() + " --data " + (dir_ / "curve.csv").string() + " " + extra;
  }
};

TEST_F(FitCli, BadProblemsExitTwoNamingTheKeyBeforeAnyRun) {
  expect_refused(fit_args("--free material.sigma"), "material.sigma");
  expect_refused(fit_args("--free material.n --bounds material.n=0.6:0.1"), "material.n");
  expect_refused(fit_args("--free material.n --bounds material.n=0.1:1.5"), "material.n");
  expect_refused(fit_args("--free material.E --bounds material.E=-1:1e12"), "material.E");
  expect_refused(fit_args("--free material.kappa"), "material.kappa");  // the case hardens by a power law
  expect_refused(fit_args("--free material.n --bounds material.E=1e9:1e12"), "material.E");  // bounds of a fixed one
  expect_refused(fit_args("--free material.e0,material.yield_stress"), "material.yield_stress");
  expect_refused(fit_args(""), "--free");
  expect_refused("fit " + (dir_ / "case.toml").string() + " --free material.n", "--data");
  // Data deeper than the case's load path, and fewer points than parameters.
  std::ofstream(dir_ / "deep.csv") << "alpha,P\n1e-5,1\n1e-4,2\n";
  expect_refused("fit " + (dir_ / "case.toml").string() + " --data " + (dir_ / "deep.csv").string() + " --free material.n",
                 "point 2");
  std::ofstream(dir_ / "one.csv") << "alpha,P\n1e-5,1\n";
  expect_refused("fit " + (dir_ / "case.toml").string() + " --data " + (dir_ / "one.csv").string() +
                     " --free material.n,material.yield_stress",
                 "curve");
  // A fit file with a key it does not know.
  std::ofstream(dir_ / "fit.toml") << "[fit]\nfree = [\"material.n\"]\nstart = 3\n[[data]]\ncase = \"case.toml\"\ncurve = \"curve.csv\"\n";
  expect_refused("fit " + (dir_ / "fit.toml").string(), "fit.start");
  // Keys it knows, of the wrong type.
  std::ofstream(dir_ / "typed.toml") << "[fit]\nfree = [\"material.n\"]\nstarts = \"3\"\n[[data]]\ncase = \"case.toml\"\ncurve = \"curve.csv\"\n";
  expect_refused("fit " + (dir_ / "typed.toml").string(), "fit.starts");
  std::ofstream(dir_ / "level.toml") << "[fit]\nfree = [\"material.n\"]\nsingle_level = 1\n[[data]]\ncase = \"case.toml\"\ncurve = \"curve.csv\"\n";
  expect_refused("fit " + (dir_ / "level.toml").string(), "fit.single_level");
}

}  // namespace
}  // namespace indentsim
