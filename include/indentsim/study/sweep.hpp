#pragma once
// A parameter sweep: a base load case, the keys to vary, and what to keep of each run, read from
// a sweep file (TOML) and expanded into a manifest of runs, each keyed by a hash of its complete
// load case.  The manifest is compact: a run is its index, its hash and its varied values; its
// case is the base case with [set] and those values, made again when the run is solved (a sweep
// of a million runs is tens of megabytes, not gigabytes).  The manifest is engine-neutral:
// `indentsim sweep` runs shards of it in one process, a Slurm job array runs one shard per array
// task, and the Python module hands batches of it to Dask workers; all of them write each
// finished run under its hash (sweep_results.hpp), so a sweep started on one engine can be
// finished on another.  Runs are numbered from 0 everywhere (results.csv, --list, messages).
//
//   [sweep]
//   base = "../loadcases/elastic.toml"   # relative to the sweep file
//   out = "out/sweep"                    # results folder (relative to the working directory)
//   design = "grid"                      # every combination, or "latin_hypercube"
//   samples = 24                         # latin_hypercube: how many runs
//   seed = 1                             # latin_hypercube: the same seed gives the same runs
//   keep = ["curve", "summary"]          # each run's files kept besides result.json
//   max_runs = 200000                    # the most runs the sweep may have (default 100000)
//   [set]                                # keys set in every run (a key may not also be in [vary])
//   "mesh.error_estimate" = "off"
//   [vary]
//   "material.E" = [100e9, 200e9]                                    # a list
//   "material.nu" = { from = 0.2, to = 0.4, count = 3 }              # a range, ends included
//   "material.yield_stress" = { from = 1e8, to = 1e9, count = 4, scale = "log" }
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "indentsim/input/load_case.hpp"

namespace indentsim {

enum class SweepDesign { grid, latin_hypercube };

/// The most runs a sweep may have unless its [sweep] max_runs raises the limit.
constexpr std::int64_t default_max_sweep_runs = 100000;
/// The largest max_runs a sweep file may give.
constexpr std::int64_t largest_max_sweep_runs = 100000000;

/// One varied key and its values, each a TOML value as text (1e+11, 0.3, "cone", 20).
struct SweptKey {
  std::string key;  ///< section.name of the load case
  std::vector<std::string> values;  ///< grid: the values; latin_hypercube: unused
  /// A range {from, to} (latin_hypercube samples it; grid takes `count` values).
  double from = 0.0, to = 0.0;
  bool logarithmic = false;
  bool integer = false;  ///< an integer key (mesh.contact_nodes, ...): values are integers
};

/// What a sweep file asks for.
struct SweepDefinition {
  std::filesystem::path file;  ///< the sweep file
  std::filesystem::path base;  ///< the base load case
  std::filesystem::path out;   ///< the results folder
  SweepDesign design = SweepDesign::grid;
  int samples = 0;            ///< latin_hypercube
  std::uint64_t seed = 1;     ///< latin_hypercube
  std::vector<std::string> keep{"curve", "summary"};
  std::int64_t max_runs = default_max_sweep_runs;  ///< [sweep] max_runs
  std::vector<std::string> set;  ///< "key=value" overrides of every run
  std::vector<SweptKey> vary;

  /// The number of combinations before identical cases are merged: a grid's product of the value
  /// counts (saturated at INT64_MAX), a Latin hypercube's samples.
  std::int64_t combinations() const;
};

/// One run of the sweep: its varied values (its case is SweepManifest::run_case).
struct SweepRun {
  int index = 0;                                ///< 0-based, in the manifest's order
  std::string hash;                             ///< 16 hex digits of the case's content hash
  std::vector<std::string> values;              ///< one per varied key, as TOML text
  /// The complete load case (to_toml) when it is already made: empty in an expanded manifest;
  /// what SweepResults::run solves (the caller fills it: run_case, or a Dask batch's case).
  std::string case_toml;
};

/// The expanded sweep: every run, validated.
struct SweepManifest {
  SweepDefinition definition;
  std::vector<std::string> keys;  ///< the varied keys, sorted by name (a grid varies the first slowest)
  std::vector<SweepRun> runs;
  int merged_duplicates = 0;  ///< combinations that gave an earlier run's case (run once)

  /// The overrides that make a run's case of the base case: [set], then its varied values.
  std::vector<std::string> overrides(const SweepRun& run) const;
  /// A run's complete load case (to_toml), made again of the base case and its overrides (or its
  /// case_toml when it has one).  Throws InputError naming the base case when that no longer
  /// gives the run's hash (it was changed since the sweep was expanded).
  std::string run_case(const SweepRun& run) const;
  /// manifest.json (format 2): the definition's essentials ([set] included) and every run's
  /// index, hash and values, a line each.  Throws Interrupted on SIGINT/SIGTERM.
  std::string to_json() const;
  /// The same with every run's complete case ("case"): what the Python module hands Dask.
  std::string to_json_with_cases() const;
  /// Reads format 2, and format 1 (whose runs hold their cases).
  static SweepManifest from_json(const std::string& text, const std::string& source);
};

/// Reads a sweep file; throws InputError naming the file, the key and the problem (unknown keys,
/// empty or reversed ranges, a design without what it needs, a key both in [set] and [vary],
/// more runs than max_runs).
SweepDefinition read_sweep_definition(const std::filesystem::path& file);

/// Expands the sweep into its runs and validates every one of them as a load case: a combination
/// a load case does not accept throws InputError naming the sweep file, the key, the problem and
/// the run's values, before anything is started.  Identical cases appear once.  No case text is
/// kept (SweepManifest::run_case makes it again); a sweep of more than definition.max_runs runs
/// throws InputError before any run is expanded.  Polls the interruption flag (interruption.hpp)
/// run by run: throws Interrupted on SIGINT/SIGTERM.
SweepManifest expand_sweep(const SweepDefinition& definition);

/// The hash of a load case's content: everything but its source and its [output] section, so
/// that the same physics and numerics have the same hash wherever the case came from.
std::string case_hash(const LoadCase& load_case);

/// "i/N" of --shard (1 <= i <= N): throws InputError("--shard", ...) otherwise.
std::pair<int, int> parse_shard(const std::string& text);
/// The runs of shard i of N: every N-th run from the i-th (those whose 0-based index mod N is i - 1).
std::vector<const SweepRun*> shard_runs(const SweepManifest& manifest, int shard, int shards);

}  // namespace indentsim
