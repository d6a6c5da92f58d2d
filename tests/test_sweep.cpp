// Parameter sweeps: the sweep file's designs, the hash that keys each run, and the promises of
// the results folder -- each run's curve is the CLI run's, shards and the Slurm array's tasks
// add up to the whole sweep, an interrupted sweep redoes only its missing runs, a run that fails
// for its own reasons is recorded once, and bad sweep files start nothing.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
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
  /// results.csv as rows of {column: cell}, quoted cells unquoted.
  static std::vector<std::map<std::string, std::string>> read_table(const fs::path& file) {
    const std::string text = indentsim::testing::slurp(file);
    std::vector<std::vector<std::string>> lines(1);
    std::string cell;
    bool quoted = false;
    for (std::size_t k = 0; k < text.size(); ++k) {
      const char c = text[k];
      if (quoted) {
        if (c == '"' && k + 1 < text.size() && text[k + 1] == '"') cell += text[++k];
        else if (c == '"') quoted = false;
        else cell += c;
      } else if (c == '"') {
        quoted = true;
      } else if (c == ',') {
        lines.back().push_back(cell);
        cell.clear();
      } else if (c == '\n') {
        lines.back().push_back(cell);
        cell.clear();
        lines.emplace_back();
      } else {
        cell += c;
      }
    }
    if (lines.back().empty()) lines.pop_back();
    std::vector<std::map<std::string, std::string>> rows;
    for (std::size_t r = 1; r < lines.size(); ++r) {
      EXPECT_EQ(lines[r].size(), lines[0].size()) << "row " << r << " of " << file;
      std::map<std::string, std::string> row;
      for (std::size_t k = 0; k < lines[0].size() && k < lines[r].size(); ++k) row[lines[0][k]] = lines[r][k];
      rows.push_back(row);
    }
    return rows;
  }
  /// The row of results.csv with this hash.
  static std::map<std::string, std::string> row_of(const fs::path& table, const std::string& hash) {
    for (const auto& row : read_table(table))
      if (row.at("hash") == hash) return row;
    ADD_FAILURE() << "no row of " << hash << " in " << table;
    return {};
  }
  static void write(const fs::path& file, const std::string& text) { std::ofstream(file, std::ios::binary) << text; }
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
    // The complete case, made again of the base case, holds the run's values.
    const LoadCase lc = parse_load_case(m.run_case(r), "manifest");
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

TEST_F(SweepTest, AResultJsonOfAnotherRunIsNoResultWarnedAboutAndItsRunIsDoneAgain) {
  const fs::path results_dir = dir_ / "out";
  const fs::path file = write_sweep("s.toml", "out = \"" + results_dir.string() + "\"", "[vary]\n\"material.E\" = [150e9, 250e9]\n");
  ASSERT_EQ(cli("sweep " + file.string() + " --quiet"), 0) << err();
  const SweepManifest m = expand_sweep(read_sweep_definition(file));
  ASSERT_EQ(m.runs.size(), 2u);
  const std::string first = m.runs[0].hash, second = m.runs[1].hash;
  // The first run's whole folder copied over the second's: whole, but the first run's result.
  fs::remove_all(results_dir / "runs" / second);
  fs::copy(results_dir / "runs" / first, results_dir / "runs" / second);
  const fs::path foreign = results_dir / "runs" / second / "result.json";
  const SweepResults results(results_dir);
  EXPECT_FALSE(results.complete(second));
  EXPECT_NE(results.look_up(second).problem.find(first), std::string::npos) << results.look_up(second).problem;

  ASSERT_EQ(cli("sweep " + file.string() + " --collect"), 0) << err();
  EXPECT_NE(err().find("warning: " + foreign.string()), std::string::npos) << err();
  EXPECT_NE(out().find("1 finished"), std::string::npos) << out();
  EXPECT_NE(out().find("1 pending"), std::string::npos) << out();
  const auto row = row_of(results_dir / "results.csv", second);
  EXPECT_EQ(row.at("status"), "pending");
  EXPECT_EQ(row.at("index"), "1");
  EXPECT_NE(row.at("message").find(first), std::string::npos) << row.at("message");

  // The sweep does the run again, under its own hash.
  ASSERT_EQ(cli("sweep " + file.string() + " --quiet"), 0) << err();
  EXPECT_NE(err().find(foreign.string()), std::string::npos) << err();
  EXPECT_NE(err().find("run 1 is done again"), std::string::npos) << err();
  const auto redone = results.result(second);
  ASSERT_TRUE(redone);
  EXPECT_EQ(redone->hash, second);
  ASSERT_TRUE(redone->material_E);
  EXPECT_EQ(*redone->material_E, 250e9);
  for (const auto& r : read_table(results_dir / "results.csv")) EXPECT_EQ(r.at("status"), "finished") << r.at("hash");
}

TEST_F(SweepTest, ADamagedResultJsonIsAMissingResultNamedInAWarningNeverAnExit2AndItsRunIsDoneAgain) {
  const fs::path results_dir = dir_ / "out";
  const fs::path file = write_sweep("s.toml", "out = \"" + results_dir.string() + "\"", "[vary]\n\"material.E\" = [200e9]\n");
  ASSERT_EQ(cli("sweep " + file.string() + " --quiet"), 0) << err();
  const std::string hash = expand_sweep(read_sweep_definition(file)).runs.at(0).hash;
  const fs::path result_file = results_dir / "runs" / hash / "result.json";
  const std::string whole = indentsim::testing::slurp(result_file);
  // result.json with one member's value replaced by `by`.
  const auto replaced = [&](const std::string& member, const std::string& by) {
    const auto at = whole.find("\"" + member + "\": ");
    EXPECT_NE(at, std::string::npos) << member;
    const auto value = at + member.size() + 4, end = whole.find_first_of(",\n}", value);
    return whole.substr(0, value) + by + whole.substr(end);
  };
  const struct {
    const char* what;
    std::string text;
  } damages[] = {
      {"cut short", whole.substr(0, whole.size() / 2)},
      {"garbage", "\x01\x7fgarbage not JSON"},
      {"an empty object", "{}"},
      {"Infinity", replaced("wall_s", "Infinity")},
      {"a number overflowing", replaced("peak_force", "1e999")},
      {"an unknown status", replaced("status", "\"done\"")},
      {"a hash of no run", replaced("hash", "\"not a hash\"")},
  };
  const SweepResults results(results_dir);
  for (const auto& d : damages) {
    SCOPED_TRACE(d.what);
    write(result_file, d.text);
    EXPECT_FALSE(results.complete(hash));
    EXPECT_NE(results.look_up(hash).problem.find("is not a sweep run's result"), std::string::npos)
        << results.look_up(hash).problem;
    // --collect: the row is pending and says why; the file is named; exit 0.
    ASSERT_EQ(cli("sweep " + file.string() + " --collect"), 0) << err();
    EXPECT_NE(err().find("warning: " + result_file.string() + ": is not a sweep run's result"), std::string::npos) << err();
    const auto row = row_of(results_dir / "results.csv", hash);
    EXPECT_EQ(row.at("status"), "pending");
    EXPECT_NE(row.at("message").find("is not a sweep run's result"), std::string::npos) << row.at("message");
    ASSERT_EQ(cli("sweep " + file.string() + " --list"), 0) << err();
    EXPECT_NE(out().find(hash + " pending"), std::string::npos) << out();
    // The sweep does it again.
    ASSERT_EQ(cli("sweep " + file.string() + " --quiet"), 0) << err();
    EXPECT_NE(err().find(result_file.string()), std::string::npos) << err();
    EXPECT_NE(err().find("run 0 is done again"), std::string::npos) << err();
    EXPECT_TRUE(results.complete(hash));
    EXPECT_EQ(row_of(results_dir / "results.csv", hash).at("status"), "finished");
  }
}

TEST_F(SweepTest, AKeptFileCutShortChangedOrLostIsSeenAgainstResultJsonAndItsRunIsDoneAgain) {
  const fs::path results_dir = dir_ / "out";
  const fs::path file = write_sweep("s.toml", "out = \"" + results_dir.string() + "\"", "[vary]\n\"material.E\" = [200e9]\n");
  ASSERT_EQ(cli("sweep " + file.string() + " --quiet"), 0) << err();
  const std::string hash = expand_sweep(read_sweep_definition(file)).runs.at(0).hash;
  const fs::path run_dir = results_dir / "runs" / hash;
  fs::copy_file(run_dir / "curve.csv", dir_ / "original_curve.csv");
  // Each damage of the curve as it is then (a run done again has other wall-clock times).
  const auto curve = [&] { return indentsim::testing::slurp(run_dir / "curve.csv"); };
  const struct {
    const char* what;
    std::function<void()> damage;
    const char* says;
  } damages[] = {
      {"curve.csv cut short (its last row lost)",
       [&] {
         const std::string text = curve();
         write(run_dir / "curve.csv", text.substr(0, text.rfind('\n', text.size() - 2) + 1));
       },
       "curve.csv has"},
      {"curve.csv changed, its size kept",
       [&] {
         std::string text = curve();
         const auto digit = text.find_last_of("0123456789");
         text[digit] = text[digit] == '1' ? '2' : '1';
         write(run_dir / "curve.csv", text);
       },
       "curve.csv is not the file"},
      {"summary.json lost", [&] { fs::remove(run_dir / "summary.json"); }, "summary.json, kept with it, is missing"},
  };
  for (const auto& d : damages) {
    SCOPED_TRACE(d.what);
    d.damage();
    ASSERT_EQ(cli("sweep " + file.string() + " --collect"), 0) << err();
    EXPECT_NE(err().find((run_dir / "result.json").string() + ": " + d.says), std::string::npos) << err();
    EXPECT_EQ(row_of(results_dir / "results.csv", hash).at("status"), "pending");
    ASSERT_EQ(cli("sweep " + file.string() + " --quiet"), 0) << err();
    EXPECT_NE(err().find("run 0 is done again"), std::string::npos) << err();
    EXPECT_EQ(indentsim::testing::curve_without_timing(run_dir / "curve.csv"),
              indentsim::testing::curve_without_timing(dir_ / "original_curve.csv"));
    EXPECT_TRUE(fs::is_regular_file(run_dir / "summary.json"));
    EXPECT_EQ(row_of(results_dir / "results.csv", hash).at("status"), "finished");
  }
}

TEST_F(SweepTest, ASweepOfMoreRunsThanItsMaximumIsRefusedSayingHowManyAndHowToRaiseTheLimit) {
  const fs::path never = dir_ / "never";
  const std::string section = "out = \"" + never.string() + "\"";
  const std::string million = "[vary]\n\"material.E\" = {from = 100e9, to = 300e9, count = 1000}\n"
                              "\"material.nu\" = {from = 0.1, to = 0.4, count = 1000}\n";
  const fs::path big = write_sweep("big.toml", section, million);
  const auto start = std::chrono::steady_clock::now();
  EXPECT_EQ(cli("sweep " + big.string()), 2) << err();
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5.0);  // nothing expanded
  EXPECT_NE(err().find("big.toml"), std::string::npos) << err();
  EXPECT_NE(err().find("1000000 runs"), std::string::npos) << err();
  EXPECT_NE(err().find(fmt::format("the {} a sweep may have", default_max_sweep_runs)), std::string::npos) << err();
  EXPECT_NE(err().find("max_runs = 1000000"), std::string::npos) << err();
  EXPECT_FALSE(fs::exists(never));
  const fs::path lhs = write_sweep("lhs.toml", section + "\ndesign = \"latin_hypercube\"\nsamples = 200000",
                                   "[vary]\n\"material.E\" = {from = 100e9, to = 300e9}\n");
  EXPECT_EQ(cli("sweep " + lhs.string()), 2) << err();
  EXPECT_NE(err().find("200000 runs"), std::string::npos) << err();

  // The file's own limit: 6 runs refused at max_runs = 5, taken at 6.
  const std::string six = "[vary]\n\"material.E\" = [1e11, 2e11]\n\"material.nu\" = [0.2, 0.25, 0.3]\n";
  EXPECT_EQ(cli("sweep " + write_sweep("six.toml", section + "\nmax_runs = 5", six).string() + " --list"), 2) << err();
  EXPECT_NE(err().find("6 runs (2 x 3 values), more than the 5"), std::string::npos) << err();
  EXPECT_NE(err().find("max_runs = 6"), std::string::npos) << err();
  EXPECT_EQ(cli("sweep " + write_sweep("six.toml", section + "\nmax_runs = 6", six).string() + " --list"), 0) << err();
  EXPECT_NE(out().find("6 runs"), std::string::npos) << out();
  EXPECT_EQ(cli("sweep " + write_sweep("six.toml", section + "\nmax_runs = 0", six).string()), 2) << err();
  EXPECT_NE(err().find("sweep.max_runs"), std::string::npos) << err();
  EXPECT_FALSE(fs::exists(never));
}

TEST_F(SweepTest, SigtermStopsTheExpansionOfABigSweepWithinASecondAndStartsNothing) {
  const fs::path never = dir_ / "never";
  // A million runs allowed: validating each takes tens of microseconds, so this one is still
  // being expanded a second after it started.
  const fs::path big = write_sweep("big.toml", "out = \"" + never.string() + "\"\nmax_runs = 1000000",
                                   "[vary]\n\"material.E\" = {from = 100e9, to = 300e9, count = 1000}\n"
                                   "\"material.nu\" = {from = 0.1, to = 0.4, count = 1000}\n");
  const std::string command =
      fmt::format("{} sweep {} --quiet >{} 2>{} </dev/null & pid=$!; sleep 1; kill -TERM $pid; wait $pid; echo $? >{}",
                  INDENTSIM_CLI, big.string(), (dir_ / "out.txt").string(), (dir_ / "err.txt").string(),
                  (dir_ / "status.txt").string());
  const auto start = std::chrono::steady_clock::now();
  ASSERT_EQ(std::system(command.c_str()), 0);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(std::stoi(indentsim::testing::slurp(dir_ / "status.txt")), 128 + 15) << err();
  EXPECT_LT(seconds, 1.0 + 3.0) << err();  // the signal came after 1 s; it stops within a run's validation
  EXPECT_NE(err().find("stopped by signal 15"), std::string::npos) << err();
  EXPECT_FALSE(fs::exists(never / "manifest.json"));
  EXPECT_FALSE(fs::exists(never / "runs"));
}

TEST_F(SweepTest, AKeyBothInSetAndInVaryExitsWith2NamingTheKeyAndTheSweepFile) {
  const fs::path never = dir_ / "never";
  const struct {
    const char* body;
    const char* key;
  } both[] = {
      {"[set]\n\"material.E\" = 1e11\n[vary]\n\"material.E\" = [1e11, 2e11]\n", "material.E"},
      {"[set]\nmaterial.E = 1e11\n[vary]\n\"material.E\" = {from = 1e11, to = 2e11, count = 2}\n", "material.E"},
      {"[set]\n\"material.nu\" = 0.3\n[vary]\nmaterial = {nu = [0.2, 0.3]}\n", "material.nu"},
  };
  for (const auto& b : both) {
    SCOPED_TRACE(b.body);
    const fs::path file = write_sweep("both.toml", "out = \"" + never.string() + "\"", b.body);
    EXPECT_EQ(cli("sweep " + file.string()), 2) << err();
    EXPECT_NE(err().find(file.string() + ": " + b.key + ": is both in [set] and in [vary]"), std::string::npos) << err();
    EXPECT_EQ(cli("sweep " + file.string() + " --list"), 2) << err();
    EXPECT_FALSE(fs::exists(never));
  }
}

TEST_F(SweepTest, ListAndMessagesNumberTheRunsAsResultsCsvDoes) {
  const fs::path results_dir = dir_ / "out";
  const fs::path file = write_sweep("s.toml", "out = \"" + results_dir.string() + "\"",
                                    "[set]\n\"solver.max_cutbacks\" = 0\n"
                                    "[vary]\n\"material.nu\" = [0.25, 0.3]\n\"solver.max_newton\" = [1, 50]\n");
  ASSERT_EQ(cli("sweep " + file.string() + " --quiet"), 0) << err();
  const auto rows = read_table(results_dir / "results.csv");
  ASSERT_EQ(rows.size(), 4u);
  std::map<std::string, std::string> index_of;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    EXPECT_EQ(rows[k].at("index"), std::to_string(k));  // from 0, in the manifest's order
    index_of[rows[k].at("hash")] = rows[k].at("index");
  }
  // "run N (HASH): not_converged: ..." names the run by its row's index.
  std::istringstream errors(err());
  int named = 0;
  for (std::string line; std::getline(errors, line);) {
    if (line.rfind("run ", 0) != 0 || line.find("not_converged") == std::string::npos) continue;
    const auto open = line.find(" ("), close = line.find("):");
    ASSERT_NE(close, std::string::npos) << line;
    EXPECT_EQ(line.substr(4, open - 4), index_of.at(line.substr(open + 2, close - open - 2))) << line;
    ++named;
  }
  int not_converged = 0;
  for (const auto& row : rows) not_converged += row.at("status") == "not_converged" ? 1 : 0;
  EXPECT_GE(not_converged, 1);
  EXPECT_EQ(named, not_converged) << err();
  // --list: the same index for the same hash.
  ASSERT_EQ(cli("sweep " + file.string() + " --list"), 0) << err();
  std::istringstream listing(out());
  int listed = 0;
  for (std::string line; std::getline(listing, line);) {
    std::istringstream words(line);
    int index = -1;
    std::string hash, state;
    if (!(words >> index >> hash >> state)) continue;
    EXPECT_EQ(std::to_string(index), index_of.at(hash)) << line;
    EXPECT_EQ(state, "done") << line;
    ++listed;
  }
  EXPECT_EQ(listed, 4) << out();
}

TEST_F(SweepTest, TheTableHoldsTheSpecimenModulusPileUpRatioAndResidualDepthAndSaysWhyAnAnalysisFailed) {
  const fs::path results_dir = dir_ / "out";
  // An elastic sphere loaded and unloaded: in 16 increments the unloading has points enough for
  // Oliver-Pharr's fit; in 2 it has none.
  const fs::path file = write_sweep("s.toml", "out = \"" + results_dir.string() + "\"",
                                    "[set]\n\"geometry.kind\" = \"axisymmetric\"\n\"load.path\" = [0.0, 2e-5, 0.0]\n"
                                    "[vary]\n\"load.increments\" = [2, 16]\n");
  ASSERT_EQ(cli("sweep " + file.string() + " --quiet"), 0) << err();
  const std::string header = indentsim::testing::slurp(results_dir / "results.csv").substr(0, 400);
  EXPECT_NE(header.find(",H,E_r,E,h_f,pile_up_ratio,material_E,"), std::string::npos) << header;
  std::map<std::string, std::map<std::string, std::string>> by_increments;
  for (const auto& row : read_table(results_dir / "results.csv")) by_increments[row.at("load.increments")] = row;
  ASSERT_EQ(by_increments.size(), 2u);

  const auto& analysed = by_increments.at("16");
  EXPECT_EQ(analysed.at("status"), "finished");
  EXPECT_EQ(analysed.at("message"), "");
  EXPECT_EQ(std::stod(analysed.at("material_E")), 210e9);  // the base case's E
  EXPECT_NEAR(std::stod(analysed.at("E")) / 210e9, 1.0, 0.1);  // Oliver-Pharr's specimen modulus
  EXPECT_GT(std::stod(analysed.at("h_f")), 0.0);
  EXPECT_LT(std::stod(analysed.at("h_f")), 2e-5);
  EXPECT_NEAR(std::stod(analysed.at("pile_up_ratio")), 1.0, 0.1);
  EXPECT_FALSE(analysed.at("H").empty());

  const auto& failed = by_increments.at("2");
  EXPECT_EQ(failed.at("status"), "finished");
  EXPECT_EQ(failed.at("H"), "");
  EXPECT_EQ(failed.at("E"), "");
  EXPECT_EQ(std::stod(failed.at("material_E")), 210e9);
  EXPECT_NE(failed.at("message").find("no Oliver-Pharr figures"), std::string::npos) << failed.at("message");
  EXPECT_NE(failed.at("message").find("needs at least 4"), std::string::npos) << failed.at("message");
}

TEST_F(SweepTest, AnUnusableDaskSchedulerExitsWith2InOneLineNamingIt) {
  if (!fs::is_regular_file(fs::path(INDENTSIM_CLI).parent_path() / "python" / "indentsim" / "sweep.py"))
    GTEST_SKIP() << "the Python package is not built beside the CLI (INDENTSIM_BUILD_PYTHON=OFF)";
  const fs::path file = write_sweep("s.toml", "out = \"" + (dir_ / "out").string() + "\"", "[vary]\n\"material.E\" = [200e9]\n");
  // Malformed (refused at once), and unreachable (a port nothing listens on: given up after a
  // few seconds, not Dask's 30).
  for (const std::string scheduler : {"foo://head:8786", "tcp://head", "tcp://127.0.0.1:1"}) {
    SCOPED_TRACE(scheduler);
    const auto start = std::chrono::steady_clock::now();
    const int status = cli("sweep " + file.string() + " --dask --quiet --scheduler " + scheduler);
    if (err().find("No module named") != std::string::npos) GTEST_SKIP() << "Dask is not installed: " << err();
    EXPECT_EQ(status, 2) << err();
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 20.0);
    EXPECT_EQ(count(err(), "\n"), 1) << err();  // one line, no traceback
    EXPECT_EQ(err().rfind("error: --scheduler " + scheduler + ": ", 0), 0u) << err();
    EXPECT_FALSE(fs::exists(dir_ / "out" / "runs")) << "nothing run";
  }
}
