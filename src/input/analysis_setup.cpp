#include "indentsim/input/load_case.hpp"

#include <fmt/format.h>
#include <toml++/toml.h>

#include "indentsim/base/error.hpp"
#include "indentsim/input/curve_csv.hpp"
#include "key_declarations.hpp"

namespace indentsim {

using namespace input_detail;

AnalysisSetup read_analysis_setup(const std::optional<std::filesystem::path>& file,
                                  const std::vector<std::string>& overrides) {
  const std::string source = file ? file->string() : std::string("--set");
  const toml::table root = parse_with_overrides(file ? read_text(*file) : std::string(), source, overrides);

  // The load-case keys an analysis reads (the indenter, its scene, Oliver-Pharr's constants and
  // the specimen's Poisson's ratio), none required, and the [curve] keys of a measured file.
  std::vector<KeyDeclaration> keys;
  for (const auto& k : key_declarations()) {
    const std::string section = k.section, name = k.name;
    if (section == "punch" || section == "analysis" || (section == "geometry" && name == "kind") ||
        (section == "material" && name == "nu")) {
      keys.push_back(k);
      keys.back().required = false;
    }
  }
  AnalysisSetup setup;
  const std::pair<const char*, std::string*> curve_keys[] = {{"depth_column", &setup.columns.depth_column},
                                                             {"force_column", &setup.columns.force_column},
                                                             {"depth_unit", &setup.columns.depth_unit},
                                                             {"force_unit", &setup.columns.force_unit},
                                                             {"time_column", &setup.columns.time_column},
                                                             {"time_unit", &setup.columns.time_unit}};
  for (const auto& [name, target] : curve_keys) keys.push_back(KeyDeclaration{"curve", name, "string", "", "", ""});

  const Reader r(root, source, file ? folder_of(*file) : std::filesystem::current_path());
  r.check_structure(keys);
  LoadCase lc;
  lc.source = source;
  lc.geometry.kind = SceneKind::axisymmetric;  // instruments indent with bodies of revolution
  for (const auto& key : keys)
    if (key.read) key.read(r, lc);
  for (const auto& [name, target] : curve_keys) r.read_string("curve", name, *target);
  // A unit given here is this file's (or --set's) mistake, not the data file's.
  if (!setup.columns.depth_unit.empty() && depth_unit_factor(setup.columns.depth_unit) == 0.0)
    r.fail("curve.depth_unit", fmt::format("\"{}\" is not a depth unit (accepted: nm, um, mm, m)",
                                           printable(setup.columns.depth_unit, 20)));
  if (!setup.columns.time_unit.empty() && time_unit_factor(setup.columns.time_unit) == 0.0)
    r.fail("curve.time_unit", fmt::format("\"{}\" is not a time unit (accepted: s, ms, min)",
                                          printable(setup.columns.time_unit, 20)));
  if (!setup.columns.force_unit.empty() && force_unit_factor(setup.columns.force_unit) == 0.0)
    r.fail("curve.force_unit", fmt::format("\"{}\" is not a force unit (accepted: mN, uN, nN, N)",
                                           printable(setup.columns.force_unit, 20)));
  if (!r.find("punch", "shape"))
    r.fail("punch.shape", "missing key: the indenter's shape (sphere, cone, flat, profile or area_function) gives the area function "
                          "A(h_c) (--indenter FILE, or --set punch.shape=...)");
  check_punch_keys(r, lc);
  validate_punch_shape(lc);
  validate_analysis(lc);
  if (r.find("material", "nu")) {
    if (!(lc.material.nu > -1.0 && lc.material.nu < 0.5))
      r.fail("material.nu", fmt::format("must lie in (-1, 0.5) (got {})", lc.material.nu));
    setup.specimen_nu = lc.material.nu;
  }
  setup.source = source;
  setup.scene = lc.geometry.kind;
  setup.punch = lc.punch;
  setup.analysis = lc.analysis;
  return setup;
}

}  // namespace indentsim
