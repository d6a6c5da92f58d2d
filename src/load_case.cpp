#include "indentsim/load_case.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <toml++/toml.h>

#include "indentsim/error.hpp"

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
constexpr Choice<JacobianChoice> jacobian_names[] = {{"reuse", JacobianChoice::reuse}, {"fresh", JacobianChoice::fresh}};
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

namespace {

// The schema: every section and key a load case may contain, and which are required.
struct KeySpec {
  const char* name;
  bool required;
};
struct SectionSpec {
  const char* name;
  bool required;
  std::vector<KeySpec> keys;
};

const std::vector<SectionSpec>& schema() {
  static const std::vector<SectionSpec> sections = {
      {"geometry", true, {{"lx", true}, {"ly", true}}},
      {"punch", true, {{"radius", true}}},
      {"material",
       true,
       {{"model", true}, {"E", true}, {"nu", true}, {"e0", false}, {"hardening", false},
        {"kappa", false}, {"n", false}}},
      {"load", true, {{"path", true}, {"increments", true}}},
      {"mesh",
       false,
       {{"contact_nodes", false}, {"contact_half_width", false}, {"fine_width", false},
        {"fine_depth", false}, {"growth", false}, {"element", false}}},
      {"output",
       false,
       {{"dir", false}, {"fields_every", false}, {"profile_depths", false}, {"checkpoint_every", false},
        {"keep_checkpoints", false}}},
      {"solver", false, {{"tolerance", false}, {"max_newton", false}, {"max_cutbacks", false}, {"linear", false},
                              {"far_field", false}, {"jacobian", false}}},
  };
  return sections;
}

const SectionSpec* find_section(std::string_view name) {
  for (const auto& s : schema())
    if (name == s.name) return &s;
  return nullptr;
}

std::string known_keys(const SectionSpec& section) {
  std::string list;
  for (const auto& k : section.keys) list += (list.empty() ? "" : ", ") + std::string(k.name);
  return list;
}

class Reader {
public:
  Reader(const toml::table& root, std::string source) : root_(root), source_(std::move(source)) {}

  [[noreturn]] void fail(const std::string& key, const std::string& problem) const {
    throw InputError(source_, key, problem);
  }

  void check_structure() const {
    for (const auto& [name, node] : root_) {
      const std::string section_name(name.str());
      const SectionSpec* spec = find_section(section_name);
      if (!spec) {
        std::string sections;
        for (const auto& s : schema()) sections += (sections.empty() ? "" : ", ") + std::string(s.name);
        fail(section_name, fmt::format("unknown section (known sections: {})", sections));
      }
      const toml::table* table = node.as_table();
      if (!table) fail(section_name, "must be a table ([" + section_name + "])");
      for (const auto& [key, value] : *table) {
        const std::string key_name(key.str());
        const bool known = std::any_of(spec->keys.begin(), spec->keys.end(),
                                       [&](const KeySpec& k) { return key_name == k.name; });
        if (!known)
          fail(section_name + "." + key_name,
               fmt::format("unknown key (known keys of [{}]: {})", section_name, known_keys(*spec)));
      }
    }
    for (const auto& section : schema()) {
      const toml::table* table = root_[section.name].as_table();
      if (!table) {
        if (section.required) fail(section.name, "missing section");
        continue;
      }
      for (const auto& key : section.keys)
        if (key.required && !table->contains(key.name))
          fail(std::string(section.name) + "." + key.name, "missing key");
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

  template <class E, std::size_t N>
  void read_choice(const std::string& section, const std::string& key, const Choice<E> (&names)[N], E& target) const {
    std::string word;
    if (!find(section, key)) return;
    read_string(section, key, word);
    std::string known;
    for (const auto& c : names) {
      if (word == c.name) {
        target = c.value;
        return;
      }
      known += (known.empty() ? "" : ", ") + std::string(c.name);
    }
    fail(section + "." + key, fmt::format("\"{}\" is not one of: {}", printable(word, 60), known));
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

  const std::string& source() const { return source_; }

private:
  const toml::table& root_;
  std::string source_;
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

LoadCase from_table(const toml::table& root, const std::string& source) {
  Reader r(root, source);
  r.check_structure();
  LoadCase lc;
  lc.source = source;
  r.read_number("geometry", "lx", lc.geometry.lx);
  r.read_number("geometry", "ly", lc.geometry.ly);
  r.read_number("punch", "radius", lc.punch.radius);

  r.read_choice("material", "model", model_names, lc.material.model);
  r.read_number("material", "E", lc.material.E);
  r.read_number("material", "nu", lc.material.nu);
  r.read_number("material", "e0", lc.material.e0);
  r.read_choice("material", "hardening", hardening_names, lc.material.hardening);
  r.read_number("material", "kappa", lc.material.kappa);
  r.read_number("material", "n", lc.material.n);

  r.read_number_array("load", "path", lc.load.path);
  if (const toml::node* inc = r.find("load", "increments"); inc && inc->is_array()) {
    const toml::array& counts = *inc->as_array();
    lc.load.segment_increments.clear();
    int total = 0;
    for (std::size_t i = 0; i < counts.size(); ++i) {
      auto n = counts.get(i)->value_exact<int64_t>();
      if (!n || *n < 1 || *n > 10'000'000)
        r.fail("load.increments", fmt::format("element {} must be an integer in [1, 1e7]", i));
      lc.load.segment_increments.push_back(static_cast<int>(*n));
      total += static_cast<int>(*n);
      if (total > 10'000'000) r.fail("load.increments", "more than 1e7 increments in all");
    }
    lc.load.increments = total;
  } else {
    r.read_integer("load", "increments", lc.load.increments);
  }

  r.read_integer("mesh", "contact_nodes", lc.mesh.contact_nodes);
  r.read_choice("mesh", "element", element_names, lc.mesh.element);
  r.read_optional_number("mesh", "contact_half_width", lc.mesh.contact_half_width);
  r.read_optional_number("mesh", "fine_width", lc.mesh.fine_width);
  r.read_optional_number("mesh", "fine_depth", lc.mesh.fine_depth);
  r.read_optional_number("mesh", "growth", lc.mesh.growth);

  r.read_string("output", "dir", lc.output.dir);
  r.read_integer("output", "fields_every", lc.output.fields_every);
  r.read_number_array("output", "profile_depths", lc.output.profile_depths);
  r.read_integer("output", "checkpoint_every", lc.output.checkpoint_every);
  if (const toml::node* keep = r.find("output", "keep_checkpoints"); keep && keep->is_string()) {
    if (keep->value_exact<std::string>() != "all")
      r.fail("output.keep_checkpoints", "must be a count >= 1 or \"all\"");
    lc.output.keep_checkpoints = 0;
  } else {
    r.read_integer("output", "keep_checkpoints", lc.output.keep_checkpoints);
    if (keep && lc.output.keep_checkpoints < 1)
      r.fail("output.keep_checkpoints", fmt::format("must be a count >= 1 or \"all\" (got {})", lc.output.keep_checkpoints));
  }

  r.read_number("solver", "tolerance", lc.solver.tolerance);
  r.read_choice("solver", "linear", linear_names, lc.solver.linear);
  r.read_choice("solver", "far_field", far_field_names, lc.solver.far_field);
  r.read_choice("solver", "jacobian", jacobian_names, lc.solver.jacobian);
  r.read_integer("solver", "max_newton", lc.solver.max_newton);
  r.read_integer("solver", "max_cutbacks", lc.solver.max_cutbacks);
  validate(lc);
  return lc;
}

LoadCase parse_and_override(const std::string& text, const std::string& source,
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
  return from_table(root, source);
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
  positive("punch.radius", lc.punch.radius);
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
  const double resolvable = 1e-9 * std::max(lc.punch.radius, lc.geometry.ly);
  if (lc.max_depth() < resolvable)
    fail("load.path", fmt::format("the deepest depth {:g} m is below what double precision resolves against the "
                                  "punch radius and the block ({:g} m, 1e-9 of them)",
                                  lc.max_depth(), resolvable));
  if (lc.max_depth() >= lc.punch.radius)
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
  if (lc.mesh.fine_width) positive("mesh.fine_width", *lc.mesh.fine_width);
  if (lc.mesh.fine_depth) positive("mesh.fine_depth", *lc.mesh.fine_depth);
  if (lc.mesh.growth && !(*lc.mesh.growth >= 1.0 && *lc.mesh.growth <= 2.0))
    fail("mesh.growth", fmt::format("must lie in [1, 2] (got {})", *lc.mesh.growth));

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

std::string to_toml(const LoadCase& lc) {
  const auto numbers = [](const std::vector<double>& v) {
    std::string s = "[";
    for (std::size_t i = 0; i < v.size(); ++i) s += fmt::format("{}{:.17g}", i ? ", " : "", v[i]);
    return s + "]";
  };
  std::string t = fmt::format("# The load case as run (from {}), every key explicit.\n", lc.source);
  t += fmt::format("[geometry]\nlx = {:.17g}\nly = {:.17g}\n\n", lc.geometry.lx, lc.geometry.ly);
  t += fmt::format("[punch]\nradius = {:.17g}\n\n", lc.punch.radius);
  t += fmt::format("[material]\nmodel = \"{}\"\nE = {:.17g}\nnu = {:.17g}\ne0 = {:.17g}\nhardening = \"{}\"\n"
                   "kappa = {:.17g}\nn = {:.17g}\n\n",
                   to_string(lc.material.model), lc.material.E, lc.material.nu, lc.material.e0,
                   to_string(lc.material.hardening), lc.material.kappa, lc.material.n);
  std::string increments = std::to_string(lc.load.increments);
  if (!lc.load.segment_increments.empty()) {
    increments = "[";
    for (std::size_t i = 0; i < lc.load.segment_increments.size(); ++i)
      increments += fmt::format("{}{}", i ? ", " : "", lc.load.segment_increments[i]);
    increments += "]";
  }
  t += fmt::format("[load]\npath = {}\nincrements = {}\n\n", numbers(lc.load.path), increments);
  t += fmt::format("[mesh]\nelement = \"{}\"\ncontact_nodes = {}\n", name_of(element_names, lc.mesh.element),
                   lc.mesh.contact_nodes);
  if (lc.mesh.contact_half_width) t += fmt::format("contact_half_width = {:.17g}\n", *lc.mesh.contact_half_width);
  if (lc.mesh.fine_width) t += fmt::format("fine_width = {:.17g}\n", *lc.mesh.fine_width);
  if (lc.mesh.fine_depth) t += fmt::format("fine_depth = {:.17g}\n", *lc.mesh.fine_depth);
  if (lc.mesh.growth) t += fmt::format("growth = {:.17g}\n", *lc.mesh.growth);
  toml::table dir_table{{"dir", lc.output.dir}};
  std::ostringstream dir_line;
  dir_line << dir_table;
  t += fmt::format("\n[output]\n{}\nfields_every = {}\nprofile_depths = {}\ncheckpoint_every = {}\n"
                   "keep_checkpoints = {}\n\n",
                   dir_line.str(), lc.output.fields_every, numbers(lc.output.profile_depths),
                   lc.output.checkpoint_every,
                   lc.output.keep_checkpoints == 0 ? std::string("\"all\"") : std::to_string(lc.output.keep_checkpoints));
  t += fmt::format("[solver]\ntolerance = {:.17g}\nmax_newton = {}\nmax_cutbacks = {}\nlinear = \"{}\"\n"
                   "far_field = \"{}\"\njacobian = \"{}\"\n",
                   lc.solver.tolerance, lc.solver.max_newton, lc.solver.max_cutbacks,
                   name_of(linear_names, lc.solver.linear), name_of(far_field_names, lc.solver.far_field),
                   name_of(jacobian_names, lc.solver.jacobian));
  return t;
}

LoadCase parse_load_case(const std::string& toml_text, const std::string& source,
                         const std::vector<std::string>& overrides) {
  return parse_and_override(toml_text, source, overrides);
}

LoadCase read_load_case(const std::filesystem::path& file, const std::vector<std::string>& overrides) {
  const std::string source = file.string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec))
    throw InputError(source, "", "cannot open: not a readable file");
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(source, "", "cannot open for reading");
  std::ostringstream text;
  text << in.rdbuf();
  return parse_and_override(text.str(), source, overrides);
}

}  // namespace indentsim
