#pragma once
// The discretization error of a run, estimated with the run (mesh.error_estimate).
//
// The error of the force P and of the contact half-width a falls with the fine-zone spacing h
// as C h^p.  Two runs of the same case whose spacings differ by r = h_coarse / h_fine give
// Richardson's extrapolation
//     P* = P_h + (P_h - P_rh) / (r^p - 1),      error of P_h ~ |P_h - P*|,
// the classical a posteriori estimate of a mesh sequence (Richardson 1911; Roache, Verification
// and Validation in Computational Science and Engineering, 1998, ch. 5).  The companion run is
// the same case on the same plan (the main run's planned contact width, no pilot) with half the
// contact nodes: about an eighth of the work of the run itself (9-15% measured, docs/performance.md).
//
// The orders: P converges at p = 2 (the work-precision study measures 1.6-2.3 on the shipped
// cases; an estimate with p = 2 stays within a factor 1.5 of the truth for any p in [1.6, 2.6]);
// a is located to within a node spacing and converges at first order, p = 1.  With
// mesh.error_estimate = "observed" a second companion at a quarter of the contact nodes gives
// the order of P at each increment from the three meshes instead (where the three values are in
// the asymptotic range: monotone, with an order in [0.5, 6]; the nominal order otherwise).
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "indentsim/input/load_case.hpp"
#include "indentsim/simulation/load_stepping.hpp"
#include "indentsim/simulation/simulation.hpp"

namespace indentsim {

/// Richardson's extrapolation of a value computed on a fine mesh and on one coarser by `ratio`
/// (of the spacings, > 1), for an error of order `order`.
struct RichardsonEstimate {
  double extrapolated = 0.0;  ///< P* = fine + (fine - coarse) / (ratio^order - 1)
  double error = 0.0;         ///< |fine - extrapolated|
};
RichardsonEstimate richardson(double fine, double coarse, double ratio, double order);

/// The order p of f(h) = f* + C h^p through three values on spacings h1 < h2 < h3; nullopt when
/// they are not in the asymptotic range (not monotone in h, or p outside [0.5, 6]).
std::optional<double> observed_order(double f1, double f2, double f3, double h1, double h2, double h3);

/// A coarser run of the same case, kept as its curve.
struct CompanionRun {
  int contact_nodes = 0;
  std::vector<IncrementRecord> curve;
  std::string failure;  ///< why it stopped before the end of the load path ("" when it did not)
  double wall_seconds = 0.0;
};

/// True when a run's result depends on the path between its increments, not on the depth alone:
/// J2 flow theory and friction carry a history; elasticity and Ilyushin's deformation theory do not.
bool depends_on_the_increments(const LoadCase& load_case);

/// The same case with half the increments in each segment of its load path (at least one).
LoadCase with_halved_increments(const LoadCase& load_case);

/// What halving the increments does to P at the deepest point of the path, on the first
/// companion's mesh: the path integration's error of a history-dependent run, which the mesh
/// companions do not see (docs/DESIGN.md §16).  Where the integration is in its first-order range
/// the change is about the error of the run's own increments; where it is not (a J2 sphere or cone
/// needs several increments for each node entering contact) the error is larger than the change.
struct IncrementSensitivity {
  int contact_nodes = 0;                  ///< of the mesh it was measured on (the first companion's)
  double alpha = 0.0;                     ///< the deepest depth of the path [m]
  double force = 0.0;                     ///< P there with the run's increments [N/m or N]
  double force_halved = 0.0;              ///< with half of them
  double relative_change() const { return force != 0.0 ? std::abs(force - force_halved) / std::abs(force) : 0.0; }
};
/// A relative change beyond this is warned about, naming load.increments.
inline constexpr double increment_change_warning = 0.005;

/// Why `load_case` cannot have the error estimate it asks for (its companions would have fewer
/// than 2 contact nodes), or nullopt.  Such a run goes without one, with this as a warning.
std::optional<std::string> error_estimate_unavailable(const LoadCase& load_case);
/// The contact_nodes of the companion runs (half the run's; for "observed" also a quarter), or
/// none when the estimate is off or unavailable.
std::vector<int> companion_contact_nodes(const LoadCase& load_case);

/// The order p of P - P_exact ~ h^p that the estimate assumes for a load case: the punch shape's
/// (PunchShape::force_convergence_order: 2, or 1 under a flat punch's singular rim), lowered to 1.5
/// for a plastic material -- the tangent jumps across the elastic-plastic boundary, and at the
/// default meshes the orders measured between successive meshes were 1.3-2.0 on deep_plastic
/// (rising to 2 only beyond 24 contact nodes) against 1.9-2.0 on the elastic cases.  A lower
/// order errs on the safe side: where the true order is 2 the estimate is 1.6x the error.
double force_order_assumed(const LoadCase& load_case);

class DiscretizationErrorEstimate {
public:
  static constexpr double nominal_force_order = 2.0;  ///< of a bounded pressure (PunchShape)
  static constexpr double nominal_width_order = 1.0;

  /// Runs the companions of `main` (only its load case and plan are used; it need not have run):
  /// contact_nodes / 2, and / 4 for "observed".  Throws std::invalid_argument when the estimate
  /// is off or unavailable (error_estimate_unavailable), Interrupted on a stop signal; a
  /// companion that does not converge is kept up to where it stopped (rows beyond have no
  /// estimate) and said in warnings().
  explicit DiscretizationErrorEstimate(const Simulation& main);
  /// The same from the main run's load case and plan alone, before its model is built: a new run
  /// starts its companions on a second thread while it builds its own (run_driver.cpp).
  DiscretizationErrorEstimate(const LoadCase& main_case, const RunPlan& main_plan);

  struct AtIncrement {
    double force_error = 0.0;         ///< estimated |P - P_exact| [N/m or N]
    double width_error = 0.0;         ///< estimated |a - a_exact| [m]
    double force_extrapolated = 0.0;  ///< Richardson's P*
    double force_order = 0.0;         ///< the order used for P (nominal or observed)
    bool order_observed = false;
  };
  /// The estimate for one increment of the main run (matched by step and depth), nullopt where a
  /// companion has no such increment (it stopped before it).
  std::optional<AtIncrement> at(const IncrementRecord& row) const;

  ErrorEstimateChoice method() const { return method_; }
  /// The order assumed for P (force_order_assumed).
  double force_order() const { return force_order_; }
  int contact_nodes() const { return contact_nodes_; }  ///< of the main run
  const std::vector<CompanionRun>& companions() const { return companions_; }
  /// For a run that depends on its increments: P at the deepest point on the first companion's
  /// mesh with the run's increments and with half of them (nullopt otherwise, or when either
  /// companion stopped before that point).
  const std::optional<IncrementSensitivity>& increment_sensitivity() const { return increment_sensitivity_; }
  double wall_seconds() const;
  const std::vector<std::string>& warnings() const { return warnings_; }

private:
  const IncrementRecord* companion_row(std::size_t companion, const IncrementRecord& row) const;

  ErrorEstimateChoice method_;
  double force_order_ = nominal_force_order;
  int contact_nodes_ = 0;
  std::vector<CompanionRun> companions_;
  std::optional<IncrementSensitivity> increment_sensitivity_;
  double halved_wall_seconds_ = 0.0;  ///< the halved-increments companion's
  std::vector<std::string> warnings_;
};

/// How mesh.target_error chose a run's mesh and increments: the runs before it (the pilots, and a
/// run whose estimate missed the target), each with its contact nodes, its increments, the
/// relative error it estimated of the final P and, for a run that depends on its increments,
/// the relative change of P that halving them made.  The run itself reports its own estimates
/// against the target.
struct TargetErrorChoice {
  struct Attempt {
    std::string role;  ///< "pilot" or "run"
    int contact_nodes = 0;
    int increments = 0;
    double relative_error = 0.0;             ///< estimated |P - P_exact| / |P| at the final increment
    std::optional<double> increment_change;  ///< IncrementSensitivity::relative_change, where measured
  };
  double target = 0.0;
  std::vector<Attempt> attempts;
  bool retried = false;  ///< a run missed and was refined once (it is not refined twice)
};

/// The relative error estimate of a curve's final P (of its peak force when the curve ends at
/// P = 0, unloaded); nullopt when the estimate has no such increment.
std::optional<double> relative_force_error(const DiscretizationErrorEstimate& estimate,
                                           const std::vector<IncrementRecord>& curve);

/// mesh.target_error's plan: pilots of the case, in memory, each with its error estimate, from
/// `first_pilot_contact_nodes` up.  A pilot whose estimate asks for more than twice its contact
/// nodes is followed by one at twice them, at most five times (the prediction from a coarse pilot
/// is where an estimate is least asymptotic; a run at N costs about N^3, so the pilots together
/// cost about 8/7 of the last one, between a seventh of the run and about as much again), so that
/// the run is the cheapest whose estimate meets the target.  For a
/// run that depends on its increments the path comes first: a pilot whose change on halving its
/// increments misses the target is repeated on the same mesh with more of them
/// (increments_factor_for_target; at most 16 times the case's), and the run takes the last
/// pilot's increments.  Records the pilots in
/// `choice` (whose target it sets) and returns the case to run: mesh.contact_nodes and the
/// increments chosen, mesh.target_error cleared.
LoadCase plan_case_for_target(const LoadCase& load_case, TargetErrorChoice& choice, int first_pilot_contact_nodes = 10);

/// The case to run after `as_run` missed the target with the estimates of `missed`: finer where
/// the mesh's estimate missed, more increments where the increments' change did.
LoadCase refine_case_for_target(const LoadCase& as_run, const TargetErrorChoice::Attempt& missed, double target);

/// The factor on a path's increments for which its first-order increment error, measured as the
/// change `relative_change` that halving them makes, meets `target` (with a margin of 15%);
/// 1 where it already does, at most 16.
int increments_factor_for_target(double relative_change, double target);

/// mesh.target_error: the contact nodes for a relative error `target` of the final P, from an
/// estimate `relative_error` measured at `contact_nodes` and the error's order (with a margin of
/// 15% on the spacing, so that a case just in the asymptotic range meets the target).
int contact_nodes_for_target(double relative_error, int contact_nodes, double target,
                             double order = DiscretizationErrorEstimate::nominal_force_order);

}  // namespace indentsim
