#include "indentsim/materials/material_parameter.hpp"

#include <algorithm>
#include <array>
#include <limits>

namespace indentsim {

namespace {

struct ParameterName {
  MaterialParameter parameter;
  const char* key;
};
constexpr std::array<ParameterName, 6> names{{{MaterialParameter::E, "material.E"},
                                              {MaterialParameter::nu, "material.nu"},
                                              {MaterialParameter::e0, "material.e0"},
                                              {MaterialParameter::yield_stress, "material.yield_stress"},
                                              {MaterialParameter::kappa, "material.kappa"},
                                              {MaterialParameter::n, "material.n"}}};

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

std::string fittable_keys() {
  std::string list;
  for (const auto& n : names) list += (list.empty() ? "" : ", ") + std::string(n.key);
  return list;
}

double value_of(const MaterialInput& m, MaterialParameter parameter) {
  switch (parameter) {
    case MaterialParameter::E: return m.E;
    case MaterialParameter::nu: return m.nu;
    case MaterialParameter::e0: return m.e0;
    case MaterialParameter::yield_stress: return m.yield_stress.value_or(yield_stress_of_e0(m.e0, m.E, m.nu));
    case MaterialParameter::kappa: return m.kappa;
    case MaterialParameter::n: return m.n;
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
  }
  if (m.yield_stress) m.e0 = e0_of_yield_stress(*m.yield_stress, m.E, m.nu);
}

std::pair<double, double> physical_range(MaterialParameter parameter) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  switch (parameter) {
    case MaterialParameter::E:
    case MaterialParameter::e0:
    case MaterialParameter::yield_stress: return {0.0, inf};
    case MaterialParameter::nu: return {-1.0, 0.5};
    case MaterialParameter::kappa: return {0.0, 1.0};
    case MaterialParameter::n: return {0.0, 1.0};
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
    case MaterialParameter::yield_stress: {
      const auto [low, high] = plausible_range(parameter);
      return {std::max(start / 10.0, low), std::min(start * 10.0, high)};
    }
    case MaterialParameter::e0: return {start / 10.0, std::min(start * 10.0, 0.99)};
    case MaterialParameter::nu: return {0.0, 0.49};
    case MaterialParameter::kappa: return {0.0, 0.99};
    case MaterialParameter::n: return {0.01, 0.9};
  }
  return {start / 10.0, start * 10.0};
}

}  // namespace indentsim
