#include "indentsim/geometry/kinematics.hpp"

#include <numbers>

namespace indentsim {

namespace {
// Q1 on the rectangle: N1 = (1-xi)(1-eta), N2 = (1-xi) eta, N3 = xi (1-eta), N4 = xi eta.
struct ShapeValues {
  double n[4], dx[4], dy[4];
};
ShapeValues shape_values(const Rectangle& rect, double xi, double eta) {
  return {{(1 - xi) * (1 - eta), (1 - xi) * eta, xi * (1 - eta), xi * eta},
          {-(1 - eta) / rect.width, -eta / rect.width, (1 - eta) / rect.width, eta / rect.width},
          {-(1 - xi) / rect.height, (1 - xi) / rect.height, -xi / rect.height, xi / rect.height}};
}

/// The in-plane rows of Q1's B; the hoop row (3) is left zero.
StrainDisplacement in_plane_rows(const ShapeValues& s) {
  StrainDisplacement b = StrainDisplacement::Zero();
  for (int q = 0; q < 4; ++q) {
    b(0, q) = s.dx[q];
    b(1, 4 + q) = s.dy[q];
    b(2, q) = s.dy[q];
    b(2, 4 + q) = s.dx[q];
  }
  return b;
}
}  // namespace

ElementMatrix Kinematics::elastic_stiffness(const Rectangle& rect, const LameConstants& lame, ElementKind kind) const {
  return stiffness(rect, isotropic_stiffness(lame), kind);
}

std::array<StrainDisplacement, 4> Kinematics::gauss_point_strain_displacements(const Rectangle& rect,
                                                                               ElementKind kind) const {
  const auto& points = gauss_points_2x2();
  std::array<StrainDisplacement, 4> b;
  for (std::size_t g = 0; g < points.size(); ++g) b[g] = strain_displacement(rect, points[g].xi, points[g].eta, kind);
  return b;
}

/// The in-plane rows of Q1's gradient operator; the out-of-plane row (4) is left zero.
static GradientOperator in_plane_gradient(const ShapeValues& s) {
  GradientOperator g = GradientOperator::Zero();
  for (int q = 0; q < 4; ++q) {
    g(0, q) = s.dx[q];      // d u1 / d X1
    g(1, q) = s.dy[q];      // d u1 / d X2
    g(2, 4 + q) = s.dx[q];  // d u2 / d X1
    g(3, 4 + q) = s.dy[q];  // d u2 / d X2
  }
  return g;
}

FiniteStrainQuadrature Kinematics::finite_strain_quadrature(const Rectangle& rect, ElementKind kind) const {
  FiniteStrainQuadrature q;
  const auto& points = gauss_points_2x2();
  for (std::size_t p = 0; p < points.size(); ++p) {
    q.g[p] = gradient_operator(rect, points[p].xi, points[p].eta);
    q.volume[p] = points[p].weight * measure(rect, points[p].xi);
  }
  q.f_bar = kind == ElementKind::bbar;
  q.dilatation_dimensions = dilatation_dimensions();
  return q;
}

namespace {
/// d J / d F, J = (F11 F22 - F12 F21) F33.
Eigen::Matrix<double, 1, 5> jacobian_derivative(const DeformationGradient& F) {
  return (Eigen::Matrix<double, 1, 5>() << F[3] * F[4], -F[2] * F[4], -F[1] * F[4], F[0] * F[4],
          F[0] * F[3] - F[1] * F[2])
      .finished();
}

/// F-bar's scaling: s = (J-bar / J_g)^(1/d) at each point (and s - 1, as precise as H) and
/// ds/due, and which components it scales (all five about the axis; the in-plane four in plane
/// strain).
struct FBarScaling {
  std::array<double, 4> s{1.0, 1.0, 1.0, 1.0};
  std::array<double, 4> s_excess{};
  std::array<Eigen::Matrix<double, 1, 8>, 4> ds{};
  Eigen::Matrix<double, 5, 1> scaled = Eigen::Matrix<double, 5, 1>::Ones();
};
FBarScaling f_bar_scaling(const FiniteStrainQuadrature& q, const std::array<Deformation, 4>& F) {
  FBarScaling f;
  for (auto& d : f.ds) d.setZero();
  if (q.dilatation_dimensions == 2) f.scaled[4] = 0.0;
  if (!q.f_bar) return f;
  double mean_excess = 0.0, volume = 0.0;
  Eigen::Matrix<double, 1, 8> d_mean = Eigen::Matrix<double, 1, 8>::Zero();
  std::array<double, 4> j_excess{};
  std::array<Eigen::Matrix<double, 1, 8>, 4> dj;
  for (std::size_t p = 0; p < 4; ++p) {
    j_excess[p] = jacobian_excess(F[p]);
    dj[p] = jacobian_derivative(F[p].F()) * q.g[p];
    mean_excess += q.volume[p] * j_excess[p];
    d_mean += q.volume[p] * dj[p];
    volume += q.volume[p];
  }
  mean_excess /= volume;
  d_mean /= volume;
  const double d = q.dilatation_dimensions, mean = 1.0 + mean_excess;
  for (std::size_t p = 0; p < 4; ++p) {
    const double j = 1.0 + j_excess[p];
    // s - 1 = (J-bar / J)^(1/d) - 1 with J-bar / J - 1 = (J-bar - J) / J.
    f.s_excess[p] = std::expm1(std::log1p((mean_excess - j_excess[p]) / j) / d);
    f.s[p] = 1.0 + f.s_excess[p];
    f.ds[p] = f.s[p] / d * (d_mean / mean - dj[p] / j);
  }
  return f;
}

/// F's components scaled by s where `scaled` says so.
DeformationGradient scale(const DeformationGradient& v, double s, const Eigen::Matrix<double, 5, 1>& scaled) {
  DeformationGradient out = v;
  for (int i = 0; i < 5; ++i)
    if (scaled[i] != 0.0) out[i] *= s;
  return out;
}
}  // namespace

std::array<Deformation, 4> FiniteStrainQuadrature::gradients(const ElementVector& ue) const {
  std::array<Deformation, 4> F;
  for (std::size_t p = 0; p < 4; ++p) F[p] = Deformation::from_displacement_gradient(g[p] * ue);
  return F;
}

std::array<Deformation, 4> FiniteStrainQuadrature::law_gradients(const ElementVector& ue) const {
  std::array<Deformation, 4> F = gradients(ue);
  if (!f_bar) return F;
  const FBarScaling f = f_bar_scaling(*this, F);
  // F-bar = s F on the scaled components: H-bar = s H + (s - 1) I there.
  const DeformationGradient identity = identity_deformation();
  for (std::size_t p = 0; p < 4; ++p) {
    DeformationGradient h = F[p].H();
    for (int i = 0; i < 5; ++i)
      if (f.scaled[i] != 0.0) h[i] = f.s[p] * h[i] + f.s_excess[p] * identity[i];
    F[p] = Deformation::from_displacement_gradient(h);
  }
  return F;
}

ElementVector FiniteStrainQuadrature::internal_force(const ElementVector& ue,
                                                     const std::array<NominalStress, 4>& law_stress) const {
  // tau(F-bar) F^-T = P(F-bar) F-bar^T F^-T = s P(F-bar) on the scaled components.
  const FBarScaling f = f_bar ? f_bar_scaling(*this, gradients(ue)) : FBarScaling{};
  ElementVector force = ElementVector::Zero();
  for (std::size_t p = 0; p < 4; ++p)
    force.noalias() += volume[p] * g[p].transpose() * (f_bar ? scale(law_stress[p], f.s[p], f.scaled) : law_stress[p]);
  return force;
}

ElementMatrix FiniteStrainQuadrature::stiffness(const ElementVector& ue, const std::array<NominalStress, 4>& law_stress,
                                                const std::array<NominalTangent, 4>& law_tangent) const {
  ElementMatrix k = ElementMatrix::Zero();
  if (!f_bar) {
    for (std::size_t p = 0; p < 4; ++p) k.noalias() += volume[p] * g[p].transpose() * law_tangent[p] * g[p];
    return k;
  }
  // P_mod = S P(F-bar), F-bar = S F with S = diag(s on the scaled components):
  //   dP_mod = S A (S G + (scaled o F) ds) + (scaled o P) ds.
  const std::array<Deformation, 4> F = gradients(ue);
  const FBarScaling f = f_bar_scaling(*this, F);
  for (std::size_t p = 0; p < 4; ++p) {
    const Eigen::Matrix<double, 5, 5> S = scale(DeformationGradient::Ones(), f.s[p], f.scaled).asDiagonal();
    const Eigen::Matrix<double, 5, 8> d_f_bar = S * g[p] + F[p].F().cwiseProduct(f.scaled) * f.ds[p];
    const Eigen::Matrix<double, 5, 8> d_p = S * law_tangent[p] * d_f_bar + law_stress[p].cwiseProduct(f.scaled) * f.ds[p];
    k.noalias() += volume[p] * g[p].transpose() * d_p;
  }
  return k;
}

ElementQuadrature Kinematics::quadrature(const Rectangle& rect, ElementKind kind) const {
  ElementQuadrature q;
  q.b = gauss_point_strain_displacements(rect, kind);
  const auto& points = gauss_points_2x2();
  for (std::size_t g = 0; g < points.size(); ++g) q.volume[g] = points[g].weight * measure(rect, points[g].xi);
  return q;
}

ElementMatrix Kinematics::stiffness(const Rectangle& rect, const std::array<ConstitutiveMatrix, 4>& d,
                                    ElementKind kind) const {
  return quadrature(rect, kind).stiffness(d);
}

ElementVector Kinematics::internal_force(const Rectangle& rect, const std::array<VoigtVector, 4>& stress,
                                         ElementKind kind) const {
  return quadrature(rect, kind).internal_force(stress);
}

std::array<VoigtVector, 4> ElementQuadrature::strains(const ElementVector& ue) const {
  std::array<VoigtVector, 4> eps;
  for (std::size_t g = 0; g < b.size(); ++g) eps[g] = b[g] * ue;
  return eps;
}

ElementMatrix ElementQuadrature::stiffness(const std::array<ConstitutiveMatrix, 4>& d) const {
  ElementMatrix k = ElementMatrix::Zero();
  for (std::size_t g = 0; g < b.size(); ++g) k.noalias() += volume[g] * b[g].transpose() * d[g] * b[g];
  return k;
}

ElementVector ElementQuadrature::internal_force(const std::array<VoigtVector, 4>& stress) const {
  ElementVector f = ElementVector::Zero();
  for (std::size_t g = 0; g < b.size(); ++g) f.noalias() += volume[g] * b[g].transpose() * stress[g];
  return f;
}

// ---------------------------------------------------------------------------------------------
StrainDisplacement PlaneStrain::strain_displacement(const Rectangle& rect, double xi, double eta,
                                                    ElementKind kind) const {
  StrainDisplacement b = in_plane_rows(shape_values(rect, xi, eta));
  if (kind == ElementKind::bbar) {
    // Mean dilatation: with eps33 = 0 the dilatation is eps11 + eps22; its element mean is its
    // value at the centre (it is linear in xi, eta), and each normal strain takes half the shift.
    const StrainDisplacement centre = in_plane_rows(shape_values(rect, 0.5, 0.5));
    const Eigen::Matrix<double, 1, 8> shift = 0.5 * ((centre.row(0) + centre.row(1)) - (b.row(0) + b.row(1)));
    b.row(0) += shift;
    b.row(1) += shift;
  }
  return b;
}

GradientOperator PlaneStrain::gradient_operator(const Rectangle& rect, double xi, double eta) const {
  return in_plane_gradient(shape_values(rect, xi, eta));
}

ElementMatrix PlaneStrain::elastic_stiffness(const Rectangle& rect, const LameConstants& lame, ElementKind kind) const {
  // The paper's exact element; B-bar has no closed form here.
  return kind == ElementKind::q1 ? closed_form_stiffness(rect, lame) : Kinematics::elastic_stiffness(rect, lame, kind);
}

// ---------------------------------------------------------------------------------------------
namespace {
StrainDisplacement axisymmetric_q1(const Rectangle& rect, double xi, double eta) {
  const ShapeValues s = shape_values(rect, xi, eta);
  StrainDisplacement b = in_plane_rows(s);
  const double r = rect.x0 + xi * rect.width;  // Gauss points never lie on the axis
  for (int q = 0; q < 4; ++q) b(3, q) = s.n[q] / r;
  return b;
}
}  // namespace

namespace {
using DilatationRow = Eigen::Matrix<double, 1, 8>;

/// Q1's B at the four Gauss points of the ring element.
std::array<StrainDisplacement, 4> axisymmetric_q1_at_gauss_points(const Rectangle& rect) {
  const auto& points = gauss_points_2x2();
  std::array<StrainDisplacement, 4> b;
  for (std::size_t g = 0; g < points.size(); ++g) b[g] = axisymmetric_q1(rect, points[g].xi, points[g].eta);
  return b;
}

// Mean dilatation (Hughes 1980; Hughes, The Finite Element Method, §4.4): the dilatation
// eps11 + eps22 + eps33 at a point is replaced by its mean over the element's volume (weights
// 2 pi r dA, by the same 2x2 rule), a third of the shift on each normal strain.
DilatationRow mean_dilatation(const Axisymmetric& kinematics, const Rectangle& rect,
                              const std::array<StrainDisplacement, 4>& q1) {
  DilatationRow mean = DilatationRow::Zero();
  double volume = 0.0;
  const auto& points = gauss_points_2x2();
  for (std::size_t g = 0; g < points.size(); ++g) {
    const double w = points[g].weight * kinematics.measure(rect, points[g].xi);
    mean += w * (q1[g].row(0) + q1[g].row(1) + q1[g].row(3));
    volume += w;
  }
  return mean / volume;
}

void shift_to_mean_dilatation(StrainDisplacement& b, const DilatationRow& mean) {
  const DilatationRow shift = (mean - (b.row(0) + b.row(1) + b.row(3))) / 3.0;
  b.row(0) += shift;
  b.row(1) += shift;
  b.row(3) += shift;
}
}  // namespace

StrainDisplacement Axisymmetric::strain_displacement(const Rectangle& rect, double xi, double eta,
                                                     ElementKind kind) const {
  StrainDisplacement b = axisymmetric_q1(rect, xi, eta);
  if (kind == ElementKind::bbar)
    shift_to_mean_dilatation(b, mean_dilatation(*this, rect, axisymmetric_q1_at_gauss_points(rect)));
  return b;
}

std::array<StrainDisplacement, 4> Axisymmetric::gauss_point_strain_displacements(const Rectangle& rect,
                                                                                 ElementKind kind) const {
  // As strain_displacement at each point, with the element's mean dilatation formed once.
  std::array<StrainDisplacement, 4> b = axisymmetric_q1_at_gauss_points(rect);
  if (kind != ElementKind::bbar) return b;
  const DilatationRow mean = mean_dilatation(*this, rect, b);
  for (StrainDisplacement& bg : b) shift_to_mean_dilatation(bg, mean);
  return b;
}

GradientOperator Axisymmetric::gradient_operator(const Rectangle& rect, double xi, double eta) const {
  // F33 = 1 + u_r / R: the hoop stretch of the ring at reference radius R (Gauss points are off
  // the axis).
  const ShapeValues s = shape_values(rect, xi, eta);
  GradientOperator g = in_plane_gradient(s);
  const double r = rect.x0 + xi * rect.width;
  for (int q = 0; q < 4; ++q) g(4, q) = s.n[q] / r;
  return g;
}

double Axisymmetric::measure(const Rectangle& rect, double xi) const {
  return 2.0 * std::numbers::pi * (rect.x0 + xi * rect.width) * rect.width * rect.height;
}

double Axisymmetric::tributary_measure(double left, double x, double right) const {
  // 2 pi [ (x - left)(left + 2 x) / 6 + (right - x)(2 x + right) / 6 ]: the hat function of x
  // integrated against r over its two elements.
  return std::numbers::pi / 3.0 * ((x - left) * (left + 2.0 * x) + (right - x) * (2.0 * x + right));
}

double Axisymmetric::surface_density(double x) const { return 2.0 * std::numbers::pi * x; }

double Axisymmetric::nodal_force_scale(double stress_times_length, double contact) const {
  return stress_times_length * 2.0 * std::numbers::pi * contact;
}

std::shared_ptr<const Kinematics> make_kinematics(SceneKind kind) {
  static const auto plane = std::make_shared<const PlaneStrain>();
  static const auto axisymmetric = std::make_shared<const Axisymmetric>();
  return kind == SceneKind::axisymmetric ? std::shared_ptr<const Kinematics>(axisymmetric)
                                         : std::shared_ptr<const Kinematics>(plane);
}

}  // namespace indentsim
