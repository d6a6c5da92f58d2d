#pragma once
// The analysis of coated specimens (docs/MODEL.md §14.4): how much of an indentation's apparent
// modulus is the film's, and the film's modulus from the apparent one.
//
// Gao, Chiu and Lee (Int. J. Solids Struct. 29, 1992) perturbed a homogeneous half-space to first
// order in the film-substrate mismatch: a rigid flat punch of radius a on a film of thickness t
// feels a half-space of shear modulus and Poisson's ratio
//   mu = mu_s + (mu_f - mu_s) I0(t/a),   nu = nu_s + (nu_f - nu_s) I1(t/a),
//   I0(x) = (2/pi) atan x + [(1 - 2 nu) x ln((1 + x^2)/x^2) - x/(1 + x^2)] / (2 pi (1 - nu)),
//   I1(x) = (2/pi) atan x + (x/pi) ln((1 + x^2)/x^2),
// with the contact modulus E* = 2 mu / (1 - nu).  Checked against indentsim's own flat punches
// (tests/test_layers.cpp): d E*/d E_f at E_f = E_s is I0 to 1-2% for t/a from 0.25 to 4.
// Applied, as usual (Chen and Vlassak, J. Mater. Res. 16, 2001), at the Oliver-Pharr contact
// radius of any indenter and beyond the first order, where it is an approximation whose error
// the simulation, which knows the film's modulus, shows beside it.
#include <optional>

#include "indentsim/input/load_case.hpp"

namespace indentsim {

/// A coated specimen's top film and what lies under it, as a run knows them.
struct CoatingContext {
  double thickness = 0.0;                 ///< the top film's t [m]
  double film_E = 0.0, film_nu = 0.0;     ///< its true elastic constants
  double substrate_E = 0.0, substrate_nu = 0.0;  ///< of the region under it (the next layer or the substrate)
};
/// The coating of a load case, or none for a homogeneous specimen.
std::optional<CoatingContext> coating_of(const LoadCase& load_case);

/// Gao's weights I0 and I1 at x = t / a, with `nu` the Poisson's ratio in I0 (the substrate's:
/// the perturbation's zeroth order).
struct GaoWeights {
  double I0 = 0.0, I1 = 0.0;
};
GaoWeights gao_weights(double thickness_over_radius, double nu);

/// The contact modulus E* = E / (1 - nu^2) of a film (E_f, nu_f, thickness t) on a substrate
/// (E_s, nu_s) under a contact of radius a, by Gao's model.
double gao_contact_modulus(double film_E, double film_nu, double substrate_E, double substrate_nu,
                           double thickness_over_radius);

/// The film's Young's modulus that gives the apparent contact modulus `contact_modulus` by Gao's
/// model, the substrate and the film's nu known; none where the film's share I0 is below 1e-3 (the
/// substrate alone answers) or the inversion gives no positive modulus.
std::optional<double> gao_film_modulus(double contact_modulus, double film_nu, double substrate_E,
                                       double substrate_nu, double thickness_over_radius);

}  // namespace indentsim
