// Replays the seed corpus through both fuzz targets: an ordinary test of the same code the
// fuzzers run, so every compiler and sanitizer build checks it.
//   fuzz_replay CORPUS_DIR   (with load_case/ and checkpoint/ inside)
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "targets.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_replay CORPUS_DIR\n");
    return 2;
  }
  const std::filesystem::path root = argv[1];
  int passed = 0;
  for (const auto& [folder, target] : {std::pair{"load_case", &indentsim::fuzz::load_case},
                                       std::pair{"checkpoint", &indentsim::fuzz::checkpoint}}) {
    for (const auto& entry : std::filesystem::directory_iterator(root / folder)) {
      std::ifstream in(entry.path(), std::ios::binary);
      const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      target(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
      ++passed;
    }
  }
  std::printf("%d passed, 0 failed\n", passed);
  return passed > 0 ? 0 : 1;
}
