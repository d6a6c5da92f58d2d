// What a new user trips over: the mesh `check` promises is the one `run` uses, the yield stress
// as an alternative to e0, every key listed by `indentsim keys` (and in the README), the command
// line's answers to typos, --version.
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>

#include <gtest/gtest.h>

#include "indentsim/base/error.hpp"
#include "indentsim/input/load_case.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using namespace indentsim;
using indentsim::testing::slurp;
using indentsim::testing::source_path;

namespace {

class NewUser : public indentsim::testing::CliTest {};

using indentsim::testing::curve_without_timing;

std::string fmt_e0(double e0) {
  std::ostringstream s;
  s.precision(17);
  s << " --set material.e0=" << e0;
  return s.str();
}

std::string mesh_line(const std::string& text) {
  std::smatch m;
  if (!std::regex_search(text, m, std::regex(R"((\d+) x (\d+) nodes, (\d+) unknowns)"))) return "no mesh line in: " + text;
  return m.str(0);
}

}  // namespace

TEST_F(NewUser, CheckPrintsTheMeshRunUsesForPlasticCases) {
  for (const char* name : {"paper.toml", "deep_plastic.toml", "power_law.toml", "elastic.toml"}) {
    SCOPED_TRACE(name);
    const std::string c = source_path(std::string("loadcases/") + name);
    ASSERT_EQ(cli("check " + c + " --set mesh.contact_nodes=8"), 0) << err();
    const std::string checked = mesh_line(out());
    ASSERT_EQ(cli("run " + c + " --set mesh.contact_nodes=8 --set load.increments=1 --out " + (dir_ / name).string()), 0)
        << err();
    EXPECT_EQ(mesh_line(out()), checked);
  }
}

TEST_F(NewUser, YieldStressAndTheEquivalentE0GiveBitIdenticalRuns) {
  const std::string c = source_path("loadcases/deep_plastic.toml");
  const LoadCase lc = read_load_case(c);
  const double sigma_y = 180e6;
  // e0 = sigma_y / (3 mu), mu = E / (2 (1 + nu)): the relation the README states.
  const double e0 = sigma_y / (3.0 * (lc.material.E / (2.0 * (1.0 + lc.material.nu))));
  const std::string args = " --quiet --set mesh.contact_nodes=6 --set load.increments=4 --out ";
  // The shipped case gives e0: replace it by the yield stress through a copy without that line.
  std::string text = slurp(c);
  text = std::regex_replace(text, std::regex(R"(\ne0 = [^\n]*)"), "\nyield_stress = 180e6");
  const fs::path with_yield = dir_ / "yield.toml";
  std::ofstream(with_yield) << text;
  ASSERT_EQ(cli("run " + with_yield.string() + args + (dir_ / "a").string()), 0) << err();
  ASSERT_EQ(cli("run " + c + fmt_e0(e0) + args + (dir_ / "b").string()), 0) << err();
  EXPECT_EQ(curve_without_timing(dir_ / "a" / "curve.csv"), curve_without_timing(dir_ / "b" / "curve.csv"));
  const std::string summary = slurp(dir_ / "a" / "summary.json");
  EXPECT_NE(summary.find("\"yield_stress\": 180000000"), std::string::npos) << summary;
  EXPECT_NE(slurp(dir_ / "a" / "case.toml").find("# yield_stress = 180000000"), std::string::npos);
  // Both given: refused, naming the key; nothing written.
  EXPECT_EQ(cli("run " + c + " --set material.yield_stress=180e6" + args + (dir_ / "both").string()), 2);
  EXPECT_NE(err().find("material.yield_stress"), std::string::npos) << err();
  EXPECT_FALSE(fs::exists(dir_ / "both"));
}

TEST(NewUserKeys, KeysListsExactlyTheKeysTheReaderAccepts) {
  // The reader's own account of each section's keys: the message for an unknown key lists them.
  std::set<std::string> accepted;
  std::set<std::string> sections;
  for (const auto& k : describe_keys()) sections.insert(k.key.substr(0, k.key.find('.')));
  for (const auto& section : sections) {
    if (section == "layer") {
      // An array of tables ([[layer]]): its own keys, and its material's, which are [material]'s.
      try {
        parse_load_case(slurp(source_path("loadcases/elastic.toml")) + "\n[[layer]]\nno_such_key = 1\n", "layer.toml");
        ADD_FAILURE() << "an unknown key in [[layer]] was accepted";
      } catch (const InputError& e) {
        EXPECT_NE(e.problem().find("known keys of [[layer]]: thickness, material"), std::string::npos) << e.problem();
      }
      accepted.insert({"layer.thickness", "layer.material.KEY"});
      continue;
    }
    try {
      read_load_case(source_path("loadcases/elastic.toml"), {section + ".no_such_key=1"});
      ADD_FAILURE() << "an unknown key in [" << section << "] was accepted";
    } catch (const InputError& e) {
      const std::string problem = e.problem();
      const auto colon = problem.find("]: ");
      ASSERT_NE(colon, std::string::npos) << problem;
      std::istringstream list(problem.substr(colon + 3, problem.rfind(')') - colon - 3));
      for (std::string key; std::getline(list, key, ',');) accepted.insert(section + "." + key.substr(key.find_first_not_of(' ')));
    }
  }
  std::set<std::string> listed;
  for (const auto& k : describe_keys()) listed.insert(k.key);
  EXPECT_EQ(listed, accepted);
  // And each listed key is read: setting it to its listed default (where there is one) is accepted.
  for (const auto& k : describe_keys()) {
    if (!k.default_is_value) continue;
    SCOPED_TRACE(k.key);
    EXPECT_NO_THROW(read_load_case(source_path("loadcases/elastic.toml"), {k.key + "=" + k.default_value}));
  }
}

TEST(NewUserKeys, TheReadmeKeyTableIsTheGeneratedOne) {
  EXPECT_NE(slurp(source_path("README.md")).find(keys_markdown()), std::string::npos)
      << "README.md's key table differs from `indentsim keys --markdown`:\n"
      << keys_markdown();
}

TEST_F(NewUser, UnknownCommandsAreNamedAndVersionIsPrinted) {
  for (const char* typo : {"frobnicate", "runn"}) {
    EXPECT_EQ(cli(typo), 2);
    EXPECT_NE(err().find(typo), std::string::npos) << err();
    EXPECT_NE(err().find("run, resume"), std::string::npos) << err();
  }
  EXPECT_EQ(cli("--version"), 0) << err();
  EXPECT_TRUE(std::regex_search(out(), std::regex(R"(indentsim \d+\.\d+\.\d+ \(commit [0-9a-f]+)")) ||
              out().find("(commit unknown") != std::string::npos)
      << out();
  ASSERT_EQ(cli("run " + source_path("loadcases/elastic.toml") + " --quiet --set mesh.contact_nodes=4 --out " +
                (dir_ / "v").string()),
            0);
  EXPECT_NE(slurp(dir_ / "v" / "summary.json").find("\"indentsim\": \"indentsim "), std::string::npos);
  EXPECT_NE(slurp(dir_ / "v" / "case.toml").find("# Written by indentsim "), std::string::npos);
}

TEST_F(NewUser, UnitSlipsAreWarnedAboutNotRefused) {
  const std::string c = source_path("loadcases/elastic.toml");
  // E meant in GPa: runs, and says so.
  ASSERT_EQ(cli("check " + c + " --set material.E=200"), 0) << err();
  EXPECT_NE(err().find("warning: material.E = 200 Pa"), std::string::npos) << err();
  ASSERT_EQ(cli("run " + c + " --quiet --set material.E=200 --set mesh.contact_nodes=4 --set load.increments=1 --out " +
                (dir_ / "gpa").string()),
            0)
      << err();
  EXPECT_NE(err().find("material.E"), std::string::npos) << err();
  // A punch radius in metres that was meant in millimetres: the contact is half the block.
  ASSERT_EQ(cli("check " + c + " --set punch.radius=1"), 0) << err();
  EXPECT_NE(err().find("of geometry.lx"), std::string::npos) << err();
  // The shipped case itself draws no warning.
  ASSERT_EQ(cli("check " + c), 0) << err();
  EXPECT_EQ(err().find("warning"), std::string::npos) << err();
}
