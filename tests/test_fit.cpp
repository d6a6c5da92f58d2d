// The inverse problem (fit.hpp): parameters back from curves the model itself made for known
// parameters with noise, from starts a factor 2 away; non-uniqueness reported where dimensional
// analysis says it must be (a sharp cone's loading curve, P = C alpha^2, holds one number), and
// resolved by a second data set; bad problems refused with the key named; bad fits judged poor;
// dense curves reduced to what the model resolves; a stop request honoured.
#include <algorithm>
#include <csignal>
#include <cmath>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "indentsim/base/error.hpp"
#include "indentsim/base/interruption.hpp"
#include "indentsim/fitting/fit.hpp"
#include "indentsim/fitting/fit_files.hpp"
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
  for (const auto& f : free) set_value(lc, f.parameter, value_of(lc, f.parameter) * factor);
  validate(lc);
  return lc;
}

/// What a fit must say of the truth: a good fit whose model error was estimated; every 95%
/// interval holds the truth; a parameter called determined is within determination_limit of it.
/// Returns how many parameters were called determined.
int expect_honest(const FitResult& r, const LoadCase& truth, const std::vector<FreeParameter>& free) {
  EXPECT_TRUE(r.good()) << r.quality;
  EXPECT_TRUE(r.model_error_estimated);
  int determined = 0;
  for (std::size_t j = 0; j < free.size(); ++j) {
    const double exact = value_of(truth, free[j].parameter);
    const ParameterDetermination& pd = r.determination[j];
    const std::string key = key_of(free[j].parameter);
    EXPECT_LE(pd.lower, exact) << key << ": " << pd.verdict;
    EXPECT_GE(pd.upper, exact) << key << ": " << pd.verdict;
    if (!pd.determined) continue;
    ++determined;
    EXPECT_LE(std::abs(r.values[j] / exact - 1.0), determination_limit) << key << ": " << pd.verdict;
  }
  EXPECT_EQ(r.identifiable, determined == static_cast<int>(free.size()) && r.good());
  return determined;
}

/// The truth's curve made on a mesh `factor` times finer than the fit's (its contact nodes):
/// the model's own discretization error is then in the data as nature's would be.
/// (and, for a path-dependent model, `increments_factor` times the increments).
FitData data_on_a_finer_mesh(LoadCase truth, FitDataKind kind, const std::vector<double>& abscissa,
                             const std::vector<FreeParameter>& free, double noise, unsigned seed, int factor = 3,
                             int increments_factor = 1) {
  const LoadCase fit_case = truth;
  truth.mesh.contact_nodes *= factor;
  truth.load.multiply_increments(increments_factor);
  validate(truth);
  FitData d = synthetic_data(truth, kind, abscissa, free, noise, seed);
  d.load_case = fit_case;
  return d;
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
    std::printf("  %s = %.6g +- %.3g (noise), model shift %.3g: %s\n", key_of(free[j].parameter).c_str(), r.values[j],
                r.std_errors[j], r.determination[j].model_shift, r.determination[j].verdict.c_str());
  if (!r.poorly_determined.empty()) std::printf("  %s\n", r.poorly_determined.c_str());
}

const std::vector<FreeParameter> yield_and_hardening{{MaterialParameter::yield_stress, 40e6, 4e9},
                                                     {MaterialParameter::n, 0.01, 0.6}};

/// A sphere (cylinder) and a cone (wedge) loading curve of one material, 20 points each, 0.5% noise,
/// made on meshes three times finer than the fit's, started a factor 2 away (sigma_y 800 MPa,
/// n 0.4 for the truth's 400 MPa, 0.2).
FitProblem sphere_and_cone(SceneKind scene, bool with_sphere, bool with_cone, int cone_points = 20) {
  FitProblem problem;
  problem.free = yield_and_hardening;
  if (with_sphere) {
    const LoadCase truth = sphere(scene);
    FitData d = data_on_a_finer_mesh(truth, FitDataKind::force_depth_curve, depths(20e-6, 20), problem.free, 0.005, 1);
    d.load_case = started_away(truth, problem.free, 2.0);
    problem.data.push_back(d);
  }
  if (with_cone) {
    const LoadCase truth = cone(scene);
    FitData d = data_on_a_finer_mesh(truth, FitDataKind::force_depth_curve, depths(1e-6, cone_points), problem.free, 0.005, 2);
    d.load_case = started_away(truth, problem.free, 2.0);
    problem.data.push_back(d);
  }
  return problem;
}

/// The sphere's load-unload curve (14 depths loading to 50 um, 6 back to 40 um) on 12 contact
/// nodes, with 0.5% noise, E and sigma_y free, started 1.5 times away.
LoadCase load_unload_truth() {
  LoadCase truth = sphere(SceneKind::axisymmetric);
  truth.mesh.contact_nodes = 12;
  validate(truth);
  return truth;
}

FitProblem load_unload_problem() {
  const LoadCase truth = load_unload_truth();
  FitProblem problem;
  problem.free = {{MaterialParameter::E, 50e9, 800e9}, yield_and_hardening[0]};
  FitData d = synthetic_data(truth, FitDataKind::force_depth_curve, load_unload_depths(50e-6, 14, 40e-6, 6),
                             problem.free, 0.005, 4);
  d.load_case = started_away(truth, problem.free, 1.5);
  problem.data.push_back(d);
  return problem;
}

TEST(Fit, AxisymmetricSphereAndConeGiveYieldStressAndHardeningBack) {
  const FitProblem problem = sphere_and_cone(SceneKind::axisymmetric, true, true);
  const FitResult r = fit(problem);
  print(r, problem.free);
  const int determined = expect_honest(r, sphere(SceneKind::axisymmetric), problem.free);
  std::printf("determined: %d of 2\n", determined);
  EXPECT_EQ(r.data[0].gradients, "forward sensitivities");
}

TEST(Fit, PlaneStrainCylinderAndWedgeGiveYieldStressAndHardeningBack) {
  const FitProblem problem = sphere_and_cone(SceneKind::plane_strain, true, true);
  const FitResult r = fit(problem);
  print(r, problem.free);
  const int determined = expect_honest(r, sphere(SceneKind::plane_strain), problem.free);
  std::printf("determined: %d of 2\n", determined);
}

// J2 flow theory carries its history, so its curve depends on the increments as well as the mesh:
// data made on a mesh three times finer with four times the increments, fitted with the case's own,
// must have both shares of the model's error in the interval (the increments' estimated, not 0).
TEST(Fit, AJ2FitCarriesTheErrorOfItsIncrementsIntoItsInterval) {
  LoadCase truth = sphere(SceneKind::plane_strain);
  truth.material.model = MaterialModel::j2;
  truth.load.increments = 10;
  validate(truth);
  FitProblem problem;
  problem.free = {yield_and_hardening[0]};
  problem.settings.starts = 2;
  problem.settings.design_experiments = false;
  FitData d = data_on_a_finer_mesh(truth, FitDataKind::force_depth_curve, depths(20e-6, 10), problem.free, 0.005, 5, 3, 4);
  d.load_case = started_away(truth, problem.free, 1.5);
  problem.data.push_back(d);
  const FitResult r = fit(problem);
  print(r, problem.free);
  EXPECT_EQ(r.data[0].gradients, "finite differences (J2 flow theory carries its history)");
  EXPECT_NE(r.determination[0].model_shift_increments, 0.0);
  expect_honest(r, truth, problem.free);
}

// The profile likelihood where the model is nearly linear in its parameter: one parameter
// (sigma_y of a sphere's loading curve, n fixed), the profile's crossings on both sides at the
// linearized half-width t * standard error, to the curvature of P in sigma_y (10%).
TEST(Fit, TheProfileOfANearlyLinearParameterIsItsLinearizedInterval) {
  const LoadCase truth = sphere(SceneKind::axisymmetric);
  FitProblem problem;
  problem.free = {yield_and_hardening[0]};
  FitData d = synthetic_data(truth, FitDataKind::force_depth_curve, depths(20e-6, 20), problem.free, 0.005, 5);
  d.load_case = started_away(truth, problem.free, 1.3);
  problem.data.push_back(d);
  problem.settings.mesh_refinements = 0;
  problem.settings.design_experiments = false;
  const FitResult r = fit(problem);
  print(r, problem.free);
  const ParameterDetermination& pd = r.determination[0];
  ASSERT_TRUE(pd.profiled);
  EXPECT_FALSE(pd.profile_open);
  const double linear = r.noise_relative_half_width[0] * r.values[0];
  std::printf("profile [%.6g, %.6g] about %.6g; linearized half-width %.4g\n", pd.profile_lower, pd.profile_upper,
              r.values[0], linear);
  EXPECT_NEAR((r.values[0] - pd.profile_lower) / linear, 1.0, 0.1);
  EXPECT_NEAR((pd.profile_upper - r.values[0]) / linear, 1.0, 0.1);
}

TEST(Fit, ConeLoadingCurveAloneCannotSeparateYieldStressFromHardening) {
  // Kick's law: under a sharp cone P = C alpha^2 with C(E, nu, sigma_y, n), one number.
  FitProblem problem = sphere_and_cone(SceneKind::axisymmetric, false, true, 10);
  problem.settings.max_iterations = 10;  // the valley is flat: the optimiser crawls along it
  const FitResult r = fit(problem);
  print(r, problem.free);
  EXPECT_FALSE(r.identifiable);
  EXPECT_GT(r.condition_number, 100.0);  // measured about 270 (fit.hpp)
  EXPECT_NE(r.poorly_determined.find("material.yield_stress"), std::string::npos);
  EXPECT_NE(r.poorly_determined.find("material.n"), std::string::npos);
  // The weak combination is the one Kick's constant does not feel: both move together or against.
  EXPECT_GT(std::abs(r.weakest_direction[0]) * std::abs(r.weakest_direction[1]), 0.05);
  // Neither parameter is called determined, and the valley reported holds the truth: the starts
  // spread over the bounds end along it at costs the noise cannot tell apart, and say so.
  const LoadCase truth = cone(SceneKind::axisymmetric);
  for (std::size_t j = 0; j < 2; ++j) {
    const ParameterDetermination& pd = r.determination[j];
    EXPECT_FALSE(pd.determined) << pd.verdict;
    EXPECT_NE(pd.verdict.find("not determined"), std::string::npos) << pd.verdict;
    EXPECT_LE(pd.lower, value_of(truth, problem.free[j].parameter)) << pd.verdict;
    EXPECT_GE(pd.upper, value_of(truth, problem.free[j].parameter)) << pd.verdict;
  }
  EXPECT_TRUE(std::any_of(r.warnings.begin(), r.warnings.end(), [](const std::string& w) {
    return w.find("distinct starts ended at distinct points") != std::string::npos;
  }));
  // The profile of one of them stays within the noise up to a bound: open there.
  EXPECT_TRUE(r.determination[0].profile_open || r.determination[1].profile_open);
}

// The design table's prediction against the fit that includes the addition: a sphere's loading
// curve alone, then with the cone the table proposes (and, separately, with the deeper indent):
// the noise-only 95% half-width of each parameter in the joint fit is the one predicted, within a
// factor 1.5 (issue 39).  The prediction is made at the fitted parameters; on a flat valley (a
// cone alone) they are far from the truth and so is a prediction; and it assumes the data's
// misfit is their noise (data made on a finer mesh add the model's misfit to the scatter).
TEST(Fit, TheDesignTablePredictsTheIntervalsOfTheFitWithTheAddition) {
  // Data on the fit's own mesh: the noise is then all the misfit, as the table assumes.
  const LoadCase truth = sphere(SceneKind::axisymmetric);
  FitProblem sphere_alone;
  sphere_alone.free = yield_and_hardening;
  FitData own = synthetic_data(truth, FitDataKind::force_depth_curve, depths(20e-6, 20), sphere_alone.free, 0.005, 1);
  own.load_case = started_away(truth, sphere_alone.free, 2.0);
  sphere_alone.data.push_back(own);
  sphere_alone.settings.mesh_refinements = 0;
  const FitResult alone = fit(sphere_alone);
  print(alone, sphere_alone.free);
  const double deepest = 20e-6;
  for (const std::string name : {"cone", "deeper indent"}) {
    SCOPED_TRACE(name);
    const auto c = std::find_if(alone.experiment_design.begin(), alone.experiment_design.end(),
                                [&](const CandidateExperiment& e) { return e.name == name; });
    ASSERT_NE(c, alone.experiment_design.end());
    ASSERT_TRUE(c->failure.empty()) << c->failure;
    std::printf("%s: %s\n", name.c_str(), c->description.c_str());
    LoadCase added = truth;
    std::vector<double> depths_added;
    if (name == "cone") {
      added.punch = PunchInput{};
      added.punch.shape = PunchShapeKind::cone;
      added.punch.half_angle = 70.3;
      added.load.path = {0.0, deepest};
      depths_added = depths(deepest, 20);
    } else {
      added.load.path = {0.0, 2.0 * deepest};
      depths_added = depths(2.0 * deepest, 20);
    }
    added.mesh.contact_half_width.reset();
    validate(added);
    FitProblem joint = sphere_alone;
    FitData d = synthetic_data(added, FitDataKind::force_depth_curve, depths_added, joint.free, 0.005, 7);
    d.load_case = started_away(added, joint.free, 2.0);
    joint.data.push_back(d);
    joint.settings.design_experiments = false;
    const FitResult with = fit(joint);
    print(with, joint.free);
    for (std::size_t j = 0; j < joint.free.size(); ++j) {
      const double predicted = c->relative_half_width[j], measured = with.noise_relative_half_width[j];
      std::printf("  %s: predicted +-%.3g%%, the joint fit's +-%.3g%% (today +-%.3g%%)\n",
                  key_of(joint.free[j].parameter).c_str(), 100 * predicted, 100 * measured,
                  100 * alone.noise_relative_half_width[j]);
      EXPECT_LT(measured / predicted, 1.5) << key_of(joint.free[j].parameter);
      EXPECT_GT(measured / predicted, 1.0 / 1.5) << key_of(joint.free[j].parameter);
    }
  }
}

TEST(Fit, LoadUnloadCurveGivesModulusAndYieldStressWithFewerRunsThanFiniteDifferences) {
  // E from the unloading (through Ilyushin's unloading branch), sigma_y from the loading (with n
  // free too, a sphere's single curve holds sigma_y and n only to 5-10% at this noise: docs/verification.md);
  // 12 contact nodes, so the coarse phase runs on 6.  Sensitivities give every run its Jacobian:
  // one run per Levenberg-Marquardt step; finite differences need p + 1.
  const LoadCase truth = load_unload_truth();
  FitProblem problem = load_unload_problem();
  const std::vector<FreeParameter>& free = problem.free;
  // The subject is the gradients' cost: one start, no refinement for the model's error (the data
  // are the fit's own mesh's, so the model's estimated error is no error of these data).
  problem.settings.starts = 1;
  problem.settings.mesh_refinements = 0;
  const FitResult with_sensitivities = fit(problem);
  print(with_sensitivities, free);
  expect_honest(with_sensitivities, truth, free);
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
  const int determined = expect_honest(r, truth, problem.free);
  std::printf("determined: %d of 2\n", determined);
  EXPECT_EQ(r.data[1].gradients, "forward sensitivities");  // through Ilyushin's unloading branch
}

TEST(Fit, ManyRowsAreReducedToOnePointPerIncrementWithTheTurningPointKept) {
  // 10^5 noisy rows of a load-unload curve (to 50 um in the case's 20 increments of 2.5 um, back
  // to 40 um) would be 10^5 increments of every forward run: reduced to one point per increment
  // of each branch, the peak exact, each point the curve's value there with the noise averaged.
  FitData d;
  d.file = "dense.csv";
  d.load_case = sphere(SceneKind::axisymmetric);
  const auto loading = [](double a) { return 300.0 * std::pow(a / 50e-6, 1.5); };
  const auto unloading = [](double a) { return 300.0 * std::pow((a - 35e-6) / 15e-6, 2.0); };
  std::mt19937 random(7);
  std::normal_distribution<double> noise(0.0, 1.0);
  // Depths with 1 nm of noise, but for the rows near the ends (the turning points are the rows'
  // extremes); forces with 1.5 N, 0.5% of the peak.
  const auto depth_noise = [&](int i, int n) { return i > 100 && i < n - 100 ? 1e-9 * noise(random) : 0.0; };
  for (int i = 1; i <= 80000; ++i) {
    const double a = 50e-6 * i / 80000;
    d.abscissa.push_back(a + depth_noise(i, 80000));
    d.values.push_back(loading(a) + 1.5 * noise(random));
  }
  for (int i = 1; i <= 20000; ++i) {
    const double a = 50e-6 - 10e-6 * i / 20000;
    d.abscissa.push_back(a + depth_noise(i, 20000));
    d.values.push_back(unloading(a) + 1.5 * noise(random));
  }
  const double peak_depth = *std::max_element(d.abscissa.begin(), d.abscissa.end()), last_depth = d.abscissa.back();
  const CurveReduction r = reduce_to_resolution(d);
  EXPECT_TRUE(r.reduced);
  EXPECT_EQ(r.rows, 100000u);
  EXPECT_EQ(r.branches, 2);
  EXPECT_EQ(d.rows, 100000u);
  EXPECT_EQ(d.abscissa.size(), r.points);
  EXPECT_EQ(r.points, 20u + 5u);  // 20 increments of loading; 4 of unloading, at least 5 points
  EXPECT_NE(r.note.find("100000 rows"), std::string::npos) << r.note;
  EXPECT_NE(r.note.find(fmt::format("{} points", r.points)), std::string::npos) << r.note;
  EXPECT_NE(r.note.find("load.increments"), std::string::npos) << r.note;
  // The turning point and the last depth are kept exactly; the path is loading, then unloading.
  const auto peak = std::max_element(d.abscissa.begin(), d.abscissa.end());
  EXPECT_EQ(*peak, peak_depth);
  EXPECT_EQ(d.abscissa.back(), last_depth);
  for (std::size_t i = 1; i < d.abscissa.size(); ++i)
    EXPECT_EQ(d.abscissa[i] > d.abscissa[i - 1], i <= static_cast<std::size_t>(peak - d.abscissa.begin())) << i;
  for (std::size_t i = 0; i < d.abscissa.size(); ++i) {
    const bool loads = i <= static_cast<std::size_t>(peak - d.abscissa.begin());
    const double exact = loads ? loading(d.abscissa[i]) : unloading(d.abscissa[i]);
    // The rows' noise is 1.5; a point's (a quadratic through thousands of rows) 0.04 to 0.1.
    EXPECT_NEAR(d.values[i], exact, 0.5) << "point " << i << " at " << d.abscissa[i];
  }

  // A curve with no more than two rows per increment, and an imprint, are left as they are.
  FitData sparse;
  sparse.load_case = sphere(SceneKind::axisymmetric);
  sparse.abscissa = depths(50e-6, 40);
  for (double a : sparse.abscissa) sparse.values.push_back(loading(a));
  const FitData before = sparse;
  EXPECT_FALSE(reduce_to_resolution(sparse).reduced);
  EXPECT_EQ(sparse.abscissa, before.abscissa);
  EXPECT_EQ(sparse.rows, 0u);
  FitData imprint = d;
  imprint.kind = FitDataKind::imprint_profile;
  const std::size_t points = imprint.abscissa.size();
  EXPECT_FALSE(reduce_to_resolution(imprint).reduced);
  EXPECT_EQ(imprint.abscissa.size(), points);
}

TEST(Fit, ForcesAThousandTimesTooLargeAreAPoorFitAtABoundWithAUnitWarningNeverIdentifiable) {
  // mN written as N: no yield stress in the bounds reaches forces 1000 times the model's.
  const LoadCase truth = sphere(SceneKind::axisymmetric);
  const std::vector<FreeParameter> free{yield_and_hardening[0]};
  FitData d = synthetic_data(truth, FitDataKind::force_depth_curve, depths(20e-6, 8), free, 0.0, 1);
  for (double& v : d.values) v *= 1e3;
  d.load_case = started_away(truth, free, 2.0);
  FitProblem problem;
  problem.free = free;
  problem.data.push_back(d);
  std::vector<std::string> warned;
  problem.settings.on_warning = [&](const std::string& w) { warned.push_back(w); };
  const FitResult r = fit(problem);
  print(r, free);
  EXPECT_FALSE(r.good());
  EXPECT_FALSE(r.identifiable);
  EXPECT_EQ(r.quality.rfind("poor fit: rms ", 0), 0u) << r.quality;
  EXPECT_NE(r.quality.find("of the peak force"), std::string::npos) << r.quality;
  EXPECT_NE(r.quality.find("material.yield_stress at its upper bound 4e+09"), std::string::npos) << r.quality;
  EXPECT_EQ(r.quality_problems.size(), 2u);
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_EQ(warned, r.warnings);
  EXPECT_NE(r.warnings[0].find("force unit is probably wrong"), std::string::npos) << r.warnings[0];
  EXPECT_NE(r.warnings[0].find("column \"P\" was read in N"), std::string::npos) << r.warnings[0];
}

TEST(Fit, AStopRequestEndsTheFitWithTheBestParametersSoFar) {
  // SIGTERM's handler raises the interruption flag; here the first iteration raises it.
  const LoadCase truth = sphere(SceneKind::axisymmetric);
  const std::vector<FreeParameter> free{yield_and_hardening[0]};
  FitData d = synthetic_data(truth, FitDataKind::force_depth_curve, depths(20e-6, 8), free, 0.0, 1);
  d.load_case = started_away(truth, free, 2.0);
  FitProblem problem;
  problem.free = free;
  problem.data.push_back(d);
  problem.settings.starts = 3;
  int iterations = 0;
  problem.settings.on_iteration = [&](const FitProgress&) {
    if (++iterations == 1) request_interruption(SIGTERM);
  };
  struct Lowered {
    ~Lowered() { clear_interruption(); }
  } lowered;
  try {
    fit(problem);
    ADD_FAILURE() << "the fit did not stop";
  } catch (const FitInterrupted& e) {
    EXPECT_EQ(e.signal(), SIGTERM);
    ASSERT_EQ(e.best().size(), 1u);  // the first start's first point: its cost is known
    EXPECT_DOUBLE_EQ(e.best()[0], 800e6);
    EXPECT_TRUE(std::isfinite(e.cost()));
    EXPECT_EQ(e.phase(), "fine");  // 10 contact nodes: no coarse phase
  }
  EXPECT_EQ(iterations, 1);  // no start after the request
}

// A fit stopped within its second start resumes from the checkpoint of its last accepted step:
// the finished start is taken as it was, the one in progress continues from its point, and the
// fit ends where the fit that was never stopped ends.
TEST(Fit, AStoppedFitResumedFromItsCheckpointEndsWhereTheWholeFitEnds) {
  FitProblem problem = load_unload_problem();
  const std::vector<FreeParameter>& free = problem.free;
  problem.settings.starts = 2;
  problem.settings.threads = 1;
  problem.settings.mesh_refinements = 0;
  const FitResult whole = fit(problem);

  FitCheckpoint last;
  problem.settings.on_checkpoint = [&](const FitCheckpoint& c) {
    last = c;
    for (const StartOutcome& o : c.in_progress)
      if (o.phase == "coarse" && o.index == 2) request_interruption(SIGTERM);
  };
  struct Lowered {
    ~Lowered() { clear_interruption(); }
  } lowered;
  EXPECT_THROW(fit(problem), FitInterrupted);
  clear_interruption();
  ASSERT_EQ(last.in_progress.size(), 1u);
  ASSERT_EQ(last.finished.size(), 1u);
  EXPECT_EQ(last.finished[0].result, whole.starts[0].result);  // the first start, bit for bit

  problem.settings.on_checkpoint = nullptr;
  problem.settings.resume_from = &last;
  const FitResult resumed = fit(problem);
  ASSERT_EQ(resumed.starts.size(), whole.starts.size());
  EXPECT_EQ(resumed.starts[0].result, whole.starts[0].result);
  for (std::size_t j = 0; j < free.size(); ++j)
    EXPECT_NEAR(resumed.values[j], whole.values[j], 1e-3 * whole.determination[j].total_std_error) << key_of(free[j].parameter);
  EXPECT_GE(resumed.coarse_runs, last.coarse_runs);  // the counters go on from the checkpoint's
}

// Starts and profile sides side by side (two threads) are the same solves one after another: each
// solve's runs are its own, so every outcome, the answer, its intervals and the runs counted are
// the same, bit for bit.  Stopped with two starts in progress, the checkpoint holds both, and the
// resumed fit ends where it would have.
TEST(Fit, SolvesSideBySideEndWhereSolvesOneAfterAnotherEnd) {
  FitProblem problem = load_unload_problem();
  const std::vector<FreeParameter>& free = problem.free;
  problem.settings.starts = 2;
  problem.settings.mesh_refinements = 0;
  problem.settings.design_experiments = false;
  problem.settings.threads = 1;
  const FitResult one_after_another = fit(problem);
  problem.settings.threads = 2;
  const FitResult side_by_side = fit(problem);
  ASSERT_EQ(side_by_side.starts.size(), one_after_another.starts.size());
  for (std::size_t k = 0; k < side_by_side.starts.size(); ++k) {
    EXPECT_EQ(side_by_side.starts[k].result, one_after_another.starts[k].result) << "start " << k;
    EXPECT_EQ(side_by_side.starts[k].iterations, one_after_another.starts[k].iterations) << "start " << k;
  }
  EXPECT_EQ(side_by_side.values, one_after_another.values);
  for (std::size_t j = 0; j < free.size(); ++j) {
    EXPECT_TRUE(side_by_side.determination[j].profiled) << key_of(free[j].parameter);
    EXPECT_EQ(side_by_side.determination[j].lower, one_after_another.determination[j].lower) << key_of(free[j].parameter);
    EXPECT_EQ(side_by_side.determination[j].upper, one_after_another.determination[j].upper) << key_of(free[j].parameter);
  }
  EXPECT_EQ(side_by_side.forward_runs, one_after_another.forward_runs);
  EXPECT_EQ(side_by_side.coarse_runs, one_after_another.coarse_runs);
  EXPECT_EQ(side_by_side.iterations, one_after_another.iterations);

  FitCheckpoint last;
  problem.settings.on_checkpoint = [&](const FitCheckpoint& c) {
    last = c;
    if (c.in_progress.size() == 2) request_interruption(SIGTERM);
  };
  struct Lowered {
    ~Lowered() { clear_interruption(); }
  } lowered;
  EXPECT_THROW(fit(problem), FitInterrupted);
  clear_interruption();
  ASSERT_EQ(last.in_progress.size(), 2u);
  problem.settings.on_checkpoint = nullptr;
  problem.settings.resume_from = &last;
  problem.settings.threads = 1;  // resumed on fewer cores: the waiting start is kept until its turn
  const FitResult resumed = fit(problem);
  ASSERT_EQ(resumed.starts.size(), one_after_another.starts.size());
  for (std::size_t j = 0; j < free.size(); ++j)
    EXPECT_NEAR(resumed.values[j], one_after_another.values[j], 1e-3 * one_after_another.determination[j].total_std_error)
        << key_of(free[j].parameter);
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
  /// The case's own curve (a run, under a second): alpha [m] and P [N] at its 20 increments.
  std::vector<std::pair<double, double>> run_curve() {
    EXPECT_EQ(cli("run " + (dir_ / "case.toml").string() + " --quiet --out " + (dir_ / "run").string()), 0) << err();
    std::vector<std::pair<double, double>> curve;
    for (const auto& row : testing::read_curve(dir_ / "run" / "curve.csv")) curve.emplace_back(row[1], row[2]);
    return curve;
  }
  /// Writes rows "alpha,P" (with `header`) to `name`, forces times `factor`.
  std::string write_curve(const std::string& name, const std::vector<std::pair<double, double>>& curve,
                          double factor = 1.0, const std::string& header = "alpha,P") {
    std::ofstream out(dir_ / name);
    out.precision(17);
    out << header << "\n";
    for (const auto& [a, P] : curve) out << a << "," << factor * P << "\n";
    return (dir_ / name).string();
  }
  std::string fit_of(const std::string& curve, const std::string& extra) const {
    return "fit " + (dir_ / "case.toml").string() + " --data " + curve + " --no-plot --free material.yield_stress " + extra;
  }
  nlohmann::json fit_json(const std::string& out) const {
    return nlohmann::json::parse(testing::slurp(dir_ / out / "fit.json"));
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
  expect_refused(fit_args("--free material.n --threads 0"), "--threads");
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
  // Bounds beyond the key's declared interval or beyond the magnitudes of solids (a unit slip).
  expect_refused(fit_args("--free material.E --bounds material.E=1e9:1e300"), "material.E");
  expect_refused(fit_args("--free material.E --bounds material.E=1e9:1e13"), "material.E");
  expect_refused(fit_args("--free material.yield_stress --bounds material.yield_stress=1e6:1e12"), "material.yield_stress");
  // A start outside the bounds is refused, not moved: the key, the start and the bounds named.
  expect_refused(fit_args("--free material.yield_stress --bounds material.yield_stress=1e8:3e8"), "material.yield_stress");
  EXPECT_NE(err().find("starts at 4e+08"), std::string::npos) << err();
  EXPECT_NE(err().find("[1e+08, 3e+08]"), std::string::npos) << err();
  expect_refused(fit_args("--free material.n --set material.n=0.7 --bounds material.n=0.01:0.6"), "material.n");
  // Forces that pull: the sign convention of another instrument.
  std::ofstream(dir_ / "negative.csv") << "alpha,P\n1e-5,-1\n2e-5,-3\n3e-5,-5.5\n";
  expect_refused("fit " + (dir_ / "case.toml").string() + " --data " + (dir_ / "negative.csv").string() +
                     " --free material.yield_stress",
                 "negative");
  // A unit of the other scene: forces (N) for a plane-strain case, N/m for an axisymmetric one.
  std::ofstream(dir_ / "newtons.csv") << "alpha (m),P (N)\n1e-5,1\n2e-5,3\n3e-5,5.5\n";
  expect_refused("fit " + (dir_ / "case.toml").string() + " --data " + (dir_ / "newtons.csv").string() +
                     " --free material.yield_stress --set geometry.kind=plane_strain",
                 "force_unit");
  EXPECT_NE(err().find("plane strain"), std::string::npos) << err();
  EXPECT_NE(err().find("in N ("), std::string::npos) << err();
  std::ofstream(dir_ / "per_metre.csv") << "alpha (m),P (N/m)\n1e-5,1\n2e-5,3\n3e-5,5.5\n";
  expect_refused("fit " + (dir_ / "case.toml").string() + " --data " + (dir_ / "per_metre.csv").string() +
                     " --free material.yield_stress",
                 "force_unit");
  EXPECT_NE(err().find("axisymmetric"), std::string::npos) << err();
}

TEST_F(FitCli, ADenseCurveIsFittedAtThePointsTheModelResolvesAndSaysSo) {
  // 2000 rows between the 20 increments of the case's own curve: without the reduction every run
  // would solve 2000 increments (minutes); with it, about the case's own 20.
  const auto curve = run_curve();
  std::vector<std::pair<double, double>> dense;
  for (int i = 1; i <= 2000; ++i) {
    const double a = curve.back().first * i / 2000;
    std::size_t k = 1;
    while (k + 1 < curve.size() && curve[k].first < a) ++k;
    const double t = (a - curve[k - 1].first) / (curve[k].first - curve[k - 1].first);
    dense.emplace_back(a, (1.0 - t) * curve[k - 1].second + t * curve[k].second);
  }
  const std::string data = write_curve("dense.csv", dense);
  // The reduction is asserted by the note below; the timeout only ends a run that hangs (under the
  // sanitizers on a loaded 2-core machine this fit took over 120 s).
  ASSERT_EQ(cli(fit_of(data, "--set material.e0=0.0026 --out " + (dir_ / "dense").string()), "timeout 600"), 0)
      << err();
  EXPECT_NE(out().find("note: " + data + ": 2000 rows fitted as "), std::string::npos) << out();
  const auto j = fit_json("dense");
  EXPECT_EQ(j["data"][0]["rows"], 2000);
  EXPECT_LE(j["data"][0]["points"].get<int>(), 21);
  EXPECT_EQ(j["quality"], "good");
  EXPECT_NEAR(j["parameters"]["material.yield_stress"]["value"].get<double>() / 400e6, 1.0, 0.03);
}

TEST_F(FitCli, ABadFitExitsThreeWithAWarningPerProblemAndItsVerdictInFitJson) {
  // Forces in mN written as N: a unit warning before the fit, then a poor fit at a bound.
  const std::string data = write_curve("milli.csv", run_curve(), 1e3);
  EXPECT_EQ(cli(fit_of(data, "--set material.e0=0.0026 --quiet --out " + (dir_ / "poor").string())), 3)
      << err();
  EXPECT_NE(err().find("warning: " + data + ": its largest force"), std::string::npos) << err();
  EXPECT_NE(err().find("force unit is probably wrong"), std::string::npos) << err();
  EXPECT_NE(err().find("warning: poor fit: rms "), std::string::npos) << err();
  EXPECT_NE(err().find("warning: poor fit: material.yield_stress at its upper bound"), std::string::npos) << err();
  EXPECT_EQ(out().find("identifiable"), std::string::npos) << out();
  EXPECT_NE(out().find("(quality: poor fit)"), std::string::npos) << out();
  const auto j = fit_json("poor");
  EXPECT_EQ(j["quality"].get<std::string>().rfind("poor fit: rms ", 0), 0u) << j["quality"];
  EXPECT_EQ(j["quality_problems"].size(), 2u);
  EXPECT_EQ(j["identifiable"], false);
  EXPECT_EQ(j["warnings"].size(), 1u);
}

TEST_F(FitCli, FailedForwardRunsAreCountedInOwnWordsWithoutCeresLogLines) {
  // The first forward run fails (injected, whatever its steps): the first start's first evaluation
  // with it, which Ceres logs through glog; the second start fits.
  const std::string data = write_curve("own.csv", run_curve());
  const std::string args =
      fit_of(data, "--set material.e0=0.0026 --bounds material.yield_stress=100e6:2e9 --starts 2 --out " +
                       (dir_ / "counted").string());
  ASSERT_EQ(cli(args, "INDENTSIM_FAULT=fit_run:1"), 0) << err();
  EXPECT_NE(out().find("  1 forward run(s) failed even with steps a sixteenth as long"), std::string::npos) << out();
  for (const char* glog : {"InitGoogleLogging", "trust_region_minimizer", "Terminating"})
    EXPECT_EQ(err().find(glog), std::string::npos) << err();
  EXPECT_EQ(fit_json("counted")["failed_runs"], 1);
  EXPECT_EQ(fit_json("counted")["quality"], "good");
  ASSERT_EQ(cli(args + " --quiet", "INDENTSIM_FAULT=fit_run:1"), 0) << err();
  // -q: nothing but the result, warnings and errors (here the model's own error, larger than the
  // noise-free data's scatter, is warned about).
  std::istringstream lines(err());
  for (std::string line; std::getline(lines, line);) EXPECT_EQ(line.rfind("warning: ", 0), 0u) << line;
  EXPECT_EQ(out().find("run(s) failed"), std::string::npos) << out();
}

TEST_F(FitCli, SigtermStopsTheFitKeepingItsCheckpointAndResumeFinishesItWhereTheWholeFitEnds) {
  // Killed after its first accepted step: the checkpoint is all the folder holds; --resume (the
  // same command) finishes it, with the result of the fit that was never stopped.
  const std::string data = write_curve("own.csv", run_curve());
  const std::filesystem::path out = dir_ / "stopped";
  const std::string args = fit_of(data, "--set material.e0=0.0026 --starts 3 --mesh-refinements 0 --out " + out.string());
  const std::string errors = (dir_ / "err.txt").string();
  const std::string command = "timeout 120 " + std::string(INDENTSIM_CLI) + " " + args + " >/dev/null 2>" + errors +
                              " & pid=$!; for i in $(seq 2400); do grep -q \"iteration  1\" " + errors +
                              " && break; sleep 0.025; done; kill -TERM $pid; wait $pid";
  const int raw = std::system(("bash -c '" + command + "'").c_str());
  ASSERT_TRUE(WIFEXITED(raw));
  ASSERT_EQ(WEXITSTATUS(raw), 128 + SIGTERM) << testing::slurp(errors);
  const std::string stopped = testing::slurp(errors);
  EXPECT_NE(stopped.find("fit stopped by signal 15"), std::string::npos) << stopped;
  EXPECT_NE(stopped.find("the same command with --resume continues it"), std::string::npos) << stopped;
  EXPECT_NE(stopped.find("to fit again from there: --set material.e0="), std::string::npos) << stopped;
  EXPECT_FALSE(std::filesystem::exists(out / "fit.json"));
  ASSERT_TRUE(std::filesystem::exists(out / fit_checkpoint_name));

  // Another fit's checkpoint is refused, naming it, and left as it was.
  EXPECT_EQ(cli(fit_of(data, "--set material.e0=0.003 --starts 3 --mesh-refinements 0 --out " + out.string()) +
                " --resume"),
            2);
  EXPECT_NE(err().find("the checkpoint is another fit's"), std::string::npos) << err();
  ASSERT_TRUE(std::filesystem::exists(out / fit_checkpoint_name));

  ASSERT_EQ(cli(args + " --resume --quiet"), 0) << err();
  EXPECT_FALSE(std::filesystem::exists(out / fit_checkpoint_name));
  const auto resumed = fit_json("stopped");
  ASSERT_EQ(cli(fit_of(data, "--set material.e0=0.0026 --starts 3 --mesh-refinements 0 --quiet --out " +
                                 (dir_ / "whole").string())),
            0)
      << err();
  const auto whole = fit_json("whole");
  const auto& r = resumed["parameters"]["material.yield_stress"];
  const auto& w = whole["parameters"]["material.yield_stress"];
  // The optimiser's trust region starts afresh at the resumed point: the same optimum to its
  // tolerance (a cost change of 1e-6 of itself: far below a standard error).
  EXPECT_NEAR(r["value"].get<double>(), w["value"].get<double>(), 1e-3 * w["std_error_total"].get<double>());
  EXPECT_EQ(resumed["starts"].size(), whole["starts"].size());
}

}  // namespace
}  // namespace indentsim
