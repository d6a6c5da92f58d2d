// Finite-strain kinematics at a point (docs/MODEL.md §12): the logarithmic strain of stretches,
// rotations and their products, its derivative and the nominal tangent against central
// differences, the small-strain limit, and J2 in the multiplicative split under a finite
// uniaxial stretch (the log-strain form of each hardening law, plastic flow isochoric).
#include <cmath>
#include <memory>
#include <random>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <gtest/gtest.h>

#include "indentsim/materials/finite_strain.hpp"
#include "indentsim/materials/finite_strain_law.hpp"
#include "indentsim/materials/hardening.hpp"

using namespace indentsim;

namespace {

const ElasticMaterial steel{200e9, 0.3};

DeformationGradient gradient(double f11, double f12, double f21, double f22, double f33) {
  return (DeformationGradient() << f11, f12, f21, f22, f33).finished();
}
/// R(theta) U: a rotation of the in-plane stretch (u1, u2) and the out-of-plane stretch u3.
DeformationGradient rotated_stretch(double theta, double u1, double u2, double u3) {
  const double c = std::cos(theta), s = std::sin(theta);
  return gradient(c * u1, -s * u2, s * u1, c * u2, u3);
}
/// A random gradient within `size` of the identity, in-plane determinant positive.
DeformationGradient random_gradient(std::mt19937& rng, double size) {
  std::uniform_real_distribution<double> c(-size, size);
  return gradient(1 + c(rng), c(rng), c(rng), 1 + c(rng), 1 + 0.5 * c(rng));
}

/// Central differences of a function of F, column by column.
template <int Rows, class Of>
Eigen::Matrix<double, Rows, 5> finite_differences(const Of& of, const DeformationGradient& F, double step = 1e-7) {
  Eigen::Matrix<double, Rows, 5> fd;
  for (int k = 0; k < 5; ++k) {
    DeformationGradient plus = F, minus = F;
    plus[k] += step;
    minus[k] -= step;
    fd.col(k) = (of(plus) - of(minus)) / (2 * step);
  }
  return fd;
}

/// Both readings of the elastic law's D : e at large strain (docs/MODEL.md §12.2).
constexpr ElasticStressMeasure measures[] = {ElasticStressMeasure::cauchy, ElasticStressMeasure::kirchhoff};
std::string name_of(ElasticStressMeasure m) { return m == ElasticStressMeasure::cauchy ? "cauchy" : "kirchhoff"; }

std::unique_ptr<FiniteStrainPointLaw> hencky_elastic(ElasticStressMeasure m = ElasticStressMeasure::cauchy) {
  return std::make_unique<HenckyPointLaw>(steel, nullptr, m);
}
std::unique_ptr<FiniteStrainPointLaw> hencky_ilyushin(ElasticStressMeasure m = ElasticStressMeasure::cauchy) {
  return std::make_unique<HenckyPointLaw>(
      steel, std::make_unique<IlyushinPointLaw>(IlyushinLaw(steel, 0.003, HardeningLaw::power, 0.9, 0.2), false, 1), m);
}
std::unique_ptr<J2LogStrainPointLaw> j2_log(double n = 0.2, ElasticStressMeasure m = ElasticStressMeasure::cauchy,
                                            std::size_t points = 1) {
  return std::make_unique<J2LogStrainPointLaw>(J2Law(steel, std::make_shared<PowerLawHardening>(400e6, steel.E, n)),
                                               points, m);
}

}  // namespace

TEST(FiniteStrain, TheLogarithmicStrainOfAStretchIsTheLogOfItsStretches) {
  for (const auto& [u1, u2, u3] : {std::array{1.0, 1.0, 1.0}, std::array{1.5, 0.7, 1.0}, std::array{2.0, 2.0, 0.5},
                                   std::array{0.3, 1.0, 1.2}, std::array{1.0 + 1e-9, 1.0, 1.0}}) {
    const VoigtVector e = logarithmic_strain(gradient(u1, 0, 0, u2, u3), identity_tensor()).strain;
    EXPECT_NEAR(e[0], std::log(u1), 1e-15);
    EXPECT_NEAR(e[1], std::log(u2), 1e-15);
    EXPECT_NEAR(e[2], 0.0, 1e-15);
    EXPECT_NEAR(e[3], std::log(u3), 1e-15);
  }
}

TEST(FiniteStrain, ARigidRotationStrainsAndStressesNothing) {
  for (const double theta : {1e-3, 0.5, std::acos(-1.0) / 2, 2.5})
    for (const ElasticStressMeasure m : measures) {
      SCOPED_TRACE(fmt::format("{} {}", theta, name_of(m)));
      const DeformationGradient R = rotated_stretch(theta, 1, 1, 1);
      EXPECT_LE(logarithmic_strain(R, identity_tensor()).strain.norm(), 1e-15);
      EXPECT_LE(hencky_elastic(m)->respond(0, R).nominal.norm(), 1e-15 * steel.E);
      EXPECT_LE(hencky_ilyushin(m)->respond(0, R).nominal.norm(), 1e-15 * steel.E);
      EXPECT_LE(j2_log(0.2, m)->respond(0, R).nominal.norm(), 1e-15 * steel.E);
    }
}

TEST(FiniteStrain, ARotatedStretchHasTheRotatedStrainAndStress) {
  // Objectivity: e(R U) = R ln(U) R^T and tau(R U) = R tau(U) R^T, here for a plastic J2 point.
  const double theta = 0.7, c = std::cos(theta), s = std::sin(theta);
  const auto rotate = [&](const VoigtVector& t, bool engineering) {
    const double t12 = engineering ? 0.5 * t[2] : t[2];
    const double a = c * c * t[0] - 2 * c * s * t12 + s * s * t[1];
    const double d = s * s * t[0] + 2 * c * s * t12 + c * c * t[1];
    const double b = c * s * (t[0] - t[1]) + (c * c - s * s) * t12;
    return VoigtVector(a, d, engineering ? 2 * b : b, t[3]);
  };
  const DeformationGradient U = gradient(1.3, 0, 0, 0.8, 1.0), RU = rotated_stretch(theta, 1.3, 0.8, 1.0);
  const VoigtVector e_u = logarithmic_strain(U, identity_tensor()).strain;
  EXPECT_LE((logarithmic_strain(RU, identity_tensor()).strain - rotate(e_u, true)).norm(), 1e-14);
  for (const ElasticStressMeasure m : measures) {
    SCOPED_TRACE(name_of(m));
    const auto law = j2_log(0.2, m);
    const FiniteStrainResponse stretched = law->respond(0, U), turned = law->respond(0, RU);
    EXPECT_TRUE(stretched.plastic);
    EXPECT_LE((turned.kirchhoff - rotate(stretched.kirchhoff, false)).norm(), 1e-12 * stretched.kirchhoff.norm());
  }
}

TEST(FiniteStrain, TheLogarithmicStrainsDerivativeMatchesCentralDifferences) {
  std::mt19937 rng(13);
  std::vector<std::pair<DeformationGradient, SymmetricTensor>> cases{
      {identity_deformation(), identity_tensor()},                  // equal eigenvalues
      {gradient(1.2, 0, 0, 1.2, 1.0), identity_tensor()},           // equal, stretched
      {gradient(1.0, 1e-6, 0, 1.0, 1.0), identity_tensor()},        // nearly equal
      {gradient(1.0, 0.8, 0, 1.0, 1.3), SymmetricTensor(1.1, 0.9, 0.05, 1.0 / 0.99)}};  // simple shear, a history
  for (int k = 0; k < 20; ++k) cases.emplace_back(random_gradient(rng, k < 10 ? 0.05 : 0.6), identity_tensor());
  for (const auto& [F, G] : cases) {
    const LogarithmicStrain e = logarithmic_strain(F, G);
    const auto fd = finite_differences<4>([&](const DeformationGradient& f) { return logarithmic_strain(f, G).strain; }, F);
    EXPECT_LE((e.derivative - fd).cwiseAbs().maxCoeff(), 1e-7) << "F = " << F.transpose() << "\n" << e.derivative << "\n" << fd;
  }
}

TEST(FiniteStrain, TheNominalTangentMatchesCentralDifferencesForEachLaw) {
  std::mt19937 rng(17);
  for (int trial = 0; trial < 20; ++trial) {
    const DeformationGradient F = random_gradient(rng, trial < 10 ? 0.01 : 0.3);
    std::vector<std::pair<std::string, std::unique_ptr<FiniteStrainPointLaw>>> laws;
    const DeformationGradient history = random_gradient(rng, 0.2);
    for (const ElasticStressMeasure m : measures) {
      laws.emplace_back("hencky elastic " + name_of(m), hencky_elastic(m));
      laws.emplace_back("hencky ilyushin " + name_of(m), hencky_ilyushin(m));
      // J2 from a plastic history (a first stretch committed), then another gradient.
      auto j2 = j2_log(0.2, m);
      j2->commit(0, history);
      laws.emplace_back("j2 log strain " + name_of(m), std::move(j2));
    }
    for (const auto& [name, law] : laws) {
      SCOPED_TRACE(name);
      const FiniteStrainResponse r = law->respond(0, F);
      const auto fd = finite_differences<5>([&](const DeformationGradient& f) { return law->respond(0, f).nominal; }, F);
      const double scale = r.tangent.cwiseAbs().maxCoeff();
      EXPECT_LE((r.tangent - fd).cwiseAbs().maxCoeff(), 1e-6 * scale)
          << "F = " << F.transpose() << " plastic " << r.plastic << "\n" << r.tangent << "\n" << fd;
    }
  }
}

TEST(FiniteStrain, SmallDeformationsGiveTheSmallStrainStress) {
  // F = I + t H: P = sigma(sym H t) + O(t^2), so the relative difference falls as t.
  const Eigen::Matrix<double, 5, 1> h = (Eigen::Matrix<double, 5, 1>() << 0.3, -0.5, 0.2, -0.4, 0.1).finished();
  const ConstitutiveMatrix d = steel.stiffness();
  for (const ElasticStressMeasure m : measures) {
    SCOPED_TRACE(name_of(m));
    double previous = 1.0;
    for (const double t : {1e-3, 1e-4, 1e-5}) {
      const DeformationGradient F = identity_deformation() + t * h;
      const VoigtVector small_strain(t * h[0], t * h[3], t * (h[1] + h[2]), t * h[4]);
      const VoigtVector sigma = d * small_strain;
      const NominalStress p = hencky_elastic(m)->respond(0, F).nominal;
      // P's 12 and 21 both tend to sigma12.
      const Eigen::Matrix<double, 5, 1> expected =
          (Eigen::Matrix<double, 5, 1>() << sigma[0], sigma[2], sigma[2], sigma[1], sigma[3]).finished();
      const double relative = (p - expected).norm() / expected.norm();
      EXPECT_LE(relative, 3.0 * t);
      EXPECT_LT(relative, 0.2 * previous);
      previous = relative;
    }
  }
}

TEST(FiniteStrain, J2UnderAFiniteUniaxialStretchFollowsItsFlowCurveInLogStrain) {
  // Uniaxial stress along 2 (P11 = P33 = 0 by lateral stretches): the log strain is additive,
  // ln(stretch) = s / E + eps_p, and s = sigma_y(eps_p), to 1e-10, up to a stretch of 2, with s
  // the measure's stress: the Cauchy stress tau / J or the Kirchhoff stress tau.  The exponential
  // map keeps det C_p = 1.
  for (const ElasticStressMeasure m : measures)
    for (const double n : {0.0, 0.2}) {
      SCOPED_TRACE(fmt::format("{} n = {}", name_of(m), n));
      const auto law = j2_log(n, m);
      const PowerLawHardening curve(400e6, steel.E, n);
      double lateral = 1.0;
      int plastic_steps = 0;
      for (int step = 1; step <= 40; ++step) {
        const double stretch = std::exp(std::log(2.0) * step / 40.0);
        FiniteStrainResponse r;
        for (int iteration = 0; iteration < 50; ++iteration) {
          const DeformationGradient F = gradient(lateral, 0, 0, stretch, lateral);
          r = law->respond(0, F);
          if (std::abs(r.nominal[0]) <= 1e-12 * std::abs(r.nominal[3])) break;
          lateral -= r.nominal[0] / (r.tangent(0, 0) + r.tangent(0, 4));  // P11 = P33 by symmetry
        }
        const DeformationGradient F = gradient(lateral, 0, 0, stretch, lateral);
        law->commit(0, F);
        const double eps_p = law->state(0).equivalent_plastic_strain;
        const double J = lateral * lateral * stretch;
        const double s = m == ElasticStressMeasure::cauchy ? r.kirchhoff[1] / J : r.kirchhoff[1];
        if (eps_p == 0.0) continue;
        ++plastic_steps;
        EXPECT_NEAR(s, curve.flow_stress(eps_p), 1e-10 * s) << "step " << step;
        EXPECT_NEAR(std::log(stretch), s / steel.E + eps_p, 1e-10) << "step " << step;
        const SymmetricTensor& g = law->state(0).inverse_plastic_metric;
        EXPECT_NEAR((g[0] * g[1] - g[2] * g[2]) * g[3], 1.0, 1e-12);
      }
      EXPECT_GE(plastic_steps, 35);
    }
}

TEST(FiniteStrain, TheElasticLawSetsTheCauchyOrTheKirchhoffStressToDTimesTheLogStrain) {
  // Homogeneous gradients (stretches, shears, rotations, compression to J = 0.6): the Cauchy
  // stress sigma = P F^T / J recovered from the nominal stress is D e ("cauchy", Abaqus's) or
  // D e / J ("kirchhoff", Hencky's hyperelastic law), e the Hencky strain.  Below yield J2 is the
  // same elastic law.
  std::mt19937 rng(31);
  std::vector<DeformationGradient> cases{gradient(1.3, 0, 0, 0.8, 1.0), gradient(1, 0.5, 0, 1, 1),
                                         rotated_stretch(0.6, 0.85, 0.8, 0.88), gradient(0.9, 0.2, -0.1, 1.1, 0.95)};
  for (int k = 0; k < 6; ++k) cases.push_back(random_gradient(rng, 0.3));
  const ElasticMaterial soft{200e9, 0.3};
  const auto j2_elastic = [&](ElasticStressMeasure m) {  // yields at 1e3 E: elastic throughout
    return std::make_unique<J2LogStrainPointLaw>(J2Law(soft, std::make_shared<PowerLawHardening>(1e3 * soft.E, soft.E, 0.0)), 1, m);
  };
  for (const DeformationGradient& F : cases)
    for (const ElasticStressMeasure m : measures) {
      SCOPED_TRACE(fmt::format("{} F = {}", name_of(m), fmt::join(F.data(), F.data() + 5, " ")));
      const VoigtVector de = soft.stiffness() * logarithmic_strain(F, identity_tensor()).strain;
      const double J = (F[0] * F[3] - F[1] * F[2]) * F[4];
      const VoigtVector expected = m == ElasticStressMeasure::cauchy ? de : VoigtVector(de / J);
      std::vector<std::unique_ptr<FiniteStrainPointLaw>> laws;
      laws.push_back(std::make_unique<HenckyPointLaw>(soft, nullptr, m));
      laws.push_back(j2_elastic(m));
      for (const auto& law : laws) {
        const FiniteStrainResponse r = law->respond(0, F);
        const NominalStress& p = r.nominal;
        // sigma = P F^T / J in the plane (P = (P11, P12, P21, P22)), sigma33 = P33 F33 / J.
        const double s11 = (p[0] * F[0] + p[1] * F[1]) / J, s12 = (p[0] * F[2] + p[1] * F[3]) / J;
        const double s21 = (p[2] * F[0] + p[3] * F[1]) / J, s22 = (p[2] * F[2] + p[3] * F[3]) / J;
        const VoigtVector sigma(s11, s22, s12, p[4] * F[4] / J);
        EXPECT_FALSE(r.plastic);
        EXPECT_NEAR(s12, s21, 1e-13 * expected.norm());
        EXPECT_LE((sigma - expected).norm(), 1e-13 * expected.norm()) << sigma.transpose() << "\n" << expected.transpose();
      }
    }
}

// ---------------------------------------------------------------------------------------------
#include "indentsim/geometry/kinematics.hpp"

namespace {

/// The element force and tangent of one element through a finite-strain law (points 0..3).
struct ElementResponse {
  ElementVector force;
  ElementMatrix tangent;
};
ElementResponse respond(const FiniteStrainQuadrature& q, const FiniteStrainPointLaw& law, const ElementVector& ue,
                        std::size_t first_point = 0) {
  const auto F = q.law_gradients(ue);
  std::array<NominalStress, 4> p;
  std::array<NominalTangent, 4> a;
  for (std::size_t g = 0; g < 4; ++g) {
    const FiniteStrainResponse r = law.respond(first_point + g, F[g]);
    p[g] = r.nominal;
    a[g] = r.tangent;
  }
  return {q.internal_force(ue, p), q.stiffness(ue, p, a)};
}

/// The unknowns of a rectangle (left side at x0, bottom at y0) under u = (F - I) X (paper order:
/// vertices (x0, y0), (x0, y0 + h), (x0 + w, y0), (x0 + w, y0 + h); u1 of the four, then u2).
ElementVector homogeneous_unknowns(const Rectangle& rect, double y0, const Eigen::Matrix2d& f) {
  const double xs[4] = {rect.x0, rect.x0, rect.x0 + rect.width, rect.x0 + rect.width};
  const double ys[4] = {y0, y0 + rect.height, y0, y0 + rect.height};
  ElementVector ue;
  for (int q = 0; q < 4; ++q) {
    const Eigen::Vector2d u = (f - Eigen::Matrix2d::Identity()) * Eigen::Vector2d(xs[q], ys[q]);
    ue[q] = u[0];
    ue[4 + q] = u[1];
  }
  return ue;
}

}  // namespace

TEST(FiniteStrainPatch, HomogeneousDeformationsLeaveTheInteriorNodesInEquilibrium) {
  // A graded 3x3 patch under u = (F - I) X: every Gauss point takes F itself (F-bar too, J being
  // uniform), and the four interior nodes carry no force, to round-off.  Plane strain: a stretch
  // and a simple shear; about the axis (off it, r from 0.4): a uniform compression.
  struct Case {
    const char* name;
    SceneKind scene;
    Eigen::Matrix2d f;
  };
  const std::vector<Case> cases{{"plane-strain stretch", SceneKind::plane_strain, (Eigen::Matrix2d() << 1.3, 0, 0, 0.8).finished()},
                                {"simple shear", SceneKind::plane_strain, (Eigen::Matrix2d() << 1, 0.5, 0, 1).finished()},
                                {"axisymmetric compression", SceneKind::axisymmetric,
                                 (Eigen::Matrix2d() << 1.1, 0, 0, 0.85).finished()}};
  const double xs[4] = {0.4, 0.7, 1.5, 1.8}, ys[4] = {-1.0, -0.6, -0.5, 0.0};
  for (const auto& c : cases) {
    for (const ElementKind kind : {ElementKind::q1, ElementKind::bbar}) {
      for (int law_kind = 0; law_kind < 4; ++law_kind) {
        const bool plastic = law_kind % 2 == 1;
        const ElasticStressMeasure m = measures[law_kind / 2];
        SCOPED_TRACE(std::string(c.name) + (kind == ElementKind::bbar ? " F-bar" : " Q1") + (plastic ? " J2 " : " elastic ") +
                     name_of(m));
        const auto kinematics = make_kinematics(c.scene);
        std::unique_ptr<FiniteStrainPointLaw> law = plastic ? std::unique_ptr<FiniteStrainPointLaw>(j2_log(0.2, m, 36))
                                                            : hencky_elastic(m);
        const double f33 = c.scene == SceneKind::axisymmetric ? c.f(0, 0) : 1.0;
        const DeformationGradient expected = gradient(c.f(0, 0), c.f(0, 1), c.f(1, 0), c.f(1, 1), f33);
        Eigen::Matrix<double, 2, 16> nodal = Eigen::Matrix<double, 2, 16>::Zero();  // node (i, j) = 4 i + j
        double stress_scale = 0.0;
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) {
            const Rectangle rect{xs[i + 1] - xs[i], ys[j + 1] - ys[j], xs[i]};
            const FiniteStrainQuadrature q = kinematics->finite_strain_quadrature(rect, kind);
            const ElementVector ue = homogeneous_unknowns(rect, ys[j], c.f);
            for (const Deformation& F : q.law_gradients(ue)) EXPECT_LE((F.F() - expected).norm(), 1e-14);
            const ElementResponse r = respond(q, *law, ue, 4 * static_cast<std::size_t>(3 * i + j));
            stress_scale = std::max(stress_scale, law->respond(0, expected).nominal.norm());
            const int nodes[4] = {4 * i + j, 4 * i + j + 1, 4 * (i + 1) + j, 4 * (i + 1) + j + 1};
            for (int v = 0; v < 4; ++v) {
              nodal(0, nodes[v]) += r.force[v];
              nodal(1, nodes[v]) += r.force[4 + v];
            }
          }
        const double area_scale = 1.4 * 1.0 * (c.scene == SceneKind::axisymmetric ? 2 * 3.1416 * 1.8 : 1.0);
        for (const int interior : {5, 6, 9, 10})
          EXPECT_LE(nodal.col(interior).norm(), 1e-13 * stress_scale * area_scale) << "node " << interior;
      }
    }
  }
}

TEST(FiniteStrainElement, TheTangentMatchesCentralDifferencesOfTheForce) {
  // Material and geometric stiffness together, Q1 and F-bar, both kinematics, an elastic Hencky
  // law and J2 from a plastic history; displacements of 10-30% of the element.
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> c(-0.3, 0.3);
  for (const SceneKind scene : {SceneKind::plane_strain, SceneKind::axisymmetric}) {
    for (const ElementKind kind : {ElementKind::q1, ElementKind::bbar}) {
      SCOPED_TRACE(std::string(scene == SceneKind::axisymmetric ? "axisymmetric" : "plane strain") +
                   (kind == ElementKind::bbar ? " F-bar" : " Q1"));
      const Rectangle rect{0.5, 0.8, 0.3};
      const FiniteStrainQuadrature q = make_kinematics(scene)->finite_strain_quadrature(rect, kind);
      for (int trial = 0; trial < 6; ++trial) {
        ElementVector ue;
        for (double& v : ue) v = 0.3 * c(rng);
        const auto first = q.law_gradients(0.5 * ue);
        std::vector<std::unique_ptr<FiniteStrainPointLaw>> laws;
        for (const ElasticStressMeasure m : measures) {
          auto j2 = j2_log(0.2, m, 4);
          for (std::size_t g = 0; g < 4; ++g) j2->commit(g, first[g]);
          laws.push_back(hencky_elastic(m));
          laws.push_back(std::move(j2));
        }
        for (const auto& law : laws) {
          const ElementResponse r = respond(q, *law, ue);
          ElementMatrix fd;
          const double step = 1e-7;
          for (int k = 0; k < 8; ++k) {
            ElementVector plus = ue, minus = ue;
            plus[k] += step;
            minus[k] -= step;
            fd.col(k) = (respond(q, *law, plus).force - respond(q, *law, minus).force) / (2 * step);
          }
          const double scale = r.tangent.cwiseAbs().maxCoeff();
          EXPECT_LE((r.tangent - fd).cwiseAbs().maxCoeff(), 2e-6 * scale) << r.tangent << "\n\n" << fd;
        }
      }
    }
  }
}

TEST(FiniteStrainElement, AStrainOfOnePartInATrillionKeepsItsRelativePrecision) {
  // A coarse element far from the punch strains by 1e-9 and less.  Its finite-strain force is the
  // small-strain K ue to O(strain) relative, and to round-off beyond that: the strain is formed
  // from the displacement gradient H, not from F = I + H, which rounds it to 1e-16 absolute
  // (1e-4 relative here).  Q1 and F-bar (whose linearization is B-bar), both kinematics, an
  // elastic Hencky law and J2 in its elastic range.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> c(-1.0, 1.0);
  for (const SceneKind scene : {SceneKind::plane_strain, SceneKind::axisymmetric}) {
    for (const ElementKind kind : {ElementKind::q1, ElementKind::bbar}) {
      SCOPED_TRACE(std::string(scene == SceneKind::axisymmetric ? "axisymmetric" : "plane strain") +
                   (kind == ElementKind::bbar ? " F-bar" : " Q1"));
      const Rectangle rect{0.5, 0.8, 0.3};
      const auto kinematics = make_kinematics(scene);
      const FiniteStrainQuadrature q = kinematics->finite_strain_quadrature(rect, kind);
      const ElementMatrix k = kinematics->elastic_stiffness(rect, steel.lame(), kind);
      std::vector<std::unique_ptr<FiniteStrainPointLaw>> laws;
      for (const ElasticStressMeasure m : measures) {
        laws.push_back(hencky_elastic(m));
        laws.push_back(j2_log(0.2, m, 4));
      }
      for (int trial = 0; trial < 4; ++trial) {
        ElementVector ue;
        for (double& v : ue) v = 1e-12 * c(rng);
        const ElementVector small_strain = k * ue;
        for (const auto& law : laws) {
          const ElementVector force = respond(q, *law, ue).force;
          EXPECT_LE((force - small_strain).norm(), 1e-9 * small_strain.norm()) << force.transpose() << "\n" << small_strain.transpose();
        }
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
#include "indentsim/solvers/finite_strain_bulk.hpp"

namespace {
/// A small graded block (x from the axis, y from -ly to 0) in the given scene and element.
Mesh small_block(SceneKind scene, ElementKind kind) {
  Mesh mesh({0.0, 0.3, 0.5, 0.9, 1.6}, {-1.5, -0.8, -0.4, -0.15, 0.0});
  mesh.set_scene(scene);
  mesh.set_element_kind(kind);
  return mesh;
}
}  // namespace

TEST(FiniteStrainBulk, AUniformCompressionOfTheBlockLeavesEveryInteriorNodeInEquilibrium) {
  // u2 = (lambda - 1)(y + ly), u1 = 0: the homogeneous deformation the base and the axis allow.
  // Assembled over the graded mesh, the internal force vanishes at every node off the boundary.
  for (const SceneKind scene : {SceneKind::plane_strain, SceneKind::axisymmetric})
    for (const ElementKind kind : {ElementKind::q1, ElementKind::bbar}) {
      SCOPED_TRACE(std::string(scene == SceneKind::axisymmetric ? "axisymmetric" : "plane strain") +
                   (kind == ElementKind::bbar ? " F-bar" : " Q1"));
      const Mesh mesh = small_block(scene, kind);
      const StiffnessPattern pattern(mesh);
      const ElasticStiffness elastic(mesh, steel, pattern);
      FiniteStrainBulk bulk(elastic, j2_log(0.2, ElasticStressMeasure::cauchy, 4 * static_cast<std::size_t>(mesh.elements())));
      std::vector<double> u(static_cast<std::size_t>(mesh.equations()), 0.0), f(u.size());
      for (int i = 0; i < mesh.nodes_x(); ++i)
        for (int j = 0; j < mesh.nodes_y(); ++j) {
          const int e = mesh.equation(Mesh::dof_v(mesh.node(i, j)));
          if (e >= 0) u[static_cast<std::size_t>(e)] = (0.7 - 1.0) * (mesh.y(j) + 1.5);
        }
      bulk.internal_force(u.data(), f.data());
      double largest = 0.0;
      for (double v : f) largest = std::max(largest, std::abs(v));
      ASSERT_GT(largest, 0.0);
      for (int i = 1; i + 1 < mesh.nodes_x(); ++i)
        for (int j = 1; j + 1 < mesh.nodes_y(); ++j)
          for (const int dof : {Mesh::dof_u(mesh.node(i, j)), Mesh::dof_v(mesh.node(i, j))})
            EXPECT_LE(std::abs(f[static_cast<std::size_t>(mesh.equation(dof))]), 1e-12 * largest) << i << ", " << j;
    }
}

TEST(FiniteStrainBulk, TheAssembledTangentMatchesCentralDifferencesOfTheInternalForce) {
  std::mt19937 rng(29);
  std::uniform_real_distribution<double> c(-0.05, 0.05);
  for (const SceneKind scene : {SceneKind::plane_strain, SceneKind::axisymmetric})
    for (const ElementKind kind : {ElementKind::q1, ElementKind::bbar})
      for (const ElasticStressMeasure m : measures) {
      SCOPED_TRACE(std::string(scene == SceneKind::axisymmetric ? "axisymmetric" : "plane strain") +
                   (kind == ElementKind::bbar ? " F-bar " : " Q1 ") + name_of(m));
      const Mesh mesh = small_block(scene, kind);
      const StiffnessPattern pattern(mesh);
      const ElasticStiffness elastic(mesh, steel, pattern);
      FiniteStrainBulk bulk(elastic, hencky_elastic(m));
      // Unsymmetric: F-bar's dJbar/du, and the Cauchy measure's J s m^T.
      EXPECT_EQ(bulk.symmetric_tangent(), kind == ElementKind::q1 && m == ElasticStressMeasure::kirchhoff);
      const std::size_t n = static_cast<std::size_t>(mesh.equations());
      std::vector<double> u(n), values(static_cast<std::size_t>(pattern.nonzeros()));
      for (double& v : u) v = c(rng);
      bulk.tangent(u.data(), values.data());
      // Column k of the tangent by central differences, against K e_k from the pattern.
      const double step = 1e-7;
      double worst = 0.0, scale = 0.0;
      for (std::size_t k = 0; k < n; ++k) {
        std::vector<double> plus = u, minus = u, f_plus(n), f_minus(n), unit(n, 0.0), column(n);
        plus[k] += step;
        minus[k] -= step;
        bulk.internal_force(plus.data(), f_plus.data());
        bulk.internal_force(minus.data(), f_minus.data());
        unit[k] = 1.0;
        pattern.multiply(values, unit.data(), column.data());
        for (std::size_t i = 0; i < n; ++i) {
          worst = std::max(worst, std::abs(column[i] - (f_plus[i] - f_minus[i]) / (2 * step)));
          scale = std::max(scale, std::abs(column[i]));
        }
      }
      EXPECT_LE(worst, 1e-6 * scale);
    }
}

// ---------------------------------------------------------------------------------------------
#include <functional>
#include <limits>
#include <map>

#include "indentsim/solvers/coulomb_current_configuration_contact.hpp"
#include "indentsim/solvers/current_configuration_contact.hpp"
#include "indentsim/solvers/solver.hpp"
#include "indentsim/simulation/run_configuration.hpp"
#include "test_support.hpp"

namespace {

/// The surface of a shipped case pressed onto its punch (some candidates past it, some short of
/// it) with horizontal displacements that move the nodes along its face; the bulk in finite
/// strain.  The Newton Jacobian of the whole system with the contact `make_contact` builds
/// (given the displaced state), and the contact rows' depth derivative, against central
/// differences of its residual; `inspect` sees the contact at the state.
using ContactFactory = std::function<std::unique_ptr<ContactDiscretization>(
    const Mesh&, const StiffnessPattern&, const ElasticStiffness&, std::shared_ptr<const PunchShape> punch, double alpha,
    const std::vector<double>& u)>;
void expect_jacobian_rows_are_the_residuals_derivative(
    const char* name, const ContactFactory& make_contact,
    const std::function<void(const ContactDiscretization&, const std::vector<double>& u, const std::vector<double>& force,
                             double alpha)>& inspect = {}) {
  SCOPED_TRACE(name);
  const LoadCase lc = indentsim::testing::shipped_case(name, {"mesh.contact_nodes=8", "geometry.strain=\"finite\""});
  Mesh mesh = Mesh::from_plan(lc, plan_mesh(lc));
  mesh.set_element_kind(ElementKind::bbar);
  const StiffnessPattern pattern(mesh);
  const ElasticMaterial material{lc.material.E, lc.material.nu};
  ElasticStiffness k(mesh, material, pattern);
  FiniteStrainBulk bulk(k, std::make_unique<HenckyPointLaw>(material, nullptr, ElasticStressMeasure::cauchy));
  const CurrentConfigurationContact surface(mesh, make_punch(lc.punch), pattern, k.values());
  const auto& cs = surface.candidates();
  ASSERT_GE(cs.size(), 12u);
  // The punch reaching the 8th candidate; the surface's displacement fading with depth over 20
  // elements, so that strains stay at a few percent and no element turns over.
  const auto punch = make_punch(lc.punch);
  const double alpha = punch->surface_height(cs[8].x), fade = 20.0 * mesh.x(1);
  const auto n = static_cast<std::size_t>(mesh.equations());
  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<double> u(n, 0.0);
  for (std::size_t i = 0; i < cs.size(); ++i) {
    const double inward = i > 0 && i < 12 ? -0.1 * alpha * (1.0 + 0.5 * unit(random)) : 0.0;
    const double x = cs[i].x + inward;
    // Past the punch by up to 4% of the depth where it reaches below the surface, else at rest;
    // every fourth node short of it (open).
    const double reach = std::max(0.0, alpha - punch->surface_height(x));
    double down = reach > 0.0 ? -reach - 0.02 * (1.0 + unit(random)) * alpha : 0.0;
    if (reach > 0.0 && i % 4 == 3) down = -reach + 0.05 * alpha;
    const int column = static_cast<int>(i);
    for (int j = 0; j < mesh.nodes_y(); ++j) {
      const double decay = std::exp(mesh.y(j) / fade);
      const int node = mesh.node(column, j);
      if (const int e = mesh.equation(Mesh::dof_u(node)); e >= 0) u[static_cast<std::size_t>(e)] = inward * decay;
      if (const int e = mesh.equation(Mesh::dof_v(node)); e >= 0) u[static_cast<std::size_t>(e)] = down * decay;
    }
  }
  const std::unique_ptr<ContactDiscretization> contact = make_contact(mesh, pattern, k, punch, alpha, u);
  ContactEquations equations(pattern, bulk, k, *contact);
  std::vector<double> values(static_cast<std::size_t>(pattern.nonzeros())), f(n), f_plus(n), f_minus(n), jd(n);
  equations.residual(u.data(), alpha, f.data());
  equations.jacobian(u.data(), alpha, values.data());
  std::vector<double> direction(n, 0.0);
  // A step of 1e-6 of the depth: the nonlinear bulk's central differences err by ~1e-12 there,
  // and the active set stays.
  for (std::size_t i = 0; i < n; ++i) direction[i] = alpha * unit(random);
  pattern.multiply(values, direction.data(), jd.data());
  const double step = 1e-6;
  std::vector<double> plus = u, minus = u;
  for (std::size_t i = 0; i < n; ++i) {
    plus[i] += step * direction[i];
    minus[i] -= step * direction[i];
  }
  equations.residual(plus.data(), alpha, f_plus.data());
  equations.residual(minus.data(), alpha, f_minus.data());
  double scale = 0.0;
  for (std::size_t i = 0; i < n; ++i) scale = std::max(scale, std::abs(jd[i]));
  for (std::size_t i = 0; i < n; ++i)
    EXPECT_NEAR((f_plus[i] - f_minus[i]) / (2.0 * step), jd[i], 1e-6 * scale) << "equation " << i;
  std::vector<double> force(n);
  bulk.internal_force(u.data(), force.data());
  int active = 0;
  for (const char on : contact->evaluate(u.data(), force.data(), alpha).in_contact) active += on;
  EXPECT_GT(active, 2);
  EXPECT_LT(active, static_cast<int>(cs.size()));
  // The rows' derivative in the depth at fixed u (what the linearized unloading stiffness solves
  // with) against central differences, on every row the contact writes.
  std::vector<double> row_force;
  for (int row : contact->row_equations()) row_force.push_back(force[static_cast<std::size_t>(row)]);
  std::vector<double> at_plus = force, at_minus = force, d_alpha(n, 0.0);
  const double h = 1e-6 * alpha;
  contact->write_residual_rows(u.data(), alpha + h, row_force.data(), at_plus.data());
  contact->write_residual_rows(u.data(), alpha - h, row_force.data(), at_minus.data());
  contact->write_depth_derivative_rows(u.data(), alpha, row_force.data(), d_alpha.data());
  for (int row : contact->row_equations()) {
    const auto i = static_cast<std::size_t>(row);
    EXPECT_NEAR((at_plus[i] - at_minus[i]) / (2.0 * h), d_alpha[i], 1e-6 * scale / alpha) << "depth row " << row;
  }
  if (inspect) inspect(*contact, u, force, alpha);
}

const char* const pressed_cases[] = {"axisymmetric/berkovich_cone.toml", "axisymmetric/elastic_sphere.toml",
                                     "elastic.toml"};

}  // namespace

TEST(CurrentConfigurationContact, TheJacobianRowsAreTheResidualsDerivative) {
  for (const char* name : pressed_cases)
    expect_jacobian_rows_are_the_residuals_derivative(
        name, [](const Mesh& mesh, const StiffnessPattern& pattern, const ElasticStiffness& k,
                 std::shared_ptr<const PunchShape> punch, double,
                 const std::vector<double>&) -> std::unique_ptr<ContactDiscretization> {
          return std::make_unique<CurrentConfigurationContact>(mesh, punch, pattern, k.values());
        });
}

TEST(CoulombCurrentConfigurationContact, TheJacobianRowsAreTheResidualsDerivativeOnEveryBranch) {
  // Friction on the current surface (mu = 0.3, and sticking): the committed state the increment
  // starts from lies a random 0-6% of the depth away horizontally, so that some contact nodes
  // stick and some slide either way; the open ones keep q = 0.
  for (const double mu : {0.3, std::numeric_limits<double>::infinity()})
    for (const char* name : pressed_cases) {
      SCOPED_TRACE(fmt::format("mu = {}", mu));
      expect_jacobian_rows_are_the_residuals_derivative(
          name,
          [mu](const Mesh& mesh, const StiffnessPattern& pattern, const ElasticStiffness& k,
               std::shared_ptr<const PunchShape> punch, double alpha,
               const std::vector<double>& u) -> std::unique_ptr<ContactDiscretization> {
            auto contact = std::make_unique<CoulombCurrentConfigurationContact>(mesh, punch, pattern, k.values(), mu);
            std::vector<double> committed = u;
            std::mt19937 random(11);
            std::uniform_real_distribution<double> unit(-1.0, 1.0);
            for (const ContactCandidate& c : contact->candidates())
              if (c.tangential_equation >= 0) committed[static_cast<std::size_t>(c.tangential_equation)] += 0.03 * alpha * (unit(random) + unit(random));
            contact->hold_committed_state(committed.data());
            return contact;
          },
          [mu](const ContactDiscretization& contact, const std::vector<double>& u, const std::vector<double>& force,
               double alpha) {
            const auto& coulomb = dynamic_cast<const CoulombCurrentConfigurationContact&>(contact);
            std::vector<double> row_force;
            for (int row : contact.row_equations()) row_force.push_back(force[static_cast<std::size_t>(row)]);
            std::map<CoulombCurrentConfigurationContact::Branch, int> count;
            for (std::size_t k = 0; k < contact.candidates().size(); ++k)
              if (contact.candidates()[k].tangential_equation >= 0) ++count[coulomb.branch(k, u.data(), alpha, row_force.data())];
            EXPECT_GT(count[CoulombCurrentConfigurationContact::Branch::stick], 0);
            EXPECT_GT(count[CoulombCurrentConfigurationContact::Branch::open], 0);
            if (std::isfinite(mu))
              EXPECT_GT(count[CoulombCurrentConfigurationContact::Branch::slip_positive] +
                            count[CoulombCurrentConfigurationContact::Branch::slip_negative],
                        0);
          });
    }
}

// ---------------------------------------------------------------------------------------------
#include "indentsim/base/error.hpp"
#include "indentsim/simulation/simulation.hpp"

namespace {
double peak_force(const LoadCase& lc) {
  Simulation sim(lc);
  sim.run();
  return sim.contact().force;
}
}  // namespace

TEST(FiniteStrainRun, ShallowIndentationsApproachTheSmallStrainForceAsTheContactShrinks) {
  // An elastic sphere at alpha / R = 1e-4, 1e-3, 1e-2: finite strain's force exceeds small
  // strain's by a geometric share of the order of a / R = sqrt(alpha / R) -- measured 2.0e-3,
  // 6.3e-3, 2.0e-2 -- so the difference falls by about sqrt(10) per decade of depth.
  std::vector<double> excess;
  for (const char* depth : {"1e-7", "1e-6", "1e-5"}) {
    const std::vector<std::string> common{std::string("load.path=[0, ") + depth + "]", "load.increments=4",
                                          "mesh.error_estimate=\"off\"", "mesh.contact_nodes=12"};
    auto finite = common;
    finite.push_back("geometry.strain=\"finite\"");
    const double small = peak_force(indentsim::testing::shipped_case("axisymmetric/elastic_sphere.toml", common));
    excess.push_back(peak_force(indentsim::testing::shipped_case("axisymmetric/elastic_sphere.toml", finite)) / small - 1.0);
  }
  RecordProperty("excess", fmt::format("{:.3e} {:.3e} {:.3e}", excess[0], excess[1], excess[2]));
  EXPECT_GT(excess[0], 0.0);
  EXPECT_LT(excess[0], 4e-3);
  for (std::size_t k = 1; k < excess.size(); ++k) {
    EXPECT_GT(excess[k] / excess[k - 1], 2.0);
    EXPECT_LT(excess[k] / excess[k - 1], 5.0);
  }
}

TEST(FiniteStrainRun, TheExactUnloadingStiffnessIsTheSlopeOfTheFirstUnloadingStep) {
  // The unloading stiffness of finite strain is the linearization along its own tangent (the
  // geometric terms and the contact on the current surface included): an unloading step of 1e-4
  // of the depth falls along it to the step's own first-order error.  Elastic cone (every node
  // in contact stays) and J2 sphere (elastic unloading from the plastic state), frictionless;
  // and both with Coulomb friction on the current surface (mu = 0.3), whose S is the one-sided
  // derivative of an unloading increment on the tangent (which nodes stick is part of it).
  struct Case {
    const char* name;
    const char* model;
    const char* friction;
  };
  for (const Case& c : {Case{"axisymmetric/berkovich_cone.toml", "elastic", "0"},
                        Case{"axisymmetric/steel_sphere.toml", "j2", "0"},
                        Case{"axisymmetric/berkovich_cone.toml", "elastic", "1e-9"}, Case{"axisymmetric/berkovich_cone.toml", "elastic", "0.3"},
                        Case{"axisymmetric/steel_sphere.toml", "j2", "0.3"}}) {
    SCOPED_TRACE(fmt::format("{}, mu = {}", c.name, c.friction));
    LoadCase lc = indentsim::testing::shipped_case(
        c.name, {"geometry.strain=\"finite\"", std::string("material.model=\"") + c.model + "\"",
                 "mesh.contact_nodes=10", "mesh.error_estimate=\"off\"", std::string("contact.friction=") + c.friction});
    const double depth = lc.max_depth();
    lc.load.path = {0.0, depth, (1.0 - 1e-4) * depth};
    lc.load.segment_increments = {6, 1};
    lc.load.increments = 7;
    validate(lc);
    Simulation sim(lc);
    double s_exact = 0.0, p_peak = 0.0, p_after = 0.0;
    sim.run([&](const IncrementRecord& r) {
      if (r.step == 6) {
        s_exact = sim.unloading_stiffness();
        p_peak = r.force;
      }
      if (r.step == 7) p_after = r.force;
    });
    const double slope = (p_peak - p_after) / (1e-4 * depth);
    EXPECT_NEAR(slope / s_exact, 1.0, 2e-3) << "S exact " << s_exact << ", slope " << slope;
  }
}

TEST(FiniteStrainRun, FrictionOnTheCurrentSurfaceVanishesWithItsCoefficient) {
  // Coulomb's rows with mu -> 0 are the frictionless rows of the current surface: the force and
  // the contact radius of an elastic cone agree to the Newton tolerance at mu = 1e-9, and a real
  // coefficient (0.15) moves them by more than that (friction holds the surface's inward slide).
  // Elastic, so that the cutbacks either run may take do not change its history.
  const auto run = [](const char* mu) {
    Simulation sim(indentsim::testing::shipped_case(
        "axisymmetric/berkovich_cone.toml", {"geometry.strain=\"finite\"", "material.model=\"elastic\"",
                                             "load.path=[0, 5e-7]", "load.increments=5", "mesh.contact_nodes=10",
                                             "mesh.error_estimate=\"off\"", std::string("contact.friction=") + mu}));
    sim.run();
    return std::pair{sim.contact().force, sim.contact_half_width()};
  };
  const auto [p0, a0] = run("0");
  const auto [p_small, a_small] = run("1e-9");
  const auto [p_real, a_real] = run("0.15");
  EXPECT_NEAR(p_small / p0, 1.0, 1e-6);
  EXPECT_NEAR(a_small / a0, 1.0, 1e-6);
  EXPECT_GT(std::abs(p_real / p0 - 1.0) + std::abs(a_real / a0 - 1.0), 1e-4);
  RecordProperty("mu_0.15", fmt::format("P {:+.3e}, a {:+.3e}", p_real / p0 - 1.0, a_real / a0 - 1.0));
}

TEST(FiniteStrainRun, KicksLawStillHoldsUnderTheConeInFiniteStrain) {
  // Finite strain adds no length to a sharp cone on an elasto-plastic solid: the solution stays
  // self-similar and P / h^2 constant.  The test of small strain's Kick's law
  // (AxisymmetricCone.KicksLawHoldsOverTheSecondHalfOfTheLoading), in finite strain: Ilyushin's
  // law of the Hencky strain is path independent on loading, so one increment reaches h_max / 2
  // and 40 sample the second half; the node-by-node sawtooth stays within 0.5% of the mean.
  const LoadCase lc = indentsim::testing::shipped_case(
      "axisymmetric/berkovich_cone.toml", {"geometry.strain=\"finite\"", "material.model=\"ilyushin\"",
                                           "load.path=[0.0, 0.5e-6, 1e-6]", "load.increments=[1, 40]",
                                           "mesh.error_estimate=\"off\""});
  Simulation sim(lc);
  std::vector<double> kick;
  sim.run([&](const IncrementRecord& r) {
    if (r.step >= 1) kick.push_back(r.force / (r.alpha * r.alpha));
  });
  ASSERT_EQ(kick.size(), 41u);
  double mean = 0.0;
  for (double c : kick) mean += c / static_cast<double>(kick.size());
  double worst = 0.0;
  for (double c : kick) worst = std::max(worst, std::abs(c / mean - 1.0));
  RecordProperty("kick_deviation", fmt::format("{:.3e}", worst));
  EXPECT_LT(worst, 5e-3) << "P/h^2 = " << mean;
}

TEST(FiniteStrainRun, AutoWeighsAnUpperEstimateOfWhatFiniteStrainChanges) {
  // "auto" takes finite strain where its share of P, estimated as a multiple of alpha / a, exceeds
  // the accuracy the run aims at.  The estimate must bound the change it stands for, without
  // overstating it tenfold: an elastic sphere (the largest share per alpha / a measured) and
  // J2 under a sphere, each run in both kinematics.
  for (const auto& [name, overrides] :
       {std::pair<const char*, std::vector<std::string>>{"axisymmetric/elastic_sphere.toml",
                                                         {"load.path=[0, 1e-6]", "load.increments=4"}},
        std::pair<const char*, std::vector<std::string>>{"axisymmetric/steel_sphere.toml", {"load.path=[0, 5e-6]", "load.increments=10"}}}) {
    SCOPED_TRACE(name);
    auto common = overrides;
    common.insert(common.end(), {"mesh.error_estimate=\"off\"", "mesh.contact_nodes=12"});
    auto finite = common;
    finite.push_back("geometry.strain=\"finite\"");
    const LoadCase small_case = indentsim::testing::shipped_case(name, common);
    const double change =
        std::abs(peak_force(indentsim::testing::shipped_case(name, finite)) / peak_force(small_case) - 1.0);
    const double share = finite_strain_share(small_case);
    RecordProperty(std::string("change_over_share_") + (name[13] == 'e' ? "elastic" : "j2"), fmt::format("{:.3f}", change / share));
    EXPECT_LE(change, share);
    EXPECT_GT(change, 0.1 * share);
  }
  // The choices, and why: finite under the cone, with or without friction (which finite strain
  // runs), small for a shallow sphere, small when the run asks for less accuracy than the share.
  const auto choice = [](const char* name, std::vector<std::string> overrides) {
    overrides.push_back("geometry.strain=\"auto\"");
    const LoadCase lc = indentsim::testing::shipped_case(name, overrides);
    return choose_strain(lc);
  };
  EXPECT_EQ(choice("axisymmetric/berkovich_cone.toml", {}).first, StrainChoice::finite);
  EXPECT_EQ(choice("axisymmetric/elastic_sphere.toml", {"load.path=[0, 1e-8]"}).first, StrainChoice::small);
  EXPECT_EQ(choice("axisymmetric/berkovich_cone.toml", {"contact.friction=0.1"}).first, StrainChoice::finite);
  EXPECT_EQ(choice("axisymmetric/steel_sphere.toml", {"mesh.target_error=0.05"}).first, StrainChoice::small);
  // Planning for a target drops mesh.target_error from the case it runs: the choice made against
  // the target is pinned in the case first, with its reason.
  LoadCase targeted = indentsim::testing::shipped_case("axisymmetric/steel_sphere.toml",
                                                       {"geometry.strain=\"auto\"", "mesh.target_error=0.05"});
  pin_kinematics(targeted);
  targeted.mesh.target_error.reset();
  const auto pinned = choose_strain(targeted);
  EXPECT_EQ(pinned.first, StrainChoice::small);
  EXPECT_NE(pinned.second.find("mesh.target_error"), std::string::npos) << pinned.second;
  EXPECT_EQ(choice("axisymmetric/steel_sphere.toml", {}).first, StrainChoice::finite);
}

TEST(FiniteStrainRun, UnbuiltCombinationsAreRefusedNamingTheKey) {
  const auto refused = [](std::vector<std::string> overrides, const std::string& key) {
    overrides.push_back("geometry.strain=\"finite\"");
    try {
      indentsim::testing::shipped_case("axisymmetric/elastic_sphere.toml", overrides);
      ADD_FAILURE() << "accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(e.key(), key) << e.what();
    }
  };
  refused({"contact.discretization=\"integrated_gap\""}, "geometry.strain");
  refused({"solver.linear=\"cholmod\""}, "solver.linear");
}

TEST(FiniteStrainRun, AFlatPunchWhoseRimNodeSlidesOffItsFaceStopsNamingTheRimAndTheWaysOut) {
  // A J2 block (nu = 0.45) under a plane-strain flat punch flows outwards under the face: in
  // finite strain the rim node slides past x = R, where the vertical gap ends, opens, springs back
  // and closes again (MODEL.md §12.3).  The run stops as an increment that did not converge, and
  // its message names the rim; the same edge given a finite slope as a profile converges.
  const auto block = [](const std::string& punch) {
    return parse_load_case(R"(
[geometry]
kind = "plane_strain"
lx = 1.33207e-4
ly = 1.53042e-4
strain = "finite"
[punch]
)" + punch + R"(
[material]
model = "j2"
E = 4e11
nu = 0.45
yield_stress = 1.2e9
hardening = "power"
n = 0.3
[load]
path = [0.0, 2e-7]
increments = 5
[mesh]
contact_nodes = 8
error_estimate = "off"
)",
                           "rim.toml");
  };
  try {
    Simulation sim(block("shape = \"flat\"\nradius = 1.56927e-5"));
    sim.run();
    ADD_FAILURE() << "the flat punch's rim did not stop the run: is its side wall modelled now? (MODEL.md §12.3)";
  } catch (const SolverError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("did not converge"), std::string::npos) << what;
    EXPECT_NE(what.find("flat punch's rim (x = 1.56927e-05 m)"), std::string::npos) << what;
    EXPECT_NE(what.find("geometry.strain = \"small\""), std::string::npos) << what;
    EXPECT_NE(what.find("punch.shape = \"profile\""), std::string::npos) << what;
  }
  EXPECT_GT(peak_force(block("shape = \"profile\"\nprofile_points = [[0.0, 0.0], [1.56927e-5, 0.0], [1.6e-5, 1e-5]]")),
            0.0);
}

TEST(FiniteStrainRun, TheElasticStressMeasureBelongsToFiniteStrainAndTravelsWithTheCase) {
  // Small strain cannot tell sigma from tau: the key is refused there, naming it.  In finite
  // strain the Cauchy stress is the default, and a case written out (case.toml, what a resumed run
  // and a study's runs read) keeps the choice.
  try {
    indentsim::testing::shipped_case("axisymmetric/elastic_sphere.toml",
                                     {"geometry.strain=\"small\"", "material.elastic_stress=\"kirchhoff\""});
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "material.elastic_stress") << e.what();
  }
  const LoadCase plain = indentsim::testing::shipped_case("axisymmetric/elastic_sphere.toml", {"geometry.strain=\"finite\""});
  EXPECT_EQ(plain.material.elastic_stress, ElasticStressMeasure::cauchy);
  for (const char* strain : {"finite", "auto"}) {
    const LoadCase lc = indentsim::testing::shipped_case(
        "axisymmetric/elastic_sphere.toml",
        {fmt::format("geometry.strain=\"{}\"", strain), "material.elastic_stress=\"kirchhoff\""});
    EXPECT_EQ(lc.material.elastic_stress, ElasticStressMeasure::kirchhoff);
    EXPECT_EQ(parse_load_case(to_toml(lc), "case.toml").material.elastic_stress, ElasticStressMeasure::kirchhoff);
  }
}

#include <csignal>

#include <nlohmann/json.hpp>

class FiniteStrainCli : public indentsim::testing::CliTest {};

TEST_F(FiniteStrainCli, AFiniteStrainJ2RunKilledWhileLoadingAndUnloadingResumesToTheSameCurveWithAndWithoutFriction) {
  // The checkpoint carries C_p^-1 and the equivalent plastic strain of every point: resumed runs
  // end bit for bit where the uninterrupted one did.  summary.json names the kinematics.
  // With Coulomb friction on the current surface too: its slip history is the committed state.
  const std::string source = indentsim::testing::source_path("loadcases/axisymmetric/steel_sphere.toml");
  const std::string args = " --quiet --set geometry.strain=\\\"finite\\\" --set mesh.contact_nodes=8 "
                           "--set load.increments=[6,4,1] --set mesh.error_estimate=\\\"off\\\" "
                           "--set output.checkpoint_every=2";
  const std::string friction = " --set contact.friction=0.2";
  ASSERT_EQ(cli("run " + source + args + " --out " + (dir_ / "full").string()), 0) << err();
  ASSERT_EQ(cli("run " + source + args + friction + " --out " + (dir_ / "full_friction").string()), 0) << err();
  for (const bool with_friction : {false, true}) {
    const std::string expected =
        indentsim::testing::curve_without_timing(dir_ / (with_friction ? "full_friction" : "full") / "curve.csv");
    for (const char* fault : {"increment:4", "increment:8"}) {
      SCOPED_TRACE(std::string(fault) + (with_friction ? ", friction" : ""));
      const auto out = dir_ / (std::string("killed_") + fault[10] + (with_friction ? "_friction" : ""));
      EXPECT_EQ(cli("run " + source + args + (with_friction ? friction : "") + " --out " + out.string(),
                    std::string("INDENTSIM_FAULT=") + fault),
                128 + SIGKILL);
      ASSERT_EQ(cli("resume " + (out / "checkpoints").string() + " --quiet"), 0) << err();
      EXPECT_EQ(indentsim::testing::curve_without_timing(out / "curve.csv"), expected);
    }
  }
  EXPECT_NE(indentsim::testing::curve_without_timing(dir_ / "full_friction" / "curve.csv"),
            indentsim::testing::curve_without_timing(dir_ / "full" / "curve.csv"));
  EXPECT_NE(indentsim::testing::slurp(dir_ / "full" / "case.toml").find("strain = \"finite\""), std::string::npos);
  EXPECT_NE(indentsim::testing::slurp(dir_ / "full" / "summary.json").find("\"strain\": \"finite\""), std::string::npos);
  // The condensed far field stayed within the gradient it may be linearized at (the near field
  // grows before it is passed), and the killed runs carried its record through the checkpoint.
  const auto far_field = [&](const std::filesystem::path& run) {
    return nlohmann::json::parse(indentsim::testing::slurp(run / "summary.json"))["far_field"];
  };
  const auto full = far_field(dir_ / "full");
  const double gradient = full["largest_displacement_gradient"].get<double>();
  EXPECT_GT(gradient, 0.0);
  EXPECT_LE(gradient, FiniteStrainBulk::small_strain_limit);
  EXPECT_EQ(far_field(dir_ / "killed_4"), full);
  EXPECT_EQ(far_field(dir_ / "killed_8"), full);
}
