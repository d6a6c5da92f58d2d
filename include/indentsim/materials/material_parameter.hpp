#pragma once
// The material parameters a fit may identify, by their load-case keys: material.E, material.nu,
// material.e0 or material.yield_stress (the uniaxial yield stress users think in; e0 follows from
// it, e0 = sigma_y / (3 mu)), material.kappa (linear hardening), material.n (the power laws'
// exponent), material.K, .prestrain (Ludwik, Swift), material.Q, .b (Voce), and a rate-dependent J2's
// flow rule: material.reference_strain_rate (Perzyna), .creep_coefficient, .reference_stress
// (Norton), .rate_exponent (both).
// One place for their names, their values in a load case and their physically safe ranges.
#include <compare>
#include <cstddef>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "indentsim/input/load_case.hpp"

namespace indentsim {

enum class MaterialParameter {
  E, nu, e0, yield_stress, kappa, n, K, prestrain, Q, b,
  reference_strain_rate, creep_coefficient, reference_stress, rate_exponent  ///< the flow rule's (MODEL.md §13.3)
};

/// "material.E", ...
std::string key_of(MaterialParameter parameter);
/// The parameter of a key ("material.yield_stress"), or nullopt when the key is not a fittable one.
std::optional<MaterialParameter> parameter_of_key(const std::string& key);
/// Every fittable key, for messages.
std::string fittable_keys();
/// Why the parameter does not act in the material (an elastic model; another hardening law's
/// parameter, naming the law's own), or nullopt when it does.
std::optional<std::string> inapplicable(const MaterialInput& material, MaterialParameter parameter);

/// The parameter's value in a load case (yield_stress: given, or derived from e0).
double value_of(const MaterialInput& material, MaterialParameter parameter);
/// Sets the parameter, keeping the others as the load case states them: with yield_stress the
/// load case then carries sigma_y and e0 follows from it (also when E or nu change afterwards).
void set_value(MaterialInput& material, MaterialParameter parameter, double value);

/// A material parameter of one region of the specimen (docs/MODEL.md §14.5): region 0 is
/// [material] (the substrate of a coated specimen), region k the k-th [[layer]] from the surface.
struct RegionParameter {
  MaterialParameter which = MaterialParameter::E;
  std::size_t region = 0;
  friend auto operator<=>(const RegionParameter&, const RegionParameter&) = default;
};
/// "material.E", "layer.2.material.E": the key --free, --bounds, --set and fit.json name it by.
std::string key_of(const RegionParameter& parameter);
/// The parameter a key names ("material.n", "layer.1.material.yield_stress"), or nullopt when the
/// key is not a fittable one.
std::optional<RegionParameter> region_parameter_of_key(const std::string& key);
/// The parameter's value in the load case, and setting it (as value_of and set_value of its
/// region's material); the region must exist (RegionParameter::region <= layers.size()).
double value_of(const LoadCase& load_case, const RegionParameter& parameter);
void set_value(LoadCase& load_case, const RegionParameter& parameter, double value);

/// The open interval of values the model accepts: E > 0, -1 < nu < 0.5, e0 and sigma_y > 0,
/// kappa in [0, 1), n in (0, 1), the rates and the reference stress > 0, the rate exponent in
/// [1, 100].  A bound outside it is refused.
std::pair<double, double> physical_range(MaterialParameter parameter);
/// The closed interval of values a solid plausibly has: the magnitudes the key's declaration states
/// (plausible_magnitudes: E 1e3 to 2e12 Pa, sigma_y 1e5 to 3e10 Pa), else the physical range.  A
/// fit's bounds must lie within it (and within the key's declared interval).
std::pair<double, double> plausible_range(MaterialParameter parameter);
/// Default fit bounds around a start value: a factor 10 either way for E, e0 and sigma_y (within the
/// plausible range; e0 below 0.99), nu in [0, 0.49], kappa in [0, 0.99], n in [0.01, 0.9]; a factor
/// 10 for the rates and the reference stress, 3 for the rate exponent (within [1, 100]).
std::pair<double, double> default_bounds(MaterialParameter parameter, double start);

}  // namespace indentsim
