// The paper's closed-form local stiffness matrix against 2x2 Gauss quadrature.
#include <random>

#include <gtest/gtest.h>

#include "indentsim/geometry/element.hpp"
#include "indentsim/geometry/kinematics.hpp"
#include "indentsim/materials/material.hpp"

using namespace indentsim;

TEST(Element, ClosedFormEqualsGaussOnRandomRectanglesAndMaterials) {
  std::mt19937 rng(12345);
  std::uniform_real_distribution<double> log_size(-6.0, -1.0), log_modulus(6.0, 12.0), poisson(-0.9, 0.499);
  for (int trial = 0; trial < 500; ++trial) {
    const Rectangle rect{std::pow(10.0, log_size(rng)), std::pow(10.0, log_size(rng))};
    const ElasticMaterial material{std::pow(10.0, log_modulus(rng)), poisson(rng)};
    const ElementMatrix closed = closed_form_stiffness(rect, material.lame());
    const ElementMatrix gauss = PlaneStrain().stiffness(rect, material.stiffness(), ElementKind::q1);
    const double scale = gauss.cwiseAbs().maxCoeff();
    EXPECT_LE((closed - gauss).cwiseAbs().maxCoeff(), 1e-12 * scale)
        << "h = " << rect.width << ", tau = " << rect.height << ", nu = " << material.nu;
  }
}

TEST(Element, StiffnessIsSymmetricWithRigidBodyModesInItsKernel) {
  const Rectangle rect{2e-4, 5e-5};
  const ElementMatrix k = closed_form_stiffness(rect, ElasticMaterial{210e9, 0.3}.lame());
  EXPECT_LE((k - k.transpose()).cwiseAbs().maxCoeff(), 1e-15 * k.cwiseAbs().maxCoeff());
  // Vertices (paper order): 1 = (0,0), 2 = (0,tau), 3 = (h,0), 4 = (h,tau).
  const double xs[4] = {0, 0, rect.width, rect.width}, ys[4] = {0, rect.height, 0, rect.height};
  ElementVector translation_x = ElementVector::Zero(), translation_y = ElementVector::Zero(), rotation;
  for (int q = 0; q < 4; ++q) {
    translation_x[u_index(q + 1)] = 1.0;
    translation_y[v_index(q + 1)] = 1.0;
    rotation[u_index(q + 1)] = -ys[q];
    rotation[v_index(q + 1)] = xs[q];
  }
  const double scale = k.cwiseAbs().maxCoeff();
  EXPECT_LE((k * translation_x).cwiseAbs().maxCoeff(), 1e-13 * scale);
  EXPECT_LE((k * translation_y).cwiseAbs().maxCoeff(), 1e-13 * scale);
  EXPECT_LE((k * rotation).cwiseAbs().maxCoeff(), 1e-13 * scale * rect.width);
}

TEST(Element, PaperTypoInA22IsNotReproduced) {
  // The paper prints A22(4,4) = mu tau/(6h) - (lambda+2mu) h/(3 tau); the rectangle's symmetry
  // (its four vertices are equivalent) requires mu tau/(3h) + (lambda+2mu) h/(3 tau), like the
  // other diagonal entries of the block.
  const Rectangle rect{1.0, 2.0};
  const LameConstants lame{3.0, 1.0};
  const ElementMatrix k = closed_form_stiffness(rect, lame);
  const double expected = lame.mu * rect.height / (3 * rect.width) +
                          (lame.lambda + 2 * lame.mu) * rect.width / (3 * rect.height);
  EXPECT_DOUBLE_EQ(k(v_index(4), v_index(4)), expected);
  EXPECT_DOUBLE_EQ(k(v_index(4), v_index(4)), k(v_index(1), v_index(1)));
}

TEST(Element, BbarIsSymmetricKeepsRigidBodyModesAndAgreesOnUniformDilatation) {
  const Rectangle rect{3e-4, 1e-4};
  const ElasticMaterial material{210e9, 0.4999};
  const PlaneStrain plane;
  const ElementMatrix k = plane.stiffness(rect, material.stiffness(), ElementKind::bbar);
  const double scale = k.cwiseAbs().maxCoeff();
  EXPECT_LE((k - k.transpose()).cwiseAbs().maxCoeff(), 1e-13 * scale);
  const double xs[4] = {0, 0, rect.width, rect.width}, ys[4] = {0, rect.height, 0, rect.height};
  ElementVector tx = ElementVector::Zero(), ty = ElementVector::Zero(), rotation, stretch;
  for (int q = 0; q < 4; ++q) {
    tx[u_index(q + 1)] = 1.0;
    ty[v_index(q + 1)] = 1.0;
    rotation[u_index(q + 1)] = -ys[q];
    rotation[v_index(q + 1)] = xs[q];
    stretch[u_index(q + 1)] = 0.7 * xs[q];  // a uniform strain field
    stretch[v_index(q + 1)] = -0.2 * ys[q] + 0.1 * xs[q];
  }
  EXPECT_LE((k * tx).cwiseAbs().maxCoeff(), 1e-12 * scale);
  EXPECT_LE((k * ty).cwiseAbs().maxCoeff(), 1e-12 * scale);
  EXPECT_LE((k * rotation).cwiseAbs().maxCoeff(), 1e-12 * scale * rect.width);
  // For a uniform strain the dilatation equals its mean: B-bar and B give the same strain.
  for (const auto& p : gauss_points_2x2()) {
    const VoigtVector plain = plane.strain_displacement(rect, p.xi, p.eta, ElementKind::q1) * stretch;
    const VoigtVector bar = plane.strain_displacement(rect, p.xi, p.eta, ElementKind::bbar) * stretch;
    EXPECT_LE((plain - bar).norm(), 1e-14 * plain.norm());
  }
}

// An element pass asks for the four Gauss points' B at once (B-bar's mean formed once): it must be
// the pointwise B of each point, for both kinematics, both elements, and rings far from and next
// to the axis.
TEST(Kinematics, TheFourPointsAtOnceArePointwiseB) {
  const PlaneStrain plane;
  const Axisymmetric axisymmetric;
  for (const Kinematics* kinematics : {static_cast<const Kinematics*>(&plane), static_cast<const Kinematics*>(&axisymmetric)})
    for (ElementKind kind : {ElementKind::q1, ElementKind::bbar})
      for (const Rectangle& rect : {Rectangle{1e-4, 2e-4, 0.0}, Rectangle{5e-4, 1e-4, 3e-3}}) {
        const std::array<StrainDisplacement, 4> at_once = kinematics->gauss_point_strain_displacements(rect, kind);
        const auto& points = gauss_points_2x2();
        for (std::size_t g = 0; g < points.size(); ++g) {
          const StrainDisplacement b = kinematics->strain_displacement(rect, points[g].xi, points[g].eta, kind);
          EXPECT_LE((at_once[g] - b).cwiseAbs().maxCoeff(), 1e-12 * b.cwiseAbs().maxCoeff())
              << kinematics->name() << " point " << g;
        }
      }
}
