#include "indentsim/input/load_case.hpp"

#include <algorithm>
#include <functional>
#include <optional>
#include <cctype>
#include <cmath>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <toml++/toml.h>

#include "indentsim/base/error.hpp"
#include "indentsim/input/profile_csv.hpp"
#include "indentsim/base/version.hpp"

namespace indentsim {

double LoadCase::max_depth() const {
  double deepest = 0.0;
  for (double alpha : load.path) deepest = std::max(deepest, alpha);
  return deepest;
}

namespace {

constexpr double min_modulus = 1e-100, max_modulus = 1e100;  // material.E [Pa]

// The words a load case uses for each choice, shared by the reader and by to_toml().
template <class E>
struct Choice {
  const char* name;
  E value;
};
constexpr Choice<MaterialModel> model_names[] = {
    {"elastic", MaterialModel::elastic}, {"ilyushin", MaterialModel::ilyushin}, {"j2", MaterialModel::j2}};
constexpr Choice<HardeningLaw> hardening_names[] = {{"linear", HardeningLaw::linear}, {"power", HardeningLaw::power}};
constexpr Choice<ElementChoice> element_names[] = {
    {"auto", ElementChoice::automatic}, {"q1", ElementChoice::q1}, {"bbar", ElementChoice::bbar}};
constexpr Choice<LinearSolverChoice> linear_names[] = {
    {"klu", LinearSolverChoice::klu}, {"cholmod", LinearSolverChoice::cholmod}, {"auto", LinearSolverChoice::automatic}};
constexpr Choice<JacobianChoice> jacobian_names[] = {{"auto", JacobianChoice::automatic},
                                                     {"krylov", JacobianChoice::krylov},
                                                     {"reuse", JacobianChoice::reuse},
                                                     {"fresh", JacobianChoice::fresh}};
constexpr Choice<SceneKind> scene_names[] = {{"plane_strain", SceneKind::plane_strain},
                                             {"axisymmetric", SceneKind::axisymmetric}};
// "cylinder" is the plane-strain reading of "sphere": the same circular profile of punch.radius.
constexpr Choice<PunchShapeKind> shape_names[] = {{"sphere", PunchShapeKind::sphere},
                                                  {"cone", PunchShapeKind::cone},
                                                  {"flat", PunchShapeKind::flat},
                                                  {"profile", PunchShapeKind::profile},
                                                  {"cylinder", PunchShapeKind::sphere}};
constexpr Choice<ErrorEstimateChoice> error_estimate_names[] = {{"richardson", ErrorEstimateChoice::richardson},
                                                                {"observed", ErrorEstimateChoice::observed},
                                                                {"off", ErrorEstimateChoice::off}};
constexpr Choice<FarFieldChoice> far_field_names[] = {
    {"auto", FarFieldChoice::automatic}, {"condense", FarFieldChoice::condense}, {"full", FarFieldChoice::full}};

template <class E, std::size_t N>
const char* name_of(const Choice<E> (&names)[N], E value) {
  for (const auto& c : names)
    if (c.value == value) return c.name;
  return "?";
}

}  // namespace

std::string to_string(MaterialModel model) { return name_of(model_names, model); }
std::string to_string(HardeningLaw law) { return name_of(hardening_names, law); }
std::string to_string(SceneKind kind) { return name_of(scene_names, kind); }
std::string to_string(PunchShapeKind shape) { return name_of(shape_names, shape); }

namespace {

class Reader;

/// One load-case key, declared once: how it is read and written, what it means, and whether a
/// resumed run may change it.  The reader, the writer (to_toml), the resume check, `indentsim
/// keys` and the README's key table all come from this one list (key_declarations()).
struct KeyDeclaration {
  const char* section;
  const char* name;
  const char* type;   ///< as `indentsim keys` shows it
  std::string range;  ///< the values accepted, in words (validate() enforces them)
  const char* unit;   ///< SI unit, or "" for a pure number, a word or a path
  const char* help;
  bool required = false;
  /// Reads the key from the TOML table (when present) into the load case.
  std::function<void(const Reader&, LoadCase&)> read;
  /// The key's value as TOML text, or nothing when it is absent (an optional override unset).
  std::function<std::optional<std::string>(const LoadCase&)> write;
  /// Shown as a comment in case.toml, not as a key (a value derived from another key).
  bool derived = false;
};

std::vector<std::string> section_names(const std::vector<KeyDeclaration>& keys) {
  std::vector<std::string> names;
  for (const auto& k : keys)
    if (std::find(names.begin(), names.end(), k.section) == names.end()) names.emplace_back(k.section);
  return names;
}

std::vector<std::string> key_names(const std::vector<KeyDeclaration>& keys, const std::string& section) {
  std::vector<std::string> names;
  for (const auto& k : keys)
    if (section == k.section) names.emplace_back(k.name);
  return names;
}

std::string join(const std::vector<std::string>& words) {
  std::string out;
  for (const auto& w : words) out += (out.empty() ? "" : ", ") + w;
  return out;
}

std::string toml_numbers(const std::vector<double>& values) {
  std::string s = "[";
  for (std::size_t i = 0; i < values.size(); ++i) s += (i ? ", " : "") + toml_number(values[i]);
  return s + "]";
}

class Reader {
public:
  Reader(const toml::table& root, std::string source, std::filesystem::path base_dir)
      : root_(root), source_(std::move(source)), base_dir_(std::move(base_dir)) {}

  [[noreturn]] void fail(const std::string& key, const std::string& problem) const {
    throw InputError(source_, key, problem);
  }

  /// Every section and key present is declared; every required one is present.
  void check_structure(const std::vector<KeyDeclaration>& keys) const {
    const auto sections = section_names(keys);
    for (const auto& [name, node] : root_) {
      const std::string section_name(name.str());
      if (std::find(sections.begin(), sections.end(), section_name) == sections.end())
        fail(section_name, fmt::format("unknown section (known sections: {})", join(sections)));
      const toml::table* table = node.as_table();
      if (!table) fail(section_name, "must be a table ([" + section_name + "])");
      for (const auto& [key, value] : *table) {
        const std::string key_name(key.str());
        const bool known = std::any_of(keys.begin(), keys.end(), [&](const KeyDeclaration& k) {
          return section_name == k.section && key_name == k.name;
        });
        if (!known)
          fail(section_name + "." + key_name,
               fmt::format("unknown key (known keys of [{}]: {})", section_name, join(key_names(keys, section_name))));
      }
    }
    for (const auto& key : keys) {
      if (!key.required) continue;
      const toml::table* table = root_[key.section].as_table();
      if (!table) fail(key.section, "missing section");
      if (!table->contains(key.name)) fail(std::string(key.section) + "." + key.name, "missing key");
    }
  }

  const toml::node* find(const std::string& section, const std::string& key) const {
    const toml::table* table = root_[section].as_table();
    return table ? table->get(key) : nullptr;
  }

  void read_number(const std::string& section, const std::string& key, double& target) const {
    const toml::node* node = find(section, key);
    if (!node) return;
    if (auto v = node->value_exact<double>()) target = *v;
    else if (auto i = node->value_exact<int64_t>()) target = static_cast<double>(*i);
    else fail(section + "." + key, fmt::format("expected a number, got {}", type_name(*node)));
    if (!std::isfinite(target)) fail(section + "." + key, "must be a finite number");
  }

  void read_optional_number(const std::string& section, const std::string& key,
                            std::optional<double>& target) const {
    if (!find(section, key)) return;
    double value = 0.0;
    read_number(section, key, value);
    target = value;
  }

  void read_integer(const std::string& section, const std::string& key, int& target) const {
    const toml::node* node = find(section, key);
    if (!node) return;
    auto i = node->value_exact<int64_t>();
    if (!i) fail(section + "." + key, fmt::format("expected an integer, got {}", type_name(*node)));
    if (*i < std::numeric_limits<int>::min() || *i > std::numeric_limits<int>::max())
      fail(section + "." + key, fmt::format("{} is out of range", *i));
    target = static_cast<int>(*i);
  }

  void read_string(const std::string& section, const std::string& key, std::string& target) const {
    const toml::node* node = find(section, key);
    if (!node) return;
    auto s = node->value_exact<std::string>();
    if (!s) fail(section + "." + key, fmt::format("expected a string, got {}", type_name(*node)));
    target = *s;
  }

  template <class E>
  void read_choice(const std::string& section, const std::string& key, const Choice<E>* names, std::size_t count,
                   E& target) const {
    std::string word;
    if (!find(section, key)) return;
    read_string(section, key, word);
    std::string known;
    for (std::size_t i = 0; i < count; ++i) {
      if (word == names[i].name) {
        target = names[i].value;
        return;
      }
      known += (known.empty() ? "" : ", ") + std::string(names[i].name);
    }
    fail(section + "." + key, fmt::format("\"{}\" is not one of: {}", printable(word, 60), known));
  }

  /// load.increments: a total, or one count per segment of the path.
  void read_increments(LoadInput& load) const {
    const toml::node* inc = find("load", "increments");
    if (!inc || !inc->is_array()) {
      read_integer("load", "increments", load.increments);
      return;
    }
    const toml::array& counts = *inc->as_array();
    load.segment_increments.clear();
    int total = 0;
    for (std::size_t i = 0; i < counts.size(); ++i) {
      auto n = counts.get(i)->value_exact<int64_t>();
      if (!n || *n < 1 || *n > 10'000'000) fail("load.increments", fmt::format("element {} must be an integer in [1, 1e7]", i));
      load.segment_increments.push_back(static_cast<int>(*n));
      total += static_cast<int>(*n);
      if (total > 10'000'000) fail("load.increments", "more than 1e7 increments in all");
    }
    load.increments = total;
  }

  /// A count >= 1 or the word "all" (stored as 0).
  void read_count_or_all(const std::string& section, const std::string& key, int& target) const {
    const toml::node* node = find(section, key);
    if (!node) return;
    if (node->is_string()) {
      if (node->value_exact<std::string>() != "all") fail(section + "." + key, "must be a count >= 1 or \"all\"");
      target = 0;
      return;
    }
    read_integer(section, key, target);
    if (target < 1) fail(section + "." + key, fmt::format("must be a count >= 1 or \"all\" (got {})", target));
  }

  void read_number_array(const std::string& section, const std::string& key,
                         std::vector<double>& target) const {
    const toml::node* node = find(section, key);
    if (!node) return;
    const toml::array* array = node->as_array();
    if (!array) fail(section + "." + key, fmt::format("expected an array of numbers, got {}", type_name(*node)));
    target.clear();
    for (std::size_t i = 0; i < array->size(); ++i) {
      const toml::node& item = *array->get(i);
      if (auto v = item.value_exact<double>()) target.push_back(*v);
      else if (auto n = item.value_exact<int64_t>()) target.push_back(static_cast<double>(*n));
      else fail(section + "." + key, fmt::format("element {} is {}, expected a number", i, type_name(item)));
      if (!std::isfinite(target.back())) fail(section + "." + key, fmt::format("element {} is not finite", i));
    }
  }

  static std::string type_name(const toml::node& node) {
    switch (node.type()) {
      case toml::node_type::string: return "a string";
      case toml::node_type::integer: return "an integer";
      case toml::node_type::floating_point: return "a floating-point number";
      case toml::node_type::boolean: return "a boolean";
      case toml::node_type::array: return "an array";
      case toml::node_type::table: return "a table";
      default: return "a date/time";
    }
  }

  /// punch.profile_points: an array of [r, g] pairs.
  void read_points(const std::string& section, const std::string& key,
                   std::vector<std::pair<double, double>>& target) const {
    const toml::node* node = find(section, key);
    if (!node) return;
    const toml::array* array = node->as_array();
    const std::string where = section + "." + key;
    if (!array) fail(where, fmt::format("expected an array of [r, g] pairs, got {}", type_name(*node)));
    target.clear();
    for (std::size_t i = 0; i < array->size(); ++i) {
      const toml::array* pair = array->get(i)->as_array();
      if (!pair || pair->size() != 2) fail(where, fmt::format("element {} is not a pair [r, g]", i));
      double values[2];
      for (std::size_t c = 0; c < 2; ++c) {
        const toml::node& item = *pair->get(c);
        if (auto v = item.value_exact<double>()) values[c] = *v;
        else if (auto n = item.value_exact<int64_t>()) values[c] = static_cast<double>(*n);
        else fail(where, fmt::format("element {} holds {}, expected numbers", i, type_name(item)));
      }
      target.emplace_back(values[0], values[1]);
    }
  }

  const std::string& source() const { return source_; }
  /// Where relative paths in the load case (punch.profile) are taken from: the file's folder.
  const std::filesystem::path& base_dir() const { return base_dir_; }

private:
  const toml::table& root_;
  std::string source_;
  std::filesystem::path base_dir_;
};

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
  const auto dot = path.find('.');
  if (dot == std::string::npos || !is_name(path.substr(0, dot)) || !is_name(path.substr(dot + 1)))
    fail(printable(path, 80), "expects section.key=value (one section, one key: letters, digits, _)");
  const std::string section = path.substr(0, dot);
  const std::string key = path.substr(dot + 1);

  toml::table parsed;
  bool is_toml_value = true;
  try {
    parsed = toml::parse("value = " + value_text);
  } catch (const toml::parse_error&) {
    is_toml_value = false;
  }
  if (!root.contains(section)) root.insert(section, toml::table{});
  toml::table* table = root[section].as_table();
  if (!table) throw InputError(source, section, "must be a table");
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

const std::vector<KeyDeclaration>& key_declarations();

/// The punch keys that apply to each shape; any other punch key given is a mistake.
void check_punch_keys(const Reader& r, LoadCase& lc) {
  struct ShapeKeys {
    PunchShapeKind shape;
    std::vector<std::string> keys;
  };
  const std::vector<ShapeKeys> table = {{PunchShapeKind::sphere, {"radius"}},
                                        {PunchShapeKind::cone, {"half_angle", "tip_radius"}},
                                        {PunchShapeKind::flat, {"radius"}},
                                        {PunchShapeKind::profile, {"profile", "profile_points"}}};
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
  }
}

LoadCase from_table(const toml::table& root, const std::string& source, const std::filesystem::path& base_dir) {
  Reader r(root, source, base_dir);
  const auto& keys = key_declarations();
  r.check_structure(keys);
  LoadCase lc;
  lc.source = source;
  for (const auto& key : keys) key.read(r, lc);
  // e0 or the uniaxial yield stress: exactly one may be given; the law works with e0.
  if (r.find("material", "yield_stress")) {
    if (r.find("material", "e0"))
      r.fail("material.yield_stress", "give either material.e0 or material.yield_stress, not both");
    if (!(*lc.material.yield_stress > 0.0))
      r.fail("material.yield_stress", fmt::format("must be > 0 (got {})", *lc.material.yield_stress));
    lc.material.e0 = e0_of_yield_stress(*lc.material.yield_stress, lc.material.E, lc.material.nu);
  }
  check_punch_keys(r, lc);
  // A cone has no length scale: its contact edge sweeps the whole contact zone node by node, and
  // under a plastic material the edge carries the full hardness, so the node-by-node engagement is
  // a first-order error.  30 elements hold Kick's law P/h^2 = const to 0.34% (docs/verification.md, "Kick's law on a cone").
  if (lc.punch.shape == PunchShapeKind::cone && !r.find("mesh", "contact_nodes"))
    lc.mesh.contact_nodes = cone_contact_nodes;
  validate(lc);
  return lc;
}

// The declarations, section by section in the order case.toml shows them.
template <class Access>
KeyDeclaration number_key(KeyDeclaration k, Access access) {
  const std::string section = k.section, name = k.name;
  k.read = [=](const Reader& r, LoadCase& lc) { r.read_number(section, name, access(lc)); };
  k.write = [=](const LoadCase& lc) -> std::optional<std::string> { return toml_number(access(lc)); };
  return k;
}
template <class Access>
KeyDeclaration optional_number_key(KeyDeclaration k, Access access) {
  const std::string section = k.section, name = k.name;
  k.read = [=](const Reader& r, LoadCase& lc) { r.read_optional_number(section, name, access(lc)); };
  k.write = [=](const LoadCase& lc) -> std::optional<std::string> {
    const auto& value = access(lc);
    if (!value) return std::nullopt;
    return toml_number(*value);
  };
  return k;
}
template <class Access>
KeyDeclaration integer_key(KeyDeclaration k, Access access) {
  const std::string section = k.section, name = k.name;
  k.read = [=](const Reader& r, LoadCase& lc) { r.read_integer(section, name, access(lc)); };
  k.write = [=](const LoadCase& lc) -> std::optional<std::string> { return std::to_string(access(lc)); };
  return k;
}
template <class Access>
KeyDeclaration numbers_key(KeyDeclaration k, Access access) {
  const std::string section = k.section, name = k.name;
  k.read = [=](const Reader& r, LoadCase& lc) { r.read_number_array(section, name, access(lc)); };
  k.write = [=](const LoadCase& lc) -> std::optional<std::string> { return toml_numbers(access(lc)); };
  return k;
}
template <class E, std::size_t N, class Access>
KeyDeclaration choice_key(KeyDeclaration k, const Choice<E> (&names)[N], Access access) {
  const std::string section = k.section, name = k.name;
  const Choice<E>* words = names;
  std::vector<std::string> accepted;
  for (std::size_t i = 0; i < N; ++i) accepted.emplace_back(fmt::format("\"{}\"", names[i].name));
  k.range = "one of " + join(accepted);
  k.read = [=](const Reader& r, LoadCase& lc) { r.read_choice(section, name, words, N, access(lc)); };
  k.write = [=](const LoadCase& lc) -> std::optional<std::string> {
    for (std::size_t i = 0; i < N; ++i)
      if (words[i].value == access(lc)) return fmt::format("\"{}\"", words[i].name);
    return std::nullopt;
  };
  return k;
}

const std::vector<KeyDeclaration>& key_declarations() {
  static const std::vector<KeyDeclaration> keys = [] {
    std::vector<KeyDeclaration> k;
    k.push_back(choice_key({"geometry", "kind", "choice", "", "",
                            "plane_strain (a long punch on a block, P per unit thickness in N/m), axisymmetric (a "
                            "punch of revolution on a cylindrical specimen, P in N)"},
                           scene_names, [](auto& c) -> auto& { return c.geometry.kind; }));
    k.push_back(number_key({"geometry", "lx", "number", "> 0", "m",
                            "half width of the block (plane strain: the model is the half x >= 0 of a symmetric block); "
                            "the specimen's radius in axisymmetry (its outer side free)",
                            true},
                           [](auto& c) -> auto& { return c.geometry.lx; }));
    k.push_back(number_key({"geometry", "ly", "number", "> 0, > the deepest depth", "m",
                            "depth of the block, height of the specimen (its base is clamped)", true},
                           [](auto& c) -> auto& { return c.geometry.ly; }));
    k.push_back(choice_key({"punch", "shape", "choice", "", "",
                            "sphere (circular profile of radius R: a sphere in axisymmetry, a cylinder in plane "
                            "strain; \"cylinder\" is a synonym), cone (a wedge in plane strain), flat (flat-ended), "
                            "profile (a measured tip)"},
                           shape_names, [](auto& c) -> auto& { return c.punch.shape; }));
    {
      KeyDeclaration radius{"punch", "radius", "number", "> 0, > the deepest depth (sphere)", "m",
                            "sphere and flat: the punch radius R (required for them, refused for other shapes)"};
      radius.read = [](const Reader& r, LoadCase& lc) { r.read_number("punch", "radius", lc.punch.radius); };
      radius.write = [](const LoadCase& lc) -> std::optional<std::string> {
        if (lc.punch.shape != PunchShapeKind::sphere && lc.punch.shape != PunchShapeKind::flat) return std::nullopt;
        return toml_number(lc.punch.radius);
      };
      k.push_back(radius);
    }
    {
      KeyDeclaration angle{"punch", "half_angle", "number", "(0, 90)", "degrees",
                           "cone: angle between axis and face (70.3: Berkovich- and Vickers-equivalent; required for "
                           "the cone)"};
      angle.read = [](const Reader& r, LoadCase& lc) { r.read_number("punch", "half_angle", lc.punch.half_angle); };
      angle.write = [](const LoadCase& lc) -> std::optional<std::string> {
        if (lc.punch.shape != PunchShapeKind::cone) return std::nullopt;
        return toml_number(lc.punch.half_angle);
      };
      k.push_back(angle);
    }
    {
      KeyDeclaration tip{"punch", "tip_radius", "number", ">= 0, cap within the specimen", "m",
                         "cone: radius of the spherical cap tangent to the face (a blunt tip; 0 = sharp)"};
      tip.read = [](const Reader& r, LoadCase& lc) { r.read_number("punch", "tip_radius", lc.punch.tip_radius); };
      tip.write = [](const LoadCase& lc) -> std::optional<std::string> {
        if (lc.punch.shape != PunchShapeKind::cone) return std::nullopt;
        return toml_number(lc.punch.tip_radius);
      };
      k.push_back(tip);
    }
    {
      KeyDeclaration file{"punch", "profile", "string", "a CSV file of r, g(r)", "m",
                          "profile: a measured tip, rows r, g(r) from r = 0, g(0) = 0, r increasing, g not "
                          "decreasing (a header row is allowed); relative to the load case's folder"};
      file.read = [](const Reader& r, LoadCase& lc) { r.read_string("punch", "profile", lc.punch.profile_file); };
      file.write = [](const LoadCase& lc) -> std::optional<std::string> {
        if (lc.punch.shape != PunchShapeKind::profile || lc.punch.profile_file.empty()) return std::nullopt;
        std::ostringstream text;
        text << toml::value<std::string>(lc.punch.profile_file);
        return text.str() + " read into profile_points";
      };
      file.derived = true;  // case.toml holds the points themselves: a resumed run needs no file
      k.push_back(file);
    }
    {
      KeyDeclaration points{"punch", "profile_points", "array of [r, g] pairs", "as punch.profile", "m",
                            "profile: the tip's points inline, instead of punch.profile (case.toml writes them so)"};
      points.read = [](const Reader& r, LoadCase& lc) { r.read_points("punch", "profile_points", lc.punch.profile); };
      points.write = [](const LoadCase& lc) -> std::optional<std::string> {
        if (lc.punch.shape != PunchShapeKind::profile) return std::nullopt;
        std::string text = "[";
        for (std::size_t i = 0; i < lc.punch.profile.size(); ++i)
          text += fmt::format("{}[{}, {}]", i ? ", " : "", toml_number(lc.punch.profile[i].first),
                              toml_number(lc.punch.profile[i].second));
        return text + "]";
      };
      k.push_back(points);
    }
    k.push_back(choice_key({"material", "model", "choice", "", "",
                            "elastic; ilyushin (deformation theory, the paper's); j2 (flow theory)", true},
                           model_names, [](auto& c) -> auto& { return c.material.model; }));
    k.push_back(number_key({"material", "E", "number", "[1e-100, 1e100]", "Pa", "Young's modulus", true},
                           [](auto& c) -> auto& { return c.material.E; }));
    k.push_back(number_key({"material", "nu", "number", "(-1, 0.5)", "", "Poisson's ratio", true},
                           [](auto& c) -> auto& { return c.material.nu; }));
    k.push_back(number_key({"material", "e0", "number", "(0, 1)", "",
                            "elastic limit of the strain intensity e_u; the uniaxial yield stress is sigma_y = 3 mu e0 "
                            "= E e0 3 / (2 (1 + nu)) (give e0 or yield_stress, not both)"},
                           [](auto& c) -> auto& { return c.material.e0; }));
    {
      KeyDeclaration ys{"material", "yield_stress", "number", "> 0", "Pa",
                        "uniaxial yield stress sigma_y, instead of e0 (e0 = sigma_y / (3 mu))"};
      ys.read = [](const Reader& r, LoadCase& lc) { r.read_optional_number("material", "yield_stress", lc.material.yield_stress); };
      ys.write = [](const LoadCase& lc) -> std::optional<std::string> {
        return toml_number(lc.material.yield_stress.value_or(yield_stress_of_e0(lc.material.e0, lc.material.E, lc.material.nu)));
      };
      ys.derived = true;
      k.push_back(ys);
    }
    k.push_back(choice_key({"material", "hardening", "choice", "", "",
                            "linear: omega = kappa (1 - e0/e_u); power: omega = 1 - (e0/e_u)^(1-n)"},
                           hardening_names, [](auto& c) -> auto& { return c.material.hardening; }));
    k.push_back(number_key({"material", "kappa", "number", "[0, 1)", "",
                            "linear law: post-yield slope of sigma_u(e_u) is (1 - kappa) 3 mu"},
                           [](auto& c) -> auto& { return c.material.kappa; }));
    k.push_back(number_key({"material", "n", "number", "(0, 1)", "", "power law: sigma_u grows as e_u^n beyond e0"},
                           [](auto& c) -> auto& { return c.material.n; }));
    k.push_back(numbers_key({"load", "path", "array of numbers", "from 0, each >= 0", "m",
                             "depth waypoints alpha, piecewise linear; may go down (unload, separate) and up again", true},
                            [](auto& c) -> auto& { return c.load.path; }));
    {
      KeyDeclaration inc{"load", "increments", "integer or array of integers", "[1, 1e7] in all", "",
                         "increments along the whole path (spread by path length), or one count per segment", true};
      inc.read = [](const Reader& r, LoadCase& lc) { r.read_increments(lc.load); };
      inc.write = [](const LoadCase& lc) -> std::optional<std::string> {
        if (lc.load.segment_increments.empty()) return std::to_string(lc.load.increments);
        std::string text = "[";
        for (std::size_t i = 0; i < lc.load.segment_increments.size(); ++i)
          text += fmt::format("{}{}", i ? ", " : "", lc.load.segment_increments[i]);
        return text + "]";
      };
      k.push_back(inc);
    }
    k.push_back(choice_key({"mesh", "element", "choice", "", "",
                            "q1 (the paper's exact element), bbar (mean dilatation, locking-free), auto (B-bar when "
                            "nu >= 0.45 or kappa > 0.95 or n < 0.1, or a plastic material under a cone)"},
                           element_names, [](auto& c) -> auto& { return c.mesh.element; }));
    k.push_back(integer_key({"mesh", "contact_nodes", "integer", ">= 2", "",
                             "fine-zone elements across the estimated final contact half-width (raise it to buy "
                             "accuracy); 30 under a cone"},
                            [](auto& c) -> auto& { return c.mesh.contact_nodes; }));
    k.push_back(optional_number_key({"mesh", "contact_half_width", "number", "> 0", "m",
                                     "override of the estimate a* that sizes the mesh (default: Hertz, or a pilot run)"},
                                    [](auto& c) -> auto& { return c.mesh.contact_half_width; }));
    k.push_back(optional_number_key({"mesh", "fine_width", "number", "> 0", "m", "override: width of the uniform zone (default 1.5 a*)"},
                                    [](auto& c) -> auto& { return c.mesh.fine_width; }));
    k.push_back(optional_number_key({"mesh", "fine_depth", "number", "> 0", "m", "override: depth of the uniform zone (default 1.5 a*)"},
                                    [](auto& c) -> auto& { return c.mesh.fine_depth; }));
    k.push_back(optional_number_key({"mesh", "growth", "number", "[1, 2]", "",
                                     "override: growth ratio of the far field (default 1 + 2.5 / contact_nodes)"},
                                    [](auto& c) -> auto& { return c.mesh.growth; }));
    k.push_back(choice_key({"mesh", "error_estimate", "choice", "", "",
                            "richardson: a companion run at half the contact_nodes gives each increment's "
                            "discretization error of P and a (curve.csv, summary.json); observed: a second one at "
                            "a quarter measures the order; off"},
                           error_estimate_names, [](auto& c) -> auto& { return c.mesh.error_estimate; }));
    k.push_back(optional_number_key({"mesh", "target_error", "number", "[1e-5, 0.1]", "",
                                     "relative error of the final P asked for: the run chooses contact_nodes from a "
                                     "pilot, checks its estimate and refines once if it was missed"},
                                    [](auto& c) -> auto& { return c.mesh.target_error; }));
    {
      KeyDeclaration dir{"output", "dir", "string", "not empty", "", "output folder (relative to the working directory)"};
      dir.read = [](const Reader& r, LoadCase& lc) { r.read_string("output", "dir", lc.output.dir); };
      dir.write = [](const LoadCase& lc) -> std::optional<std::string> {
        std::ostringstream text;
        text << toml::value<std::string>(lc.output.dir);
        return text.str();
      };
      k.push_back(dir);
    }
    k.push_back(integer_key({"output", "fields_every", "integer", ">= 0", "",
                             "write a VTU every N increments (0: the final state only)"},
                            [](auto& c) -> auto& { return c.output.fields_every; }));
    k.push_back(numbers_key({"output", "profile_depths", "array of numbers", "within [0, ly]", "m",
                             "depths of the stress profiles besides the surface"},
                            [](auto& c) -> auto& { return c.output.profile_depths; }));
    k.push_back(integer_key({"output", "checkpoint_every", "integer", ">= 0", "",
                             "checkpoint at increments numbered a multiple of N, at every peak and valley and at the "
                             "end (0: reversals and signals only)"},
                            [](auto& c) -> auto& { return c.output.checkpoint_every; }));
    {
      KeyDeclaration keep{"output", "keep_checkpoints", "integer or \"all\"", ">= 1", "",
                          "newest checkpoints kept; every peak's and valley's are kept besides"};
      keep.read = [](const Reader& r, LoadCase& lc) { r.read_count_or_all("output", "keep_checkpoints", lc.output.keep_checkpoints); };
      keep.write = [](const LoadCase& lc) -> std::optional<std::string> {
        return lc.output.keep_checkpoints == 0 ? std::string("\"all\"") : std::to_string(lc.output.keep_checkpoints);
      };
      k.push_back(keep);
    }
    k.push_back(numbers_key({"analysis", "fit_range", "array of two numbers", "0 <= lower < upper <= 1", "",
                             "the unloading fit P = B (h - h_f)^m uses the points with lower P_max <= P <= upper "
                             "P_max (ISO 14577 practice: 20% to 98%)"},
                            [](auto& c) -> auto& { return c.analysis.fit_range; }));
    k.push_back(optional_number_key({"analysis", "epsilon", "number", "(0, 1]", "",
                                     "h_c = h_max - epsilon P_max / S (default 0.75 sphere and profile, 0.72 cone, "
                                     "1 flat)"},
                                    [](auto& c) -> auto& { return c.analysis.epsilon; }));
    k.push_back(number_key({"analysis", "beta", "number", "[1, 1.2]", "",
                            "E_r = sqrt(pi) / (2 beta) S / sqrt(A_c) (1 for a body of revolution, 1.034 for a "
                            "Berkovich pyramid)"},
                           [](auto& c) -> auto& { return c.analysis.beta; }));
    k.push_back(optional_number_key({"analysis", "indenter_E", "number", "> 0", "Pa",
                                     "the indenter's Young's modulus for the specimen modulus (default: rigid; "
                                     "diamond 1141e9)"},
                                    [](auto& c) -> auto& { return c.analysis.indenter_E; }));
    k.push_back(number_key({"analysis", "indenter_nu", "number", "(-1, 0.5)", "", "the indenter's Poisson's ratio"},
                           [](auto& c) -> auto& { return c.analysis.indenter_nu; }));
    k.push_back(number_key({"solver", "tolerance", "number", "[1e-14, 1e-2)", "",
                            "residual max-norm relative to E* times the deepest depth (times 2 pi a* in axisymmetry: ring forces)"},
                           [](auto& c) -> auto& { return c.solver.tolerance; }));
    k.push_back(integer_key({"solver", "max_newton", "integer", "[1, 1000]", "", "Newton iterations per attempt"},
                            [](auto& c) -> auto& { return c.solver.max_newton; }));
    k.push_back(integer_key({"solver", "max_cutbacks", "integer", "[0, 60]", "", "halvings of one increment before the run stops"},
                            [](auto& c) -> auto& { return c.solver.max_cutbacks; }));
    k.push_back(choice_key({"solver", "linear", "choice", "", "",
                            "klu (SuiteSparse KLU), cholmod (supernodal Cholesky), auto (CHOLMOD above 1000 unknowns "
                            "of the Newton system)"},
                           linear_names, [](auto& c) -> auto& { return c.solver.linear; }));
    k.push_back(choice_key({"solver", "far_field", "choice", "", "",
                            "condense (Newton solves the near field, the elastic far field condensed exactly), full "
                            "(the whole mesh), auto (condense unless the near field is over 80% of the unknowns)"},
                           far_field_names, [](auto& c) -> auto& { return c.solver.far_field; }));
    k.push_back(choice_key({"solver", "jacobian", "choice", "", "",
                            "how a Newton iteration solves its linear system: krylov (GMRES preconditioned by a "
                            "factorization kept across the iterations), reuse (a factorization per iteration; a "
                            "converging one may keep the last), fresh (factor every iteration), auto (krylov for a "
                            "plastic specimen, reuse for an elastic one)"},
                           jacobian_names, [](auto& c) -> auto& { return c.solver.jacobian; }));
    return k;
  }();
  return keys;
}

/// The TOML text with the --set overrides applied; a syntax error names its line and column.
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

}  // namespace

/// A tip profile: r from 0 strictly increasing, g from 0 not decreasing, all finite; with a load
/// path (`within_run`), high enough that the deepest depth stays on it and within the specimen.
void validate_profile(const LoadCase& lc, bool within_run) {
  const auto& points = lc.punch.profile;
  const bool from_file = !lc.punch.profile_file.empty();
  const std::string key = from_file ? "punch.profile" : "punch.profile_points";
  const auto fail = [&](std::size_t k, const std::string& problem) {
    throw InputError(lc.source, key,
                     fmt::format("{}point {} {}", from_file ? printable(lc.punch.profile_file, 200) + ": " : "", k + 1,
                                 problem));
  };
  if (points.size() < 2) throw InputError(lc.source, key, "a profile needs at least 2 points (r, g)");
  for (std::size_t k = 0; k < points.size(); ++k) {
    const auto [r, g] = points[k];
    if (!std::isfinite(r) || !std::isfinite(g)) fail(k, "is not finite");
    if (k == 0 && (r != 0.0 || g != 0.0))
      fail(k, fmt::format("is ({}, {}): the profile must start at the tip, r = 0, g = 0", r, g));
    if (k > 0 && !(r > points[k - 1].first))
      fail(k, fmt::format("has r = {} after r = {}: r must increase", r, points[k - 1].first));
    if (k > 0 && g < points[k - 1].second)
      fail(k, fmt::format("has g = {} after g = {}: the profile must not descend (not monotone)", g,
                          points[k - 1].second));
  }
  if (!within_run) return;
  if (!(points.back().second > lc.max_depth()))
    throw InputError(lc.source, key,
                     fmt::format("the profile rises only {} m, not above the deepest depth {} m: the specimen would "
                                 "reach beyond the measured tip",
                                 points.back().second, lc.max_depth()));
  if (!(points.back().first < lc.geometry.lx))
    throw InputError(lc.source, key, fmt::format("reaches r = {} m, beyond the specimen (geometry.lx = {} m)",
                                                 points.back().first, lc.geometry.lx));
}

namespace {

/// The indenter on its own: what its shape needs, whatever specimen it meets.
void validate_punch_shape(const LoadCase& lc) {
  const auto& punch = lc.punch;
  if ((punch.shape == PunchShapeKind::sphere || punch.shape == PunchShapeKind::flat) && !(punch.radius > 0.0))
    throw InputError(lc.source, "punch.radius", fmt::format("must be > 0 (got {})", punch.radius));
  if (punch.shape == PunchShapeKind::cone) {
    if (!(punch.half_angle > 0.0 && punch.half_angle < 90.0))
      throw InputError(lc.source, "punch.half_angle",
                       fmt::format("must lie in (0, 90) degrees, the angle between axis and face (got {})",
                                   punch.half_angle));
    if (!(punch.tip_radius >= 0.0))
      throw InputError(lc.source, "punch.tip_radius", fmt::format("must be >= 0 (got {})", punch.tip_radius));
  }
  if (punch.shape == PunchShapeKind::profile) validate_profile(lc, false);
}

void validate_analysis(const LoadCase& lc) {
  const auto fail = [&](const std::string& key, const std::string& problem) {
    throw InputError(lc.source, key, problem);
  };
  const auto& fit = lc.analysis.fit_range;
  if (fit.size() != 2 || !(fit[0] >= 0.0 && fit[0] < fit[1] && fit[1] <= 1.0))
    fail("analysis.fit_range", "must be two fractions of P_max, 0 <= lower < upper <= 1 (for example [0.2, 0.98])");
  if (lc.analysis.epsilon && !(*lc.analysis.epsilon > 0.0 && *lc.analysis.epsilon <= 1.0))
    fail("analysis.epsilon", fmt::format("must lie in (0, 1] (got {})", *lc.analysis.epsilon));
  if (!(lc.analysis.beta >= 1.0 && lc.analysis.beta <= 1.2))
    fail("analysis.beta", fmt::format("must lie in [1, 1.2] (got {})", lc.analysis.beta));
  if (lc.analysis.indenter_E && !(*lc.analysis.indenter_E > 0.0))
    fail("analysis.indenter_E", fmt::format("must be > 0 (got {})", *lc.analysis.indenter_E));
  if (!(lc.analysis.indenter_nu > -1.0 && lc.analysis.indenter_nu < 0.5))
    fail("analysis.indenter_nu", fmt::format("must lie in (-1, 0.5) (got {})", lc.analysis.indenter_nu));
}

}  // namespace

void validate(const LoadCase& lc) {
  const auto fail = [&](const std::string& key, const std::string& problem) {
    throw InputError(lc.source, key, problem);
  };
  const auto positive = [&](const std::string& key, double value) {
    if (!(value > 0.0)) fail(key, fmt::format("must be > 0 (got {})", value));
  };
  positive("geometry.lx", lc.geometry.lx);
  positive("geometry.ly", lc.geometry.ly);
  const auto& punch = lc.punch;
  const bool has_radius = punch.shape == PunchShapeKind::sphere || punch.shape == PunchShapeKind::flat;
  validate_punch_shape(lc);
  if (punch.shape == PunchShapeKind::flat && !(punch.radius < lc.geometry.lx))
    fail("punch.radius", fmt::format("the flat punch ({} m) is not narrower than the specimen (geometry.lx = {} m)",
                                     punch.radius, lc.geometry.lx));
  if (punch.shape == PunchShapeKind::cone) {
    const double cap = punch.tip_radius * std::cos(punch.half_angle * std::acos(-1.0) / 180.0);
    if (!(cap < lc.geometry.lx))
      fail("punch.tip_radius", fmt::format("the spherical cap of radius {} m meets the face at r = {:.4g} m, beyond "
                                           "the specimen (geometry.lx = {} m): it does not fit",
                                           punch.tip_radius, cap, lc.geometry.lx));
  }
  if (punch.shape == PunchShapeKind::profile && !lc.load.path.empty()) validate_profile(lc, true);
  positive("material.E", lc.material.E);
  // Stresses and forces are E times O(1) numbers and their squares are formed (norms, J2); beyond
  // these bounds double precision cannot hold them.  Plausible moduli are warned about, not here.
  if (!(lc.material.E >= min_modulus && lc.material.E <= max_modulus))
    fail("material.E", fmt::format("{} Pa is outside [{:g}, {:g}] Pa, beyond what double precision can solve "
                                   "(the results scale with E: use SI units, pascals)",
                                   lc.material.E, min_modulus, max_modulus));
  if (!(lc.material.nu > -1.0 && lc.material.nu < 0.5))
    fail("material.nu", fmt::format("must lie in (-1, 0.5) (got {})", lc.material.nu));
  // Every key given is checked, whatever the model uses: a case that is switched to another model
  // later must not carry a value that was never valid.
  positive("material.e0", lc.material.e0);
  if (!(lc.material.e0 < 1.0)) fail("material.e0", fmt::format("must lie in (0, 1): a strain (got {})", lc.material.e0));
  if (!(lc.material.kappa >= 0.0 && lc.material.kappa < 1.0))
    fail("material.kappa", fmt::format("must lie in [0, 1) (got {})", lc.material.kappa));
  if (!(lc.material.n > 0.0 && lc.material.n < 1.0))
    fail("material.n", fmt::format("must lie in (0, 1) (got {})", lc.material.n));

  const auto& path = lc.load.path;
  if (path.size() < 2) fail("load.path", "needs at least two waypoints, starting at 0");
  if (path.front() != 0.0) fail("load.path", fmt::format("must start at 0 (got {})", path.front()));
  for (std::size_t i = 0; i < path.size(); ++i)
    if (path[i] < 0.0) fail("load.path", fmt::format("waypoint {} is a negative depth ({})", i, path[i]));
  if (!(lc.max_depth() > 0.0)) fail("load.path", "never indents: every waypoint is 0");
  // The gap g(x) = R - sqrt(R^2 - x^2) and the displacements are resolved against R and the
  // block in double precision: a depth below 1e-9 of them is round-off, not an indentation.
  const double resolvable = 1e-9 * std::max(has_radius ? lc.punch.radius : 0.0, lc.geometry.ly);
  if (lc.max_depth() < resolvable)
    fail("load.path", fmt::format("the deepest depth {:g} m is below what double precision resolves against the "
                                  "punch radius and the block ({:g} m, 1e-9 of them)",
                                  lc.max_depth(), resolvable));
  if (punch.shape == PunchShapeKind::sphere && lc.max_depth() >= lc.punch.radius)
    fail("load.path", fmt::format("depth {} reaches the punch radius {}: no circular contact possible",
                                  lc.max_depth(), lc.punch.radius));
  if (lc.max_depth() >= lc.geometry.ly)
    fail("load.path", fmt::format("depth {} is not small against the block depth {}", lc.max_depth(),
                                  lc.geometry.ly));
  if (!lc.load.segment_increments.empty() && lc.load.segment_increments.size() + 1 != path.size())
    fail("load.increments", fmt::format("has {} per-segment counts for a path of {} segments",
                                        lc.load.segment_increments.size(), path.size() - 1));
  if (lc.load.increments < 1) fail("load.increments", fmt::format("must be >= 1 (got {})", lc.load.increments));
  if (lc.load.increments > 10'000'000)
    fail("load.increments", fmt::format("{} is more than 1e7 increments", lc.load.increments));

  if (lc.mesh.contact_nodes < 2) fail("mesh.contact_nodes", fmt::format("must be >= 2 (got {})", lc.mesh.contact_nodes));
  if (lc.mesh.contact_half_width) positive("mesh.contact_half_width", *lc.mesh.contact_half_width);
  if (lc.mesh.contact_half_width && punch.shape == PunchShapeKind::flat)
    fail("mesh.contact_half_width", "a flat punch's contact radius is punch.radius: the mesh is sized from it");
  if (lc.mesh.fine_width) positive("mesh.fine_width", *lc.mesh.fine_width);
  if (lc.mesh.fine_depth) positive("mesh.fine_depth", *lc.mesh.fine_depth);
  if (lc.mesh.growth && !(*lc.mesh.growth >= 1.0 && *lc.mesh.growth <= 2.0))
    fail("mesh.growth", fmt::format("must lie in [1, 2] (got {})", *lc.mesh.growth));
  if (lc.mesh.target_error) {
    if (!(*lc.mesh.target_error >= 1e-5 && *lc.mesh.target_error <= 0.1))
      fail("mesh.target_error", fmt::format("must lie in [1e-5, 0.1] (got {})", *lc.mesh.target_error));
    if (lc.mesh.error_estimate == ErrorEstimateChoice::off)
      fail("mesh.target_error", "needs an error estimate: mesh.error_estimate = \"off\" cannot check a target");
  }

  validate_analysis(lc);
  if (lc.output.dir.empty()) fail("output.dir", "must not be empty");
  if (lc.output.checkpoint_every < 0)
    fail("output.checkpoint_every", fmt::format("must be >= 0 (got {})", lc.output.checkpoint_every));
  if (lc.output.fields_every < 0) fail("output.fields_every", fmt::format("must be >= 0 (got {})", lc.output.fields_every));
  for (std::size_t i = 0; i < lc.output.profile_depths.size(); ++i) {
    const double d = lc.output.profile_depths[i];
    if (!(d >= 0.0 && d <= lc.geometry.ly))
      fail("output.profile_depths", fmt::format("element {} = {} is not a depth within the block [0, {}]", i, d, lc.geometry.ly));
  }

  // The residual is relative to E* alpha_max; round-off in assembling it is about 1e-16 times the
  // condition of the stiffness, so a tolerance below 1e-14 cannot be reached, only run into.
  if (!(lc.solver.tolerance >= 1e-14 && lc.solver.tolerance < 1e-2))
    fail("solver.tolerance", fmt::format("must lie in [1e-14, 1e-2) (got {}): below 1e-14 round-off dominates the "
                                         "residual",
                                         lc.solver.tolerance));
  if (lc.solver.max_newton < 1 || lc.solver.max_newton > 1000)
    fail("solver.max_newton", fmt::format("must lie in [1, 1000] (got {})", lc.solver.max_newton));
  if (lc.solver.max_cutbacks < 0 || lc.solver.max_cutbacks > 60)
    fail("solver.max_cutbacks", fmt::format("must lie in [0, 60] (got {})", lc.solver.max_cutbacks));
}

std::string toml_number(double value) {
  std::string text = fmt::format("{}", value);
  if (text.find_first_of(".eEn") == std::string::npos) text += ".0";  // "15" would read as an integer
  return text;
}

std::string toml_string(const std::string& s) {
  std::string quoted = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') quoted += std::string("\\") + c;
    else if (c == '\n') quoted += "\\n";
    else if (c == '\t') quoted += "\\t";
    else if (c == '\r') quoted += "\\r";
    else if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) quoted += fmt::format("\\u{:04X}", static_cast<unsigned char>(c));
    else quoted += c;
  }
  return quoted + "\"";
}

std::string to_toml(const LoadCase& lc) {
  std::string t = fmt::format("# The load case as run (from {}), every key explicit.\n# Written by {}.\n",
                              printable(lc.source, 400), version_line());
  std::string section;
  for (const auto& key : key_declarations()) {
    if (section != key.section) {
      t += fmt::format("{}[{}]\n", section.empty() ? "" : "\n", key.section);
      section = key.section;
    }
    const std::optional<std::string> value = key.write(lc);
    if (!value) continue;
    if (key.derived) t += fmt::format("# {} = {}  ({}: derived, shown for reference)\n", key.name, *value, key.unit);
    else t += fmt::format("{} = {}\n", key.name, *value);
  }
  return t;
}

double yield_stress_of_e0(double e0, double E, double nu) { return 3.0 * (E / (2.0 * (1.0 + nu))) * e0; }
double e0_of_yield_stress(double yield_stress, double E, double nu) {
  return yield_stress / (3.0 * (E / (2.0 * (1.0 + nu))));
}

std::string keys_markdown() {
  std::string t = "| key | type | default | accepted | unit | meaning |\n|---|---|---|---|---|---|\n";
  for (const auto& k : describe_keys()) {
    const auto cell = [](std::string text) {
      std::string out;
      for (char c : text) out += c == '|' ? std::string("\\|") : std::string(1, c);
      return out;
    };
    t += fmt::format("| `{}` | {} | {} | {} | {} | {} |\n", k.key, cell(k.type),
                     k.required ? "required" : "`" + cell(k.default_value) + "`", cell(k.range), k.unit.empty() ? "" : k.unit,
                     cell(k.help));
  }
  return t;
}

std::vector<KeyDescription> describe_keys() {
  const LoadCase defaults;
  std::vector<KeyDescription> out;
  for (const auto& key : key_declarations()) {
    KeyDescription d;
    d.key = std::string(key.section) + "." + key.name;
    d.type = key.type;
    d.range = key.range;
    d.unit = key.unit;
    d.help = key.help;
    d.required = key.required;
    if (key.required) d.default_value = "required";
    else if (key.derived) d.default_value = "from e0";
    else d.default_value = key.write(defaults).value_or("(computed)");
    out.push_back(d);
  }
  return out;
}

std::string first_physics_difference(const LoadCase& a, const LoadCase& b) {
  for (const auto& key : key_declarations()) {
    const std::string section = key.section;
    if (section != "geometry" && section != "punch" && section != "material" && section != "mesh") continue;
    if (key.derived) continue;
    if (key.write(a) != key.write(b)) return section + "." + key.name;
  }
  return "";
}

LoadCase parse_load_case(const std::string& toml_text, const std::string& source,
                         const std::vector<std::string>& overrides) {
  return parse_and_override(toml_text, source, overrides, std::filesystem::current_path());
}

namespace {
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
}  // namespace

LoadCase read_load_case(const std::filesystem::path& file, const std::vector<std::string>& overrides) {
  return parse_and_override(read_text(file), file.string(), overrides, folder_of(file));
}

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
                                                             {"force_unit", &setup.columns.force_unit}};
  for (const auto& [name, target] : curve_keys) keys.push_back(KeyDeclaration{"curve", name, "string", "", "", ""});

  const Reader r(root, source, file ? folder_of(*file) : std::filesystem::current_path());
  r.check_structure(keys);
  LoadCase lc;
  lc.source = source;
  lc.geometry.kind = SceneKind::axisymmetric;  // instruments indent with bodies of revolution
  for (const auto& key : keys)
    if (key.read) key.read(r, lc);
  for (const auto& [name, target] : curve_keys) r.read_string("curve", name, *target);
  if (!r.find("punch", "shape"))
    r.fail("punch.shape", "missing key: the indenter's shape (sphere, cone, flat or profile) gives the area function "
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
