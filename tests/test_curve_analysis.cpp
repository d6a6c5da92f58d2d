// indentsim analyze: measured load-depth curves (columns, units, branches by the force) and a
// run's own folder.  The synthetic measured test is built from the power law itself, so Oliver
// and Pharr's numbers are known in closed form; the bad files must be refused, naming the file
// and the problem, with nothing written.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <random>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "indentsim/analysis/curve_analysis.hpp"
#include "indentsim/base/error.hpp"
#include "test_support.hpp"

using namespace indentsim;
using namespace indentsim::testing;

namespace {

/// A Berkovich-equivalent cone's test as an instrument would export it: a metadata line, a
/// tab-separated header with units, loading P = C h^2 (Kick) to h_max, a hold with creep, then
/// the unloading P = B (h - h_f)^m with 0.05% noise in the force.
struct SyntheticTest {
  double h_max = 1000e-9, h_f = 720e-9, m = 1.38, P_max = 20e-3, creep = 2e-9;
  double B() const { return P_max / std::pow(h_max - h_f, m); }
  double stiffness() const { return m * P_max / (h_max - h_f); }

  std::string csv(double depth_scale, double force_scale, const std::string& header) const {
    std::mt19937 random(7);
    std::normal_distribution<double> noise(0.0, 5e-4);
    std::string text = "Instrument: synthetic\t\t\n" + header + "\n";
    double time = 0.0;
    const auto row = [&](double h, double P) {
      text += fmt::format("{:.9g}\t{:.9g}\t{:.3f}\n", h / depth_scale, P / force_scale, time);
      time += 0.1;
    };
    const double h_load = h_max - creep;
    for (int k = 0; k <= 60; ++k) {
      const double h = h_load * k / 60.0;
      row(h, P_max * (h / h_load) * (h / h_load));
    }
    for (int k = 1; k <= 10; ++k) row(h_load + creep * k / 10.0, P_max * (1.0 + 2e-4 * noise(random)));
    for (int k = 1; k <= 80; ++k) {
      const double P = P_max * (1.0 - k / 80.0);
      const double h = h_f + std::pow(P / B(), 1.0 / m);
      row(h, k == 80 ? 0.0 : P * (1.0 + noise(random)));
    }
    return text;
  }
};

class MeasuredCurve : public CliTest {
protected:
  std::filesystem::path write(const std::string& name, const std::string& text) {
    const auto path = dir_ / name;
    std::ofstream(path) << text;
    return path;
  }
  AnalysisSetup cone_setup(const std::vector<std::string>& more = {}) {
    std::vector<std::string> overrides{"punch.shape=\"cone\"", "punch.half_angle=70.3", "curve.depth_column=\"depth\"",
                                       "curve.force_column=\"load\""};
    overrides.insert(overrides.end(), more.begin(), more.end());
    return read_analysis_setup(std::nullopt, overrides);
  }
  SyntheticTest test;
};

}  // namespace

TEST_F(MeasuredCurve, OliverPharrOfASyntheticConeTestIsTheClosedForm) {
  const auto file = write("cone.txt", test.csv(1e-9, 1e-3, "Depth (nm)\tLoad (mN)\tTime (s)"));
  const CurveAnalysis c = analyze_measured_curve(file, cone_setup());
  ASSERT_EQ(c.branches.size(), 1u);  // the hold's noise is not a branch
  const BranchAnalysis& a = c.branches[0].result;
  // Closed form: S = m P_max / (h_max - h_f), h_c = h_max - 0.72 P_max / S, A = pi tan^2 h_c^2.
  const double S = test.stiffness(), h_c = test.h_max - 0.72 * test.P_max / S;
  const double tan_theta = std::tan(70.3 * std::numbers::pi / 180.0);
  const double area = std::numbers::pi * tan_theta * tan_theta * h_c * h_c;
  EXPECT_NEAR(a.h_max / test.h_max, 1.0, 1e-6);
  EXPECT_NEAR(a.P_max / test.P_max, 1.0, 1e-3);  // the last point of the hold
  EXPECT_NEAR(a.fit.stiffness / S, 1.0, 0.01);
  EXPECT_NEAR(a.fit.m / test.m, 1.0, 0.02);
  EXPECT_NEAR(a.h_c / h_c, 1.0, 0.003);
  EXPECT_NEAR(a.area / area, 1.0, 0.006);
  EXPECT_NEAR(a.hardness / (test.P_max / area), 1.0, 0.006);
  ASSERT_TRUE(a.reduced_modulus);
  EXPECT_NEAR(*a.reduced_modulus / (std::sqrt(std::numbers::pi) / 2.0 * S / std::sqrt(area)), 1.0, 0.01);
  EXPECT_FALSE(a.specimen_modulus);  // no material.nu given
  EXPECT_FALSE(a.pile_up_ratio);     // a measured curve has no true area
  EXPECT_EQ(c.depth_unit, "nm");
  EXPECT_EQ(c.force_unit, "mN");
}

TEST_F(MeasuredCurve, UnitsGivenOrReadFromTheHeaderGiveTheSameNumbers) {
  const auto in_nm = write("nm.txt", test.csv(1e-9, 1e-3, "Depth (nm)\tLoad (mN)\tTime (s)"));
  const auto in_um = write("um.txt", test.csv(1e-6, 1e-6, "depth\tload\ttime"));
  const CurveAnalysis a = analyze_measured_curve(in_nm, cone_setup());
  const CurveAnalysis b = analyze_measured_curve(in_um, cone_setup({"curve.depth_unit=\"um\"", "curve.force_unit=\"uN\""}));
  EXPECT_NEAR(b.branches[0].result.hardness / a.branches[0].result.hardness, 1.0, 1e-6);
  EXPECT_NEAR(*b.branches[0].result.reduced_modulus / *a.branches[0].result.reduced_modulus, 1.0, 1e-6);
  // The specimen modulus with a diamond indenter: 1/E_r = (1 - nu^2)/E + (1 - nu_i^2)/E_i.
  const CurveAnalysis d = analyze_measured_curve(in_nm, cone_setup({"material.nu=0.3", "analysis.indenter_E=1141e9"}));
  const double E_r = *d.branches[0].result.reduced_modulus, E = *d.branches[0].result.specimen_modulus;
  EXPECT_NEAR((1 - 0.09) / E + (1 - 0.07 * 0.07) / 1141e9, 1.0 / E_r, 1e-9 / E_r);
}

// A spreadsheet's export of the same test: a UTF-8 byte-order mark before the header (no metadata
// line), semicolons and Windows line ends.  The header's first field must still be "Depth".
TEST_F(MeasuredCurve, AByteOrderMarkSemicolonsAndWindowsLineEndsReadAsThePlainFile) {
  const std::string plain = test.csv(1e-9, 1e-3, "Depth (nm)\tLoad (mN)\tTime (s)");
  std::string exported = "\xEF\xBB\xBF" + plain.substr(plain.find('\n') + 1);
  std::replace(exported.begin(), exported.end(), '\t', ';');
  std::string windows;
  for (char c : exported) windows += c == '\n' ? std::string("\r\n") : std::string(1, c);
  const CurveAnalysis a = analyze_measured_curve(write("plain.txt", plain), cone_setup());
  const CurveAnalysis b = analyze_measured_curve(write("export.csv", windows), cone_setup());
  ASSERT_EQ(b.branches.size(), 1u);
  EXPECT_EQ(b.branches[0].result.hardness, a.branches[0].result.hardness);
  EXPECT_EQ(*b.branches[0].result.reduced_modulus, *a.branches[0].result.reduced_modulus);
  EXPECT_EQ(b.depth_unit, "nm");
}

// A load-controlled test with a hold: the depth creeps at a constant rate c through the hold and
// on through an unloading at a constant rate r, whose elastic stiffness is S_e.  The unloading
// curve is then the straight line of slope S_u = 1 / (1/S_e - c/r), too stiff by 11% here (the
// "nose" of an unloading begun too soon), and Feng and Ngan's correction 1/S_e = 1/S_u + c/r
// gives S_e back: exactly, but for the 9 digits the file is written with.
TEST_F(MeasuredCurve, AHoldsCreepIsMeasuredAndFengNgansCorrectionGivesTheElasticStiffnessBack) {
  const double P_max = 20e-3, h_load = 1000e-9, creep_rate = 1e-9, unloading_rate = 1e-3, S_e = 1e5;
  std::string text = "Time (s);Depth (nm);Load (mN)\n";
  const auto row = [&](double t, double h, double P) { text += fmt::format("{:.9g};{:.9g};{:.9g}\n", t, h / 1e-9, P / 1e-3); };
  for (int k = 0; k <= 60; ++k) row(0.1 * k, h_load * k / 60.0, P_max * (k / 60.0) * (k / 60.0));
  const double t_hold = 6.0, hold = 20.0;
  for (int k = 1; k <= 40; ++k) row(t_hold + hold * k / 40.0, h_load + creep_rate * hold * k / 40.0, P_max);
  const double t_unload = t_hold + hold, h_peak = h_load + creep_rate * hold;
  for (int k = 1; k <= 80; ++k) {
    const double t = t_unload + 20.0 * k / 80.0, P = P_max - unloading_rate * (t - t_unload);
    row(t, h_peak + (P - P_max) / S_e + creep_rate * (t - t_unload), std::max(P, 0.0));
  }
  const auto file = write("hold.csv", text);
  const CurveAnalysis c = analyze_measured_curve(file, cone_setup({"curve.time_column=\"time\""}));
  ASSERT_EQ(c.branches.size(), 1u);
  const BranchAnalysis& a = c.branches[0].result;
  ASSERT_TRUE(a.hold);
  EXPECT_NEAR(a.hold->duration, hold, 1e-9);
  EXPECT_NEAR(a.hold->creep_depth / (creep_rate * hold), 1.0, 1e-6);
  EXPECT_NEAR(a.hold->depth_rate / creep_rate, 1.0, 1e-6);
  ASSERT_TRUE(a.hold->unloading_rate);
  EXPECT_NEAR(*a.hold->unloading_rate / unloading_rate, 1.0, 1e-6);
  EXPECT_NEAR(a.fit.stiffness / (1.0 / (1.0 / S_e - creep_rate / unloading_rate)), 1.0, 1e-4);
  ASSERT_TRUE(a.hold->stiffness);
  EXPECT_NEAR(*a.hold->stiffness / S_e, 1.0, 1e-4);
  ASSERT_TRUE(a.hold->corrected && a.hold->corrected->reduced_modulus && a.reduced_modulus);
  EXPECT_LT(*a.hold->corrected->reduced_modulus, *a.reduced_modulus);  // creep made E_r look higher
  // Without the time column the curve is analysed as before, and has no hold.
  const CurveAnalysis untimed = analyze_measured_curve(file, cone_setup());
  EXPECT_FALSE(untimed.branches[0].result.hold);
  EXPECT_EQ(untimed.branches[0].result.fit.stiffness, a.fit.stiffness);
}

// A power-law creeping solid under a self-similar tip at constant load creeps as
// h = c (t - t_s)^(1/(2n)) (the similarity solution; Bower et al. 1993): h'/h = 1/(2n (t - t_s))
// and H ~ P/h^2 ~ (t - t_s)^(-1/n), so Mayo and Nix's / Lucas and Oliver's
// d ln(h'/h) / d ln H over the hold is n itself.  The hold's central differences in time err at
// second order in its 200 steps.  A sphere is not self-similar: no exponent.
TEST_F(MeasuredCurve, AHoldCreepingAsTheSimilaritySolutionGivesItsStressExponentBack) {
  const double P_max = 20e-3, h_load = 1000e-9, n = 4.0, t_s = -2.0, t_hold = 6.0, hold = 30.0;
  std::string text = "Time (s);Depth (nm);Load (mN)\n";
  const auto row = [&](double t, double h, double P) { text += fmt::format("{:.12g};{:.12g};{:.12g}\n", t, h / 1e-9, P / 1e-3); };
  for (int k = 0; k <= 60; ++k) row(t_hold * k / 60.0, h_load * k / 60.0, P_max * (k / 60.0) * (k / 60.0));
  const auto creep = [&](double t) { return h_load * std::pow((t - t_s) / (t_hold - t_s), 1.0 / (2.0 * n)); };
  for (int k = 1; k <= 200; ++k) row(t_hold + hold * k / 200.0, creep(t_hold + hold * k / 200.0), P_max);
  const double t_unload = t_hold + hold, h_peak = creep(t_unload);
  for (int k = 1; k <= 40; ++k)
    row(t_unload + 0.1 * k, h_peak - 200e-9 * k / 40.0, P_max * std::pow(1.0 - k / 40.0, 1.5));
  const auto file = write("similar.csv", text);
  const CurveAnalysis c = analyze_measured_curve(file, cone_setup({"curve.time_column=\"time\""}));
  ASSERT_EQ(c.branches.size(), 1u);
  ASSERT_TRUE(c.branches[0].result.hold);
  ASSERT_TRUE(c.branches[0].result.hold->stress_exponent);
  EXPECT_NEAR(*c.branches[0].result.hold->stress_exponent / n, 1.0, 1e-3);
  const CurveAnalysis sphere = analyze_measured_curve(
      file, read_analysis_setup(std::nullopt, {"punch.shape=\"sphere\"", "punch.radius=10e-6", "curve.depth_column=\"depth\"",
                                               "curve.force_column=\"load\"", "curve.time_column=\"time\""}));
  ASSERT_TRUE(sphere.branches.size() == 1u && sphere.branches[0].result.hold);
  EXPECT_FALSE(sphere.branches[0].result.hold->stress_exponent);
}

TEST_F(MeasuredCurve, TheCliWritesAnalysisJsonWithUnits) {
  const auto file = write("cone.csv", test.csv(1e-9, 1e-3, "Depth (nm)\tLoad (mN)\tTime (s)"));
  write("berkovich.toml", "[punch]\nshape = \"cone\"\nhalf_angle = 70.3\n[analysis]\nbeta = 1.034\n"
                          "[curve]\ndepth_column = \"Depth\"\nforce_column = \"Load\"\n");
  ASSERT_EQ(cli("analyze " + file.string() + " --indenter " + (dir_ / "berkovich.toml").string()), 0) << err();
  const auto json = nlohmann::json::parse(slurp(dir_ / "cone.analysis.json"));
  EXPECT_EQ(json["units"]["stress"], "Pa");
  EXPECT_EQ(json["branches"].size(), 1u);
  EXPECT_DOUBLE_EQ(json["branches"][0]["beta"].get<double>(), 1.034);
  EXPECT_NE(out().find("E_r"), std::string::npos);
  // The terminal speaks the file's units (nm, mN), analysis.json SI: P_max and h_max as read.
  EXPECT_NE(out().find("depths in nm, forces in mN"), std::string::npos) << out();
  const double P_max = json["branches"][0]["P_max"].get<double>(), h_max = json["branches"][0]["h_max"].get<double>();
  EXPECT_NE(out().find(fmt::format("P_max = {:.5g} mN, h_max = {:.5g} nm", P_max / 1e-3, h_max / 1e-9)),
            std::string::npos)
      << out();
  const double H = json["branches"][0]["H"].get<double>();
  EXPECT_NE(out().find(H >= 1e9 ? fmt::format("H = {:.5g} GPa", H / 1e9) : fmt::format("H = {:.5g} MPa", H / 1e6)),
            std::string::npos)
      << out();
}

TEST_F(MeasuredCurve, BadFilesAreRefusedNamingTheFileAndTheProblem) {
  const std::string flags = " --set punch.shape=cone --set punch.half_angle=70.3 --depth-column depth --force-column load";
  const auto refused = [&](const std::string& name, const std::string& text, const std::string& problem,
                           const std::string& extra = "") {
    SCOPED_TRACE(name);
    const auto file = write(name, text);
    const auto json = dir_ / "never.json";
    EXPECT_EQ(cli("analyze " + file.string() + flags + extra + " --out " + json.string()), 2) << err();
    EXPECT_NE(err().find(name), std::string::npos) << err();
    EXPECT_NE(err().find(problem), std::string::npos) << err();
    EXPECT_FALSE(std::filesystem::exists(json));
  };
  const std::string header = "depth (nm),load (mN)\n";
  std::string loading_only = header;
  for (int k = 0; k <= 10; ++k) loading_only += fmt::format("{},{}\n", 100 * k, 0.2 * k * k);
  refused("loading.csv", loading_only, "no unloading branch");

  std::string nose = test.csv(1e-9, 1e-3, "depth (nm)\tload (mN)\ttime (s)");
  // The unloading's 10th point moved 30 nm deeper than the 9th: the depth rises while the force falls.
  std::istringstream lines(nose);
  std::string line, edited;
  for (int n = 1; std::getline(lines, line); ++n) {
    if (n == 2 + 61 + 10 + 10) {
      const auto tab = line.find('\t');
      line = fmt::format("{:.9g}", std::stod(line.substr(0, tab)) + 30.0) + line.substr(tab);
    }
    edited += line + "\n";
  }
  refused("nose.csv", edited, "not monotone");

  refused("nan.csv", header + "0,0\n100,nan\n50,0\n", "row 3");
  refused("columns.csv", "h (nm),F (mN)\n0,0\n100,1\n50,0\n", "no header row names both");
  refused("nounits.csv", "depth,load\n0,0\n100,1\n50,0\n", "depth unit is missing");
  refused("badunit.csv", "depth (furlong),load (mN)\n0,0\n100,1\n50,0\n", "not a depth unit");
  refused("short.csv", header + "0,0\n100,1\n90,0.6\n50,0\n", "at least 4");
  // With a time column: time running back (a hold whose time stands still is fine), a time column
  // the header lacks, a time without its unit, NaN in the time, one row.
  const std::string timed = "time (s),depth (nm),load (mN)\n";
  const std::string with_time = " --time-column time";
  refused("backwards.csv", timed + "0,0,0\n1,100,1\n1,110,1\n0.5,50,0\n", "row 5", with_time);
  refused("notime.csv", header + "0,0\n100,1\n50,0\n", "no column \"time\"", with_time);
  refused("timeunit.csv", "time,depth (nm),load (mN)\n0,0,0\n1,100,1\n2,50,0\n", "time unit is missing", with_time);
  refused("timenan.csv", timed + "0,0,0\nnan,100,1\n2,50,0\n", "row 3", with_time);
  refused("onerow.csv", timed + "0,0,0\n", "1 point", with_time);
  // Three columns and none named; no indenter shape.
  const auto three = write("three.csv", "1,2,3\n4,5,6\n");
  EXPECT_EQ(cli("analyze " + three.string() + " --set punch.shape=cone --set punch.half_angle=70.3 --depth-unit nm "
                "--force-unit mN"),
            2);
  EXPECT_NE(err().find("has 3 columns"), std::string::npos) << err();
  EXPECT_EQ(cli("analyze " + three.string() + " --depth-unit nm --force-unit mN"), 2);
  EXPECT_NE(err().find("punch.shape"), std::string::npos) << err();
}

TEST_F(MeasuredCurve, ARunFolderIsAnalysedWithItsOwnIndenterAndTruth) {
  const auto run = dir_ / "run";
  ASSERT_EQ(cli("run " + source_path("loadcases/axisymmetric/elastic_sphere.toml") +
                " --quiet --set load.path=[0.0,5e-6,0.0] --set load.increments=[8,12] --set mesh.contact_nodes=12 "
                "--out " + run.string()),
            0)
      << err();
  ASSERT_EQ(cli("analyze " + run.string()), 0) << err();
  const auto json = nlohmann::json::parse(slurp(run / "analysis.json"));
  const auto& b = json["branches"][0];
  EXPECT_EQ(json["origin"], "run");
  ASSERT_TRUE(b["S_exact"].is_number());
  ASSERT_TRUE(b["pile_up_ratio"].is_number());
  // Hertz: E_r = E* within Oliver-Pharr's and the mesh's error; an elastic sphere neither piles
  // up nor sinks in beyond Hertz's a^2 = R h.
  const double e_star = 210e9 / (1 - 0.09);
  EXPECT_NEAR(b["E_r"].get<double>() / e_star, 1.0, 0.03);
  EXPECT_NEAR(b["pile_up_ratio"].get<double>(), 1.0, 0.05);
  // beta divides E_r and nothing else.
  ASSERT_EQ(cli("analyze " + run.string() + " --set analysis.beta=1.05 --out " + (dir_ / "beta.json").string()), 0)
      << err();
  const auto beta = nlohmann::json::parse(slurp(dir_ / "beta.json"))["branches"][0];
  EXPECT_NEAR(beta["E_r"].get<double>() * 1.05 / b["E_r"].get<double>(), 1.0, 1e-12);
  EXPECT_DOUBLE_EQ(beta["H"].get<double>(), b["H"].get<double>());
  // A run's indenter and material are its own.
  EXPECT_EQ(cli("analyze " + run.string() + " --set material.E=1e9"), 2);
  EXPECT_NE(err().find("analysis.* keys only"), std::string::npos) << err();
}
