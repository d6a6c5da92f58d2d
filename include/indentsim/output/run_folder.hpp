#pragma once
// The output folder of one run, held for the run's lifetime:
//  - one run at a time: an advisory lock (flock) on DIR/.indentsim.lock, which the kernel releases
//    when the process ends however it ends, so a killed run never leaves a stale lock;
//  - checked before anything is solved: DIR, DIR/fields and DIR/checkpoints can be created and
//    written (a test file is written and removed in each), and no file a run writes is in the
//    way as a folder (or a folder as a file);
//  - one run's files only: before the first write, the files an earlier run left (curve.csv,
//    summary.json, fields, checkpoints, figures, ...) are removed, so that a folder never mixes two
//    runs whatever stops the second.  Files that are not a run's are left alone.
#include <filesystem>
#include <optional>
#include <string>

namespace indentsim {

/// Checks, without creating or writing anything, that `dir` could hold a run's output: throws
/// InputError(source, "output.dir", problem with the operating system's reason) otherwise.  The
/// `check` command and RunFolder both use it.
void inspect_output_dir(const std::filesystem::path& dir, const std::string& source);

class RunFolder {
public:
  /// Creates `dir` if needed and locks it.  Throws InputError(source, "output.dir", ...) when
  /// another process holds the lock ("... is in use by another indentsim run (pid N)") or the
  /// folder cannot be written.  Nothing of an earlier run is touched yet.
  RunFolder(std::filesystem::path dir, std::string source);
  /// Releases the lock; a folder this object created and never wrote into is removed again.
  ~RunFolder();
  RunFolder(const RunFolder&) = delete;
  RunFolder& operator=(const RunFolder&) = delete;

  /// Called right before the run's first write: removes an earlier run's files.  A resumed run
  /// that continues in place passes the step it continues after: its own checkpoints are kept,
  /// and only fields written after that step (by the interrupted run) are removed.
  void clear_earlier_run(std::optional<int> continuing_after_step = std::nullopt);

  const std::filesystem::path& dir() const { return dir_; }

private:
  std::filesystem::path dir_;
  std::string source_;
  int lock_fd_ = -1;
  bool created_ = false, written_ = false;
};

}  // namespace indentsim
