#include "indentsim/materials/finite_strain.hpp"

#include <cmath>

#include <Eigen/Dense>

namespace indentsim {

namespace {

using Matrix2 = Eigen::Matrix2d;

Matrix2 in_plane(const DeformationGradient& F) { return (Matrix2() << F[0], F[1], F[2], F[3]).finished(); }
Matrix2 symmetric_in_plane(const SymmetricTensor& t) { return (Matrix2() << t[0], t[2], t[2], t[1]).finished(); }
/// The unit matrix of F's in-plane component k (0: 11, 1: 12, 2: 21, 3: 22).
Matrix2 unit(int k) {
  Matrix2 e = Matrix2::Zero();
  e(k / 2, k % 2) = 1.0;
  return e;
}

/// g(y) = atanh(sqrt y) / sqrt y and g'(y), smooth in y = (r / m)^2 for 0 <= y < 1: the divided
/// difference (ln l1 - ln l2) / (l1 - l2) of a 2x2 symmetric matrix with eigenvalues m +- r is
/// g(y) / m.  Below y = 1e-2 the series sum y^k / (2k + 1) (12 terms: error below 1e-24) avoids
/// the cancellation of the closed form.
struct DividedLogDifference {
  double g, dg;
};
DividedLogDifference divided_log_difference(double y) {
  if (y < 1e-2) {
    double g = 0.0, dg = 0.0, power = 1.0;
    for (int k = 0; k < 12; ++k) {
      g += power / (2 * k + 1);
      if (k + 1 < 12) dg += (k + 1) * power / (2 * k + 3);
      power *= y;
    }
    return {g, dg};
  }
  const double s = std::sqrt(y);
  const double g = std::atanh(s) / s;
  return {g, (1.0 / (1.0 - y) - g) / (2.0 * y)};
}

/// ln M of a symmetric positive definite 2x2 M = I + X and its directional derivative, from X.
/// A function f of a 2x2 matrix is alpha I + beta M (Cayley-Hamilton): with eigenvalues l = m +- r,
///   beta = (ln l1 - ln l2) / (l1 - l2) = g(r^2 / m^2) / m,  alpha = 1/2 ln det M - beta m,
/// both smooth in M's entries, equal eigenvalues included (no eigenvectors are formed).  Written
/// as ln M = (1/2 ln det M - beta (m - 1)) I + beta X with ln det M = log1p(det M - 1) and
/// det M - 1 = tr X + det X, it is as precise relative to ln M as X is: no 1 is added and taken
/// away again.
class SymmetricLogarithm {
public:
  explicit SymmetricLogarithm(const Matrix2& x) : x_(x), m_(Matrix2::Identity() + x) {
    mean_excess_ = 0.5 * (x(0, 0) + x(1, 1));
    mean_ = 1.0 + mean_excess_;
    const double half_difference = 0.5 * (x(0, 0) - x(1, 1));
    q_ = half_difference * half_difference + x(0, 1) * x(0, 1);
    const double det_excess = x(0, 0) + x(1, 1) + (x(0, 0) * x(1, 1) - x(0, 1) * x(0, 1));
    det_ = 1.0 + det_excess;
    log_det_ = std::log1p(det_excess);
    y_ = q_ / (mean_ * mean_);
    d_ = divided_log_difference(y_);
    beta_ = d_.g / mean_;
  }
  Matrix2 value() const { return (0.5 * log_det_ - beta_ * mean_excess_) * Matrix2::Identity() + beta_ * x_; }
  /// d ln M [dM] for a symmetric dM.
  Matrix2 derivative(const Matrix2& dm) const {
    const double d_mean = 0.5 * (dm(0, 0) + dm(1, 1));
    const double d_q = 0.5 * (m_(0, 0) - m_(1, 1)) * (dm(0, 0) - dm(1, 1)) + 2.0 * m_(0, 1) * dm(0, 1);
    const double d_det = dm(0, 0) * m_(1, 1) + m_(0, 0) * dm(1, 1) - 2.0 * m_(0, 1) * dm(0, 1);
    const double d_y = d_q / (mean_ * mean_) - 2.0 * q_ * d_mean / (mean_ * mean_ * mean_);
    const double d_beta = d_.dg * d_y / mean_ - d_.g * d_mean / (mean_ * mean_);
    const double d_alpha = 0.5 * d_det / det_ - d_beta * mean_ - beta_ * d_mean;
    return d_alpha * Matrix2::Identity() + d_beta * m_ + beta_ * dm;
  }

private:
  Matrix2 x_, m_;
  double mean_excess_ = 0.0, mean_ = 0.0, q_ = 0.0, det_ = 0.0, log_det_ = 0.0, y_ = 0.0, beta_ = 0.0;
  DividedLogDifference d_{};
};

}  // namespace

DeformationGradient identity_deformation() { return (DeformationGradient() << 1.0, 0.0, 0.0, 1.0, 1.0).finished(); }
SymmetricTensor identity_tensor() { return SymmetricTensor(1.0, 1.0, 0.0, 1.0); }

Deformation::Deformation(const DeformationGradient& F) : F_(F), H_(F - identity_deformation()) {}

Deformation Deformation::from_displacement_gradient(const DeformationGradient& H) {
  Deformation d;
  d.H_ = H;
  d.F_ = identity_deformation() + H;
  return d;
}

double jacobian(const DeformationGradient& F) { return (F[0] * F[3] - F[1] * F[2]) * F[4]; }

double jacobian_excess(const Deformation& F) {
  const DeformationGradient& h = F.H();
  const double in_plane_excess = h[0] + h[3] + (h[0] * h[3] - h[1] * h[2]);
  return in_plane_excess + h[4] * (1.0 + in_plane_excess);
}

LogarithmicStrain logarithmic_strain(const Deformation& deformation, const SymmetricTensor& G) {
  const DeformationGradient& F = deformation.F();
  const Matrix2 f = in_plane(F), g = symmetric_in_plane(G), h = in_plane(deformation.H());
  // b - I = (G - I) + H G + G H^T + H G H^T of F G F^T with F = I + H.
  const Matrix2 g_excess = g - Matrix2::Identity(), hg = h * g;
  const Matrix2 b_excess = g_excess + hg + hg.transpose() + hg * h.transpose();
  const SymmetricLogarithm log_b(0.5 * (b_excess + b_excess.transpose()));
  const Matrix2 l = log_b.value();
  LogarithmicStrain e;
  // e = 1/2 ln b; the engineering shear is 2 e12 = l12.  e33 = ln F33 + 1/2 ln G33.
  e.strain = VoigtVector(0.5 * l(0, 0), 0.5 * l(1, 1), l(0, 1),
                         std::log1p(deformation.H()[4]) + 0.5 * std::log1p(G[3] - 1.0));
  for (int k = 0; k < 4; ++k) {
    const Matrix2 db = unit(k) * g * f.transpose() + f * g * unit(k).transpose();
    const Matrix2 dl = log_b.derivative(db);
    e.derivative.col(k) << 0.5 * dl(0, 0), 0.5 * dl(1, 1), dl(0, 1), 0.0;
  }
  e.derivative.col(4) << 0.0, 0.0, 0.0, 1.0 / F[4];
  return e;
}

SymmetricTensor exponential_of_twice(const VoigtVector& strain) {
  // exp M = alpha I + beta M with beta = (e^l1 - e^l2) / (l1 - l2) = e^m sinh(r) / r and
  // alpha = e^m cosh(r) - beta m, for M = 2 e with eigenvalues m +- r.
  const Matrix2 m = (Matrix2() << 2.0 * strain[0], strain[2], strain[2], 2.0 * strain[1]).finished();
  const double mean = 0.5 * (m(0, 0) + m(1, 1));
  const double half_difference = 0.5 * (m(0, 0) - m(1, 1));
  const double r = std::sqrt(half_difference * half_difference + m(0, 1) * m(0, 1));
  const double sinhc = r < 1e-4 ? 1.0 + r * r / 6.0 + r * r * r * r / 120.0 : std::sinh(r) / r;
  const double beta = std::exp(mean) * sinhc, alpha = std::exp(mean) * std::cosh(r) - beta * mean;
  const Matrix2 b = alpha * Matrix2::Identity() + beta * m;
  return SymmetricTensor(b(0, 0), b(1, 1), b(0, 1), std::exp(2.0 * strain[3]));
}

SymmetricTensor pull_back(const DeformationGradient& F, const SymmetricTensor& b) {
  const Matrix2 f_inverse = in_plane(F).inverse();
  const Matrix2 c = f_inverse * symmetric_in_plane(b) * f_inverse.transpose();
  return SymmetricTensor(c(0, 0), c(1, 1), 0.5 * (c(0, 1) + c(1, 0)), b[3] / (F[4] * F[4]));
}

NominalResponse nominal_response(const DeformationGradient& F, const VoigtVector& kirchhoff,
                                 const ConstitutiveMatrix& tangent, const StrainGradient& strain_derivative) {
  const Matrix2 f_inverse_t = in_plane(F).inverse().transpose();
  const Matrix2 tau = (Matrix2() << kirchhoff[0], kirchhoff[2], kirchhoff[2], kirchhoff[1]).finished();
  const double f33 = F[4];
  NominalResponse r;
  const Matrix2 p = tau * f_inverse_t;
  r.stress << p(0, 0), p(0, 1), p(1, 0), p(1, 1), kirchhoff[3] / f33;
  // dP = d tau F^-T + tau d(F^-T), d(F^-T) = -F^-T dF^T F^-T; P33 = tau33 / F33.
  const Eigen::Matrix<double, 4, 5> d_tau = tangent * strain_derivative;
  for (int k = 0; k < 5; ++k) {
    const Matrix2 dt = (Matrix2() << d_tau(0, k), d_tau(2, k), d_tau(2, k), d_tau(1, k)).finished();
    Matrix2 dp = dt * f_inverse_t;
    if (k < 4) dp -= tau * f_inverse_t * unit(k).transpose() * f_inverse_t;
    r.tangent.col(k) << dp(0, 0), dp(0, 1), dp(1, 0), dp(1, 1),
        d_tau(3, k) / f33 - (k == 4 ? kirchhoff[3] / (f33 * f33) : 0.0);
  }
  return r;
}

void express_in_kirchhoff_stress(ElasticStressMeasure measure, const VoigtVector& strain, VoigtVector& stress,
                                 ConstitutiveMatrix& tangent) {
  if (measure == ElasticStressMeasure::kirchhoff) return;
  // tau = J sigma with J = exp(e11 + e22 + e33): dJ/de = J m.
  const double J = std::exp(strain[0] + strain[1] + strain[3]);
  const VoigtVector m(1.0, 1.0, 0.0, 1.0);
  tangent = J * (tangent + stress * m.transpose());
  stress *= J;
}

}  // namespace indentsim
