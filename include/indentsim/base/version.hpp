#pragma once
// Which indentsim made a file: the project version and the git commit it was built from
// ("+modified" when the sources differed from that commit; "unknown" outside a git checkout).
// Shown by `indentsim --version`, and written into case.toml, checkpoints and summary.json.
#include <string>

namespace indentsim {

const char* version();
const char* build_commit();
/// "indentsim VERSION (commit COMMIT)".
inline std::string version_line() { return std::string("indentsim ") + version() + " (commit " + build_commit() + ")"; }

}  // namespace indentsim
