#include "indentsim/output/run_folder.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>

#include <fmt/format.h>

#include "indentsim/base/error.hpp"
#include "indentsim/base/file_system.hpp"

namespace fs = std::filesystem;

namespace indentsim {

namespace {

constexpr const char* lock_name = ".indentsim.lock";

/// The files of a run directly in its folder; fields/, checkpoints/ and figures/ hold the rest.
constexpr const char* run_files[] = {"case.toml",    "curve.csv",    "summary.json", "layers.csv",
                                     "profiles.csv", "fields.pvd",   "analysis.json"};
constexpr const char* run_folders[] = {"fields", "checkpoints", "figures"};

/// The step of fields/step_NNNNNN.vtu or checkpoints/checkpoint_NNNNNN.ck, or -1.
int step_of(const fs::path& file, const std::string& prefix) {
  const std::string name = file.stem().string();
  if (name.rfind(prefix, 0) != 0) return -1;
  const std::string digits = name.substr(prefix.size());
  if (digits.empty() || digits.find_first_not_of("0123456789") != std::string::npos || digits.size() > 9) return -1;
  return std::stoi(digits);
}

bool is_run_file(const fs::path& file, const std::string& folder) {
  const std::string ext = file.extension().string();
  if (ext == ".tmp") return true;
  if (folder == "fields") return ext == ".vtu" && step_of(file, "step_") >= 0;
  if (folder == "checkpoints") return ext == ".ck" && step_of(file, "checkpoint_") >= 0;
  if (folder == "figures") return ext == ".png" || ext == ".svg";
  return false;
}

[[noreturn]] void fail(const std::string& source, const std::string& problem) {
  throw InputError(source, "output.dir", problem);
}

}  // namespace

void inspect_output_dir(const fs::path& dir, const std::string& source) {
  std::error_code ec;
  const auto status = fs::status(dir, ec);
  if (fs::exists(status)) {
    if (!fs::is_directory(status)) fail(source, fmt::format("\"{}\" exists and is not a folder", dir.string()));
    if (::access(dir.c_str(), W_OK | X_OK) != 0)
      fail(source, fmt::format("cannot write in \"{}\": {}", dir.string(), std::strerror(errno)));
    // Everything a run replaces or writes, checked before anything is locked, removed or solved:
    // a file it cannot replace (immutable, read-only) or a folder where it writes a file would
    // otherwise stop it at the first write, after the earlier run's files were gone.
    const auto replaceable = [&](const fs::path& p) {
      if (!fs::exists(fs::symlink_status(p, ec))) return;
      if (!fs::is_regular_file(fs::symlink_status(p, ec)))
        fail(source, fmt::format("\"{}\" is in the way: a run writes a file there", p.string()));
      if (::access(p.c_str(), W_OK) != 0)
        fail(source, fmt::format("cannot replace \"{}\": {}", p.string(), std::strerror(errno)));
    };
    replaceable(dir / lock_name);
    for (const char* name : run_files) replaceable(dir / name);
    for (const char* name : run_folders) {
      const fs::path p = dir / name;
      if (!fs::exists(p, ec)) continue;
      if (!fs::is_directory(p, ec))
        fail(source, fmt::format("\"{}\" is in the way: a run writes a folder there", p.string()));
      if (::access(p.c_str(), W_OK | X_OK) != 0)
        fail(source, fmt::format("cannot write in \"{}\": {}", p.string(), std::strerror(errno)));
      for (const auto& entry : fs::directory_iterator(p, ec))
        if (is_run_file(entry.path(), name)) replaceable(entry.path());
    }
    return;
  }
  // The folder does not exist yet: the nearest existing ancestor must be a writable folder.
  fs::path ancestor = fs::absolute(dir, ec).parent_path();
  while (!ancestor.empty() && !fs::exists(ancestor, ec) && ancestor != ancestor.root_path())
    ancestor = ancestor.parent_path();
  if (!fs::is_directory(ancestor, ec))
    fail(source, fmt::format("cannot create \"{}\": \"{}\" is not a folder", dir.string(), ancestor.string()));
  if (::access(ancestor.c_str(), W_OK | X_OK) != 0)
    fail(source, fmt::format("cannot create \"{}\": {}", dir.string(), std::strerror(errno)));
}

RunFolder::RunFolder(fs::path dir, std::string source) : dir_(std::move(dir)), source_(std::move(source)) {
  inspect_output_dir(dir_, source_);
  std::error_code ec;
  created_ = !fs::exists(dir_, ec);
  fs::create_directories(dir_, ec);
  if (ec) fail(source_, fmt::format("cannot create \"{}\": {}", dir_.string(), ec.message()));

  const fs::path lock = dir_ / lock_name;
  lock_fd_ = ::open(lock.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (lock_fd_ < 0) fail(source_, fmt::format("cannot create \"{}\": {}", lock.string(), std::strerror(errno)));
  if (::flock(lock_fd_, LOCK_EX | LOCK_NB) != 0) {
    const int error = errno;
    ::close(lock_fd_);
    lock_fd_ = -1;
    if (error != EWOULDBLOCK) fail(source_, fmt::format("cannot lock \"{}\": {}", lock.string(), std::strerror(error)));
    std::string holder;
    std::ifstream(lock) >> holder;
    fail(source_, fmt::format("\"{}\" is in use by another indentsim run (pid {}); wait for it to end or choose "
                              "another folder",
                              dir_.string(), holder.empty() ? "unknown" : holder));
  }
  const std::string pid = std::to_string(::getpid()) + "\n";
  if (::ftruncate(lock_fd_, 0) != 0 || ::pwrite(lock_fd_, pid.data(), pid.size(), 0) != static_cast<ssize_t>(pid.size()))
    fail(source_, fmt::format("cannot write \"{}\": {}", lock.string(), std::strerror(errno)));

  // Test-write where the run will write, so that a read-only or full file system is reported now
  // and not after hours of solving.
  for (const fs::path folder : {dir_, dir_ / "fields", dir_ / "checkpoints"}) {
    fs::create_directories(folder, ec);
    if (ec) fail(source_, fmt::format("cannot create \"{}\": {}", folder.string(), ec.message()));
    const fs::path probe = folder / ".indentsim.write-test";
    const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0 || ::write(fd, "ok\n", 3) != 3) {
      const int error = errno;
      if (fd >= 0) ::close(fd);
      ::unlink(probe.c_str());
      fail(source_, fmt::format("cannot write in \"{}\": {}", folder.string(), std::strerror(error)));
    }
    ::close(fd);
    ::unlink(probe.c_str());
  }
}

RunFolder::~RunFolder() {
  if (lock_fd_ < 0) return;
  if (!created_ && !written_) {
    // Refused before any run file was written: the folder is left as it was found.
    std::error_code ec;
    fs::remove(dir_ / lock_name, ec);
    ::close(lock_fd_);
    return;
  }
  if (created_ && !written_) {
    // Nothing of a run was written: leave no trace of the attempt (bad input writes nothing).
    std::error_code ec;
    for (const char* folder : run_folders) fs::remove(dir_ / folder, ec);
    fs::remove(dir_ / lock_name, ec);
    ::close(lock_fd_);
    fs::remove(dir_, ec);
    return;
  }
  ::close(lock_fd_);  // releases the lock
}

void RunFolder::clear_earlier_run(std::optional<int> continuing_after_step) {
  written_ = true;
  std::error_code ec;
  const auto remove = [&](const fs::path& p) {
    if (!fs::remove(p, ec) && ec) throw_io_error(p, "removing", ec.value());
  };
  for (const char* name : run_files)
    if (!continuing_after_step || std::string(name) != "curve.csv") remove(dir_ / name);
  for (const auto& entry : fs::directory_iterator(dir_, ec))
    if (entry.path().extension() == ".tmp") remove(entry.path());
  for (const char* folder : run_folders) {
    const fs::path sub = dir_ / folder;
    if (!fs::is_directory(sub, ec)) continue;
    for (const auto& entry : fs::directory_iterator(sub, ec)) {
      const fs::path& p = entry.path();
      if (!is_run_file(p, folder)) continue;
      if (continuing_after_step && p.extension() != ".tmp") {
        if (std::string(folder) == "checkpoints") continue;  // the run's own history
        if (std::string(folder) == "fields" && step_of(p, "step_") <= *continuing_after_step) continue;
      }
      remove(p);
    }
  }
}

}  // namespace indentsim
