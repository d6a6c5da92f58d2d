// A sweep file expanded into its runs (sweep.hpp).
#include "indentsim/study/sweep.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <unordered_set>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <toml++/toml.h>

#include "indentsim/output/checkpoint.hpp"
#include "indentsim/base/error.hpp"
#include "indentsim/base/interruption.hpp"
#include "indentsim/study/sweep_results.hpp"

namespace fs = std::filesystem;

namespace indentsim {

namespace {

std::string join(const std::vector<std::string>& words) {
  std::string out;
  for (const auto& w : words) out += (out.empty() ? "" : ", ") + w;
  return out;
}

/// A TOML value of the sweep file as the text of a load-case override.
std::string value_text(const toml::node& node, const std::string& file, const std::string& key) {
  if (const auto i = node.value_exact<int64_t>()) return std::to_string(*i);
  if (const auto d = node.value_exact<double>()) {
    if (!std::isfinite(*d)) throw InputError(file, key, "values must be finite numbers");
    return toml_number(*d);
  }
  if (const auto b = node.value_exact<bool>()) return *b ? "true" : "false";
  if (const auto s = node.value_exact<std::string>()) return toml_string(*s);
  if (const toml::array* a = node.as_array()) {
    std::string text = "[";
    for (std::size_t k = 0; k < a->size(); ++k) text += (k ? ", " : "") + value_text(*a->get(k), file, key);
    return text + "]";
  }
  throw InputError(file, key, "a value must be a number, a string, a boolean or an array of them");
}

/// The value at `fraction` in [0, 1] of a range, as override text.
std::string value_text_of_fraction(const SweptKey& k, double fraction, bool stratum) {
  if (k.integer) {
    // An integer key: a grid rounds its evenly spaced values; a Latin hypercube's stratum of
    // [from, to + 1) maps to floor(), so each integer gets an equal share of the strata.
    const double v = stratum ? std::min(std::floor(k.from + fraction * (k.to - k.from + 1.0)), k.to)
                             : std::round(k.from + fraction * (k.to - k.from));
    return fmt::format("{}", static_cast<int64_t>(v));
  }
  if (fraction == 0.0) return toml_number(k.from);
  if (!stratum && fraction == 1.0) return toml_number(k.to);
  const double v = k.logarithmic ? std::exp(std::log(k.from) + fraction * (std::log(k.to) - std::log(k.from)))
                                 : k.from + fraction * (k.to - k.from);
  // 15 significant digits: 0.2 + 0.5 (0.4 - 0.2) is 0.3, not 0.30000000000000004.
  return toml_number(std::stod(fmt::format("{:.15g}", v)));
}

/// Whether the load case declares `key` an integer (mesh.contact_nodes, solver.max_newton, ...).
bool integer_key(const std::string& key) {
  for (const auto& d : describe_keys())
    if (d.key == key) return d.type.rfind("integer", 0) == 0;
  return false;
}

/// [vary] "section.key" = [values] or {from, to, count, scale}.
SweptKey read_swept_key(const std::string& key, const toml::node& node, const std::string& file) {
  SweptKey k;
  k.key = key;
  if (key.find('.') == std::string::npos)
    throw InputError(file, "vary." + key, "must name a load-case key as section.key (e.g. \"material.E\")");
  const std::string where = "vary." + key;
  if (const toml::array* list = node.as_array()) {
    if (list->empty()) throw InputError(file, where, "is an empty list: give at least one value");
    for (const auto& v : *list) k.values.push_back(value_text(v, file, where));
    return k;
  }
  const toml::table* range = node.as_table();
  if (!range) throw InputError(file, where, "must be a list of values or a range {from, to, count, scale}");
  for (const auto& [name, value] : *range) {
    const std::string n(name.str());
    if (n != "from" && n != "to" && n != "count" && n != "scale")
      throw InputError(file, where + "." + n, "unknown key of a range (known: from, to, count, scale)");
  }
  const auto number = [&](const char* name) {
    const toml::node* v = range->get(name);
    if (!v) throw InputError(file, where + "." + name, "missing: a range needs from and to");
    if (const auto i = v->value_exact<int64_t>()) return static_cast<double>(*i);
    if (const auto d = v->value_exact<double>(); d && std::isfinite(*d)) return *d;
    throw InputError(file, where + "." + name, "must be a finite number");
  };
  k.from = number("from");
  k.to = number("to");
  if (const toml::node* scale = range->get("scale")) {
    const auto s = scale->value_exact<std::string>();
    if (!s || (*s != "linear" && *s != "log"))
      throw InputError(file, where + ".scale", "must be \"linear\" or \"log\"");
    k.logarithmic = *s == "log";
  }
  if (k.logarithmic && (k.from <= 0.0 || k.to <= 0.0))
    throw InputError(file, where, fmt::format("a log range needs positive ends (got {} to {})", k.from, k.to));
  k.integer = integer_key(key);
  if (k.integer && (k.from != std::floor(k.from) || k.to != std::floor(k.to)))
    throw InputError(file, where, fmt::format("{} is an integer: give integer ends (got {} to {})", key, k.from, k.to));
  if (k.integer && k.logarithmic) throw InputError(file, where + ".scale", "an integer key takes a linear range");
  if (const toml::node* count = range->get("count")) {
    const auto c = count->value_exact<int64_t>();
    if (!c || *c < 1 || *c > 100000) throw InputError(file, where + ".count", "must be an integer in [1, 100000]");
    if (*c == 1 && k.from != k.to)
      throw InputError(file, where + ".count", "is 1 but from != to: which end? (give a list of one value)");
    if (*c > 1 && k.from == k.to) throw InputError(file, where, "is an empty range: from = to with count > 1");
    for (int64_t j = 0; j < *c; ++j) k.values.push_back(value_text_of_fraction(k, *c == 1 ? 0.0 : double(j) / double(*c - 1), false));
  }
  return k;
}

/// The entries of a [set] or [vary] table, dotted keys flattened ("material.E" quoted, or
/// material.E dotted); in [vary] a table with `from` or `to` is a range, not a section.
void flatten(const toml::table& table, const std::string& prefix, bool ranges,
             std::vector<std::pair<std::string, const toml::node*>>& out) {
  for (const auto& [name, node] : table) {
    const std::string key = prefix.empty() ? std::string(name.str()) : prefix + "." + std::string(name.str());
    const toml::table* inner = node.as_table();
    if (inner && !(ranges && (inner->contains("from") || inner->contains("to")))) flatten(*inner, key, ranges, out);
    else out.emplace_back(key, &node);
  }
}

/// A seeded Mersenne twister's next draw as a double in [0, 1): the same on every platform (std::uniform_real_distribution is not specified bit for bit).
double unit_draw(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

/// A random permutation of 0..n-1 (Fisher-Yates on the same portable draws).
std::vector<int> permutation(int n, std::mt19937_64& rng) {
  std::vector<int> p(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) p[static_cast<std::size_t>(i)] = i;
  for (int i = n - 1; i > 0; --i)
    std::swap(p[static_cast<std::size_t>(i)], p[static_cast<std::size_t>(rng() % static_cast<std::uint64_t>(i + 1))]);
  return p;
}

/// The varied values of each combination, made one at a time (a sweep of a million runs never
/// holds a million rows of text).  A grid's combination p is p written in the mixed radix of the
/// keys' value counts (the first key slowest); a Latin hypercube's fractions are drawn up front,
/// in the order the design always drew them (a number per key and sample).
class DesignPoints {
public:
  explicit DesignPoints(const SweepDefinition& d) : d_(d) {
    if (d.design == SweepDesign::grid) return;
    // Latin hypercube (McKay, Beckman and Conover 1979): each key's range cut into `samples`
    // strata of equal probability, one point in each, the strata paired at random across keys.
    std::mt19937_64 rng(d.seed);
    fractions_.resize(d.vary.size());
    for (std::size_t j = 0; j < d.vary.size(); ++j) {
      const std::vector<int> strata = permutation(d.samples, rng);
      fractions_[j].resize(static_cast<std::size_t>(d.samples));
      for (int i = 0; i < d.samples; ++i)
        fractions_[j][static_cast<std::size_t>(i)] = (strata[static_cast<std::size_t>(i)] + unit_draw(rng)) / d.samples;
    }
  }

  /// The values of combination p (0 <= p < combinations()), one per varied key.
  std::vector<std::string> values(std::int64_t p) const {
    std::vector<std::string> v(d_.vary.size());
    if (d_.design == SweepDesign::grid) {
      for (std::size_t j = d_.vary.size(); j-- > 0;) {
        const auto n = static_cast<std::int64_t>(d_.vary[j].values.size());
        v[j] = d_.vary[j].values[static_cast<std::size_t>(p % n)];
        p /= n;
      }
      return v;
    }
    for (std::size_t j = 0; j < d_.vary.size(); ++j)
      v[j] = value_text_of_fraction(d_.vary[j], fractions_[j][static_cast<std::size_t>(p)], true);
    return v;
  }

private:
  const SweepDefinition& d_;
  std::vector<std::vector<double>> fractions_;  ///< latin_hypercube: [key][sample]
};

/// max_runs enforced before anything is expanded: the count, and how to raise the limit.
void check_run_count(const SweepDefinition& d) {
  const std::int64_t runs = d.combinations();
  if (runs <= d.max_runs) return;
  std::string counts;
  if (d.design == SweepDesign::grid && d.vary.size() > 1) {
    for (const SweptKey& k : d.vary) counts += fmt::format("{}{}", counts.empty() ? "" : " x ", k.values.size());
    counts = " (" + counts + " values)";
  }
  if (runs > largest_max_sweep_runs)
    throw InputError(d.file.string(), "sweep.max_runs",
                     fmt::format("the sweep has {} runs{}, more than any sweep may have ({}): split it into smaller "
                                 "sweeps",
                                 runs == std::numeric_limits<std::int64_t>::max() ? std::string("over 9.2e18")
                                                                                  : std::to_string(runs),
                                 counts, largest_max_sweep_runs));
  throw InputError(d.file.string(), "sweep.max_runs",
                   fmt::format("the sweep has {} runs{}, more than the {} a sweep may have{}; if that many runs are "
                               "meant, raise the limit in [sweep]: max_runs = {}",
                               runs, counts, d.max_runs,
                               d.max_runs == default_max_sweep_runs ? " by default" : " by its max_runs", runs));
}

/// A JSON string (nlohmann's escaping; invalid UTF-8 replaced, never thrown on).
std::string json_text(const nlohmann::ordered_json& j) {
  return j.dump(-1, ' ', false, nlohmann::ordered_json::error_handler_t::replace);
}

/// manifest.json's text: the definition's essentials, then a line per run (its case when asked).
std::string manifest_json(const SweepManifest& m, bool with_cases) {
  const SweepDefinition& d = m.definition;
  std::string text = "{\n";
  text += " \"indentsim_sweep\": 2,\n";
  text += " \"sweep\": " + json_text(d.file.string()) + ",\n";
  text += " \"base\": " + json_text(d.base.string()) + ",\n";
  text += " \"out\": " + json_text(d.out.string()) + ",\n";
  text += " \"keep\": " + json_text(d.keep) + ",\n";
  text += " \"set\": " + json_text(d.set) + ",\n";
  text += " \"keys\": " + json_text(m.keys) + ",\n";
  text += " \"runs\": [";
  for (std::size_t k = 0; k < m.runs.size(); ++k) {
    if (const int signal = interruption_requested()) throw Interrupted(signal);
    const SweepRun& r = m.runs[k];
    nlohmann::ordered_json j = {{"index", r.index}, {"hash", r.hash}, {"values", r.values}};
    if (with_cases) j["case"] = m.run_case(r);
    text += (k ? ",\n  " : "\n  ") + json_text(j);
  }
  text += m.runs.empty() ? "]\n}\n" : "\n ]\n}\n";
  return text;
}

std::string hex16(std::uint64_t h) { return fmt::format("{:016x}", h); }

}  // namespace

SweepDefinition read_sweep_definition(const fs::path& file) {
  const std::string source = file.string();
  toml::table root;
  try {
    root = toml::parse_file(source);
  } catch (const toml::parse_error& e) {
    const auto& where = e.source().begin;
    throw InputError(source, "", fmt::format("not valid TOML (line {}, column {}): {}", where.line, where.column,
                                             std::string(e.description())));
  }
  for (const auto& [name, node] : root) {
    const std::string n(name.str());
    if (n != "sweep" && n != "set" && n != "vary")
      throw InputError(source, n, "unknown section of a sweep file (known: [sweep], [set], [vary])");
    if (!node.is_table()) throw InputError(source, n, "must be a table ([" + n + "])");
  }
  const toml::table* sweep = root["sweep"].as_table();
  if (!sweep) throw InputError(source, "sweep", "missing section: [sweep] with base = \"the load case\"");
  static const std::vector<std::string> known{"base", "out", "design", "samples", "seed", "keep", "max_runs"};
  for (const auto& [name, node] : *sweep)
    if (std::find(known.begin(), known.end(), std::string(name.str())) == known.end())
      throw InputError(source, "sweep." + std::string(name.str()), "unknown key (known keys of [sweep]: " + join(known) + ")");
  const auto text = [&](const char* key) -> std::optional<std::string> {
    const toml::node* node = sweep->get(key);
    if (!node) return std::nullopt;
    const auto s = node->value_exact<std::string>();
    if (!s || s->empty()) throw InputError(source, std::string("sweep.") + key, "must be a non-empty string");
    return *s;
  };
  const auto integer = [&](const char* key, int64_t lo, int64_t hi) -> std::optional<int64_t> {
    const toml::node* node = sweep->get(key);
    if (!node) return std::nullopt;
    const auto i = node->value_exact<int64_t>();
    if (!i || *i < lo || *i > hi)
      throw InputError(source, std::string("sweep.") + key, fmt::format("must be an integer in [{}, {}]", lo, hi));
    return *i;
  };

  SweepDefinition d;
  d.file = file;
  const auto base = text("base");
  if (!base) throw InputError(source, "sweep.base", "missing key: the base load case (a path relative to the sweep file)");
  d.base = fs::path(*base).is_absolute() ? fs::path(*base) : (file.parent_path().empty() ? fs::path(".") : file.parent_path()) / *base;
  d.out = text("out").value_or("out/" + file.stem().string());
  const std::string design = text("design").value_or("grid");
  if (design != "grid" && design != "latin_hypercube")
    throw InputError(source, "sweep.design", fmt::format("must be \"grid\" or \"latin_hypercube\" (got \"{}\")", design));
  d.design = design == "grid" ? SweepDesign::grid : SweepDesign::latin_hypercube;
  if (const auto samples = integer("samples", 1, 1000000)) d.samples = static_cast<int>(*samples);
  if (const auto seed = integer("seed", 0, std::numeric_limits<int64_t>::max())) d.seed = static_cast<std::uint64_t>(*seed);
  if (const auto max_runs = integer("max_runs", 1, largest_max_sweep_runs)) d.max_runs = *max_runs;
  if (d.design == SweepDesign::grid && sweep->contains("samples"))
    throw InputError(source, "sweep.samples", "is for design = \"latin_hypercube\" (a grid runs every combination)");
  if (d.design == SweepDesign::latin_hypercube && d.samples == 0)
    throw InputError(source, "sweep.samples", "missing key: design = \"latin_hypercube\" needs the number of runs");
  if (const toml::node* keep = sweep->get("keep")) {
    const toml::array* list = keep->as_array();
    if (!list) throw InputError(source, "sweep.keep", "must be a list of names (" + join(sweep_keepable_outputs()) + ")");
    d.keep.clear();
    for (const auto& entry : *list) {
      const auto name = entry.value_exact<std::string>();
      const auto& names = sweep_keepable_outputs();
      if (!name || std::find(names.begin(), names.end(), *name) == names.end())
        throw InputError(source, "sweep.keep", "each entry must be one of " + join(names));
      d.keep.push_back(*name);
    }
  }

  std::set<std::string> set_keys;
  if (const toml::table* set = root["set"].as_table()) {
    std::vector<std::pair<std::string, const toml::node*>> entries;
    flatten(*set, "", false, entries);
    for (const auto& [key, node] : entries) {
      d.set.push_back(key + "=" + value_text(*node, source, "set." + key));
      set_keys.insert(key);
    }
  }
  const toml::table* vary = root["vary"].as_table();
  if (!vary || vary->empty()) throw InputError(source, "vary", "missing section: [vary] names the keys to vary");
  std::vector<std::pair<std::string, const toml::node*>> entries;
  flatten(*vary, "", true, entries);
  std::sort(entries.begin(), entries.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& [key, node] : entries) {
    // A key set in every run and varied: the varied values would silently win over [set].
    if (set_keys.count(key))
      throw InputError(source, key, "is both in [set] and in [vary]: give it in one of them (in [vary] its values "
                                    "would override [set]'s in every run)");
    SweptKey k = read_swept_key(key, *node, source);
    if (d.design == SweepDesign::grid && k.values.empty())
      throw InputError(source, "vary." + key, "a range on a grid needs count (how many values from `from` to `to`)");
    if (d.design == SweepDesign::latin_hypercube) {
      if (!node->is_table())
        throw InputError(source, "vary." + key, "a latin hypercube samples ranges: give {from, to} (and scale)");
      if (node->as_table()->contains("count"))
        throw InputError(source, "vary." + key + ".count", "is for design = \"grid\" (sweep.samples counts the runs)");
    }
    d.vary.push_back(std::move(k));
  }
  check_run_count(d);
  return d;
}

std::int64_t SweepDefinition::combinations() const {
  if (design == SweepDesign::latin_hypercube) return samples;
  constexpr std::int64_t most = std::numeric_limits<std::int64_t>::max();
  std::int64_t n = 1;
  for (const SweptKey& k : vary) {
    const auto count = static_cast<std::int64_t>(k.values.size());
    if (count == 0) return 0;
    n = n > most / count ? most : n * count;
  }
  return n;
}

std::string case_hash(const LoadCase& load_case) {
  // The case as run, without its header comments (source, version) and its [output] section.
  const std::string toml = to_toml(load_case);
  std::string content;
  bool in_output = false, started = false;
  std::size_t start = 0;
  while (start < toml.size()) {
    const std::size_t end = std::min(toml.find('\n', start), toml.size());
    const std::string line = toml.substr(start, end - start);
    start = end + 1;
    if (!line.empty() && line.front() == '[') {
      started = true;
      in_output = line == "[output]";
    }
    if (started && !in_output) content += line + "\n";
  }
  return hex16(fnv1a(content.data(), content.size()));
}

SweepManifest expand_sweep(const SweepDefinition& d) {
  check_run_count(d);
  SweepManifest m;
  m.definition = d;
  for (const SweptKey& k : d.vary) m.keys.push_back(k.key);
  read_load_case(d.base);  // the base case's own problems name the base case
  const DesignPoints points(d);
  const std::int64_t combinations = d.combinations();
  std::unordered_set<std::uint64_t> hashes;  // the hashes' values (a million strings would be ~100 MB)
  m.runs.reserve(static_cast<std::size_t>(std::min<std::int64_t>(combinations, std::int64_t{1} << 20)));
  for (std::int64_t p = 0; p < combinations; ++p) {
    // A stop requested while a big sweep is expanded ends it here, within a run's validation.
    if (const int signal = interruption_requested()) throw Interrupted(signal);
    SweepRun run;
    run.index = static_cast<int>(m.runs.size());
    run.values = points.values(p);
    LoadCase lc;
    try {
      lc = read_load_case(d.base, m.overrides(run));
    } catch (const InputError& e) {  // a combination's problem is the sweep file's
      std::string described;
      for (std::size_t j = 0; j < m.keys.size(); ++j) described += (j ? ", " : "") + m.keys[j] + " = " + run.values[j];
      throw InputError(d.file.string(), e.key(),
                       fmt::format("{} (in run {} of the sweep: {})", e.problem(), run.index, described));
    }
    run.hash = case_hash(lc);
    if (!hashes.insert(std::stoull(run.hash, nullptr, 16)).second) {  // the same case twice (rounded integers, a repeated value)
      ++m.merged_duplicates;
      continue;
    }
    m.runs.push_back(std::move(run));
  }
  m.runs.shrink_to_fit();
  return m;
}

std::vector<std::string> SweepManifest::overrides(const SweepRun& run) const {
  std::vector<std::string> all = definition.set;
  for (std::size_t j = 0; j < keys.size() && j < run.values.size(); ++j) all.push_back(keys[j] + "=" + run.values[j]);
  return all;
}

std::string SweepManifest::run_case(const SweepRun& run) const {
  if (!run.case_toml.empty()) return run.case_toml;
  const LoadCase lc = read_load_case(definition.base, overrides(run));
  if (const std::string hash = case_hash(lc); hash != run.hash)
    throw InputError(definition.base.string(), "",
                     fmt::format("no longer gives run {} of {} the case the sweep was expanded with (hash {}, not {}): "
                                 "was the base case changed meanwhile? Start the sweep again",
                                 run.index, definition.file.string(), hash, run.hash));
  return to_toml(lc);
}

std::string SweepManifest::to_json() const { return manifest_json(*this, false); }
std::string SweepManifest::to_json_with_cases() const { return manifest_json(*this, true); }

SweepManifest SweepManifest::from_json(const std::string& text, const std::string& source) {
  try {
    const nlohmann::json j = nlohmann::json::parse(text);
    const int format = j.at("indentsim_sweep").get<int>();
    if (format != 1 && format != 2) throw InputError(source, "indentsim_sweep", "is not format 1 or 2");
    SweepManifest m;
    m.definition.file = j.at("sweep").get<std::string>();
    m.definition.base = j.at("base").get<std::string>();
    m.definition.out = j.at("out").get<std::string>();
    m.definition.keep = j.at("keep").get<std::vector<std::string>>();
    if (format >= 2) m.definition.set = j.at("set").get<std::vector<std::string>>();
    m.keys = j.at("keys").get<std::vector<std::string>>();
    for (const auto& r : j.at("runs")) {
      SweepRun run;
      run.index = r.at("index").get<int>();
      run.hash = r.at("hash").get<std::string>();
      run.values = r.at("values").get<std::vector<std::string>>();
      if (format == 1) run.case_toml = r.at("case").get<std::string>();
      else if (r.contains("case")) run.case_toml = r.at("case").get<std::string>();
      if (run.values.size() != m.keys.size()) throw InputError(source, "runs", "a run's values do not match the keys");
      m.runs.push_back(std::move(run));
    }
    return m;
  } catch (const nlohmann::json::exception& e) {
    throw InputError(source, "manifest", fmt::format("is not a sweep manifest: {}", e.what()));
  }
}

std::pair<int, int> parse_shard(const std::string& text) {
  const auto slash = text.find('/');
  int i = 0, n = 0;
  try {
    std::size_t used_i = 0, used_n = 0;
    if (slash == std::string::npos) throw std::invalid_argument("no slash");
    i = std::stoi(text.substr(0, slash), &used_i);
    n = std::stoi(text.substr(slash + 1), &used_n);
    if (used_i != slash || used_n != text.size() - slash - 1) throw std::invalid_argument("trailing text");
  } catch (const std::exception&) {
    throw InputError("--shard", "--shard", fmt::format("must be i/N, e.g. 2/8 (got \"{}\")", text));
  }
  if (n < 1 || i < 1 || i > n)
    throw InputError("--shard", "--shard", fmt::format("must be i/N with 1 <= i <= N (got \"{}\")", text));
  return {i, n};
}

std::vector<const SweepRun*> shard_runs(const SweepManifest& manifest, int shard, int shards) {
  std::vector<const SweepRun*> runs;
  for (const SweepRun& r : manifest.runs)
    if (r.index % shards == shard - 1) runs.push_back(&r);
  return runs;
}
}  // namespace indentsim
