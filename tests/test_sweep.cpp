// Parameter sweeps: the sweep file's designs, the hash that keys each run, and the promises of
// the results folder -- each run's curve is the CLI run's, shards and the Slurm array's tasks
// add up to the whole sweep, an interrupted sweep redoes only its missing runs, a run that fails
// for its own reasons is recorded once, and bad sweep files start nothing.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "indentsim/base/error.hpp"
#include "indentsim/study/sweep.hpp"
#include "indentsim/study/sweep_results.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using namespace indentsim;

namespace {

class SweepTest : public indentsim::testing::CliTest {
protected:
  /// The small elastic case as the base, and a sweep file over it (`body`: [set] and [vary]).
  fs::path write_sweep(const std::string& name, const std::string& sweep_section, const std::string& body) {
    std::ofstream(dir_ / "base.toml") << indentsim::testing::small_case_toml;
    const fs::path file = dir_ / name;
    std::ofstream(file) << "[sweep]\nbase = \"base.toml\"\n" << sweep_section << "\n" << body;
    return file;
  }
  /// results.csv's rows without the wall-clock column: what must agree between two sweeps.
  static std::vector<std::string> table_rows(const fs::path& file) {
    std::istringstream in(indentsim::testing::slurp(file));
    std::vector<std::string> rows;
    std::string header, line;
    std::getline(in, header);
    std::size_t wall_column = 0;
    {
      std::istringstream cells(header);
      std::string cell;
      for (std::size_t k = 0; std::getline(cells, cell, ','); ++k)
        if (cell == "wall_s") wall_column = k;
    }
    while (std::getline(in, line)) {
      std::istringstream cells(line);
      std::string cell, row;
      for (std::size_t k = 0; std::getline(cells, cell, ','); ++k)
        if (k != wall_column) row += cell + ",";
      rows.push_back(row);
    }
    return rows;
  }
  static int count(const std::string& text, const std::string& what) {
    int n = 0;
    for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
    return n;
  }
};

}  // namespace

TEST_F(SweepTest, AGridRunsEveryCombinationAndRangesIncludeTheirEnds) {
  const fs::path file = write_sweep("grid.toml", "out = \"" + (dir_ / "out").string() + "\"",
                                    "[vary]\n\"material.E\" = [100e9, 200e9]\n"
                                    "material.nu = {from = 0.2, to = 0.4, count = 3}\n"
                                    "\"punch.radius\" = {from = 1e-3, to = 4e-3, count = 3, scale = \"log\"}\n"
                                    "\"mesh.contact_nodes\" = {from = 6, to = 10, count = 3}\n");
  const SweepManifest m = expand_sweep(read_sweep_definition(file));
  ASSERT_EQ(m.runs.size(), 2u * 3u * 3u * 3u);
  // Sorted by name, whichever way the file writes them (quoted or dotted).
  ASSERT_EQ(m.keys, (std::vector<std::string>{"material.E", "material.nu", "mesh.contact_nodes", "punch.radius"}));
  std::vector<std::set<std::string>> seen(m.keys.size());
  std::set<std::string> hashes;
  for (const SweepRun& r : m.runs) {
    for (std::size_t j = 0; j < m.keys.size(); ++j) seen[j].insert(r.values[j]);
    hashes.insert(r.hash);
    // The complete case holds the run's values.
    const LoadCase lc = parse_load_case(r.case_toml, "manifest");
    EXPECT_DOUBLE_EQ(lc.material.E, std::stod(r.values[0]));
    EXPECT_DOUBLE_EQ(lc.material.nu, std::stod(r.values[1]));
    EXPECT_EQ(lc.mesh.contact_nodes, std::stoi(r.values[2]));
    EXPECT_DOUBLE_EQ(lc.punch.radius, std::stod(r.values[3]));
  }
  EXPECT_EQ(hashes.size(), m.runs.size());
  EXPECT_EQ(seen[1], (std::set<std::string>{"0.2", "0.3", "0.4"}));
  EXPECT_EQ(seen[2], (std::set<std::string>{"6", "8", "10"}));  // integer ends: integer values
  std::vector<double> radii;
  for (const auto& v : seen[3]) radii.push_back(std::stod(v));
  std::sort(radii.begin(), radii.end());
  EXPECT_DOUBLE_EQ(radii.front(), 1e-3);
  EXPECT_DOUBLE_EQ(radii.back(), 4e-3);
  EXPECT_NEAR(radii[1], 2e-3, 1e-15);  // the geometric mean of the ends
}

TEST_F(SweepTest, ALatinHypercubePutsOnePointInEveryStratumAndItsSeedRepeatsIt) {
  const auto sweep = [&](int seed) {
    const fs::path file = write_sweep("lhs.toml",
                                      fmt::format("design = \"latin_hypercube\"\nsamples = 16\nseed = {}", seed),
                                      "[vary]\n\"material.E\" = {from = 100e9, to = 300e9}\n"
                                      "\"material.nu\" = {from = 0.1, to = 0.45}\n"
                                      "\"punch.radius\" = {from = 1e-3, to = 1e-2, scale = \"log\"}\n");
    return expand_sweep(read_sweep_definition(file));
  };
  const SweepManifest m = sweep(7);
  ASSERT_EQ(m.runs.size(), 16u);
  const double lo[] = {100e9, 0.1, std::log(1e-3)}, hi[] = {300e9, 0.45, std::log(1e-2)};
  for (std::size_t j = 0; j < 3; ++j) {
    std::set<int> strata;
    for (const SweepRun& r : m.runs) {
      const double v = j == 2 ? std::log(std::stod(r.values[j])) : std::stod(r.values[j]);
      const double fraction = (v - lo[j]) / (hi[j] - lo[j]);
      ASSERT_GE(fraction, -1e-12);
      ASSERT_LT(fraction, 1.0);
      strata.insert(static_cast<int>(std::floor(fraction * 16.0 + 1e-12)));
    }
    EXPECT_EQ(strata.size(), 16u) << m.keys[j];  // every stratum of every key exactly once
  }
  EXPECT_EQ(sweep(7).to_json(), m.to_json());
  EXPECT_NE(sweep(8).to_json(), m.to_json());
}

TEST_F(SweepTest, TheHashIsTheCasesPhysicsNotItsFolderOrSource) {
  const LoadCase a = parse_load_case(indentsim::testing::small_case_toml, "a.toml");
  const LoadCase b = parse_load_case(indentsim::testing::small_case_toml, "b.toml", {"output.dir=\"elsewhere\"", "output.fields_every=2"});
  const LoadCase c = parse_load_case(indentsim::testing::small_case_toml, "a.toml", {"material.E=211e9"});
  const LoadCase d = parse_load_case(indentsim::testing::small_case_toml, "a.toml", {"mesh.contact_nodes=9"});
  EXPECT_EQ(case_hash(a), case_hash(b));
  EXPECT_NE(case_hash(a), case_hash(c));
  EXPECT_NE(case_hash(a), case_hash(d));
  EXPECT_EQ(case_hash(a).size(), 16u);
}

TEST_F(SweepTest, EachRunsCurveIsTheCliRunsCurveBitForBit) {
  const fs::path results_dir = dir_ / "results_dir";
  const fs::path file = write_sweep("s.toml", "out = \"" + results_dir.string() + "\"",
                                    "[set]\n\"material.model\" = \"ilyushin\"\n"
                                    "[vary]\n\"material.e0\" = [2e-3, 4e-3]\n\"material.nu\" = [0.25, 0.35]\n");
  ASSERT_EQ(cli("sweep " + file.string() + " --quiet"), 0) << err();
  const SweepManifest m = expand_sweep(read_sweep_definition(file));
  ASSERT_EQ(m.runs.size(), 4u);
  for (const SweepRun& r : m.runs) {
    const fs::path alone = dir_ / ("alone_" + r.hash);
    ASSERT_EQ(cli(fmt::format("run {} --quiet --out {} --set material.model=\"ilyushin\" --set material.e0={} --set "
                              "material.nu={}",
                              (dir_ / "base.toml").string(), alone.string(), r.values[0], r.values[1])),
              0)
        << err();
    EXPECT_EQ(indentsim::testing::curve_without_timing(results_dir / "runs" / r.hash / "curve.csv"),
              indentsim::testing::curve_without_timing(alone / "curve.csv"));
    const auto result = SweepResults(results_dir).result(r.hash);
    ASSERT_TRUE(result);
    EXPECT_EQ(result->status, "finished");
    EXPECT_EQ(result->final_force, indentsim::testing::read_curve(alone / "curve.csv").back()[2]);
  }
  // Only what the sweep keeps: result.json, curve.csv and summary.json by default.
  for (const auto& entry : fs::directory_iterator(results_dir / "runs" / m.runs[0].hash)) {
    const std::string name = entry.path().filename().string();
    EXPECT_TRUE(name == "result.json" || name == "curve.csv" || name == "summary.json") << name;
  }
  EXPECT_EQ(table_rows(results_dir / "results.csv").size(), 4u);
}

TEST_F(SweepTest, ShardsAndTheSlurmArraysTasksAddUpToTheWholeSweep) {
  const std::string vary = "[vary]\n\"material.E\" = [150e9, 200e9, 250e9]\n\"material.nu\" = [0.2, 0.3]\n";
  const fs::path whole = write_sweep("whole.toml", "out = \"" + (dir_ / "whole").string() + "\"", vary);
  ASSERT_EQ(cli("sweep " + whole.string() + " --quiet"), 0) << err();

  // By hand: three shards, in any order; then the table.
  const fs::path by_hand = write_sweep("by_hand.toml", "out = \"" + (dir_ / "by_hand").string() + "\"", vary);
  for (const char* shard : {"3/3", "1/3", "2/3"}) ASSERT_EQ(cli("sweep " + by_hand.string() + " --shard " + shard), 0) << err();
  ASSERT_EQ(cli("sweep " + by_hand.string() + " --collect"), 0) << err();
  EXPECT_NE(out().find("6 finished"), std::string::npos) << out();
  EXPECT_EQ(table_rows(dir_ / "by_hand" / "results.csv"), table_rows(dir_ / "whole" / "results.csv"));

  // The Slurm job array's script, run as Slurm would run its tasks (SLURM_ARRAY_TASK_ID set).
  const fs::path slurm = write_sweep("slurm.toml", "out = \"" + (dir_ / "slurm").string() + "\"", vary);
  ASSERT_EQ(cli("sweep " + slurm.string() + " --slurm --shards 3"), 0) << err();
  const fs::path script = dir_ / "slurm" / "sweep.sbatch";
  const std::string text = indentsim::testing::slurp(script);
  EXPECT_NE(text.find("#SBATCH --array=1-3"), std::string::npos) << text;
  EXPECT_FALSE(fs::exists(dir_ / "slurm" / "runs"));  // nothing run yet
  for (int task = 1; task <= 3; ++task) {
    const std::string command = fmt::format("cd / && SLURM_ARRAY_TASK_ID={} SLURM_ARRAY_JOB_ID=1 bash {} >{} 2>&1", task,
                                            script.string(), (dir_ / "task.log").string());
    ASSERT_EQ(std::system(command.c_str()), 0) << indentsim::testing::slurp(dir_ / "task.log");
    EXPECT_NE(indentsim::testing::slurp(dir_ / "task.log").find(fmt::format("shard {}/3: 2 runs", task)), std::string::npos)
        << indentsim::testing::slurp(dir_ / "task.log");
  }
  ASSERT_EQ(cli("sweep " + slurm.string() + " --collect"), 0) << err();
  EXPECT_EQ(table_rows(dir_ / "slurm" / "results.csv"), table_rows(dir_ / "whole" / "results.csv"));
}

TEST_F(SweepTest, AKilledSweepRedoesOnlyTheRunsWithoutAResult) {
  const fs::path results_dir = dir_ / "results_dir";
  const fs::path file = write_sweep("s.toml", "out = \"" + results_dir.string() + "\"",
                                    "[vary]\n\"material.E\" = [150e9, 200e9, 250e9, 300e9]\n");
  // SIGKILL in the third run (each reports 4 increments: alpha = 0 and three): two results.
  EXPECT_EQ(cli("sweep " + file.string() + " --quiet", "INDENTSIM_FAULT=increment:10"), 128 + 9);
  const SweepManifest m = expand_sweep(read_sweep_definition(file));
  const SweepResults results(results_dir);
  int complete = 0;
  for (const SweepRun& r : m.runs) complete += results.complete(r.hash) ? 1 : 0;
  EXPECT_EQ(complete, 2);
  ASSERT_EQ(cli("sweep " + file.string() + " --quiet"), 0) << err();
  const std::vector<std::string> rows = table_rows(results_dir / "results.csv");
  ASSERT_EQ(rows.size(), 4u);
  for (const auto& row : rows) EXPECT_NE(row.find(",finished,"), std::string::npos) << row;
  // Started again, it solves the two missing runs and nothing else.
  ASSERT_EQ(cli("sweep " + file.string() + " --shard 1/1"), 0) << err();
  EXPECT_NE(out().find("4 runs (0 solved now, 4 had results)"), std::string::npos) << out();
}

TEST_F(SweepTest, ARunThatFailsForItsOwnReasonsIsRecordedOnceWithItsError) {
  const fs::path results_dir = dir_ / "results_dir";
  const fs::path file = write_sweep("s.toml", "out = \"" + results_dir.string() + "\"",
                                    "[set]\n\"solver.max_cutbacks\" = 0\n[vary]\n\"solver.max_newton\" = [1, 50]\n");
  ASSERT_EQ(cli("sweep " + file.string() + " --quiet"), 0) << err();
  EXPECT_NE(err().find("not_converged"), std::string::npos) << err();
  const std::vector<std::string> rows = table_rows(results_dir / "results.csv");
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(count(rows[0] + rows[1], ",not_converged,"), 1);
  EXPECT_EQ(count(rows[0] + rows[1], ",finished,"), 1);
  ASSERT_EQ(cli("sweep " + file.string() + " --shard 1/1"), 0) << err();
  EXPECT_NE(out().find("(0 solved now, 2 had results)"), std::string::npos) << out();
}

TEST_F(SweepTest, BadSweepFilesExitWith2NamingTheKeyAndStartNothing) {
  const fs::path out = dir_ / "never";
  const std::string section = "out = \"" + out.string() + "\"";
  const struct {
    const char* vary;
    const char* key;
  } bad[] = {
      {"[vary]\n\"material.Ee\" = [1e9, 2e9]\n", "material.Ee"},              // not a load-case key
      {"[vary]\n\"material.E\" = []\n", "vary.material.E"},                     // an empty list
      {"[vary]\n\"material.E\" = {from = 1e9, to = 1e9, count = 3}\n", "vary.material.E"},  // an empty range
      {"[vary]\n\"material.E\" = {from = 1e9, to = 2e9}\n", "vary.material.E"},             // a grid range without count
      {"[vary]\n\"material.nu\" = {from = 0.3, to = 0.5, count = 3}\n", "material.nu"},     // nu = 0.5: impossible
      {"[vary]\n\"material.E\" = {from = -1e9, to = 2e9, count = 2, scale = \"log\"}\n", "vary.material.E"},
      {"[vary]\n\"material.E\" = [1e9]\n[extra]\n", "extra"},
      {"", "vary"},
  };
  for (const auto& b : bad) {
    SCOPED_TRACE(b.vary);
    const fs::path file = write_sweep("bad.toml", section, b.vary);
    EXPECT_EQ(cli("sweep " + file.string()), 2) << err();
    EXPECT_NE(err().find(b.key), std::string::npos) << err();
    EXPECT_NE(err().find("bad.toml"), std::string::npos) << err();
    EXPECT_FALSE(fs::exists(out));
  }
  const fs::path file = write_sweep("bad.toml", section, "[vary]\n\"material.E\" = [1e9]\n");
  for (const char* shard : {"0/3", "4/3", "1/0", "x", "1/3/4"}) {
    EXPECT_EQ(cli("sweep " + file.string() + " --shard " + shard), 2) << shard;
    EXPECT_NE(err().find("--shard"), std::string::npos) << err();
  }
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(SweepTest, IntegerKeysStayIntegersAndShareALatinHypercubesStrataEqually) {
  const fs::path file = write_sweep("lhs.toml", "design = \"latin_hypercube\"\nsamples = 8\nseed = 3",
                                    "[vary]\n\"mesh.contact_nodes\" = {from = 6, to = 9}\n"
                                    "\"material.E\" = {from = 100e9, to = 300e9}\n");
  const SweepManifest m = expand_sweep(read_sweep_definition(file));
  ASSERT_EQ(m.keys.front(), "material.E");
  std::map<std::string, int> counts;
  for (const SweepRun& r : m.runs) ++counts[r.values[1]];
  EXPECT_EQ(counts, (std::map<std::string, int>{{"6", 2}, {"7", 2}, {"8", 2}, {"9", 2}}));
  // A float key with integer ends is not an integer key; an integer key refuses fractional ends.
  const fs::path grid = write_sweep("grid.toml", "", "[vary]\n\"geometry.lx\" = {from = 1, to = 2, count = 3}\n");
  const SweepManifest g = expand_sweep(read_sweep_definition(grid));
  ASSERT_EQ(g.runs.size(), 3u);
  EXPECT_EQ(g.runs[1].values[0], "1.5");
  const fs::path bad = write_sweep("bad.toml", "", "[vary]\n\"mesh.contact_nodes\" = {from = 6.5, to = 9, count = 2}\n");
  EXPECT_THROW(read_sweep_definition(bad), InputError);
}

TEST_F(SweepTest, AFolderUnderAHashWithoutAResultIsReplacedByTheRun) {
  const fs::path results_dir = dir_ / "out";
  const fs::path file = write_sweep("s.toml", "out = \"" + results_dir.string() + "\"", "[vary]\n\"material.E\" = [200e9]\n");
  const SweepManifest m = expand_sweep(read_sweep_definition(file));
  fs::create_directories(results_dir / "runs" / m.runs[0].hash / "stray");
  ASSERT_EQ(cli("sweep " + file.string() + " --quiet"), 0) << err();
  EXPECT_TRUE(SweepResults(results_dir).complete(m.runs[0].hash));
  EXPECT_FALSE(fs::exists(results_dir / "runs" / m.runs[0].hash / "stray"));
}
