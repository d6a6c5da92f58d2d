// The hardening curves of a tensile test under J2 flow theory (docs/MODEL.md §12.1): uniaxial
// tension reproduces each law's sigma(eps_p), the return's tangent against central differences,
// Ilyushin's closed-form return against the generic one on the same curve, the keys that state
// the laws, and whole runs with them (both kinematics, a resumed run, a table against its law).
#include <cmath>
#include <fstream>
#include <functional>
#include <memory>
#include <random>
#include <csignal>

#include <gtest/gtest.h>

#include "indentsim/base/error.hpp"
#include "indentsim/materials/hardening.hpp"
#include "indentsim/materials/material.hpp"
#include "indentsim/materials/material_parameter.hpp"
#include "indentsim/simulation/simulation.hpp"
#include "test_support.hpp"

using namespace indentsim;

namespace {

const ElasticMaterial steel{200e9, 0.3};

/// The laws, each at parameters of a structural metal (sigma_y ~ 300 MPa), with their formula
/// written out here once more: what uniaxial tension must reproduce.
struct NamedCurve {
  const char* name;
  std::shared_ptr<const HardeningCurve> curve;
  std::function<double(double)> formula;
};
std::vector<NamedCurve> curves() {
  const std::vector<std::pair<double, double>> table{{0.0, 300e6}, {0.01, 360e6}, {0.05, 420e6}, {0.2, 480e6}};
  const auto tabulated = [](double e, bool sloped) {
    if (e <= 0.01) return 300e6 + 60e6 * e / 0.01;
    if (e <= 0.05) return 360e6 + 60e6 * (e - 0.01) / 0.04;
    if (e <= 0.2) return 420e6 + 60e6 * (e - 0.05) / 0.15;
    return sloped ? 480e6 + 60e6 * (e - 0.2) / 0.15 : 480e6;
  };
  const double E = steel.E;
  return {{"power_law n=0.2", std::make_shared<PowerLawHardening>(300e6, E, 0.2),
           [E](double e) { return 300e6 * std::pow(1.0 + E * e / 300e6, 0.2); }},
          {"power_law n=0 (perfectly plastic)", std::make_shared<PowerLawHardening>(300e6, E, 0.0),
           [](double) { return 300e6; }},
          {"ludwik", std::make_shared<LudwikHardening>(300e6, 500e6, 0.4),
           [](double e) { return 300e6 + 500e6 * std::pow(e, 0.4); }},
          {"swift", std::make_shared<SwiftHardening>(800e6, 0.01, 0.2),
           [](double e) { return 800e6 * std::pow(0.01 + e, 0.2); }},
          {"voce", std::make_shared<VoceHardening>(300e6, 200e6, 15.0),
           [](double e) { return 300e6 + 200e6 * (1.0 - std::exp(-15.0 * e)); }},
          {"table flat", std::make_shared<TableHardening>(table, TableExtension::flat),
           [=](double e) { return tabulated(e, false); }},
          {"table last_slope", std::make_shared<TableHardening>(table, TableExtension::last_slope),
           [=](double e) { return tabulated(e, true); }}};
}

/// Uniaxial stress along 2 (s11 = s33 = s12 = 0): the lateral strains eps11 = eps33 solved by
/// Newton on the law's own tangent, for a given axial strain, from the history `state`.
J2Response uniaxial(const J2Law& law, double axial, J2State& state) {
  VoigtVector strain(-0.5 * axial, axial, 0.0, -0.5 * axial);
  J2Response r;
  for (int iteration = 0; iteration < 50; ++iteration) {
    r = law.respond(strain, state);
    // Lateral symmetry keeps eps11 = eps33: one unknown, residual s11.
    const double slope = r.tangent(0, 0) + r.tangent(0, 3);
    const double step = -r.stress[0] / slope;
    strain[0] += step;
    strain[3] += step;
    if (std::abs(r.stress[0]) <= 1e-13 * std::abs(r.stress[1])) break;
  }
  r = law.respond(strain, state);
  state = r.state;
  return r;
}


}  // namespace

TEST(Hardening, UniaxialTensionFollowsEachLawsFlowCurveTo1e10) {
  // For plastic strains at, between and beyond a table's points: the axial strain that carries
  // eps_p is eps_p + sigma(eps_p) / E; driven there in 25 steps, the return must land on
  // sigma(eps_p) with that very eps_p.
  for (const auto& [name, curve, formula] : curves()) {
    SCOPED_TRACE(name);
    const J2Law law(steel, curve);
    J2State state;
    double previous = 0.0;
    for (const double eps_p : {0.0005, 0.005, 0.01, 0.03, 0.05, 0.1, 0.2, 0.35}) {
      const double sigma = formula(eps_p);
      const double target = eps_p + sigma / steel.E;
      J2Response r;
      for (int step = 1; step <= 25; ++step) r = uniaxial(law, previous + (target - previous) * step / 25.0, state);
      previous = target;
      EXPECT_TRUE(r.plastic);
      EXPECT_NEAR(r.state.equivalent_plastic_strain, eps_p, 1e-10 * eps_p);
      EXPECT_NEAR(r.stress[1], sigma, 1e-10 * sigma) << "eps_p = " << eps_p;
      EXPECT_NEAR(r.equivalent_stress, sigma, 1e-10 * sigma);
    }
  }
}

TEST(Hardening, TableInterpolatesLinearlyAndExtendsAsTold) {
  const std::vector<std::pair<double, double>> points{{0.0, 300e6}, {0.01, 360e6}, {0.05, 420e6}};
  const TableHardening flat(points, TableExtension::flat), sloped(points, TableExtension::last_slope);
  for (const auto& [eps_p, sigma] : points) EXPECT_DOUBLE_EQ(flat.flow_stress(eps_p), sigma);
  EXPECT_DOUBLE_EQ(flat.flow_stress(0.005), 330e6);
  EXPECT_DOUBLE_EQ(flat.hardening_modulus(0.02), 60e6 / 0.04);
  EXPECT_DOUBLE_EQ(flat.flow_stress(0.5), 420e6);
  EXPECT_EQ(flat.hardening_modulus(0.5), 0.0);
  EXPECT_NEAR(sloped.flow_stress(0.09), 420e6 + 60e6 / 0.04 * 0.04, 1e-6);
  EXPECT_DOUBLE_EQ(sloped.hardening_modulus(0.5), 60e6 / 0.04);
}

TEST(Hardening, ReturnMappingTangentMatchesFiniteDifferencesForEachLaw) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> component(-1.0, 1.0);
  for (const auto& [name, curve, formula] : curves()) {
    SCOPED_TRACE(name);
    const J2Law law(steel, curve);
    const double yield_strain = law.initial_yield() / (3.0 * law.shear_modulus());
    for (int trial = 0; trial < 30; ++trial) {
      const auto direction = [&] { return VoigtVector(component(rng), component(rng), component(rng), component(rng)); };
      const auto scaled = [](VoigtVector d, double e_u) { return VoigtVector(d * (e_u / strain_intensity(d))); };
      const VoigtVector first = scaled(direction(), 4.0 * yield_strain);
      const J2State old = law.respond(first, J2State{}).state;
      for (double size : {0.2, 3.0, 40.0}) {  // an elastic step, a plastic one, a long plastic one
        const VoigtVector strain = first + scaled(direction(), size * yield_strain);
        const J2Response r = law.respond(strain, old);
        // A strain on a table's kink has two one-sided tangents: central differences straddle it.
        if (name == std::string("table flat") || name == std::string("table last_slope")) {
          const double eps_p = r.state.equivalent_plastic_strain;
          bool near_kink = false;
          for (double kink : {0.01, 0.05, 0.2}) near_kink |= std::abs(eps_p - kink) < 1e-6;
          if (near_kink) continue;
        }
        const ConstitutiveMatrix fd =
            indentsim::testing::finite_difference_tangent([&](const VoigtVector& e) { return law.respond(e, old).stress; }, strain);
        const double scale = r.tangent.cwiseAbs().maxCoeff();
        EXPECT_LE((r.tangent - fd).cwiseAbs().maxCoeff(), 1e-6 * scale)
            << "plastic " << r.plastic << "\n" << r.tangent << "\n" << fd;
      }
    }
  }
}

namespace {
/// An Ilyushin law's curve with the generic return (the base class's), not its closed form.
class GenericReturn final : public HardeningCurve {
public:
  explicit GenericReturn(const IlyushinLaw& law) : curve_(law) {}
  double flow_stress(double eps_p) const override { return curve_.flow_stress(eps_p); }
  double hardening_modulus(double eps_p) const override { return curve_.hardening_modulus(eps_p); }

private:
  IlyushinHardening curve_;
};
}  // namespace

TEST(Hardening, IlyushinsClosedFormReturnEqualsTheGenericReturnOnItsCurve) {
  // Checks both: the closed form, and the curve sigma_y(eps_p) the inversion of e_u omega(e_u) makes.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> component(-1.0, 1.0);
  for (const IlyushinLaw& ilyushin : {IlyushinLaw(steel, 0.004, HardeningLaw::linear, 0.9, 0.3),
                                      IlyushinLaw(steel, 0.004, HardeningLaw::power, 0.9, 0.2)}) {
    const J2Law closed(ilyushin);
    const J2Law generic(steel, std::make_shared<GenericReturn>(ilyushin));
    for (int trial = 0; trial < 40; ++trial) {
      const VoigtVector d(component(rng), component(rng), component(rng), component(rng));
      const VoigtVector strain = d * (6.0 * 0.004 / strain_intensity(d));
      J2State state_closed, state_generic;
      for (int step = 1; step <= 4; ++step) {
        const J2Response a = closed.respond(strain * (step / 4.0), state_closed);
        const J2Response b = generic.respond(strain * (step / 4.0), state_generic);
        EXPECT_LE((a.stress - b.stress).norm(), 1e-10 * a.stress.norm());
        EXPECT_NEAR(a.state.equivalent_plastic_strain, b.state.equivalent_plastic_strain,
                    1e-10 * a.state.equivalent_plastic_strain);
        EXPECT_LE((a.tangent - b.tangent).cwiseAbs().maxCoeff(), 1e-8 * a.tangent.cwiseAbs().maxCoeff());
        state_closed = a.state;
        state_generic = b.state;
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
namespace {
std::string j2_case(const std::string& material_lines) {
  return std::string(R"(
[geometry]
kind = "axisymmetric"
lx = 10e-3
ly = 10e-3
[punch]
radius = 1e-3
[material]
model = "j2"
E = 200e9
nu = 0.3
)") + material_lines + R"(
[load]
path = [0.0, 20e-6]
increments = 5
[mesh]
contact_nodes = 8
)";
}

void expect_refused(const std::string& toml, const std::string& key, const std::string& words) {
  try {
    parse_load_case(toml, "case.toml");
    ADD_FAILURE() << "accepted:\n" << toml;
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), key) << e.what();
    EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
  }
}
}  // namespace

TEST(HardeningInput, EachLawTakesItsOwnKeysAndRefusesOthersNamingTheKey) {
  EXPECT_NO_THROW(parse_load_case(j2_case("hardening = \"power_law\"\nyield_stress = 300e6\nn = 0"), "case.toml"));
  EXPECT_NO_THROW(parse_load_case(j2_case("hardening = \"ludwik\"\nyield_stress = 300e6\nK = 500e6\nn = 0.4"), "c"));
  EXPECT_NO_THROW(parse_load_case(j2_case("hardening = \"swift\"\nK = 800e6\nprestrain = 0.01\nn = 0.2"), "c"));
  EXPECT_NO_THROW(parse_load_case(j2_case("hardening = \"voce\"\nyield_stress = 300e6\nQ = 2e8\nb = 15"), "c"));
  expect_refused(j2_case("hardening = \"voce\"\nyield_stress = 300e6\nQ = 2e8"), "material.b", "missing key");
  expect_refused(j2_case("hardening = \"voce\"\nQ = 2e8\nb = 15\nK = 1e8"), "material.K", "belongs to \"ludwik\"");
  expect_refused(j2_case("hardening = \"swift\"\nK = 8e8\nprestrain = 0.01\nyield_stress = 3e8"),
                 "material.yield_stress", "K prestrain^n");
  expect_refused(j2_case("hardening = \"ludwik\"\nK = 5e8\nn = 0"), "material.n", "jumps");
  expect_refused(j2_case("hardening = \"swift\"\nK = 8e8\nprestrain = 1.5"), "material.prestrain", "(0, 1)");
  // A flow curve is J2's: Ilyushin's deformation theory takes omega(e_u).
  std::string ilyushin = j2_case("hardening = \"power_law\"\nn = 0.2");
  ilyushin.replace(ilyushin.find("\"j2\""), 4, "\"ilyushin\"");
  expect_refused(ilyushin, "material.hardening", "material.model = \"j2\"");
  // A table: from eps_p = 0, eps_p increasing, sigma not falling; exactly one of file and points.
  expect_refused(j2_case("hardening = \"table\"\nhardening_points = [[0.0, 3e8], [0.1, 2e8]]"),
                 "material.hardening_points", "must not fall");
  expect_refused(j2_case("hardening = \"table\"\nhardening_points = [[0.01, 3e8], [0.1, 4e8]]"),
                 "material.hardening_points", "eps_p = 0");
  expect_refused(j2_case("hardening = \"table\"\nhardening_points = [[0.0, 3e8], [0.0, 4e8]]"),
                 "material.hardening_points", "must increase");
  expect_refused(j2_case("hardening = \"table\""), "material.hardening_table", "exactly one");
  expect_refused(j2_case("hardening = \"table\"\nhardening_points = [[0.0, 3e8], [0.1, 4e8]]\ne0 = 0.002"),
                 "material.e0", "first sigma");
  // case.toml holds each law's keys and nothing of another's: it reads back to the same case.
  const LoadCase swift = parse_load_case(j2_case("hardening = \"swift\"\nK = 8e8\nprestrain = 0.01\nn = 0.2"), "c");
  const LoadCase again = parse_load_case(to_toml(swift), "case.toml");
  EXPECT_EQ(first_physics_difference(swift, again), "");
  EXPECT_EQ(to_toml(swift).find("\ne0 ="), std::string::npos);
  EXPECT_EQ(to_toml(swift).find("\nQ ="), std::string::npos);
}

TEST(HardeningInput, AFitFreesTheParametersOfTheCasesLawAndNamesThemWhenAskedForAnothers) {
  const LoadCase ludwik = parse_load_case(j2_case("hardening = \"ludwik\"\nyield_stress = 3e8\nK = 5e8\nn = 0.4"), "c");
  for (const auto p : {MaterialParameter::E, MaterialParameter::yield_stress, MaterialParameter::K, MaterialParameter::n})
    EXPECT_FALSE(inapplicable(ludwik.material, p)) << key_of(p);
  const auto why = inapplicable(ludwik.material, MaterialParameter::Q);
  ASSERT_TRUE(why);
  EXPECT_NE(why->find("material.K"), std::string::npos) << *why;
  EXPECT_NE(why->find("\"ludwik\""), std::string::npos) << *why;
  // set_value reaches the law: K doubled, the flow stress beyond yield rises by K eps_p^n more.
  MaterialInput m = ludwik.material;
  set_value(m, MaterialParameter::K, 1e9);
  EXPECT_NEAR(make_hardening_curve(m)->flow_stress(0.01), 3e8 + 1e9 * std::pow(0.01, 0.4), 1e-3);
  const LoadCase table = parse_load_case(j2_case("hardening = \"table\"\nhardening_points = [[0.0, 3e8], [0.1, 4e8]]"), "c");
  ASSERT_TRUE(inapplicable(table.material, MaterialParameter::yield_stress));
}

TEST(HardeningRun, ATableSampledFromAPowerLawIndentsAsThePowerLawDoes) {
  // 300 points of sigma_y (1 + E eps_p / sigma_y)^n spaced evenly in log(eps_p) from 1e-7 to 2:
  // linear interpolation errs there by about (d ln eps)^2 n (1 - n) / 8 ~ 2e-5 of sigma, so the
  // force of a run on the table agrees with the law's to a few 1e-5; 8 points err by percents.
  const auto table_of = [](int points) {
    std::vector<std::pair<double, double>> t{{0.0, 300e6}};
    for (int k = 0; k < points; ++k) {
      const double eps_p = 1e-7 * std::pow(2e7, k / (points - 1.0));
      t.emplace_back(eps_p, 300e6 * std::pow(1.0 + 200e9 * eps_p / 300e6, 0.2));
    }
    return t;
  };
  for (const SceneKind scene : {SceneKind::axisymmetric, SceneKind::plane_strain}) {
    SCOPED_TRACE(to_string(scene));
    LoadCase law = indentsim::testing::small_sphere_case(scene, MaterialModel::j2, HardeningLaw::power_law);
    law.material.yield_stress = 300e6;
    law.material.e0 = e0_of_yield_stress(300e6, law.material.E, law.material.nu);
    LoadCase fine = law, coarse = law;
    fine.material.hardening = coarse.material.hardening = HardeningLaw::table;
    fine.material.hardening_points = table_of(300);
    coarse.material.hardening_points = table_of(8);
    validate(fine);
    const auto forces = [](const LoadCase& lc) {
      Simulation sim(lc);
      std::vector<double> p;
      sim.run([&](const IncrementRecord& r) { p.push_back(r.force); });
      return p;
    };
    const std::vector<double> p_law = forces(law), p_fine = forces(fine), p_coarse = forces(coarse);
    ASSERT_EQ(p_law.size(), p_fine.size());
    double fine_error = 0.0, coarse_error = 0.0;
    for (std::size_t k = 1; k < p_law.size(); ++k) {
      fine_error = std::max(fine_error, std::abs(p_fine[k] / p_law[k] - 1.0));
      coarse_error = std::max(coarse_error, std::abs(p_coarse[k] / p_law[k] - 1.0));
    }
    RecordProperty("fine_table_error", std::to_string(fine_error));
    RecordProperty("coarse_table_error", std::to_string(coarse_error));
    EXPECT_LT(fine_error, 2e-4);
    EXPECT_GT(coarse_error, 10 * fine_error);  // the comparison can see a table's error
  }
}

class HardeningCli : public indentsim::testing::CliTest {};

TEST_F(HardeningCli, ATableFromACsvRunsStopsAndResumesWithoutItsFile) {
  // A tensile test's curve in a CSV with a header; the run is killed after increment 4 (loading)
  // and after 9 (unloading), the CSV deleted, and the resumed run (from case.toml, which holds the
  // points) must end where the uninterrupted one did.
  const auto write_case = [&](const std::filesystem::path& folder) {
    std::filesystem::create_directories(folder);
    std::ofstream(folder / "tensile.csv") << "eps_p,sigma\n0,300e6\n0.01,360e6\n0.05,420e6\n0.2,480e6\n";
    std::string toml = j2_case("hardening = \"table\"\nhardening_table = \"tensile.csv\"\ntable_extension = "
                               "\"last_slope\"");
    toml.replace(toml.find("path = [0.0, 20e-6]"), 19, "path = [0.0, 20e-6, 5e-6]");
    toml.replace(toml.find("increments = 5"), 14, "increments = [6, 6]");
    std::ofstream(folder / "case.toml") << toml << "[output]\ncheckpoint_every = 2\n";
    return (folder / "case.toml").string();
  };
  ASSERT_EQ(cli("run " + write_case(dir_ / "full") + " --quiet --out " + (dir_ / "full" / "out").string()), 0) << err();
  const std::string expected = indentsim::testing::curve_without_timing(dir_ / "full" / "out" / "curve.csv");
  EXPECT_NE(indentsim::testing::slurp(dir_ / "full" / "out" / "case.toml").find("hardening_points = [[0.0, 300000000.0]"),
            std::string::npos);
  for (const char* fault : {"increment:4", "increment:9"}) {
    SCOPED_TRACE(fault);
    const auto folder = dir_ / (std::string("killed_") + fault[10]);
    const std::string source = write_case(folder);
    EXPECT_EQ(cli("run " + source + " --quiet --out " + (folder / "out").string(), std::string("INDENTSIM_FAULT=") + fault),
              128 + SIGKILL);
    std::filesystem::remove(folder / "tensile.csv");
    ASSERT_EQ(cli("resume " + (folder / "out" / "checkpoints").string() + " --quiet"), 0) << err();
    EXPECT_EQ(indentsim::testing::curve_without_timing(folder / "out" / "curve.csv"), expected);
  }
  // summary.json states the law and the yield stress it starts from.
  const std::string summary = indentsim::testing::slurp(dir_ / "full" / "out" / "summary.json");
  EXPECT_NE(summary.find("\"hardening\": \"table\""), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"yield_stress\": 300000000.0"), std::string::npos) << summary;
  // A CSV row that is no number is named with its row and column.
  std::ofstream(dir_ / "full" / "tensile.csv") << "eps_p,sigma\n0,300e6\n0.01,abc\n";
  EXPECT_EQ(cli("run " + (dir_ / "full" / "case.toml").string() + " --quiet --out " + (dir_ / "bad").string()), 2);
  EXPECT_NE(err().find("material.hardening_table"), std::string::npos) << err();
  EXPECT_NE(err().find("row 3: sigma"), std::string::npos) << err();
  EXPECT_FALSE(std::filesystem::exists(dir_ / "bad"));
}
