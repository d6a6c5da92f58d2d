// The command line as a user meets it: exit statuses, messages naming file and key, and no
// output at all when the input is bad.
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

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
