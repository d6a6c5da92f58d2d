#pragma once
// Finite-strain kinematics at a point (docs/MODEL.md §12): the logarithmic (Hencky) strain of a
// deformation gradient and the nominal stress of a Kirchhoff stress, with their derivatives, so
// that the small-strain laws (material.hpp) act unchanged on Hencky strains -- the exponential-map
// framework of Eterovic and Bathe (IJNME 30, 1990), Simo (CMAME 99, 1992) and de Souza Neto, Peric
// and Owen (Computational Methods for Plasticity, 2008, ch. 14).
//
// The scenes' deformation gradients are block diagonal: the in-plane 2x2 block and the
// out-of-plane stretch F33 (1 in plane strain; the hoop stretch r / R about the axis).  They are
// held in five components (F11, F12, F21, F22, F33), 1 the horizontal (radial) direction and 2 the
// vertical, as the first Piola-Kirchhoff stress P and its tangent dP/dF are.  The element pairs P
// with the gradient of the virtual displacement (total Lagrangian): f = int G^T P dV_0.
#include <Eigen/Core>

#include "indentsim/materials/material.hpp"

namespace indentsim {

/// (F11, F12, F21, F22, F33).
using DeformationGradient = Eigen::Matrix<double, 5, 1>;
/// The first Piola-Kirchhoff stress P in F's components.
using NominalStress = Eigen::Matrix<double, 5, 1>;
/// dP/dF on F's components.
using NominalTangent = Eigen::Matrix<double, 5, 5>;
/// d(strain in Voigt form) / dF.
using StrainGradient = Eigen::Matrix<double, 4, 5>;

/// The identity in F's components.
DeformationGradient identity_deformation();

/// A deformation gradient F = I + H held with its displacement gradient H (in F's components), of
/// which the strains are computed: F rounds a strain to 1e-16 absolute, H keeps its relative
/// precision.  A coarse element far from the punch strains by 1e-9 and less, and that rounding,
/// times its stiffness, made a residual above Newton's tolerance (docs/MODEL.md §12.2, §12.4).
class Deformation {
public:
  /// No deformation: F = I.
  Deformation() : F_(identity_deformation()) {}
  /// From F, with H = F - I: as precise as F itself (the tests' homogeneous gradients).
  Deformation(const DeformationGradient& F);  // NOLINT(google-explicit-constructor): F is a deformation
  static Deformation from_displacement_gradient(const DeformationGradient& H);
  const DeformationGradient& F() const { return F_; }
  const DeformationGradient& H() const { return H_; }

private:
  DeformationGradient F_, H_ = DeformationGradient::Zero();
};

/// A symmetric tensor of the scenes, in Voigt order (11, 22, 12, 33) with the tensor's own 12
/// component (not the engineering shear): the metric tensors C_p^-1 and b_e.
using SymmetricTensor = Eigen::Vector4d;
SymmetricTensor identity_tensor();

/// The logarithmic strain e = 1/2 ln(F G F^T) as a Voigt strain (e11, e22, 2 e12, e33), with its
/// derivative with respect to F at fixed G.  G = I gives the Hencky strain of F; G = C_p^-1 gives
/// the trial elastic strain of the multiplicative split F = F_e F_p.
struct LogarithmicStrain {
  VoigtVector strain = VoigtVector::Zero();
  StrainGradient derivative = StrainGradient::Zero();
};
/// Computed from H and G - I, so that it is as precise relative to e as H and G are.
LogarithmicStrain logarithmic_strain(const Deformation& F, const SymmetricTensor& G);

/// exp(2 e) of a tensor strain e given as a Voigt strain (e11, e22, 2 e12, e33): the elastic left
/// Cauchy-Green tensor b_e of an elastic logarithmic strain.
SymmetricTensor exponential_of_twice(const VoigtVector& strain);

/// F^-1 b F^-T: the inverse plastic right Cauchy-Green tensor C_p^-1 of F and b_e.
SymmetricTensor pull_back(const DeformationGradient& F, const SymmetricTensor& b);

/// The nominal stress P = tau F^-T of a Kirchhoff stress tau (Voigt 11, 22, 12, 33), and dP/dF
/// from d tau / d strain (`tangent`, on the engineering Voigt strain) and d strain / dF.
struct NominalResponse {
  NominalStress stress = NominalStress::Zero();
  NominalTangent tangent = NominalTangent::Zero();
};
NominalResponse nominal_response(const DeformationGradient& F, const VoigtVector& kirchhoff,
                                 const ConstitutiveMatrix& tangent, const StrainGradient& strain_derivative);

/// The Kirchhoff stress, and its tangent on the logarithmic strain e, of a law that gives the
/// stress s(e) of `measure` with tangent ds/de (docs/MODEL.md §12.2): tau = s for the Kirchhoff
/// stress; for the Cauchy stress tau = J s, J = e^{tr e}, d tau / d e = J (ds/de + s m^T) with
/// m = d tr e / d e = (1, 1, 0, 1).  `stress` and `tangent` are replaced by tau and d tau / d e.
void express_in_kirchhoff_stress(ElasticStressMeasure measure, const VoigtVector& strain, VoigtVector& stress,
                                 ConstitutiveMatrix& tangent);

/// J = det F.
double jacobian(const DeformationGradient& F);
/// J - 1, as precise as H.
double jacobian_excess(const Deformation& F);

}  // namespace indentsim
