#pragma once
// Fuzz targets: the two readers of outside data.  Each must turn any input into either a
// result or an InputError; anything else (a crash, a sanitizer report, another exception)
// is a bug.  Built into libFuzzer executables by fuzz/CMakeLists.txt (clang) and replayed
// over the seed corpus by an ordinary test (tests/CMakeLists.txt).
#include <cstddef>
#include <cstdint>

namespace indentsim::fuzz {

/// What a reader made of an input: a result, or a clean InputError.
enum class Outcome { accepted, rejected };

/// The targets: parse (and, for an intact checkpoint of a small mesh, resume) the input.
Outcome load_case_outcome(const std::uint8_t* data, std::size_t size);
Outcome checkpoint_outcome(const std::uint8_t* data, std::size_t size);

/// The same as libFuzzer entry points (always 0: only crashes and sanitizer reports count).
inline int load_case(const std::uint8_t* data, std::size_t size) {
  (void)load_case_outcome(data, size);
  return 0;
}
inline int checkpoint(const std::uint8_t* data, std::size_t size) {
  (void)checkpoint_outcome(data, size);
  return 0;
}

}  // namespace indentsim::fuzz
