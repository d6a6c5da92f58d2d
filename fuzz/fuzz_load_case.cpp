// libFuzzer entry: the load-case reader.
#include "targets.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return indentsim::fuzz::load_case(data, size);
}
