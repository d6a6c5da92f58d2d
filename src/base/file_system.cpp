#include "indentsim/base/file_system.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <map>

#include <fmt/format.h>

#include "indentsim/base/error.hpp"

namespace indentsim {

void throw_io_error(const std::filesystem::path& file, const std::string& action, int error) {
  throw IoError(file.string(), action, std::strerror(error));
}

namespace {

struct FaultPlan {
  std::string event;
  int at = 0;
  std::map<std::string, int> seen;
};

FaultPlan& fault_plan() {
  static FaultPlan plan = [] {
    FaultPlan p;
    if (const char* spec = std::getenv("INDENTSIM_FAULT")) {
      const std::string s(spec);
      const auto colon = s.find(':');
      if (colon != std::string::npos) {
        p.event = s.substr(0, colon);
        p.at = std::atoi(s.c_str() + colon + 1);
      }
    }
    return p;
  }();
  return plan;
}

}  // namespace

bool fault_due(const char* event) {
  FaultPlan& plan = fault_plan();
  if (plan.event.empty() || plan.event != event) return false;
  return ++plan.seen[event] == plan.at;
}

void inject_fault(const char* event) {
  if (fault_due(event)) std::raise(SIGKILL);
}

void write_all(int fd, const char* data, std::size_t size, const std::filesystem::path& file) {
  if (fault_due("write")) throw_io_error(file, "writing", ENOSPC);  // robustness tests: a full disk
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw_io_error(file, "writing", errno);
    }
    data += n;
    size -= static_cast<std::size_t>(n);
  }
}

std::string unique_name_part() {
  static std::atomic<long> counter{0};
  char host[256] = {};
  if (::gethostname(host, sizeof host - 1) != 0) host[0] = '\0';
  std::string name = host[0] ? host : "host";
  for (char& c : name)
    if (c == '/' || c == '.') c = '_';
  return fmt::format("{}-{}-{}", name, ::getpid(), counter++);
}

void write_file_atomically(const std::filesystem::path& path, const std::string& text) {
  // A name of its own per writer: two processes (shards of a sweep) writing the same file at
  // once must not share the temporary.  The ".tmp" extension is what cleanups look for.
  const std::filesystem::path temporary = path.string() + "." + unique_name_part() + ".tmp";
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw_io_error(temporary, "creating", errno);
  try {
    write_all(fd, text.data(), text.size(), temporary);
  } catch (...) {
    ::close(fd);
    ::unlink(temporary.c_str());
    throw;
  }
  if (::close(fd) != 0) {
    const int error = errno;
    ::unlink(temporary.c_str());
    throw_io_error(temporary, "writing", error);
  }
  if (::rename(temporary.c_str(), path.c_str()) != 0) {
    const int error = errno;
    ::unlink(temporary.c_str());
    throw_io_error(path, "renaming a temporary file to", error);
  }
}

AppendedFile::AppendedFile(const std::filesystem::path& file)
    : path_(file), fd_(::open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644)) {
  if (fd_ < 0) throw_io_error(file, "creating", errno);
}

AppendedFile::~AppendedFile() {
  if (fd_ >= 0) ::close(fd_);
}

void AppendedFile::append(const std::string& text) { write_all(fd_, text.data(), text.size(), path_); }

void AppendedFile::replace(const std::string& text) {
  write_file_atomically(path_, text);
  const int fd = ::open(path_.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC);
  if (fd < 0) throw_io_error(path_, "opening", errno);
  ::close(fd_);
  fd_ = fd;
}

}  // namespace indentsim
