#pragma once
// Material laws with a history at every Gauss point of the mesh: Ilyushin's deformation theory
// (docs/MODEL.md §4-5), with Ilyushin's unloading rule when the load path unloads, and
// incremental J2 flow theory.  Pointwise: strain in, stress, tangent and history out; the element
// loop that turns them into forces is InelasticBulk (solvers/inelastic_bulk.hpp).
#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/StdVector>

#include "indentsim/materials/material.hpp"

namespace indentsim {

/// One strain per Gauss point of the mesh (index = 4 * element + point).
using PointStrains = std::vector<VoigtVector, Eigen::aligned_allocator<VoigtVector>>;

/// The response of one Gauss point, with its committed history.
struct PointResponse {
  VoigtVector stress = VoigtVector::Zero();
  ConstitutiveMatrix tangent = ConstitutiveMatrix::Zero();
  double strain_intensity = 0.0;
  double omega = 0.0;
  bool plastic = false;  ///< on a plastic branch now
};

/// A material law with history at every Gauss point of the mesh (index = 4 * element + point).
class PointLaw {
public:
  virtual ~PointLaw() = default;
  /// True when the point responds exactly elastically at `strain` (no yielding, no history).
  virtual bool elastic(std::size_t point, const VoigtVector& strain) const = 0;
  virtual PointResponse respond(std::size_t point, const VoigtVector& strain) const = 0;
  /// d sigma / d theta at fixed strain and fixed history, for theta = e0, kappa or n; nullopt when
  /// the stress depends on the parameter through the history as well (then only finite
  /// differences of whole runs give the sensitivity).
  virtual std::optional<VoigtVector> stress_parameter_derivative(std::size_t /*point*/, const VoigtVector& /*strain*/,
                                                                 MaterialParameter /*parameter*/) const {
    return std::nullopt;
  }
  /// Takes d eps / d theta at every point of the current (converged) state, from the state's
  /// displacement sensitivity, for a law whose history is a function of the state at an earlier
  /// time (Ilyushin's peak strain): afterwards stress_parameter_derivative can account for the
  /// history's own dependence on theta.  Laws without such a history ignore it.
  virtual void record_strain_derivatives(MaterialParameter /*parameter*/, PointStrains /*d_strain*/) {}
  /// Accepts `strain` as the converged state of the point.
  virtual void commit(std::size_t point, const VoigtVector& strain) = 0;
  /// The point has yielded at some time.
  virtual bool has_yielded(std::size_t point) const = 0;
  /// Whether the load path is beyond its deepest point so far (for laws whose branch follows
  /// the global load history); incremental laws ignore it.
  virtual void set_loading(bool /*beyond_previous_peak*/) {}
  /// The duration [s] of the (sub-)increment the next responses and commits close (docs/MODEL.md
  /// §13.2): what a rate-dependent law integrates its flow over; rate-independent laws ignore it.
  virtual void set_time_step(double /*seconds*/) {}
  /// The carried state of every point, flattened, and its restoration (checkpoints).
  virtual std::vector<double> history() const = 0;
  virtual void restore(const std::vector<double>& history) = 0;
  /// What is wrong with the point's history at the committed `strain`, or nothing: a history the
  /// law can carry (within its bounds) and that committing that strain leaves.  A checkpoint's
  /// history is checked so before a run continues from it.
  virtual std::optional<std::string> history_violation(std::size_t point, const VoigtVector& strain) const = 0;
};

/// Ilyushin's deformation theory.  Without unloading rule: the secant law, path independent.
/// With it (load paths that unload), Ilyushin's unloading theorem: once the depth falls below
/// the deepest point reached so far, the whole body unloads elastically from the state at that
/// peak, sigma = sigma(eps*) + D (eps - eps*) with eps* the strain at the peak; reloading stays on
/// that elastic branch until the peak depth is regained, where the state is the peak state again
/// (the elastic branch is reversible), and the deformation law resumes, continuously.
/// Limits: the deformation law itself ignores local unloading inside the body while the punch
/// goes deeper, and the unloading branch is linear elastic (no reverse yielding, no Bauschinger
/// effect).  J2 flow theory has neither limitation.
class IlyushinPointLaw : public PointLaw {
public:
  IlyushinPointLaw(const IlyushinLaw& law, bool unloading_rule, std::size_t points);
  bool elastic(std::size_t point, const VoigtVector& strain) const override;
  PointResponse respond(std::size_t point, const VoigtVector& strain) const override;
  /// On loading the secant law has no history: d sigma_L(eps)/d theta.  On the unloading branch
  /// sigma = sigma_L(eps*) + D (eps - eps*) depends on theta through the peak strain as well:
  ///   d sigma / d theta = d sigma_L(eps*)/d theta + (C_L(eps*) - D) d eps*/d theta
  /// (C_L the loading law's tangent; D does not depend on e0, kappa, n), with d eps*/d theta as
  /// recorded at the peak (record_strain_derivatives); nullopt when it was not recorded.
  std::optional<VoigtVector> stress_parameter_derivative(std::size_t point, const VoigtVector& strain,
                                                         MaterialParameter parameter) const override;
  /// While loading, the current state is the peak: d eps/d theta becomes d eps*/d theta.  The peak
  /// moves with every loading commit, which forgets what was recorded.
  void record_strain_derivatives(MaterialParameter parameter, PointStrains d_strain) override;
  void commit(std::size_t point, const VoigtVector& strain) override;
  bool has_yielded(std::size_t point) const override { return peak_intensity_[point] > law_.elastic_limit(); }
  void set_loading(bool beyond_previous_peak) override { loading_ = !unloading_rule_ || beyond_previous_peak; }
  std::vector<double> history() const override;
  void restore(const std::vector<double>& history) override;
  /// The peak intensity is e_u of the peak strain; while loading, the peak is the committed strain.
  std::optional<std::string> history_violation(std::size_t point, const VoigtVector& strain) const override;
  const IlyushinLaw& law() const { return law_; }

private:
  IlyushinLaw law_;
  bool unloading_rule_;
  bool loading_ = true;
  ConstitutiveMatrix elastic_;
  PointStrains peak_strain_;                                      // eps* per point
  std::vector<double> peak_intensity_;                            // e_u(eps*) per point
  std::map<MaterialParameter, PointStrains> peak_strain_derivative_;  // d eps*/d theta, as recorded
};

/// J2 flow theory with any flow rule (materials/flow_rule.hpp); plastic strain and equivalent
/// plastic strain are the carried state.  A rate-dependent rule flows over the time step set last
/// (set_time_step).
class J2PointLaw : public PointLaw {
public:
  J2PointLaw(const J2Law& law, std::size_t points);
  bool elastic(std::size_t point, const VoigtVector& strain) const override;
  PointResponse respond(std::size_t point, const VoigtVector& strain) const override;
  void commit(std::size_t point, const VoigtVector& strain) override;
  bool has_yielded(std::size_t point) const override { return state_[point].equivalent_plastic_strain > 0.0; }
  void set_time_step(double seconds) override { time_step_ = seconds; }
  std::vector<double> history() const override;
  void restore(const std::vector<double>& history) override;
  /// The plastic strain is a deviator no longer than the path it accumulated along,
  /// |eps_p| <= sqrt(3/2) eps_p_bar (every return adds sqrt(3/2) dgamma n, |n| = 1), and the
  /// committed strain's trial stress lies on or inside the yield surface of eps_p_bar (a
  /// converged state returns no further plastic strain; a rate-dependent rule's state lies
  /// anywhere, as its instantaneous response flows nothing).
  std::optional<std::string> history_violation(std::size_t point, const VoigtVector& strain) const override;

private:
  J2Law law_;
  double initial_yield_ = 0.0;
  double time_step_ = 0.0;
  std::vector<J2State, Eigen::aligned_allocator<J2State>> state_;
};

}  // namespace indentsim
