#pragma once
// Helpers shared by the tests: load cases from the repository, and small edits of them.
#include <string>
#include <vector>

#include "indentsim/load_case.hpp"

namespace indentsim::testing {

inline std::string source_path(const std::string& relative) { return std::string(INDENTSIM_SOURCE_DIR) + "/" + relative; }

inline LoadCase shipped_case(const std::string& name, const std::vector<std::string>& overrides = {}) {
  return read_load_case(source_path("loadcases/" + name), overrides);
}

}  // namespace indentsim::testing
