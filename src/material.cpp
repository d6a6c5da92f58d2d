#include "indentsim/material.hpp"

namespace indentsim {

LameConstants ElasticMaterial::lame() const {
  return {E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), E / (2.0 * (1.0 + nu))};
}

PlaneStrainMatrix ElasticMaterial::stiffness() const { return plane_strain_stiffness(lame()); }

PlaneStrainMatrix plane_strain_stiffness(const LameConstants& l) {
  PlaneStrainMatrix d;
  d << l.lambda + 2.0 * l.mu, l.lambda, 0.0,  //
      l.lambda, l.lambda + 2.0 * l.mu, 0.0,   //
      0.0, 0.0, l.mu;
  return d;
}

}  // namespace indentsim
