#include "indentsim/base/error.hpp"

#include <fmt/format.h>

namespace indentsim {

std::string printable(const std::string& text, std::size_t max_length) {
  std::string out;
  std::size_t shown = 0;
  for (; shown < text.size() && out.size() < max_length; ++shown) {
    const unsigned char c = static_cast<unsigned char>(text[shown]);
    switch (c) {
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      case '\r': out += "\\r"; break;
      default:
        if (c < 0x20 || c == 0x7f) out += fmt::format("\\x{:02x}", c);
        else out += static_cast<char>(c);
    }
  }
  if (shown < text.size()) out += fmt::format("... ({} more bytes)", text.size() - shown);
  return out;
}

InputError::InputError(std::string file, std::string key, std::string problem)
    : std::runtime_error(fmt::format("{}: {}: {}", printable(file, 400), key.empty() ? "(file)" : printable(key, 200),
                                     printable(problem, 600))),
      file_(std::move(file)),
      key_(std::move(key)),
      problem_(std::move(problem)) {}

IoError::IoError(std::string file, std::string action, std::string reason)
    : std::runtime_error(fmt::format("{} {} failed: {}", action, printable(file, 400), reason)),
      file_(std::move(file)),
      reason_(std::move(reason)) {}

}  // namespace indentsim
