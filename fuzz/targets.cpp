#include "targets.hpp"

#include <string>

#include "indentsim/output/checkpoint.hpp"
#include "indentsim/driver/resume.hpp"
#include "indentsim/base/error.hpp"
#include "indentsim/input/load_case.hpp"
#include "indentsim/geometry/mesh.hpp"

namespace indentsim::fuzz {

Outcome load_case_outcome(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const LoadCase lc = parse_load_case(text, "fuzz.toml");
    plan_mesh(lc);  // sizes are checked before anything is allocated
    (void)to_toml(lc);
    return Outcome::accepted;
  } catch (const InputError&) {
    return Outcome::rejected;
  }
}

Outcome checkpoint_outcome(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  try {
    const Checkpoint c = deserialize(bytes, "fuzz.ck");
    // Only intact checkpoints get here; keep the resumed mesh small so a run stays quick.
    if (c.mesh_x.size() * c.mesh_y.size() < 20000) resume_from(c, "fuzz.ck", {});
    return Outcome::accepted;
  } catch (const InputError&) {
    return Outcome::rejected;
  }
}

}  // namespace indentsim::fuzz
