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
