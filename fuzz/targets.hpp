#pragma once
// Fuzz targets: the two readers of outside data.  Each must turn any input into either a
// result or an InputError; anything else (a crash, a sanitizer report, another exception)
// is a bug.  Built into libFuzzer executables by fuzz/CMakeLists.txt (clang) and replayed
// over the seed corpus by an ordinary test (tests/CMakeLists.txt).
#include <cstddef>
#include <cstdint>

namespace indentsim::fuzz {
int load_case(const std::uint8_t* data, std::size_t size);
int checkpoint(const std::uint8_t* data, std::size_t size);
}  // namespace indentsim::fuzz
