#pragma once
// Private to the input layer: the one list of load-case keys (key_declarations(), declared in
// key_declarations.cpp) and the TOML reader that walks it.  The reader (load_case.cpp), the
// writer and the key table (key_declarations.cpp) and the analysis setup (analysis_setup.cpp)
// all come from this list.
#include <algorithm>
#include <array>
#include <cstddef>
#include <filesystem>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <toml++/toml.h>

#include "indentsim/base/error.hpp"
#include "indentsim/input/load_case.hpp"

namespace indentsim::input_detail {

// The words a load case uses for each choice, shared by the reader and by to_toml().
template <class E>
struct Choice {
  const char* name;
  E value;
};
inline constexpr Choice<MaterialModel> model_names[] = {
    {"elastic", MaterialModel::elastic}, {"ilyushin", MaterialModel::ilyushin}, {"j2", MaterialModel::j2}};
inline constexpr Choice<StrainChoice> strain_names[] = {
    {"small", StrainChoice::small}, {"finite", StrainChoice::finite}, {"auto", StrainChoice::automatic}};
inline constexpr Choice<HardeningLaw> hardening_names[] = {
    {"linear", HardeningLaw::linear}, {"power", HardeningLaw::power},   {"power_law", HardeningLaw::power_law},
    {"ludwik", HardeningLaw::ludwik}, {"swift", HardeningLaw::swift},   {"voce", HardeningLaw::voce},
    {"table", HardeningLaw::table}};
inline constexpr Choice<TableExtension> table_extension_names[] = {{"flat", TableExtension::flat},
                                                                   {"last_slope", TableExtension::last_slope}};
inline constexpr Choice<ElasticStressMeasure> elastic_stress_names[] = {{"cauchy", ElasticStressMeasure::cauchy},
                                                                       {"kirchhoff", ElasticStressMeasure::kirchhoff}};
inline constexpr Choice<RateLaw> rate_law_names[] = {
    {"none", RateLaw::none}, {"perzyna", RateLaw::perzyna}, {"norton", RateLaw::norton}};
inline constexpr Choice<LoadControlKind> load_control_names[] = {{"depth", LoadControlKind::depth},
                                                                 {"force", LoadControlKind::force}};
inline constexpr Choice<ElementChoice> element_names[] = {
    {"auto", ElementChoice::automatic}, {"q1", ElementChoice::q1}, {"bbar", ElementChoice::bbar}};
inline constexpr Choice<LinearSolverChoice> linear_names[] = {
    {"klu", LinearSolverChoice::klu}, {"cholmod", LinearSolverChoice::cholmod}, {"auto", LinearSolverChoice::automatic}};
inline constexpr Choice<JacobianChoice> jacobian_names[] = {{"auto", JacobianChoice::automatic},
                                                     {"krylov", JacobianChoice::krylov},
                                                     {"reuse", JacobianChoice::reuse},
                                                     {"fresh", JacobianChoice::fresh}};
inline constexpr Choice<SceneKind> scene_names[] = {{"plane_strain", SceneKind::plane_strain},
                                             {"axisymmetric", SceneKind::axisymmetric}};
// "cylinder" is the plane-strain reading of "sphere": the same circular profile of punch.radius.
inline constexpr Choice<PunchShapeKind> shape_names[] = {{"sphere", PunchShapeKind::sphere},
                                                  {"cone", PunchShapeKind::cone},
                                                  {"flat", PunchShapeKind::flat},
                                                  {"profile", PunchShapeKind::profile},
                                                  {"area_function", PunchShapeKind::area_function},
                                                  {"cylinder", PunchShapeKind::sphere}};
inline constexpr Choice<ErrorEstimateChoice> error_estimate_names[] = {{"richardson", ErrorEstimateChoice::richardson},
                                                                {"observed", ErrorEstimateChoice::observed},
                                                                {"off", ErrorEstimateChoice::off}};
inline constexpr Choice<FarFieldChoice> far_field_names[] = {
    {"auto", FarFieldChoice::automatic}, {"condense", FarFieldChoice::condense}, {"full", FarFieldChoice::full}};

inline constexpr Choice<ContactDiscretizationChoice> contact_discretization_names[] = {
    {"node_to_rigid", ContactDiscretizationChoice::node_to_rigid},
    {"integrated_gap", ContactDiscretizationChoice::integrated_gap}};

template <class E, std::size_t N>
const char* name_of(const Choice<E> (&names)[N], E value) {
  for (const auto& c : names)
    if (c.value == value) return c.name;
  return "?";
}

class Reader;

/// One load-case key, declared once: how it is read and written, what it means, and whether a
/// resumed run may change it.  The reader, the writer (to_toml), the resume check, `indentsim
/// keys` and the README's key table all come from this one list (key_declarations()).
struct KeyDeclaration {
  const char* section;
  const char* name;
  const char* type;   ///< as `indentsim keys` shows it
  /// The values accepted, in words.  For a number or integer key its leading interval ("> 0",
  /// ">= 2", "(-1, 0.5)", "[1, 2]", ...) is enforced from these very words (check); what follows
  /// a comma ("> the deepest depth") involves other keys and is validate()'s.
  std::string range;
  const char* unit;   ///< SI unit, or "" for a pure number, a word or a path
  const char* help;
  bool required = false;
  /// Reads the key from the TOML table (when present) into the load case.
  std::function<void(const Reader&, LoadCase&)> read{};
  /// The key's value as TOML text, or nothing when it is absent (an optional override unset).
  std::function<std::optional<std::string>(const LoadCase&)> write{};
  /// Shown as a comment in case.toml, not as a key (a value derived from another key).
  bool derived = false;
  /// Throws InputError naming the key when its value lies outside the declared interval.
  std::function<void(const LoadCase&)> check{};
  /// What `indentsim keys` shows as the default when the default value is not a value of the
  /// key (a required-by-shape key, a derived one, a default computed from the case).
  const char* default_words = nullptr;
  /// The magnitudes a solid, an indenter or an instrument has for this key (in the key's unit):
  /// a value given outside them runs, but is most likely a unit slip, and is warned about.
  struct Plausible {
    double low = 0.0, high = 0.0;
    const char* of_what = "";  ///< "the moduli of solids"
  };
  std::optional<Plausible> plausible{};
  /// The values of the key the case uses (none when the key does not apply or is not given).
  std::function<std::vector<double>(const LoadCase&)> magnitudes{};
};

/// The accepted interval at the head of a key's range words (nullopt: none there).
struct Bounds {
  double lower = -std::numeric_limits<double>::infinity(), upper = std::numeric_limits<double>::infinity();
  bool lower_closed = false, upper_closed = false, two_sided = false;
  std::string words;  ///< as declared: "> 0", "[1, 2]"
  /// "must be > 0 (got x)" / "must lie in [1, 2] (got x)" when `value` is outside; nullopt inside.
  std::optional<std::string> problem(double value) const;
};
std::optional<Bounds> bounds_of(const std::string& range);

inline std::vector<std::string> section_names(const std::vector<KeyDeclaration>& keys) {
  std::vector<std::string> names;
  for (const auto& k : keys)
    if (std::find(names.begin(), names.end(), k.section) == names.end()) names.emplace_back(k.section);
  return names;
}

inline std::vector<std::string> key_names(const std::vector<KeyDeclaration>& keys, const std::string& section) {
  std::vector<std::string> names;
  for (const auto& k : keys)
    if (section == k.section) names.emplace_back(k.name);
  return names;
}

/// A copy of `lc` with `material` as its only material: how a layer's material is read, written,
/// checked and compared by the [material] declarations.
inline LoadCase with_material(const LoadCase& lc, const MaterialInput& material) {
  LoadCase scratch = lc;
  scratch.material = material;
  scratch.layers.clear();
  return scratch;
}

inline std::string join(const std::vector<std::string>& words) {
  std::string out;
  for (const auto& w : words) out += (out.empty() ? "" : ", ") + w;
  return out;
}

inline std::string toml_numbers(const std::vector<double>& values) {
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

  /// A finite number, or `word` (stored as `word_value`).
  void read_number_or_word(const std::string& section, const std::string& key, const char* word, double word_value,
                           double& target) const {
    const toml::node* node = find(section, key);
    if (!node) return;
    if (node->is_string()) {
      if (node->value_exact<std::string>() != word)
        fail(section + "." + key, fmt::format("must be a number or \"{}\"", word));
      target = word_value;
      return;
    }
    read_number(section, key, target);
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

  /// An array of N-number tuples, each read as doubles: `plural` names the array's elements
  /// ("[r, g] pairs"), `one` one of them ("a pair [r, g]").
  template <std::size_t N>
  void read_tuples(const std::string& section, const std::string& key, const char* plural, const char* one,
                   std::vector<std::array<double, N>>& target) const {
    const toml::node* node = find(section, key);
    if (!node) return;
    const toml::array* array = node->as_array();
    const std::string where = section + "." + key;
    if (!array) fail(where, fmt::format("expected an array of {}, got {}", plural, type_name(*node)));
    target.clear();
    for (std::size_t i = 0; i < array->size(); ++i) {
      const toml::array* tuple = array->get(i)->as_array();
      if (!tuple || tuple->size() != N) fail(where, fmt::format("element {} is not {}", i, one));
      std::array<double, N> values{};
      for (std::size_t c = 0; c < N; ++c) {
        const toml::node& item = *tuple->get(c);
        if (auto v = item.value_exact<double>()) values[c] = *v;
        else if (auto n = item.value_exact<int64_t>()) values[c] = static_cast<double>(*n);
        else fail(where, fmt::format("element {} holds {}, expected numbers", i, type_name(item)));
      }
      target.push_back(values);
    }
  }

  /// punch.profile_points: an array of [r, g] pairs.
  void read_points(const std::string& section, const std::string& key,
                   std::vector<std::pair<double, double>>& target, const std::string& pair_words = "[r, g]") const {
    if (!find(section, key)) return;
    std::vector<std::array<double, 2>> pairs;
    read_tuples(section, key, (pair_words + " pairs").c_str(), ("a pair " + pair_words).c_str(), pairs);
    target.clear();
    for (const auto& [r, g] : pairs) target.emplace_back(r, g);
  }

  const std::string& source() const { return source_; }
  /// Where relative paths in the load case (punch.profile) are taken from: the file's folder.
  const std::filesystem::path& base_dir() const { return base_dir_; }

private:
  const toml::table& root_;
  std::string source_;
  std::filesystem::path base_dir_;
};

const std::vector<KeyDeclaration>& key_declarations();

/// --set section.key=value into the TOML table (one key, one value).
void apply_override(toml::table& root, const std::string& text, const std::string& source);
/// The TOML text with the --set overrides applied; a syntax error names its line and column.
toml::table parse_with_overrides(const std::string& text, const std::string& source,
                                 const std::vector<std::string>& overrides);
/// Every declared interval of `section`'s keys (KeyDeclaration::check), in declaration order.
void check_declared_ranges(const LoadCase& lc, const std::string& section);
/// The punch keys that apply to the case's shape; any other punch key given is a mistake.  Reads
/// a profile file.
void check_punch_keys(const Reader& r, LoadCase& lc);
/// The indenter on its own: what its shape needs, whatever specimen it meets (validation.cpp).
void validate_punch_shape(const LoadCase& lc);
/// The [analysis] keys (validation.cpp).
void validate_analysis(const LoadCase& lc);
/// A file's text (InputError naming it when it cannot be read).
std::string read_text(const std::filesystem::path& file);
/// Where relative paths in a file are taken from.
std::filesystem::path folder_of(const std::filesystem::path& file);

}  // namespace indentsim::input_detail
