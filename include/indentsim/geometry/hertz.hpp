#pragma once
// Hertz line contact of a rigid cylinder on an elastic half-plane (docs/MODEL.md §8, "Reference
// results"), and the estimate of the final contact half-width used to size the mesh.

namespace indentsim::hertz {

/// P = pi E* a^2 / (4 R): total force per unit thickness for half-width a [N/m].
double force(double half_width, double radius, double plane_strain_modulus);
/// a = sqrt(4 P R / (pi E*)).
double half_width(double force, double radius, double plane_strain_modulus);
/// p(x) = p0 sqrt(1 - x^2/a^2), p0 = 2P/(pi a); zero outside the contact.
double pressure(double x, double half_width, double force);

/// Estimate of the contact half-width reached at depth alpha on a block of depth `depth`
/// clamped at its base.  Hertz's P(a) combined with the approach of a point at depth d
/// under a Hertz pressure (Johnson, Contact Mechanics, section 5.6):
///   alpha = 2P/(pi E*) [ln(2d/a) - nu/(2(1-nu))],
/// capped by the geometric chord sqrt(2 R alpha - alpha^2).  Only sizes the mesh: the run
/// computes the real contact zone and warns when it leaves the fine zone.
double estimate_half_width(double alpha, double radius, double depth, double nu);

}  // namespace indentsim::hertz
