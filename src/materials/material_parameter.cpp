#include "indentsim/materials/material_parameter.hpp"

#include <algorithm>
#include <array>
#include <limits>
#include <regex>
#include <stdexcept>

#include <fmt/format.h>

namespace indentsim {

namespace {

struct ParameterName {
  MaterialParameter parameter;
  const char* key;
};
constexpr std::array<ParameterName, 14> names{{{MaterialParameter::E, "material.E"},
                                               {MaterialParameter::nu, "material.nu"},
                                               {MaterialParameter::e0, "material.e0"},
                                               {MaterialParameter::yield_stress, "material.yield_stress"},
                                               {MaterialParameter::kappa, "material.kappa"},
                                               {MaterialParameter::n, "material.n"},
                                               {MaterialParameter::K, "material.K"},
                                               {MaterialParameter::prestrain, "material.prestrain"},
                                               {MaterialParameter::Q, "material.Q"},
                                               {MaterialParameter::b, "material.b"},
                                               {MaterialParameter::reference_strain_rate, "material.reference_strain_rate"},
                                               {MaterialParameter::creep_coefficient, "material.creep_coefficient"},
                                               {MaterialParameter::reference_stress, "material.reference_stress"},
                                               {MaterialParameter::rate_exponent, "material.rate_exponent"}}};

/// The hardening parameters each law has (besides E and nu).
std::vector<MaterialParameter> law_parameters(HardeningLaw law) {
  using P = MaterialParameter;
  switch (law) {
    case HardeningLaw::linear: return {P::e0, P::yield_stress, P::kappa};
    case HardeningLaw::power: return {P::e0, P::yield_stress, P::n};
    case HardeningLaw::power_law: return {P::e0, P::yield_stress, P::n};
    case HardeningLaw::ludwik: return {P::e0, P::yield_stress, P::K, P::n};
    case HardeningLaw::swift: return {P::K, P::prestrain, P::n};
    case HardeningLaw::voce: return {P::e0, P::yield_stress, P::Q, P::b};
    case HardeningLaw::table: return {};
  }
  return {};
}

/// The flow rule's own parameters (docs/MODEL.md §13.3).
std::vector<MaterialParameter> rate_parameters(RateLaw rate) {
  using P = MaterialParameter;
  switch (rate) {
    case RateLaw::none: return {};
    case RateLaw::perzyna: return {P::reference_strain_rate, P::rate_exponent};
    case RateLaw::norton: return {P::creep_coefficient, P::reference_stress, P::rate_exponent};
  }
  return {};
}

bool is_rate_parameter(MaterialParameter p) {
  using P = MaterialParameter;
  return p == P::reference_strain_rate || p == P::creep_coefficient || p == P::reference_stress || p == P::rate_exponent;
}

std::string listed(const std::vector<MaterialParameter>& parameters) {
  std::string list;
  for (const MaterialParameter p : parameters) list += (list.empty() ? "" : ", ") + key_of(p);
  return list;
}

}  // namespace

std::string key_of(MaterialParameter parameter) {
  for (const auto& n : names)
    if (n.parameter == parameter) return n.key;
  return "material.?";
}

std::optional<MaterialParameter> parameter_of_key(const std::string& key) {
  for (const auto& n : names)
    if (key == n.key) return n.parameter;
  return std::nullopt;
}

std::string key_of(const RegionParameter& parameter) {
  const std::string key = key_of(parameter.which);
  return parameter.region == 0 ? key : fmt::format("layer.{}.{}", parameter.region, key);
}

std::optional<RegionParameter> region_parameter_of_key(const std::string& key) {
  // layer.K.material.NAME: K a positive integer without sign or leading zero.
  static const std::regex layer_key(R"(^layer\.([1-9][0-9]{0,5})\.(material\..+)$)");
  std::smatch m;
  if (!std::regex_match(key, m, layer_key)) {
    const auto p = parameter_of_key(key);
    if (!p) return std::nullopt;
    return RegionParameter{*p, 0};
  }
  const auto p = parameter_of_key(m.str(2));
  if (!p) return std::nullopt;
  return RegionParameter{*p, static_cast<std::size_t>(std::stoul(m.str(1)))};
}

static MaterialInput& material_of(LoadCase& lc, std::size_t region) {
  if (region > lc.layers.size()) throw std::out_of_range("a parameter of a layer the load case does not have");
  return region == 0 ? lc.material : lc.layers[region - 1].material;
}

double value_of(const LoadCase& lc, const RegionParameter& parameter) {
  if (parameter.region > lc.layers.size()) throw std::out_of_range("a parameter of a layer the load case does not have");
  return value_of(lc.region_material(parameter.region), parameter.which);
}

void set_value(LoadCase& lc, const RegionParameter& parameter, double value) {
  set_value(material_of(lc, parameter.region), parameter.which, value);
}

std::string fittable_keys() {
  std::string list;
  for (const auto& n : names) list += (list.empty() ? "" : ", ") + std::string(n.key);
  return list + "; a coated specimen's layer K: layer.K.material.E, ... (docs/MODEL.md §14.5)";
}

double value_of(const MaterialInput& m, MaterialParameter parameter) {
  switch (parameter) {
    case MaterialParameter::E: return m.E;
    case MaterialParameter::nu: return m.nu;
    case MaterialParameter::e0: return m.e0;
    case MaterialParameter::yield_stress: return m.yield_stress.value_or(yield_stress_of_e0(m.e0, m.E, m.nu));
    case MaterialParameter::kappa: return m.kappa;
    case MaterialParameter::n: return m.n;
    case MaterialParameter::K: return m.K.value_or(0.0);
    case MaterialParameter::prestrain: return m.prestrain.value_or(0.0);
    case MaterialParameter::Q: return m.Q.value_or(0.0);
    case MaterialParameter::b: return m.b.value_or(0.0);
    case MaterialParameter::reference_strain_rate: return m.reference_strain_rate.value_or(0.0);
    case MaterialParameter::creep_coefficient: return m.creep_coefficient.value_or(0.0);
    case MaterialParameter::reference_stress: return m.reference_stress.value_or(0.0);
    case MaterialParameter::rate_exponent: return m.rate_exponent.value_or(0.0);
  }
  return 0.0;
}

void set_value(MaterialInput& m, MaterialParameter parameter, double value) {
  switch (parameter) {
    case MaterialParameter::E: m.E = value; break;
    case MaterialParameter::nu: m.nu = value; break;
    case MaterialParameter::e0:
      m.e0 = value;
      m.yield_stress.reset();
      break;
    case MaterialParameter::yield_stress: m.yield_stress = value; break;
    case MaterialParameter::kappa: m.kappa = value; break;
    case MaterialParameter::n: m.n = value; break;
    case MaterialParameter::K: m.K = value; break;
    case MaterialParameter::prestrain: m.prestrain = value; break;
    case MaterialParameter::Q: m.Q = value; break;
    case MaterialParameter::b: m.b = value; break;
    case MaterialParameter::reference_strain_rate: m.reference_strain_rate = value; break;
    case MaterialParameter::creep_coefficient: m.creep_coefficient = value; break;
    case MaterialParameter::reference_stress: m.reference_stress = value; break;
    case MaterialParameter::rate_exponent: m.rate_exponent = value; break;
  }
  if (m.yield_stress) m.e0 = e0_of_yield_stress(*m.yield_stress, m.E, m.nu);
}

std::optional<std::string> inapplicable(const MaterialInput& m, MaterialParameter parameter) {
  if (parameter == MaterialParameter::E || parameter == MaterialParameter::nu) return std::nullopt;
  if (m.model == MaterialModel::elastic) return "has no effect: material.model is \"elastic\"";
  if (is_rate_parameter(parameter)) {
    const std::vector<MaterialParameter> own = rate_parameters(m.rate);
    if (std::find(own.begin(), own.end(), parameter) != own.end()) return std::nullopt;
    return own.empty() ? std::string("has no effect: the case's material is rate-independent (no material.rate)")
                       : fmt::format("does not belong to this case's material.rate = \"{}\" (its parameters: {})",
                                     to_string(m.rate), listed(own));
  }
  // Norton's creep has no yield surface and no hardening (validation.cpp refuses their keys).
  if (m.rate == RateLaw::norton)
    return fmt::format("has no effect under material.rate = \"norton\", which has no yield surface (its parameters: {})",
                       listed(rate_parameters(m.rate)));
  const std::vector<MaterialParameter> own = law_parameters(m.hardening);
  if (std::find(own.begin(), own.end(), parameter) != own.end()) return std::nullopt;
  return fmt::format("does not belong to this case's material.hardening = \"{}\" ({})", to_string(m.hardening),
                     own.empty() ? "a table's points are not fitted: fit a law's parameters instead"
                                 : "its parameters: " + listed(own));
}

std::pair<double, double> physical_range(MaterialParameter parameter) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  switch (parameter) {
    case MaterialParameter::E:
    case MaterialParameter::e0:
    case MaterialParameter::yield_stress:
    case MaterialParameter::K:
    case MaterialParameter::Q:
    case MaterialParameter::b:
    case MaterialParameter::reference_strain_rate:
    case MaterialParameter::creep_coefficient:
    case MaterialParameter::reference_stress: return {0.0, inf};
    case MaterialParameter::rate_exponent: return {1.0, 100.0};
    case MaterialParameter::nu: return {-1.0, 0.5};
    case MaterialParameter::kappa: return {0.0, 1.0};
    case MaterialParameter::n:
    case MaterialParameter::prestrain: return {0.0, 1.0};
  }
  return {0.0, inf};
}

std::pair<double, double> plausible_range(MaterialParameter parameter) {
  if (const auto p = plausible_magnitudes(key_of(parameter))) return {p->low, p->high};
  return physical_range(parameter);
}

std::pair<double, double> default_bounds(MaterialParameter parameter, double start) {
  switch (parameter) {
    case MaterialParameter::E:
    case MaterialParameter::yield_stress:
    case MaterialParameter::K:
    case MaterialParameter::reference_strain_rate:
    case MaterialParameter::creep_coefficient:
    case MaterialParameter::reference_stress: {
      const auto [low, high] = plausible_range(parameter);
      return {std::max(start / 10.0, low), std::min(start * 10.0, high)};
    }
    case MaterialParameter::e0:
    case MaterialParameter::prestrain: return {start / 10.0, std::min(start * 10.0, 0.99)};
    case MaterialParameter::Q:
    case MaterialParameter::b: return {start / 10.0, start * 10.0};
    case MaterialParameter::rate_exponent: return {std::max(1.0, start / 3.0), std::min(100.0, start * 3.0)};
    case MaterialParameter::nu: return {0.0, 0.49};
    case MaterialParameter::kappa: return {0.0, 0.99};
    case MaterialParameter::n: return {0.01, 0.9};
  }
  return {start / 10.0, start * 10.0};
}

}  // namespace indentsim
