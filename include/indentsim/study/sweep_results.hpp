#pragma once
// A sweep's results folder, keyed by the hash of each run's case (sweep.hpp):
//
//   OUT/manifest.json          every run: its index, hash and varied values
//   OUT/runs/HASH/result.json  a finished run's hash, status and figures, and the size and
//                              checksum of each file kept with it (written last)
//   OUT/runs/HASH/curve.csv    ... and the files the sweep keeps of it
//   OUT/results.csv            the table: one row per run of the manifest
//
// A run is solved in a private folder (OUT/runs/.partial/HASH.PID.N) and renamed to OUT/runs/HASH
// only when it is complete, so a folder under its hash is always a whole result: an interrupted
// sweep (Ctrl-C, a killed worker or client, a Slurm task past its time) is started again and
// redoes only the runs without one.  A run that fails for its own reasons (its input, no
// convergence) is a result too, with its error, and is not run again.  A result.json that is not
// whole (damaged, of another run's hash, or its kept files not those it recorded) is no result:
// the sweep warns, naming the file and what is wrong, and does the run again.
#include <cstdint>
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
  /// ... and its specimen modulus E [Pa] (of E_r and the specimen's nu), residual depth h_f [m]
  /// and pile-up ratio (the true contact area over Oliver-Pharr's).
  std::optional<double> specimen_modulus, residual_depth, pile_up_ratio;
  std::optional<double> material_E;  ///< the case's material.E [Pa]: the specimen modulus the run used
  int newton_iterations = 0;
  double wall_seconds = 0.0;
  /// A file kept with the run (its path in the run's folder), as it was when the run was written.
  struct KeptFile {
    std::string name;
    std::uintmax_t bytes = 0;
    std::string fnv1a;  ///< 16 hex digits: FNV-1a of its bytes
  };
  std::vector<KeptFile> files;  ///< empty in a result.json of a version that did not record them

  std::string to_json() const;
  /// Throws InputError naming `source` when the text is not a whole result (not JSON, a member
  /// missing or of the wrong type, a number not finite, an unknown status).
  static SweepRunResult from_json(const std::string& text, const std::string& source);
};

/// What OUT/runs/HASH holds.
struct SweepRunLookup {
  std::optional<SweepRunResult> result;  ///< a whole result of the run with this hash
  std::string problem;                   ///< why result.json is no result (empty: none there, or good)
  std::filesystem::path file;            ///< that result.json
};

/// The counts `collect` reports.
struct SweepTally {
  int runs = 0, finished = 0, not_converged = 0, failed = 0, pending = 0;
  int damaged = 0;  ///< of the pending: a result.json there that is no result
  std::vector<std::string> problems;  ///< for each of those: "FILE: what is wrong"
};

class SweepResults {
public:
  explicit SweepResults(std::filesystem::path out);

  /// Writes OUT/manifest.json (atomically; left alone when it already holds the same text).
  void write_manifest(const SweepManifest& manifest) const;
  /// Whether the run with this hash has its result (a whole one: look_up).
  bool complete(const std::string& hash) const;
  /// The result of the run with this hash, or why the result.json under it is none: not a whole
  /// result, a result of another hash, or a kept file missing or not as recorded (each kept
  /// file's size, and the checksums of curve.csv and summary.json).  Never throws for what the
  /// folder holds.
  SweepRunLookup look_up(const std::string& hash) const;
  /// Solves `run` (quietly: its case_toml, which the caller fills, e.g. SweepManifest::run_case)
  /// and moves its folder under its hash, keeping result.json and the files named in `keep`.
  /// Throws Interrupted on SIGINT/SIGTERM (nothing of the run is kept) and IoError when the
  /// results folder cannot be written (not the run's fault: it can be retried elsewhere).  If
  /// another worker finished the same run meanwhile, its result stays; a folder under the hash
  /// without a whole result (look_up) is replaced.
  SweepRunResult run(const SweepRun& run, const std::vector<std::string>& keep) const;
  /// The result of a complete run; nullopt when it has none (or a damaged one: look_up).
  std::optional<SweepRunResult> result(const std::string& hash) const;
  /// Writes OUT/results.csv, a row per run of the manifest ("pending" for those without a result;
  /// a damaged one's row says what is wrong in `message`, and so does the tally's `problems`).
  /// Throws Interrupted on SIGINT/SIGTERM (the table is then not written).
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
