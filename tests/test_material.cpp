// Ilyushin's secant law: the consistent tangent against finite differences of the stress, the
// uniaxial curve's post-yield slope, the elastic branch, and the admissibility check.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "indentsim/materials/material.hpp"
#include "test_support.hpp"

using namespace indentsim;

namespace {

const ElasticMaterial steel{210e9, 0.3};

// A strain of direction `direction` scaled to strain intensity `e_u`.
VoigtVector strain_with_intensity(VoigtVector direction, double e_u) {
  return direction * (e_u / strain_intensity(direction));
}


void expect_tangent_matches(const IlyushinLaw& law, double e0) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> component(-1.0, 1.0);
  // Elastic, just yielded, moderately and deeply plastic.
  for (double factor : {0.5, 1.02, 3.0, 50.0}) {
    for (int trial = 0; trial < 50; ++trial) {
      const VoigtVector strain =
          strain_with_intensity(VoigtVector(component(rng), component(rng), component(rng), component(rng)), factor * e0);
      const SecantResponse r = law.respond(strain);
      EXPECT_EQ(r.plastic, factor > 1.0);
      const ConstitutiveMatrix fd =
          indentsim::testing::finite_difference_tangent([&](const VoigtVector& e) { return law.respond(e).stress; }, strain);
      const double scale = r.tangent.cwiseAbs().maxCoeff();
      EXPECT_LE((r.tangent - fd).cwiseAbs().maxCoeff(), 1e-6 * scale)
          << "e_u / e0 = " << factor << "\ntangent\n" << r.tangent << "\nfinite differences\n" << fd;
      EXPECT_LE((r.tangent - r.tangent.transpose()).cwiseAbs().maxCoeff(), 1e-12 * scale);
    }
  }
}

}  // namespace

TEST(Ilyushin, StrainIntensityIsTheVonMisesEquivalentStrain) {
  // sqrt(2/3 e:e) with the deviator of the 3-D strain: plane strain (eps33 = 0) and a hoop strain.
  for (const VoigtVector& s : {VoigtVector(3e-3, -1e-3, 4e-3, 0.0), VoigtVector(3e-3, -1e-3, 4e-3, 2.5e-3)}) {
    const double tr = s[0] + s[1] + s[3];
    const double e11 = s[0] - tr / 3, e22 = s[1] - tr / 3, e33 = s[3] - tr / 3, e12 = s[2] / 2;
    const double expected = std::sqrt(2.0 / 3.0 * (e11 * e11 + e22 * e22 + e33 * e33 + 2 * e12 * e12));
    EXPECT_NEAR(strain_intensity(s), expected, 1e-15);
  }
}

TEST(Ilyushin, LinearLawTangentMatchesFiniteDifferences) {
  expect_tangent_matches(IlyushinLaw(steel, 0.027, HardeningLaw::linear, 0.9, 0.3), 0.027);
}

TEST(Ilyushin, PowerLawTangentMatchesFiniteDifferences) {
  expect_tangent_matches(IlyushinLaw(steel, 0.005, HardeningLaw::power, 0.9, 0.2), 0.005);
}

TEST(Ilyushin, ElasticBranchIsHookesLaw) {
  const IlyushinLaw law(steel, 0.027, HardeningLaw::linear, 0.9, 0.3);
  const VoigtVector strain = strain_with_intensity(VoigtVector(1, -0.3, 0.2, 0.4), 0.02);
  const SecantResponse r = law.respond(strain);
  EXPECT_FALSE(r.plastic);
  EXPECT_EQ(r.omega, 0.0);
  EXPECT_LE((r.stress - steel.stiffness() * strain).norm(), 1e-12 * r.stress.norm());
  EXPECT_LE((r.tangent - steel.stiffness()).cwiseAbs().maxCoeff(), 1e-3);
}

TEST(Ilyushin, UniaxialCurveHasThePostYieldSlopeOfTheLaw) {
  // Linear law: d sigma_u / d e_u = (1 - kappa) 3 mu beyond e0 (MODEL.md).
  const double kappa = 0.9, e0 = 0.027, mu = steel.lame().mu;
  const IlyushinLaw law(steel, e0, HardeningLaw::linear, kappa, 0.3);
  const double h = 1e-6;
  for (double e_u : {1.5 * e0, 4 * e0, 30 * e0}) {
    const double slope = (law.stress_intensity(e_u + h) - law.stress_intensity(e_u - h)) / (2 * h);
    EXPECT_NEAR(slope, (1 - kappa) * 3 * mu, 1e-6 * 3 * mu);
  }
  // Power law: sigma_u ~ e_u^n beyond e0, continuous at e0.
  const double n = 0.2;
  const IlyushinLaw power(steel, e0, HardeningLaw::power, kappa, n);
  EXPECT_NEAR(power.stress_intensity(e0), 3 * mu * e0, 1e-9 * 3 * mu * e0);
  EXPECT_NEAR(power.stress_intensity(8 * e0) / power.stress_intensity(e0), std::pow(8.0, n), 1e-12);
}

TEST(Ilyushin, AdmissibilityHoldsForValidLawsAndCatchesABadOne) {
  EXPECT_FALSE(IlyushinLaw(steel, 0.027, HardeningLaw::linear, 0.9, 0.3).admissibility_violation());
  EXPECT_FALSE(IlyushinLaw(steel, 0.002, HardeningLaw::power, 0.9, 0.05).admissibility_violation());
  EXPECT_FALSE(IlyushinLaw(steel, 0.002, HardeningLaw::linear, 0.0, 0.3).admissibility_violation());
  // kappa = 1 is perfect plasticity: d(e_u omega)/de_u = 1, outside Ilyushin's conditions.
  EXPECT_TRUE(IlyushinLaw(steel, 0.027, HardeningLaw::linear, 1.0, 0.3).admissibility_violation());
}

namespace {
const IlyushinLaw j2_curves[] = {IlyushinLaw(steel, 0.004, HardeningLaw::linear, 0.9, 0.3),
                                 IlyushinLaw(steel, 0.004, HardeningLaw::power, 0.9, 0.2)};
}

TEST(J2, ProportionalStrainPathReproducesIlyushinExactly) {
  for (const IlyushinLaw& curve : j2_curves) {
    const J2Law j2(curve);
    for (const VoigtVector& direction : {VoigtVector(1.0, -0.4, 0.3, 0.0), VoigtVector(-1.0, -0.2, 0.0, 0.5),
                                        VoigtVector(0.1, 0.2, 1.0, -0.7)}) {
      const VoigtVector final_strain = strain_with_intensity(direction, 12 * curve.elastic_limit());
      J2State state;
      for (int step = 1; step <= 40; ++step) {
        const VoigtVector strain = final_strain * (step / 40.0);
        const J2Response r = j2.respond(strain, state);
        state = r.state;
        const SecantResponse ilyushin = curve.respond(strain);
        EXPECT_LE((r.stress - ilyushin.stress).norm(), 1e-10 * ilyushin.stress.norm()) << "step " << step;
        EXPECT_EQ(r.plastic, ilyushin.plastic);
      }
      // In one step as well: radial return from the virgin state lands on the same point.
      const J2Response once = j2.respond(final_strain, J2State{});
      EXPECT_LE((once.stress - curve.respond(final_strain).stress).norm(), 1e-10 * once.stress.norm());
    }
  }
}

TEST(J2, ReturnMappingTangentMatchesFiniteDifferences) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> component(-1.0, 1.0);
  for (const IlyushinLaw& curve : j2_curves) {
    const J2Law j2(curve);
    for (int trial = 0; trial < 40; ++trial) {
      // A history from a first plastic step, then a step in another direction.
      const VoigtVector first = strain_with_intensity(VoigtVector(component(rng), component(rng), component(rng), component(rng)),
                                                      5 * curve.elastic_limit());
      const J2State old = j2.respond(first, J2State{}).state;
      for (double size : {0.2, 3.0}) {  // an elastic unloading step and a plastic step
        const VoigtVector strain =
            first + strain_with_intensity(VoigtVector(component(rng), component(rng), component(rng), component(rng)),
                                          size * curve.elastic_limit());
        const J2Response r = j2.respond(strain, old);
        const ConstitutiveMatrix fd =
            indentsim::testing::finite_difference_tangent([&](const VoigtVector& e) { return j2.respond(e, old).stress; }, strain);
        const double scale = r.tangent.cwiseAbs().maxCoeff();
        EXPECT_LE((r.tangent - fd).cwiseAbs().maxCoeff(), 1e-6 * scale)
            << "plastic " << r.plastic << "\n" << r.tangent << "\n" << fd;
      }
    }
  }
}
