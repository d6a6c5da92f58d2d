#pragma once
// Material laws.  Isotropic linear elasticity in plane strain (MODEL.md, "Material").
#include <Eigen/Core>

namespace indentsim {

/// Plane-strain constitutive matrix acting on (eps11, eps22, gamma12 = 2 eps12).
using PlaneStrainMatrix = Eigen::Matrix3d;

struct LameConstants {
  double lambda = 0.0;
  double mu = 0.0;
};

struct ElasticMaterial {
  double E = 0.0;
  double nu = 0.0;

  LameConstants lame() const;
  /// E* = E / (1 - nu^2), the plane-strain modulus of Hertz line contact.
  double plane_strain_modulus() const { return E / (1.0 - nu * nu); }
  PlaneStrainMatrix stiffness() const;
};

/// D for given Lamé constants: sigma = lambda tr(eps) I + 2 mu eps, eps33 = 0.
PlaneStrainMatrix plane_strain_stiffness(const LameConstants& lame);

}  // namespace indentsim
