// Checkpoints and restarts: bit-for-bit continuation, kills at any moment, branching load paths,
// and rejection of every damaged or mismatched checkpoint.
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <fstream>
#include <random>
#include <sstream>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <type_traits>
#include <nlohmann/json.hpp>

#include "indentsim/output/checkpoint.hpp"
#include "indentsim/driver/resume.hpp"
#include "indentsim/base/error.hpp"
#include "indentsim/output/run_output.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using namespace indentsim;
using indentsim::testing::shipped_case;

namespace {

using indentsim::testing::slurp;

using indentsim::testing::curve_without_timing;

// A small run's checkpoint, built through the library.
// summary.json without its wall-clock times ("time_s", and the error estimate's times and their
// ratios).
std::string summary_without_timing(const fs::path& file) {
  nlohmann::ordered_json j = nlohmann::ordered_json::parse(slurp(file));
  j.erase("time_s");
  if (j.contains("error_estimate"))
    for (const char* key : {"time_s", "cost_fraction", "wall_added_s", "wall_fraction"}) j["error_estimate"].erase(key);
  return j.dump(2);
}

Checkpoint small_checkpoint(const std::string& model) {
  Simulation sim(shipped_case("deep_plastic.toml", {"material.model=" + model, "mesh.contact_nodes=3",
                                                     "load.path=[0, 5e-5, 2e-5]", "load.increments=4"}));
  std::vector<IncrementRecord> rows;
  std::vector<double> depths;
  sim.run([&](const IncrementRecord& r) {
    rows.push_back(r);
    depths.push_back(sim.free_surface_depth());
  });
  return make_checkpoint(sim, rows, depths);
}

class CheckpointCli : public indentsim::testing::CliTest {
protected:
  int cli(const std::string& args, const std::string& fault = "") {
    return CliTest::cli(args, fault.empty() ? "" : "INDENTSIM_FAULT=" + fault);
  }
};

const std::string history_case = "loadcases/load_unload.toml";
const std::string small = " --quiet --set mesh.contact_nodes=6 --set output.checkpoint_every=3";

}  // namespace

TEST(Checkpoint, RoundTripIsExact) {
  for (const char* model : {"elastic", "ilyushin", "j2"}) {
    SCOPED_TRACE(model);
    const Checkpoint c = small_checkpoint(model);
    const std::string bytes = serialize(c);
    const Checkpoint back = deserialize(bytes, "memory");
    EXPECT_EQ(serialize(back), bytes);
    EXPECT_EQ(back.state.u, c.state.u);
    EXPECT_EQ(back.state.history, c.state.history);
    EXPECT_EQ(back.curve.size(), c.curve.size());
  }
}

// Every field of the run state, each at a value other than its default, comes back from the file:
// the checkpoint writes and reads the state through its one list of fields (visit_fields).
TEST(Checkpoint, EveryFieldOfTheRunStateSurvivesTheFile) {
  Checkpoint c = small_checkpoint("j2");
  SimulationState& s = c.state;
  s.warned_fine_zone = true;
  s.warnings = {"first warning", "second warning"};
  s.near_field = NearField{true, 3, 2, 1};
  s.plastic_zone_growth.depths = {1e-5, 2e-5};
  s.plastic_zone_growth.extents = {{1e-4, 2e-4}, {3e-4, 4e-4}};
  s.force = 3.5;
  s.force_previous = 2.5;
  s.largest_force = 4.5;
  ASSERT_TRUE(s.has_previous);
  // Each field described as text, by name, through the same list.
  const auto describe = [](const SimulationState& state) {
    std::map<std::string, std::string> fields;
    visit_fields(state, [&](const char* name, const auto& field, const char*) {
      std::ostringstream text;
      text.precision(17);
      using T = std::decay_t<decltype(field)>;
      if constexpr (std::is_same_v<T, NearField>)
        text << field.condensed << ' ' << field.contact_nodes << ' ' << field.elements_x << ' ' << field.elements_y;
      else if constexpr (std::is_same_v<T, PlasticZoneGrowth>)
        for (std::size_t k = 0; k < field.depths.size(); ++k)
          text << field.depths[k] << ' ' << field.extents[k].width << ' ' << field.extents[k].depth << ';';
      else if constexpr (std::is_arithmetic_v<T>)
        text << field;
      else if constexpr (std::is_same_v<T, std::vector<std::string>>)
        for (const auto& x : field) text << x << ';';
      else
        for (const auto& x : field) text << +x << ';';
      fields[name] = text.str();
    });
    return fields;
  };
  const auto before = describe(s);
  EXPECT_EQ(before.size(), 19u);
  const auto after = describe(deserialize(serialize(c), "memory").state);
  for (const auto& [name, text] : before) EXPECT_EQ(after.at(name), text) << name;
}

TEST(Checkpoint, EveryTruncationIsRejected) {
  const std::string bytes = serialize(small_checkpoint("j2"));
  ASSERT_GT(bytes.size(), 1000u);
  for (std::size_t n = 0; n < bytes.size(); ++n) {
    try {
      deserialize(bytes.substr(0, n), "cut.ck");
      FAIL() << "accepted a checkpoint cut to " << n << " of " << bytes.size() << " bytes";
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), "cut.ck");
    }
  }
  EXPECT_THROW(deserialize(bytes + "x", "long.ck"), InputError);
}

TEST(Checkpoint, RandomBitFlipsAreRejected) {
  const std::string bytes = serialize(small_checkpoint("ilyushin"));
  std::mt19937_64 rng(2026);
  for (int trial = 0; trial < 3000; ++trial) {
    std::string damaged = bytes;
    const int flips = 1 + trial % 4;
    for (int f = 0; f < flips; ++f) damaged[rng() % damaged.size()] ^= static_cast<char>(1u << (rng() % 8));
    if (damaged == bytes) continue;  // two flips that cancelled
    EXPECT_THROW(deserialize(damaged, "flipped.ck"), InputError) << "trial " << trial;
  }
}

TEST(Checkpoint, OtherFormatVersionIsNamed) {
  std::string bytes = serialize(small_checkpoint("elastic"));
  const auto other = static_cast<char>(checkpoint_format_version + 1);
  bytes[8] = other;  // the version field follows the 8 magic bytes
  try {
    deserialize(bytes, "old.ck");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(e.problem().find(fmt::format("format {}", static_cast<int>(other))), std::string::npos) << e.problem();
  }
}

TEST_F(CheckpointCli, KillsAtAnyMomentLoseNothing) {
  const std::string source = indentsim::testing::source_path(history_case);
  ASSERT_EQ(cli("run " + source + small + " --out " + (dir_ / "full").string()), 0) << err();
  const std::string expected = curve_without_timing(dir_ / "full" / "curve.csv");
  // After increments 5 and 14 (unloading), and halfway through the 2nd and 5th checkpoint writes.
  for (const std::string fault : {"increment:5", "increment:14", "checkpoint:2", "checkpoint:5"}) {
    SCOPED_TRACE(fault);
    const fs::path out = dir_ / ("killed_" + fault.substr(0, fault.find(':')) + fault.substr(fault.find(':') + 1));
    EXPECT_EQ(cli("run " + source + small + " --out " + out.string(), fault), 128 + SIGKILL);
    ASSERT_EQ(cli("resume " + (out / "checkpoints").string() + " --quiet"), 0) << err();
    EXPECT_EQ(curve_without_timing(out / "curve.csv"), expected);
    EXPECT_EQ(summary_without_timing(out / "summary.json"), summary_without_timing(dir_ / "full" / "summary.json"));
  }
}

TEST_F(CheckpointCli, SigtermCheckpointsAndExitsCleanly) {
  // A run stopped by SIGTERM from outside: its checkpoint continues it to the same curve.  The run
  // takes about a second or more (120 plastic increments); the signal is sent once it has written
  // 3 increments, and every wait is bounded.
  const std::string source = indentsim::testing::source_path("loadcases/deep_plastic.toml");
  const std::string args = " --quiet --set mesh.contact_nodes=8 --set load.increments=120 --set output.checkpoint_every=0";
  ASSERT_EQ(cli("run " + source + args + " --out " + (dir_ / "full").string()), 0) << err();
  const fs::path out = dir_ / "stopped";
  const std::string curve = (out / "curve.csv").string();
  const std::string command = "timeout 120 " + std::string(INDENTSIM_CLI) + " run " + source + args + " --out " +
                              out.string() + " 2>" + (dir_ / "err.txt").string() + " & pid=$!; " +
                              "for i in $(seq 1200); do [ -s " + curve + " ] && [ $(wc -l < " + curve +
                              ") -ge 4 ] && break; sleep 0.05; done; kill -TERM $pid; wait $pid";
  const int raw = std::system(("bash -c '" + command + "'").c_str());
  ASSERT_TRUE(WIFEXITED(raw));
  EXPECT_EQ(WEXITSTATUS(raw), 128 + SIGTERM) << err();
  EXPECT_NE(err().find("resume with"), std::string::npos) << err();
  EXPECT_NE(slurp(out / "summary.json").find("\"status\": \"stopped\""), std::string::npos);
  ASSERT_EQ(cli("resume " + (out / "checkpoints").string() + " --quiet"), 0) << err();
  EXPECT_EQ(curve_without_timing(out / "curve.csv"), curve_without_timing(dir_ / "full" / "curve.csv"));
}

TEST_F(CheckpointCli, BranchFromACheckpointEqualsOneRunOverTheCombinedPath) {
  const std::string source = indentsim::testing::source_path("loadcases/deep_plastic.toml");
  const std::string args = " --quiet --set mesh.contact_nodes=6 --set material.model=ilyushin";
  ASSERT_EQ(cli("run " + source + args + " --set load.path=[0,5e-5,0] --set load.increments=[8,8] --out " +
                (dir_ / "combined").string()),
            0)
      << err();
  ASSERT_EQ(cli("run " + source + args + " --set load.path=[0,5e-5] --set load.increments=[8] --out " +
                (dir_ / "branch").string()),
            0)
      << err();
  // A branch without --out is refused and leaves the run it branches from exactly as it was.
  const auto files_of = [](const fs::path& folder) {
    std::map<std::string, std::string> files;
    for (const auto& entry : fs::recursive_directory_iterator(folder))
      if (entry.is_regular_file()) files[fs::relative(entry.path(), folder).string()] = slurp(entry.path());
    return files;
  };
  const auto before = files_of(dir_ / "branch");
  EXPECT_EQ(cli("resume " + (dir_ / "branch" / "checkpoints").string() +
                " --quiet --set load.path=[0,5e-5,0] --set load.increments=[8,8]"),
            2);
  EXPECT_NE(err().find("--out"), std::string::npos) << err();
  EXPECT_EQ(files_of(dir_ / "branch"), before);
  ASSERT_EQ(cli("resume " + (dir_ / "branch" / "checkpoints").string() +
                " --quiet --set load.path=[0,5e-5,0] --set load.increments=[8,8] --out " + (dir_ / "branched").string()),
            0)
      << err();
  EXPECT_EQ(files_of(dir_ / "branch"), before);
  EXPECT_EQ(curve_without_timing(dir_ / "branched" / "curve.csv"), curve_without_timing(dir_ / "combined" / "curve.csv"));
  EXPECT_EQ(summary_without_timing(dir_ / "branched" / "summary.json"),
            summary_without_timing(dir_ / "combined" / "summary.json"));
}

TEST_F(CheckpointCli, DamagedOrMismatchedCheckpointsExitWith2AndOverwriteNothing) {
  const std::string source = indentsim::testing::source_path("loadcases/deep_plastic.toml");
  const fs::path run = dir_ / "run";
  ASSERT_EQ(cli("run " + source + " --quiet --set mesh.contact_nodes=4 --set load.increments=3 --out " + run.string()), 0);
  const fs::path good = run / "checkpoints" / "checkpoint_000003.ck";
  ASSERT_TRUE(fs::exists(good));
  const std::string bytes = slurp(good);
  const std::string curve_before = slurp(run / "curve.csv");
  const auto write = [&](const std::string& name, const std::string& content) {
    const fs::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << content;
    return p;
  };
  std::string flipped = bytes;
  flipped[bytes.size() / 2] ^= 0x10;
  const fs::path bad[] = {write("truncated.ck", bytes.substr(0, bytes.size() / 3)), write("flipped.ck", flipped),
                          write("empty.ck", ""), write("text.ck", "[geometry]\nlx = 1\n"), dir_ / "absent.ck"};
  for (const fs::path& p : bad) {
    SCOPED_TRACE(p.filename().string());
    EXPECT_EQ(cli("resume " + p.string() + " --quiet --out " + run.string()), 2);
    EXPECT_NE(err().find(p.filename().string()), std::string::npos) << err();
    EXPECT_EQ(slurp(run / "curve.csv"), curve_before);
  }
  // A physics override is refused, naming the key; a path that leaves the history too.
  EXPECT_EQ(cli("resume " + good.string() + " --quiet --set material.E=1e11"), 2);
  EXPECT_NE(err().find("material.E"), std::string::npos) << err();
  EXPECT_EQ(cli("resume " + good.string() + " --quiet --set load.path=[0,4e-5,0]"), 2);
  EXPECT_NE(err().find("load.path"), std::string::npos) << err();
  EXPECT_EQ(slurp(run / "curve.csv"), curve_before);
}
