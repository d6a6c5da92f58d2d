#pragma once
// A sweep's results folder, keyed by the hash of each run's case (sweep.hpp):
//
//   OUT/manifest.json          every run: its hash, varied values and complete load case
//   OUT/runs/HASH/result.json  a finished run's status and figures (written last)
//   OUT/runs/HASH/curve.csv    ... and the files the sweep keeps of it
//   OUT/results.csv            the table: one row per run of the manifest
//
// A run is solved in a private folder (OUT/runs/.partial/HASH.PID.N) and renamed to OUT/runs/HASH
// only when it is complete, so a folder under its hash is always a whole result: an interrupted
// sweep (Ctrl-C, a killed worker or client, a Slurm task past its time) is started again and
// redoes only the runs without one.  A run that fails for its own reasons (its input, no
// convergence) is a result too, with its error, and is not run again.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "indentsim/study/sweep.hpp"

namespace indentsim {

/// What the table keeps of one run (result.json holds the same).
struct SweepRunResult {
  std::string hash;
  int index = 0;
  std::string status;   ///< "finished", "not_converged" or "failed" (its input or the solver)
  std::string message;  ///< why it did not finish
  std::string force_unit;
  int increments = 0;
  std::optional<double> peak_depth, peak_force;  ///< [m], [force unit]
  std::optional<double> final_alpha, final_force, final_contact;  ///< the last increment: alpha, P, a [m]
  std::optional<double> force_relative_error_estimate;  ///< mesh.error_estimate on: of the final P
  std::optional<double> hardness, reduced_modulus;  ///< the first unloading branch's Oliver-Pharr H, E_r [Pa]
  int newton_iterations = 0;
  double wall_seconds = 0.0;

  std::string to_json() const;
  static SweepRunResult from_json(const std::string& text, const std::string& source);
};

/// The counts `collect` reports.
struct SweepTally {
  int runs = 0, finished = 0, not_converged = 0, failed = 0, pending = 0;
};

class SweepResults {
public:
  explicit SweepResults(std::filesystem::path out);

  /// Writes OUT/manifest.json (atomically; left alone when it already holds the same text).
  void write_manifest(const SweepManifest& manifest) const;
  /// Whether the run with this hash has its result.
  bool complete(const std::string& hash) const;
  /// Solves `run` (quietly) and moves its folder under its hash, keeping result.json and the
  /// files named in `keep`.  Throws Interrupted on SIGINT/SIGTERM (nothing of the run is kept)
  /// and IoError when the results folder cannot be written (not the run's fault: it can be
  /// retried elsewhere).  If another worker finished the same run meanwhile, its result stays.
  SweepRunResult run(const SweepRun& run, const std::vector<std::string>& keep) const;
  /// The result of a complete run; nullopt when it has none.
  std::optional<SweepRunResult> result(const std::string& hash) const;
  /// Writes OUT/results.csv, a row per run of the manifest ("pending" for those without a result).
  SweepTally collect(const SweepManifest& manifest) const;

  const std::filesystem::path& out() const { return out_; }
  std::filesystem::path table_path() const { return out_ / "results.csv"; }

private:
  std::filesystem::path out_;
};

/// The files a sweep can keep of each run besides result.json: "curve" (curve.csv), "summary"
/// (summary.json), "case" (case.toml), "fields" (fields.pvd and fields/), "layers" (layers.csv,
/// profiles.csv).
const std::vector<std::string>& sweep_keepable_outputs();

}  // namespace indentsim
