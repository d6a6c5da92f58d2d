#pragma once
// The kinematics of a scene: how an element's nodal displacements make the four strain
// components the material laws take (include/indentsim/materials/material.hpp), and how much body a Gauss
// point stands for.  One implementation per scene kind (docs/MODEL.md §6):
//
//   PlaneStrain   the paper's scene: (x, y) in the plane, eps33 = 0, a body of unit thickness;
//                 the model is the half x >= 0 of a symmetric block, so the whole body's force
//                 is twice the modelled half's.
//   Axisymmetric  (x, y) = (r, z) of a body of revolution about x = 0: eps33 is the hoop strain
//                 u_r / r, and a Gauss point stands for the ring 2 pi r dA.  Nodal forces are
//                 whole-ring forces, so they sum to the body's force directly.
//
// Everything above the element (assembly, contact, layer view, output) asks the kinematics and
// never the scene kind: adding a kinematics is adding a class here.
#include <array>
#include <memory>
#include <string>

#include "indentsim/geometry/element.hpp"
#include "indentsim/materials/finite_strain.hpp"
#include "indentsim/materials/material.hpp"

namespace indentsim {

/// The 2x2 Gauss rule on one rectangle, evaluated once: B at each point of gauss_points_2x2() and
/// the body each point stands for (its weight times the measure).  Every element integral is a
/// sum over these four; elements of one class of equal rectangles share one (ElasticStiffness).
struct ElementQuadrature {
  std::array<StrainDisplacement, 4> b;
  std::array<double, 4> volume{};

  /// (eps11, eps22, gamma12, eps33) at each point from the element's 8 unknowns (paper order).
  std::array<VoigtVector, 4> strains(const ElementVector& ue) const;
  /// sum_g B_g^T D_g B_g dV_g
  ElementMatrix stiffness(const std::array<ConstitutiveMatrix, 4>& d) const;
  /// sum_g B_g^T sigma_g dV_g
  ElementVector internal_force(const std::array<VoigtVector, 4>& stress) const;
};

/// d F / d ue at a Gauss point: F = I + G ue in F's components (F11, F12, F21, F22, F33),
/// total Lagrangian (gradients with respect to the reference position).
using GradientOperator = Eigen::Matrix<double, 5, 8>;

/// The 2x2 Gauss rule on one rectangle for finite strain (docs/MODEL.md §12): the gradient operator
/// at each point and the reference body each point stands for.  For ElementKind::bbar it is the
/// F-bar element (de Souza Neto, Peric, Dutko and Owen, Int. J. Solids Struct. 33, 1996): the law
/// takes F-bar = (J-bar / J)^(1/d) F, with J-bar the element's volume mean of J = det F and d the
/// dimensions the dilatation acts in (2 in plane strain, where F33 = 1 stays; 3 about the axis);
/// its small-strain limit is mean dilatation (B-bar).  The internal force is
/// f = sum_g V_g G_g^T (tau(F-bar) F^-T), whose tangent is not symmetric.
struct FiniteStrainQuadrature {
  std::array<GradientOperator, 4> g;
  std::array<double, 4> volume{};
  bool f_bar = false;
  int dilatation_dimensions = 2;

  /// F at each point from the element's unknowns (paper order).
  std::array<Deformation, 4> gradients(const ElementVector& ue) const;
  /// What the law takes at each point: F, or F-bar.
  std::array<Deformation, 4> law_gradients(const ElementVector& ue) const;
  /// sum_g V_g G_g^T P_g with P_g the nominal stress of the law at law_gradients(ue) (F-bar:
  /// scaled back to F, P (J-bar / J)^(1/d) on the scaled components).
  ElementVector internal_force(const ElementVector& ue, const std::array<NominalStress, 4>& law_stress) const;
  /// d internal_force / d ue from the law's nominal stresses and tangents at law_gradients(ue).
  ElementMatrix stiffness(const ElementVector& ue, const std::array<NominalStress, 4>& law_stress,
                          const std::array<NominalTangent, 4>& law_tangent) const;
};

class Kinematics {
public:
  virtual ~Kinematics() = default;

  virtual SceneKind kind() const = 0;
  /// B at (xi, eta) of the rectangle: (eps11, eps22, gamma12, eps33) = B ue (B-bar for bbar).
  virtual StrainDisplacement strain_displacement(const Rectangle& rect, double xi, double eta,
                                                 ElementKind kind) const = 0;
  /// B at the four points of gauss_points_2x2(), in that order: what an element pass needs, in
  /// one call (B-bar's mean dilatation is then formed once, not once per point).
  virtual std::array<StrainDisplacement, 4> gauss_point_strain_displacements(const Rectangle& rect,
                                                                            ElementKind kind) const;
  /// The body a unit quadrature weight at abscissa xi stands for: the area (plane strain, per
  /// unit thickness) or the ring volume 2 pi r area (axisymmetry).
  virtual double measure(const Rectangle& rect, double xi) const = 0;
  /// The elastic element matrix: the paper's closed form where it holds, Gauss quadrature else.
  virtual ElementMatrix elastic_stiffness(const Rectangle& rect, const LameConstants& lame, ElementKind kind) const;
  /// Whether an element's matrices depend on where it lies, not only on its size.
  virtual bool position_dependent() const = 0;
  /// The whole body's force over the modelled part's nodal forces (2 for the symmetric half).
  virtual double symmetry_factor() const = 0;
  /// The surface a top node at x carries between its neighbours at `left` and `right` (equal to
  /// x at an end of the line): the load-consistent measure int N_x dS, which turns a uniform
  /// pressure into the node's force.  A length per unit thickness ((right - left) / 2), or the
  /// ring area 2 pi int N_x r dr -- not pi (r_+^2 - r_-^2), which is a third too small at the axis.
  virtual double tributary_measure(double left, double x, double right) const = 0;
  /// The surface a unit length of the top line at abscissa x stands for: 1 (per unit thickness)
  /// or the ring 2 pi x.  A traction t(x) on the top line makes the nodal forces
  /// int t N_k density dx (tributary_measure is int N_k density dx).
  virtual double surface_density(double x) const = 0;
  /// The size of a nodal force under a stress `stress` near the contact of radius `contact`
  /// (Newton's residual scale): stress x length in plane strain (per unit thickness, element
  /// size cancels against the strain's 1/h), stress x length x 2 pi r in axisymmetry.
  virtual double nodal_force_scale(double stress_times_length, double contact) const = 0;
  /// The unit of forces (per unit thickness in plane strain).
  virtual std::string force_unit() const = 0;
  /// "plane_strain" | "axisymmetric", as geometry.kind spells it.
  virtual std::string name() const = 0;
  /// The output name of stress component 33 (sigma33 out of plane; sigma_hoop).
  virtual std::string out_of_plane_stress() const = 0;

  /// d F / d ue at (xi, eta) of the rectangle (Q1; F-bar is FiniteStrainQuadrature's).
  virtual GradientOperator gradient_operator(const Rectangle& rect, double xi, double eta) const = 0;
  /// The dimensions a volume change acts in: 2 in plane strain (F33 = 1), 3 about the axis.
  virtual int dilatation_dimensions() const = 0;

  /// B and the measure at the four Gauss points of the rectangle.
  ElementQuadrature quadrature(const Rectangle& rect, ElementKind kind) const;
  /// The gradient operators and the reference measure at the four Gauss points (finite strain).
  FiniteStrainQuadrature finite_strain_quadrature(const Rectangle& rect, ElementKind kind) const;
  /// Stiffness by 2x2 Gauss quadrature with one constitutive matrix per Gauss point.
  ElementMatrix stiffness(const Rectangle& rect, const std::array<ConstitutiveMatrix, 4>& d, ElementKind kind) const;
  ElementMatrix stiffness(const Rectangle& rect, const ConstitutiveMatrix& d, ElementKind kind) const {
    return stiffness(rect, std::array<ConstitutiveMatrix, 4>{d, d, d, d}, kind);
  }
  /// Internal force sum_g w_g B_g^T sigma_g dV_g of the four Gauss-point stresses.
  ElementVector internal_force(const Rectangle& rect, const std::array<VoigtVector, 4>& stress, ElementKind kind) const;
};

class PlaneStrain final : public Kinematics {
public:
  SceneKind kind() const override { return SceneKind::plane_strain; }
  StrainDisplacement strain_displacement(const Rectangle& rect, double xi, double eta, ElementKind kind) const override;
  double measure(const Rectangle& rect, double) const override { return rect.width * rect.height; }
  GradientOperator gradient_operator(const Rectangle& rect, double xi, double eta) const override;
  int dilatation_dimensions() const override { return 2; }
  ElementMatrix elastic_stiffness(const Rectangle& rect, const LameConstants& lame, ElementKind kind) const override;
  bool position_dependent() const override { return false; }
  double symmetry_factor() const override { return 2.0; }
  double nodal_force_scale(double stress_times_length, double) const override { return stress_times_length; }
  double tributary_measure(double left, double x, double right) const override {
    return 0.5 * (x - left) + 0.5 * (right - x);
  }
  double surface_density(double) const override { return 1.0; }
  std::string force_unit() const override { return "N/m"; }
  std::string name() const override { return "plane_strain"; }
  std::string out_of_plane_stress() const override { return "sigma33"; }
};

/// The axisymmetric Q1 (and its mean-dilatation B-bar): the paper's closed-form matrix does not
/// apply (the integrand carries r and 1/r), so 2x2 Gauss quadrature is the element.
class Axisymmetric final : public Kinematics {
public:
  SceneKind kind() const override { return SceneKind::axisymmetric; }
  StrainDisplacement strain_displacement(const Rectangle& rect, double xi, double eta, ElementKind kind) const override;
  std::array<StrainDisplacement, 4> gauss_point_strain_displacements(const Rectangle& rect,
                                                                    ElementKind kind) const override;
  double measure(const Rectangle& rect, double xi) const override;
  GradientOperator gradient_operator(const Rectangle& rect, double xi, double eta) const override;
  int dilatation_dimensions() const override { return 3; }
  bool position_dependent() const override { return true; }
  double symmetry_factor() const override { return 1.0; }
  double nodal_force_scale(double stress_times_length, double contact) const override;
  double tributary_measure(double left, double x, double right) const override;
  double surface_density(double x) const override;
  std::string force_unit() const override { return "N"; }
  std::string name() const override { return "axisymmetric"; }
  std::string out_of_plane_stress() const override { return "sigma_hoop"; }
};

/// The kinematics of a scene kind (shared: kinematics are stateless).
std::shared_ptr<const Kinematics> make_kinematics(SceneKind kind);

}  // namespace indentsim
