#include "indentsim/input/load_case.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>
#include <toml++/toml.h>

#include "indentsim/base/error.hpp"
#include "indentsim/input/profile_csv.hpp"
#include "key_declarations.hpp"

namespace indentsim {

using namespace input_detail;

double LoadInput::largest_target() const {
  double largest = 0.0;
  for (double target : path) largest = std::max(largest, target);
  return largest;
}

double area_function_exponent(std::size_t k) { return k == 0 ? 2.0 : std::ldexp(1.0, 1 - static_cast<int>(k)); }

double area_function_area(const std::vector<double>& c, double h) {
  double area = 0.0;
  for (std::size_t k = 0; k < c.size(); ++k)
    if (c[k] != 0.0) area += c[k] * std::pow(h, area_function_exponent(k));
  return area;
}

double area_function_slope(const std::vector<double>& c, double h) {
  double slope = 0.0;
  for (std::size_t k = 0; k < c.size(); ++k) {
    const double e = area_function_exponent(k);
    if (c[k] != 0.0) slope += c[k] * e * std::pow(h, e - 1.0);
  }
  return slope;
}

double LoadCase::max_depth() const {
  if (load.control == LoadControlKind::force) return load.depth_estimate.value_or(0.0);
  return load.largest_target();
}

bool LoadCase::any_inelastic() const {
  for (std::size_t r = 0; r < regions(); ++r)
    if (region_material(r).model != MaterialModel::elastic) return true;
  return false;
}

bool LoadCase::any_rate(RateLaw rule) const {
  for (std::size_t r = 0; r < regions(); ++r)
    if (region_material(r).rate == rule) return true;
  return false;
}

bool LoadCase::any_rate_dependent() const {
  for (std::size_t r = 0; r < regions(); ++r)
    if (region_material(r).rate != RateLaw::none) return true;
  return false;
}

std::vector<double> LoadCase::interface_depths() const {
  std::vector<double> depths;
  double depth = 0.0;
  for (const LayerInput& layer : layers) depths.push_back(depth += layer.thickness);
  return depths;
}

std::size_t LoadCase::region_at_depth(double depth) const {
  double bottom = 0.0;
  for (std::size_t k = 0; k < layers.size(); ++k)
    if (depth <= (bottom += layers[k].thickness)) return k + 1;
  return 0;
}

int LoadInput::total_increments() const {
  if (segment_increments.empty()) return increments;
  int total = 0;
  for (int n : segment_increments) total += n;
  return total;
}

void LoadInput::multiply_increments(int factor) {
  if (factor < 1) throw std::invalid_argument("multiply_increments: the factor must be at least 1");
  for (int& n : segment_increments) n *= factor;
  increments *= factor;
}

std::string to_string(MaterialModel model) { return name_of(model_names, model); }
std::string to_string(HardeningLaw law) { return name_of(hardening_names, law); }
std::string to_string(TableExtension extension) { return name_of(table_extension_names, extension); }
std::string to_string(ElasticStressMeasure measure) { return name_of(elastic_stress_names, measure); }
std::string to_string(RateLaw law) { return name_of(rate_law_names, law); }
std::string to_string(SceneKind kind) { return name_of(scene_names, kind); }
std::string to_string(StrainChoice strain) { return name_of(strain_names, strain); }
std::string to_string(LoadControlKind control) { return name_of(load_control_names, control); }
std::string to_string(PunchShapeKind shape) { return name_of(shape_names, shape); }

namespace input_detail {

// --set section.key=value: one key and one value.  The value is read as one TOML value ("1e-3",
// "[0, 1e-5]", "\"j2\"") and, when it is not one, as a bare word of path characters (so --set
// material.model=j2 and --set output.dir=runs/a work).  Anything else (a second key smuggled in
// after a newline, a table, text with spaces or quotes that is not TOML) is refused.
void apply_override(toml::table& root, const std::string& text, const std::string& source) {
  const auto fail = [&](const std::string& key, const std::string& problem) {
    throw InputError(source, key, "--set: " + problem);
  };
  const auto eq = text.find('=');
  if (eq == std::string::npos) fail(printable(text, 80), "expects section.key=value");
  const std::string path = text.substr(0, eq);
  const std::string value_text = text.substr(eq + 1);
  const auto is_name = [](const std::string& s) {
    return !s.empty() && std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isalnum(c) || c == '_'; });
  };
  // A layer's key: layer.K.thickness or layer.K.material.KEY (K from 1 at the surface).
  std::vector<std::string> parts;
  for (std::size_t from = 0;;) {
    const auto next = path.find('.', from);
    parts.push_back(path.substr(from, next == std::string::npos ? std::string::npos : next - from));
    if (next == std::string::npos) break;
    from = next + 1;
  }
  const bool layer_key = parts.size() >= 3 && parts[0] == "layer";
  if (layer_key) {
    const bool well_formed =
        !parts[1].empty() && std::all_of(parts[1].begin(), parts[1].end(), [](unsigned char c) { return std::isdigit(c); }) &&
        ((parts.size() == 3 && parts[2] == "thickness") ||
         (parts.size() == 4 && parts[2] == "material" && is_name(parts[3])));
    if (!well_formed)
      fail(printable(path, 80), "a layer's key is layer.K.thickness or layer.K.material.KEY (K from 1 at the surface)");
  } else if (parts.size() != 2 || !is_name(parts[0]) || !is_name(parts[1])) {
    fail(printable(path, 80), "expects section.key=value (one section, one key: letters, digits, _)");
  }

  toml::table parsed;
  bool is_toml_value = true;
  try {
    parsed = toml::parse("value = " + value_text);
  } catch (const toml::parse_error&) {
    is_toml_value = false;
  }
  // A number beyond double precision (1e400) is no TOML value either: without this it would be
  // taken for a bare word and refused later as "a string".
  if (!is_toml_value) {
    char* end = nullptr;
    errno = 0;
    const double x = std::strtod(value_text.c_str(), &end);
    if (end != value_text.c_str() && *end == '\0' && (errno == ERANGE || !std::isfinite(x)))
      fail(path, fmt::format("{} is beyond double precision (numbers must lie within +-1.8e308, and away from "
                             "zero beyond 2.2e-308)",
                             printable(value_text, 60)));
  }
  toml::table* table = nullptr;
  std::string key;
  if (layer_key) {
    toml::array* layers = root["layer"].as_array();
    const std::size_t count = layers && layers->is_array_of_tables() ? layers->size() : 0;
    const std::size_t k = parts[1].size() > 6 ? 0 : std::stoul(parts[1]);
    if (k < 1 || k > count)
      fail(path, fmt::format("the case has {} layer{} ([[layer]] tables): there is no layer {}", count,
                             count == 1 ? "" : "s", printable(parts[1], 20)));
    table = layers->get(k - 1)->as_table();
    if (parts.size() == 4) {
      if (!table->contains("material")) table->insert("material", toml::table{});
      table = (*table)["material"].as_table();
      if (!table) throw InputError(source, fmt::format("layer[{}].material", k), "must be a table");
    }
    key = parts.back();
  } else {
    const std::string& section = parts[0];
    key = parts[1];
    if (!root.contains(section)) root.insert(section, toml::table{});
    table = root[section].as_table();
    if (!table) throw InputError(source, section, "must be a table");
  }
  if (is_toml_value) {
    if (parsed.size() != 1 || !parsed.contains("value"))
      fail(path, fmt::format("\"{}\" is more than one value: one --set sets one key", printable(value_text, 60)));
    if (parsed.get("value")->is_table())
      fail(path, "a value, not a table");
    table->insert_or_assign(key, *parsed.get("value"));
    return;
  }
  const bool bare_word = !value_text.empty() && std::all_of(value_text.begin(), value_text.end(), [](unsigned char c) {
    return std::isalnum(c) || std::string_view("_-./:+~@%,").find(static_cast<char>(c)) != std::string_view::npos;
  });
  if (!bare_word)
    fail(path, fmt::format("\"{}\" is not a TOML value (quote a string with spaces or symbols: {}=\"...\")",
                           printable(value_text, 60), path));
  table->insert_or_assign(key, value_text);
}

/// The punch keys that apply to each shape; any other punch key given is a mistake.
void check_punch_keys(const Reader& r, LoadCase& lc) {
  struct ShapeKeys {
    PunchShapeKind shape;
    std::vector<std::string> keys;
  };
  const std::vector<ShapeKeys> table = {{PunchShapeKind::sphere, {"radius"}},
                                        {PunchShapeKind::cone, {"half_angle", "tip_radius"}},
                                        {PunchShapeKind::flat, {"radius"}},
                                        {PunchShapeKind::profile, {"profile", "profile_points"}},
                                        {PunchShapeKind::area_function, {"area_coefficients"}}};
  const std::string shape = to_string(lc.punch.shape);
  for (const auto& entry : table) {
    if (entry.shape == lc.punch.shape) continue;
    for (const auto& key : entry.keys) {
      const bool applies = std::any_of(table.begin(), table.end(), [&](const ShapeKeys& e) {
        return e.shape == lc.punch.shape && std::find(e.keys.begin(), e.keys.end(), key) != e.keys.end();
      });
      if (!applies && r.find("punch", key))
        r.fail("punch." + key, fmt::format("does not apply to punch.shape = \"{}\" (it belongs to \"{}\")", shape,
                                           to_string(entry.shape)));
    }
  }
  switch (lc.punch.shape) {
    case PunchShapeKind::sphere:
    case PunchShapeKind::flat:
      if (!r.find("punch", "radius"))
        r.fail("punch.radius", fmt::format("missing key (punch.shape = \"{}\" needs its radius)", shape));
      break;
    case PunchShapeKind::cone:
      if (!r.find("punch", "half_angle"))
        r.fail("punch.half_angle", "missing key (punch.shape = \"cone\" needs its half-angle, e.g. 70.3 for the "
                                   "Berkovich-equivalent cone)");
      break;
    case PunchShapeKind::profile: {
      const bool file = r.find("punch", "profile") != nullptr, inline_points = r.find("punch", "profile_points") != nullptr;
      if (file == inline_points)
        r.fail("punch.profile", "punch.shape = \"profile\" needs exactly one of punch.profile (a CSV file of r, g) "
                                "and punch.profile_points (an array of [r, g] pairs)");
      if (file) {
        const std::filesystem::path path = r.base_dir() / lc.punch.profile_file;
        lc.punch.profile = read_profile_csv(path, r.source(), "punch.profile");
      }
      break;
    }
    case PunchShapeKind::area_function:
      if (!r.find("punch", "area_coefficients"))
        r.fail("punch.area_coefficients", "missing key (punch.shape = \"area_function\" needs the coefficients C0, "
                                          "C1, ... of its area function, e.g. [24.5] for the ideal Berkovich)");
      break;
  }
}

/// The flow-stress laws' own keys belong to their law: one given under another law is refused
/// (as a cone's key under a sphere), the initial yield stress of swift and table comes from their
/// curve (so material.e0 and material.yield_stress are refused there), and a table is read.
static void check_hardening_keys(const Reader& r, LoadCase& lc) {
  struct LawKey {
    const char* key;
    std::vector<HardeningLaw> laws;
  };
  const std::vector<LawKey> table{{"K", {HardeningLaw::ludwik, HardeningLaw::swift}},
                                  {"prestrain", {HardeningLaw::swift}},
                                  {"Q", {HardeningLaw::voce}},
                                  {"b", {HardeningLaw::voce}},
                                  {"hardening_table", {HardeningLaw::table}},
                                  {"hardening_points", {HardeningLaw::table}},
                                  {"table_extension", {HardeningLaw::table}}};
  const HardeningLaw law = lc.material.hardening;
  const std::string name = to_string(law);
  for (const auto& entry : table) {
    if (std::find(entry.laws.begin(), entry.laws.end(), law) != entry.laws.end() || !r.find("material", entry.key))
      continue;
    std::string owners;
    for (const HardeningLaw owner : entry.laws) owners += (owners.empty() ? "\"" : " and \"") + to_string(owner) + "\"";
    r.fail(std::string("material.") + entry.key,
           fmt::format("does not apply to material.hardening = \"{}\" (it belongs to {})", name, owners));
  }
  if (law == HardeningLaw::swift || law == HardeningLaw::table)
    for (const char* key : {"e0", "yield_stress"})
      if (r.find("material", key))
        r.fail(std::string("material.") + key,
               fmt::format("does not apply to material.hardening = \"{}\": its initial yield stress is {}", name,
                           law == HardeningLaw::swift ? "K prestrain^n" : "the table's first sigma"));
  if (law == HardeningLaw::table) {
    const bool file = r.find("material", "hardening_table") != nullptr;
    const bool inline_points = r.find("material", "hardening_points") != nullptr;
    if (file == inline_points)
      r.fail("material.hardening_table",
             "material.hardening = \"table\" needs exactly one of material.hardening_table (a CSV file of eps_p, "
             "sigma) and material.hardening_points (an array of [eps_p, sigma] pairs)");
    if (file)
      lc.material.hardening_points = read_two_column_csv(r.base_dir() / lc.material.hardening_table_file, r.source(),
                                                         "material.hardening_table", "eps_p", "sigma",
                                                         "a hardening table");
  }
}

/// The flow rules' own keys belong to their rule (docs/MODEL.md §13.3): one given under another
/// rule is refused, and Norton's creep, which has no yield surface, refuses the hardening curve's
/// keys (they would set nothing).
static void check_rate_keys(const Reader& r, const LoadCase& lc) {
  struct RuleKey {
    const char* key;
    std::vector<RateLaw> rules;
  };
  const std::vector<RuleKey> table{{"reference_strain_rate", {RateLaw::perzyna}},
                                   {"creep_coefficient", {RateLaw::norton}},
                                   {"reference_stress", {RateLaw::norton}},
                                   {"rate_exponent", {RateLaw::perzyna, RateLaw::norton}}};
  const RateLaw rule = lc.material.rate;
  for (const auto& entry : table) {
    if (std::find(entry.rules.begin(), entry.rules.end(), rule) != entry.rules.end() || !r.find("material", entry.key))
      continue;
    std::string owners;
    for (const RateLaw owner : entry.rules) owners += (owners.empty() ? "\"" : " and \"") + to_string(owner) + "\"";
    r.fail(std::string("material.") + entry.key,
           fmt::format("does not apply to material.rate = \"{}\" (it belongs to {})", to_string(rule), owners));
  }
  if (rule == RateLaw::norton)
    for (const char* key : {"e0", "yield_stress", "hardening", "kappa", "n", "K", "prestrain", "Q", "b",
                            "hardening_table", "hardening_points", "table_extension"})
      if (r.find("material", key))
        r.fail(std::string("material.") + key,
               "does not apply to material.rate = \"norton\": power-law creep flows at any stress, with no yield "
               "surface and no hardening curve (for creep beside a yield surface use \"perzyna\")");
}

/// What the [material] keys say beyond each key's own reading: the keys that belong to other
/// keys' choices, and e0 from a yield stress.  For the substrate's [material] and each layer's.
static void read_material_rules(const Reader& r, LoadCase& lc) {
  // Small strain cannot tell the Cauchy from the Kirchhoff stress (docs/MODEL.md §12.2).
  if (lc.geometry.strain == StrainChoice::small && r.find("material", "elastic_stress"))
    r.fail("material.elastic_stress", "applies to finite strain only (geometry.strain = \"finite\" or \"auto\"); "
                                      "in small strain the Cauchy and the Kirchhoff stress coincide");
  // e0 or the uniaxial yield stress: exactly one may be given; the law works with e0.
  if (r.find("material", "yield_stress")) {
    if (r.find("material", "e0"))
      r.fail("material.yield_stress", "give either material.e0 or material.yield_stress, not both");
    if (!(*lc.material.yield_stress > 0.0))
      r.fail("material.yield_stress", fmt::format("must be > 0 (got {})", *lc.material.yield_stress));
    lc.material.e0 = e0_of_yield_stress(*lc.material.yield_stress, lc.material.E, lc.material.nu);
    // The law works with e0 = sigma_y / (3 mu): a yield stress that gives no strain of a solid is
    // the key the user wrote, usually a unit slip in it or in material.E.
    const double e0 = lc.material.e0;
    if (!(e0 >= min_elastic_limit_strain && e0 < 1.0))
      r.fail("material.yield_stress",
             fmt::format("sigma_y = {} Pa gives the elastic-limit strain e0 = sigma_y / (3 mu) = {:.3g} with "
                         "material.E = {} Pa, but e0 must lie in [{:g}, 1): are both in pascals (300 MPa is 300e6)?",
                         *lc.material.yield_stress, e0, lc.material.E, min_elastic_limit_strain));
  }
  check_hardening_keys(r, lc);
  check_rate_keys(r, lc);
}

/// The [[layer]] tables (docs/MODEL.md §14.2), from the surface down: each a thickness and a
/// material read by the [material] declarations on a scratch case, so that a layer accepts and
/// refuses exactly what [material] does; messages name layer[k] (k from 1) and the key.
static std::vector<LayerInput> read_layers(const toml::node& node, const LoadCase& lc,
                                           const std::filesystem::path& base_dir) {
  const auto fail = [&](const std::string& key, const std::string& problem) {
    throw InputError(lc.source, key, problem);
  };
  const toml::array* layers = node.as_array();
  if (!layers || !layers->is_array_of_tables())
    fail("layer", "must be an array of tables, one [[layer]] per layer from the surface down");
  if (layers->size() > max_layers)
    fail("layer", fmt::format("{} layers: at most {} (a finer stack is a graded material, not built)", layers->size(),
                              max_layers));
  std::vector<KeyDeclaration> material_keys;
  for (const KeyDeclaration& key : key_declarations())
    if (std::string(key.section) == "material") material_keys.push_back(key);
  std::vector<LayerInput> read;
  for (std::size_t k = 0; k < layers->size(); ++k) {
    const std::string name = fmt::format("layer[{}]", k + 1);
    const toml::table& table = *layers->get(k)->as_table();
    for (const auto& [key, value] : table)
      if (key.str() != "thickness" && key.str() != "material")
        fail(name + "." + std::string(key.str()), "unknown key (known keys of [[layer]]: thickness, material)");
    LayerInput layer;
    const toml::node* thickness = table.get("thickness");
    if (!thickness) fail(name + ".thickness", "missing key (each layer needs its thickness [m])");
    if (auto v = thickness->value_exact<double>()) layer.thickness = *v;
    else if (auto i = thickness->value_exact<int64_t>()) layer.thickness = static_cast<double>(*i);
    else fail(name + ".thickness", fmt::format("expected a number, got {}", Reader::type_name(*thickness)));
    if (!(std::isfinite(layer.thickness) && layer.thickness > 0.0))
      fail(name + ".thickness", fmt::format("must be a finite length > 0 (got {})", layer.thickness));
    const toml::node* material = table.get("material");
    if (!material) fail(name + ".material", "missing table ([layer.material] with the layer's material keys)");
    if (!material->is_table()) fail(name + ".material", "must be a table ([layer.material])");
    toml::table scratch_root;
    scratch_root.insert("material", *material->as_table());
    LoadCase scratch = with_material(lc, MaterialInput{});
    try {
      const Reader r(scratch_root, lc.source, base_dir);
      r.check_structure(material_keys);
      for (const KeyDeclaration& key : material_keys) key.read(r, scratch);
      read_material_rules(r, scratch);
    } catch (const InputError& e) {
      throw InputError(e.file(), name + "." + e.key(), e.problem());
    }
    layer.material = scratch.material;
    read.push_back(std::move(layer));
  }
  return read;
}

LoadCase from_table(const toml::table& given, const std::string& source, const std::filesystem::path& base_dir) {
  // The layers are an array of tables, which the key table's sections are not: read apart.
  toml::table root = given;
  std::optional<toml::array> layer_tables;
  if (const toml::node* node = root.get("layer")) {
    if (const toml::array* array = node->as_array()) layer_tables = *array;
    else throw InputError(source, "layer", "must be an array of tables, one [[layer]] per layer from the surface down");
    root.erase("layer");
  }
  Reader r(root, source, base_dir);
  const auto& keys = key_declarations();
  r.check_structure(keys);
  LoadCase lc;
  lc.source = source;
  for (const auto& key : keys) key.read(r, lc);
  read_material_rules(r, lc);
  if (layer_tables) lc.layers = read_layers(*layer_tables, lc, base_dir);
  // Without output.dir, out/ and the case's name: two cases run from one folder keep their own
  // runs (a sweep names its folder the same way).
  if (!r.find("output", "dir")) {
    const std::filesystem::path file(source);
    if (file.extension() == ".toml" && !file.stem().empty()) lc.output.dir = "out/" + file.stem().string();
  }
  check_punch_keys(r, lc);
  // A cone has no length scale: its contact edge sweeps the whole contact zone node by node, and
  // under a plastic material the edge carries the full hardness, so the node-by-node engagement is
  // a first-order error.  30 elements hold Kick's law P/h^2 = const to 0.34% (docs/verification.md, "Kick's law on a cone").
  // A calibrated tip's area function is a cone beyond its rounding.
  if (sharp_tip(lc.punch.shape) && !r.find("mesh", "contact_nodes"))
    lc.mesh.contact_nodes = cone_contact_nodes;
  validate(lc);
  return lc;
}

toml::table parse_with_overrides(const std::string& text, const std::string& source,
                                 const std::vector<std::string>& overrides) {
  toml::table root;
  try {
    root = toml::parse(text, source);
  } catch (const toml::parse_error& e) {
    const auto& where = e.source().begin;
    throw InputError(source, fmt::format("line {}, column {}", where.line, where.column),
                     fmt::format("not valid TOML: {}", e.description()));
  }
  for (const auto& o : overrides) apply_override(root, o, source);
  return root;
}

LoadCase parse_and_override(const std::string& text, const std::string& source,
                            const std::vector<std::string>& overrides, const std::filesystem::path& base_dir) {
  return from_table(parse_with_overrides(text, source, overrides), source, base_dir);
}

std::string read_text(const std::filesystem::path& file) {
  const std::string source = file.string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec))
    throw InputError(source, "", "cannot open: not a readable file");
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(source, "", "cannot open for reading");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}
std::filesystem::path folder_of(const std::filesystem::path& file) {
  return file.parent_path().empty() ? "." : file.parent_path();
}
}  // namespace input_detail

double yield_stress_of_e0(double e0, double E, double nu) { return 3.0 * (E / (2.0 * (1.0 + nu))) * e0; }
double e0_of_yield_stress(double yield_stress, double E, double nu) {
  return yield_stress / (3.0 * (E / (2.0 * (1.0 + nu))));
}

LoadCase parse_load_case(const std::string& toml_text, const std::string& source,
                         const std::vector<std::string>& overrides) {
  return parse_and_override(toml_text, source, overrides, std::filesystem::current_path());
}

LoadCase read_load_case(const std::filesystem::path& file, const std::vector<std::string>& overrides) {
  return parse_and_override(read_text(file), file.string(), overrides, folder_of(file));
}

}  // namespace indentsim
