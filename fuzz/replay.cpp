// Replays the seed corpus through both fuzz targets: an ordinary test of the same code the
// fuzzers run, so every compiler and sanitizer build checks it.  Each seed's expected outcome is
// in CORPUS_DIR/expected.txt ("folder/file accepted|rejected", one per line): a good seed must be
// accepted and a bad one rejected with an InputError, and every seed must be listed.
//   fuzz_replay CORPUS_DIR   (with load_case/ and checkpoint/ inside)
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "targets.hpp"

using indentsim::fuzz::Outcome;

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_replay CORPUS_DIR\n");
    return 2;
  }
  const std::filesystem::path root = argv[1];
  std::map<std::string, std::string> expected;
  {
    std::ifstream manifest(root / "expected.txt");
    std::string line;
    while (std::getline(manifest, line)) {
      if (line.empty() || line[0] == '#') continue;
      std::istringstream words(line);
      std::string file, outcome;
      words >> file >> outcome;
      expected[file] = outcome;
    }
  }
  int passed = 0, failed = 0;
  for (const auto& [folder, target] : {std::pair{"load_case", &indentsim::fuzz::load_case_outcome},
                                       std::pair{"checkpoint", &indentsim::fuzz::checkpoint_outcome}}) {
    for (const auto& entry : std::filesystem::directory_iterator(root / folder)) {
      const std::string name = std::string(folder) + "/" + entry.path().filename().string();
      std::ifstream in(entry.path(), std::ios::binary);
      const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      const Outcome outcome = target(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
      const std::string got = outcome == Outcome::accepted ? "accepted" : "rejected";
      const auto want = expected.find(name);
      if (want == expected.end()) {
        std::printf("FAIL: %s is not listed in expected.txt (it was %s)\n", name.c_str(), got.c_str());
        ++failed;
      } else if (want->second != got) {
        std::printf("FAIL: %s was %s, expected %s\n", name.c_str(), got.c_str(), want->second.c_str());
        ++failed;
      } else {
        ++passed;
      }
    }
  }
  std::printf("%d passed, %d failed\n", passed, failed);
  return failed == 0 && passed > 0 ? 0 : 1;
}
