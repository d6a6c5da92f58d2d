// Reading load cases: the fixed keys, overrides, and every kind of bad input named precisely.
#include <cmath>
#include <filesystem>
#include <regex>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "indentsim/base/error.hpp"
#include "indentsim/input/load_case.hpp"
#include "indentsim/geometry/mesh.hpp"
#include "indentsim/simulation/run_configuration.hpp"
#include "test_support.hpp"

using namespace indentsim;

namespace {

const std::string& valid_case = indentsim::testing::small_case_toml;

// Parses `text` and returns the InputError's key, or "" if it parsed.
std::string rejected_key(const std::string& text, const std::vector<std::string>& overrides = {}) {
  try {
    parse_load_case(text, "case.toml", overrides);
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "case.toml");
    EXPECT_FALSE(e.problem().empty());
    return e.key();
  }
  return "";
}

}  // namespace

TEST(LoadCase, ShippedCasesAreValid) {
  // Every load case shipped under loadcases/, found by walking the folder (a new case is covered
  // without touching this test): it reads, it indents, and it plans a mesh.
  int checked = 0;
  for (const auto& entry :
       std::filesystem::recursive_directory_iterator(indentsim::testing::source_path("loadcases"))) {
    if (entry.path().extension() != ".toml") continue;
    SCOPED_TRACE(entry.path().string());
    LoadCase lc;
    ASSERT_NO_THROW(lc = read_load_case(entry.path()));
    // A force-controlled case's depth is the depth pilot's (docs/MODEL.md §13.1).
    if (lc.load.control == LoadControlKind::force) ASSERT_NO_THROW(lc = with_depth_estimate(lc));
    EXPECT_GT(lc.max_depth(), 0.0);
    const MeshPlan plan = plan_mesh(lc);
    EXPECT_GT(plan.unknowns(), 0);
    EXPECT_GT(plan.contact_half_width_estimate, 0.0);
    ++checked;
  }
  EXPECT_GE(checked, 16);
}

TEST(LoadCase, ReadsFixedKeysInSIUnits) {
  const LoadCase lc = parse_load_case(valid_case, "case.toml");
  EXPECT_DOUBLE_EQ(lc.geometry.lx, 15e-3);
  EXPECT_DOUBLE_EQ(lc.punch.radius, 2e-3);
  EXPECT_EQ(lc.material.model, MaterialModel::elastic);
  EXPECT_DOUBLE_EQ(lc.material.E, 210e9);
  EXPECT_EQ(lc.load.increments, 3);
  EXPECT_EQ(lc.mesh.contact_nodes, 8);
  EXPECT_EQ(lc.output.checkpoint_every, 10);  // default
  EXPECT_DOUBLE_EQ(lc.max_depth(), 2e-5);
}

TEST(LoadCase, OverridesAreTomlValuesOrBareStrings) {
  const LoadCase lc = parse_load_case(valid_case, "case.toml",
                                      {"material.E=70e9", "load.path=[0, 1e-5, 2e-5]", "mesh.contact_nodes=12",
                                       "output.dir=results/run1", "mesh.growth=1.2"});
  EXPECT_DOUBLE_EQ(lc.material.E, 70e9);
  ASSERT_EQ(lc.load.path.size(), 3u);
  EXPECT_DOUBLE_EQ(lc.load.path[2], 2e-5);
  EXPECT_EQ(lc.mesh.contact_nodes, 12);
  EXPECT_EQ(lc.output.dir, "results/run1");
  ASSERT_TRUE(lc.mesh.growth.has_value());
  EXPECT_DOUBLE_EQ(*lc.mesh.growth, 1.2);
}

TEST(LoadCase, IntegersAreAcceptedWhereNumbersAreExpected) {
  const LoadCase lc = parse_load_case(valid_case, "case.toml", {"material.E=210000000000"});
  EXPECT_DOUBLE_EQ(lc.material.E, 210e9);
}

TEST(LoadCase, BadInputNamesTheKey) {
  const std::string& v = valid_case;
  EXPECT_EQ(rejected_key(v + "\n[extra]\nx = 1\n"), "extra");                      // unknown section
  EXPECT_EQ(rejected_key(v, {"geometry.lz=1"}), "geometry.lz");                    // unknown key
  EXPECT_EQ(rejected_key(v, {"material.E=\"steel\""}), "material.E");              // wrong type
  EXPECT_EQ(rejected_key(v, {"load.increments=2.5"}), "load.increments");          // not an integer
  EXPECT_EQ(rejected_key(v, {"load.path=5e-5"}), "load.path");                     // not an array
  EXPECT_EQ(rejected_key(v, {"load.path=[0, \"deep\"]"}), "load.path");
  EXPECT_EQ(rejected_key(v, {"material.E=0"}), "material.E");                      // E <= 0
  EXPECT_EQ(rejected_key(v, {"material.E=-1e9"}), "material.E");
  EXPECT_EQ(rejected_key(v, {"material.nu=0.5"}), "material.nu");                  // nu outside (-1, 0.5)
  EXPECT_EQ(rejected_key(v, {"material.nu=-1"}), "material.nu");
  EXPECT_EQ(rejected_key(v, {"material.nu=nan"}), "material.nu");
  EXPECT_EQ(rejected_key(v, {"punch.radius=0"}), "punch.radius");                  // R <= 0
  EXPECT_EQ(rejected_key(v, {"load.path=[0, -1e-5]"}), "load.path");              // negative depth
  EXPECT_EQ(rejected_key(v, {"load.path=[1e-5, 2e-5]"}), "load.path");             // not from 0
  EXPECT_EQ(rejected_key(v, {"load.path=[0, 3e-3]"}), "load.path");                // deeper than R
  EXPECT_EQ(rejected_key(v, {"load.increments=0"}), "load.increments");            // zero increments
  EXPECT_EQ(rejected_key(v, {"material.model=plastic"}), "material.model");
  EXPECT_EQ(rejected_key(v, {"mesh.contact_nodes=1"}), "mesh.contact_nodes");
  EXPECT_EQ(rejected_key(v, {"mesh.growth=3"}), "mesh.growth");
  EXPECT_EQ(rejected_key(v, {"geometry=3"}), "geometry");
  EXPECT_EQ(rejected_key(v, {"nodot=3"}), "nodot");
}

TEST(LoadCase, MissingKeysAndSectionsAreNamed) {
  std::string no_radius(valid_case);
  no_radius.replace(no_radius.find("radius = 2e-3"), 13, "");
  EXPECT_EQ(rejected_key(no_radius), "punch.radius");
  std::string no_load(valid_case);
  no_load.erase(no_load.find("[load]"));
  EXPECT_EQ(rejected_key(no_load), "load");
}

TEST(LoadCase, SyntaxErrorsGiveLineAndColumn) {
  try {
    parse_load_case("[geometry]\nlx = = 1\n", "broken.toml");
    FAIL() << "accepted broken TOML";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "broken.toml");
    EXPECT_NE(e.key().find("line 2"), std::string::npos) << e.key();
  }
}

TEST(LoadCase, MissingFileIsAnInputError) {
  EXPECT_THROW(read_load_case("/nonexistent/indentsim/case.toml"), InputError);
}

TEST(LoadCase, MeshTooLargeForMemoryIsRejectedBeforeAllocation) {
  const LoadCase lc =
      parse_load_case(valid_case, "case.toml", {"mesh.contact_nodes=20000", "mesh.max_unknowns=2000000000"});
  try {
    plan_mesh(lc);
    FAIL() << "planned an enormous mesh";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "mesh.contact_nodes");
    EXPECT_NE(e.problem().find("GiB"), std::string::npos) << e.problem();
  }
}

TEST(LoadCase, AMeshBeyondMaxUnknownsIsRefusedNamingTheKeyThatRaisesIt) {
  const LoadCase lc = parse_load_case(valid_case, "case.toml", {"mesh.contact_nodes=1000"});
  try {
    plan_mesh(lc);
    FAIL() << "planned a mesh beyond mesh.max_unknowns";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "mesh.contact_nodes");
    EXPECT_NE(e.problem().find("mesh.max_unknowns = 2000000"), std::string::npos) << e.problem();
  }
  // Raised, the limit is no longer what refuses it (this machine's memory may still).
  try {
    plan_mesh(parse_load_case(valid_case, "case.toml", {"mesh.contact_nodes=1000", "mesh.max_unknowns=100000000"}));
  } catch (const InputError& e) {
    EXPECT_EQ(e.problem().find("max_unknowns"), std::string::npos) << e.problem();
  }
}

// A number key's accepted interval is stated once, in its declaration, and those very words are
// enforced: a value just outside the interval `indentsim keys` shows is refused, naming the key.
TEST(LoadCase, EveryDeclaredIntervalIsEnforcedAsWritten) {
  const std::regex one_sided(R"(^(>=?) ([-+0-9.e]+)(,.*)?$)"), two_sided(R"(^([\(\[])([-+0-9.e]+), ([-+0-9.e]+)([\)\]]).*$)");
  int checked = 0;
  for (const KeyDescription& k : describe_keys()) {
    // punch: per shape; layer: per layer (Layers.BadLayersAreRefusedNamingTheLayerAndTheKey)
    if ((k.type != "number" && k.type != "integer") || k.key.rfind("punch.", 0) == 0 || k.key.rfind("layer.", 0) == 0)
      continue;
    std::smatch m;
    double outside = 0.0;
    if (std::regex_match(k.range, m, one_sided)) {
      const double lower = std::stod(m.str(2));
      outside = m.str(1) == ">" ? lower : lower - 1.0;
    } else if (std::regex_match(k.range, m, two_sided)) {
      const double upper = std::stod(m.str(3));
      outside = m.str(4) == ")" ? upper : upper + std::max(1.0, std::abs(upper));
    } else {
      continue;
    }
    SCOPED_TRACE(k.key + " " + k.range);
    const std::string value = k.type == "integer" ? std::to_string(static_cast<long>(outside)) : fmt::format("{:.17g}", outside);
    try {
      (void)indentsim::testing::shipped_case("deep_plastic.toml", {k.key + "=" + value});
      ADD_FAILURE() << k.key << " = " << value << " was accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(e.key(), k.key) << e.what();
    }
    ++checked;
  }
  EXPECT_GE(checked, 20);  // every bounded number key of the table (geometry, material, mesh, output, solver, analysis)
}
