// The command line as a user meets it: exit statuses, messages naming file and key, and no
// output at all when the input is bad.
#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "test_support.hpp"

namespace fs = std::filesystem;

namespace {

struct Outcome {
  int status = -1;
  std::string out, err;
};

class Cli : public indentsim::testing::TempDirTest {
protected:
  Outcome run(const std::string& args) {
    const fs::path out = dir_ / "stdout.txt", err = dir_ / "stderr.txt";
    const std::string command = std::string(INDENTSIM_CLI) + " " + args + " >" + out.string() + " 2>" + err.string();
    const int raw = std::system(command.c_str());
    Outcome o;
    o.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
    o.out = slurp(out);
    o.err = slurp(err);
    return o;
  }
  static std::string slurp(const fs::path& p) { return indentsim::testing::slurp(p); }
  fs::path write_case(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p;
  }
};

const std::string& good_case = indentsim::testing::small_case_toml;

}  // namespace

TEST_F(Cli, RunWritesTheCurveWithOneRowPerIncrement) {
  const fs::path c = write_case("case.toml", good_case);
  const fs::path out = dir_ / "result";
  const Outcome o = run("run " + c.string() + " --out " + out.string());
  ASSERT_EQ(o.status, 0) << o.err;
  std::ifstream curve(out / "curve.csv");
  std::string header, line;
  std::getline(curve, header);
  EXPECT_EQ(header.rfind("step,alpha,P,a,contact_nodes,newton_iters,factorizations", 0), 0u) << header;
  int rows = 0;
  while (std::getline(curve, line)) ++rows;
  EXPECT_EQ(rows, 4);  // alpha = 0 and three increments
  EXPECT_NE(o.out.find("curve.csv"), std::string::npos);
}

TEST_F(Cli, CheckValidatesWithoutWriting) {
  const fs::path c = write_case("case.toml", good_case + "[output]\ndir = \"" + (dir_ / "never").string() + "\"\n");
  const Outcome o = run("check " + c.string());
  EXPECT_EQ(o.status, 0) << o.err;
  EXPECT_FALSE(fs::exists(dir_ / "never"));
}

TEST_F(Cli, BadInputExitsWithStatus2NamingFileAndKeyAndWritesNothing) {
  const fs::path c = write_case("case.toml", good_case);
  const fs::path out = dir_ / "must_not_exist";
  const struct {
    std::string set, key;
  } cases[] = {
      {"material.E=-5", "material.E"},          {"material.nu=0.7", "material.nu"},
      {"punch.radius=0", "punch.radius"},       {"load.path=[0,-1e-5]", "load.path"},
      {"load.increments=0", "load.increments"}, {"geometry.depth=1", "geometry.depth"},
      {"mesh.contact_nodes=300000", "mesh.contact_nodes"},
  };
  for (const auto& bad : cases) {
    SCOPED_TRACE(bad.set);
    const Outcome o = run("run " + c.string() + " --out " + out.string() + " --set " + bad.set);
    EXPECT_EQ(o.status, 2);
    EXPECT_NE(o.err.find(c.string()), std::string::npos) << o.err;
    EXPECT_NE(o.err.find(bad.key), std::string::npos) << o.err;
    EXPECT_FALSE(fs::exists(out));
  }
}

TEST_F(Cli, BrokenOrMissingFilesExitWithStatus2) {
  const fs::path broken = write_case("broken.toml", "[geometry\nlx = 1\n");
  Outcome o = run("run " + broken.string() + " --out " + (dir_ / "x").string());
  EXPECT_EQ(o.status, 2);
  EXPECT_NE(o.err.find("broken.toml"), std::string::npos) << o.err;
  o = run("run " + (dir_ / "absent.toml").string());
  EXPECT_EQ(o.status, 2);
  EXPECT_NE(o.err.find("absent.toml"), std::string::npos) << o.err;
  o = run("frobnicate");
  EXPECT_EQ(o.status, 2);
  EXPECT_FALSE(fs::exists(dir_ / "x"));
}

// mesh.error_estimate: on by default, its columns in curve.csv (before wall_s) and its figures in
// summary.json; "off" leaves both out; a mesh too coarse for a companion runs without one and says so.
TEST_F(Cli, ErrorEstimateColumnsAndSummary) {
  const fs::path c = write_case("case.toml", good_case);
  const auto header_of = [](const fs::path& curve) {
    std::ifstream in(curve);
    std::string header;
    std::getline(in, header);
    return header;
  };
  const Outcome on = run("run " + c.string() + " --quiet --out " + (dir_ / "on").string());
  ASSERT_EQ(on.status, 0) << on.err;
  EXPECT_EQ(header_of(dir_ / "on" / "curve.csv"),
            "step,alpha,P,a,contact_nodes,newton_iters,factorizations,cutbacks,plastic_points,max_strain_intensity,"
            "P_error_estimate,a_error_estimate,P_extrapolated,wall_s");
  const auto rows = indentsim::testing::read_curve(dir_ / "on" / "curve.csv");
  ASSERT_EQ(rows.size(), 4u);
  for (const auto& row : rows) {
    ASSERT_EQ(row.size(), 14u);
    EXPECT_TRUE(std::isfinite(row[10]) && std::isfinite(row[11]) && std::isfinite(row[12]));
    EXPECT_GE(row[10], 0.0);
    EXPECT_NEAR(std::abs(row[12] - row[2]), row[10], 1e-9 * std::abs(row[2]) + 1e-12);  // |P - P*| is the estimate
  }
  EXPECT_GT(rows.back()[10], 0.0);
  const auto summary = nlohmann::json::parse(slurp(dir_ / "on" / "summary.json"));
  const auto& estimate = summary["error_estimate"];
  EXPECT_EQ(estimate["method"], "richardson") << summary;
  EXPECT_EQ(estimate["contact_nodes"], 8);
  EXPECT_EQ(estimate["companion_contact_nodes"], nlohmann::json::array({4}));
  EXPECT_TRUE(summary["time_s"].contains("error estimate"));  // its time, among the run's phases
  EXPECT_GT(estimate["cost_fraction"].get<double>(), 0.0);
  EXPECT_LT(estimate["cost_fraction"].get<double>(), 1.0);

  const Outcome off = run("run " + c.string() + " --quiet --out " + (dir_ / "off").string() +
                          " --set mesh.error_estimate=\\\"off\\\"");
  ASSERT_EQ(off.status, 0) << off.err;
  EXPECT_EQ(header_of(dir_ / "off" / "curve.csv").find("error_estimate"), std::string::npos);
  EXPECT_EQ(slurp(dir_ / "off" / "summary.json").find("error_estimate"), std::string::npos);
  // The curve itself does not depend on the estimate.
  const auto off_rows = indentsim::testing::read_curve(dir_ / "off" / "curve.csv");
  ASSERT_EQ(off_rows.size(), rows.size());
  for (std::size_t k = 0; k < rows.size(); ++k) EXPECT_EQ(off_rows[k][2], rows[k][2]);

  const Outcome coarse = run("run " + c.string() + " --quiet --out " + (dir_ / "coarse").string() +
                             " --set mesh.contact_nodes=3");
  ASSERT_EQ(coarse.status, 0) << coarse.err;
  EXPECT_NE(coarse.err.find("too coarse for a companion"), std::string::npos) << coarse.err;
  EXPECT_EQ(header_of(dir_ / "coarse" / "curve.csv").find("error_estimate"), std::string::npos);
}

TEST_F(Cli, BadErrorEstimateKeysExitWithStatus2) {
  const fs::path c = write_case("case.toml", good_case);
  const fs::path out = dir_ / "must_not_exist";
  const struct {
    std::string set, key, problem;
  } cases[] = {
      {"mesh.error_estimate=\\\"bogus\\\"", "mesh.error_estimate", "is not one of: richardson, observed, off"},
      {"mesh.target_error=0.5", "mesh.target_error", "[1e-5, 0.1]"},
      {"mesh.target_error=0", "mesh.target_error", "[1e-5, 0.1]"},
      {"mesh.target_error=1e-3 --set mesh.error_estimate=\\\"off\\\"", "mesh.target_error", "needs an error estimate"},
  };
  for (const auto& bad : cases) {
    SCOPED_TRACE(bad.set);
    const Outcome o = run("run " + c.string() + " --out " + out.string() + " --set " + bad.set);
    EXPECT_EQ(o.status, 2);
    EXPECT_NE(o.err.find(bad.key), std::string::npos) << o.err;
    EXPECT_NE(o.err.find(bad.problem), std::string::npos) << o.err;
    EXPECT_FALSE(fs::exists(out));
  }
}

// mesh.target_error through the command line: the pilot, the chosen mesh in case.toml (so that a
// resume continues on it), and the estimate against the target in summary.json.
TEST_F(Cli, TargetErrorChoosesTheMeshAndReportsIt) {
  const fs::path c = write_case("case.toml", good_case);
  const fs::path out = dir_ / "target";
  const Outcome o = run("run " + c.string() + " --out " + out.string() + " --set mesh.target_error=2e-3");
  ASSERT_EQ(o.status, 0) << o.err;
  EXPECT_NE(o.out.find("target error 0.002: the pilot at contact_nodes = 10, 3 increments estimates"), std::string::npos) << o.out;
  const auto summary = nlohmann::json::parse(slurp(out / "summary.json"));
  const auto& target = summary["target_error"];
  EXPECT_EQ(target["target"], 0.002) << summary;
  EXPECT_EQ(target["before"][0]["role"], "pilot");
  EXPECT_EQ(target["before"][0]["contact_nodes"], 10);
  EXPECT_EQ(target["met"], true) << summary;
  const indentsim::LoadCase as_run = indentsim::read_load_case(out / "case.toml");
  EXPECT_FALSE(as_run.mesh.target_error);
  EXPECT_GE(as_run.mesh.contact_nodes, 10);
  EXPECT_EQ(target["contact_nodes"], as_run.mesh.contact_nodes);
  EXPECT_TRUE(target["P_relative_error_estimate"].is_number());
}

// A J2 run depends on its increments: the target chooses them with the mesh, case.toml keeps
// them (a resume continues on them), and summary.json judges both shares of the error.
TEST_F(Cli, TargetErrorChoosesTheIncrementsOfAPathDependentRun) {
  const fs::path c = write_case("case.toml", good_case);
  const fs::path out = dir_ / "target";
  const Outcome o = run("run " + c.string() + " --out " + out.string() +
                        " --set material.model=\\\"j2\\\" --set material.e0=1e-3 --set load.increments=2"
                        " --set mesh.target_error=5e-3");
  ASSERT_EQ(o.status, 0) << o.err;
  const auto summary = nlohmann::json::parse(slurp(out / "summary.json"));
  const auto& target = summary["target_error"];
  ASSERT_TRUE(target["before"][0]["P_relative_change_half_the_increments"].is_number()) << target;
  EXPECT_GT(target["before"][0]["P_relative_change_half_the_increments"].get<double>(), 5e-3);  // 2 are too few
  const indentsim::LoadCase as_run = indentsim::read_load_case(out / "case.toml");
  EXPECT_GT(as_run.load.total_increments(), 2);
  EXPECT_EQ(target["increments"], as_run.load.total_increments());
  EXPECT_LE(target["P_relative_change_half_the_increments"].get<double>(), 5e-3) << target;
  EXPECT_LE(target["P_relative_error_estimate"].get<double>(), 5e-3) << target;
  EXPECT_EQ(target["met"], true) << target;
}
