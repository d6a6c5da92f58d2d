#pragma once
// Writing files so that a reader never sees half of one, and so that every failure says which
// file and why (the operating system's reason, from errno).  Every byte a run writes goes through
// write_all(), which is also the seam where the robustness tests inject a full disk.
#include <filesystem>
#include <string>

namespace indentsim {

/// Throws IoError naming `file`, what was being done and strerror(error).
[[noreturn]] void throw_io_error(const std::filesystem::path& file, const std::string& action, int error);

/// Writes all of `data` to the open descriptor `fd` (retrying short writes and EINTR); throws IoError.
void write_all(int fd, const char* data, std::size_t size, const std::filesystem::path& file);

/// A part of a file name no other writer uses at the same time, on this host or another sharing
/// the file system: "HOST-PID-N".
std::string unique_name_part();

/// Writes `text` to `path` atomically: a temporary file beside it, written whole, then renamed.
/// On failure the temporary file is removed and the previous `path` (if any) is left untouched.
void write_file_atomically(const std::filesystem::path& path, const std::string& text);

/// A file written line by line and flushed to the kernel after each line (curve.csv), so that a
/// killed run keeps every line written before.
class AppendedFile {
public:
  explicit AppendedFile(const std::filesystem::path& file);
  ~AppendedFile();
  AppendedFile(const AppendedFile&) = delete;
  AppendedFile& operator=(const AppendedFile&) = delete;
  void append(const std::string& text);
  /// Replaces everything written so far with `text`, atomically (write_file_atomically), and
  /// appends after it from then on.
  void replace(const std::string& text);
  const std::filesystem::path& path() const { return path_; }

private:
  std::filesystem::path path_;
  int fd_ = -1;
};

/// Fault injection for the robustness tests, from the environment variable INDENTSIM_FAULT=EVENT:N:
/// true at the N-th time `event` happens in this process.  Events: "increment" (after the N-th
/// reported increment; the CLI then kills itself), "checkpoint" (halfway through the N-th
/// checkpoint write, likewise), "write" (the N-th write_all call fails with ENOSPC, as on a full
/// disk), "fit_run" (the N-th forward run of a fit fails, and so do its retries).  Always false
/// when the variable is unset.
bool fault_due(const char* event);
/// Kills the process with SIGKILL when fault_due(event).
void inject_fault(const char* event);

}  // namespace indentsim
