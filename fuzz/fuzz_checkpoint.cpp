// libFuzzer entry: the checkpoint reader.
#include "targets.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return indentsim::fuzz::checkpoint(data, size);
}
