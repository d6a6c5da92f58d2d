#pragma once
// The load path: the depth alpha is stepped along piecewise-linear waypoints.
#include <cstddef>
#include <vector>

#include "indentsim/input/load_case.hpp"

namespace indentsim {

/// Depths at the end of each planned increment (alpha_0 = 0 first, then `increments` values).
/// Increments are spread over the segments in proportion to their length |delta alpha|
/// (largest-remainder rounding, at least one per non-empty segment), uniform within a segment.
std::vector<double> plan_increments(const std::vector<double>& path, int increments);
/// The increments of each segment of the load case's path: its per-segment counts, or its total
/// spread as above -- by the segments' durations when it gives load.times (a hold is a segment
/// too), else by their lengths.
std::vector<int> segment_increments(const LoadInput& load);
/// The targets at the end of each planned increment of the load case (segment_increments).
std::vector<double> plan_increments(const LoadInput& load);
/// The time [s] of each planned increment, t_s + (t_{s+1} - t_s) k / n along its segment
/// (docs/MODEL.md §13.2); empty when the case gives no load.times.
std::vector<double> plan_times(const LoadInput& load);

/// One unloading branch of a depth sequence (a planned path, a run's curve, a measured
/// displacement-controlled curve): indices [peak, end], the loading part that led to it starting
/// at `loading_start` (the previous branch's end, or the start).
struct CurveBranch {
  std::size_t loading_start = 0, peak = 0, end = 0;
};
/// Every unloading branch: where the depth falls after having risen (a hold at the peak belongs to
/// the loading: the branch starts at the hold's last point), down to the valley, through any
/// holds, until the depth rises again (or the curve ends).  The one reversal detector: the
/// summary, the analysis and the checkpoint schedule all use it.
std::vector<CurveBranch> unloading_branches(const std::vector<double>& depth);
/// The planned increments (indices into `targets`) where the load path reverses: every branch's
/// peak, and its end where the path rises again (the valleys).
std::vector<int> reversal_steps(const std::vector<double>& targets);
/// The planned increments after which the depth falls (holds and equal depths included: the
/// last increment before each descent).  Where the path is at its deepest so far, that state is
/// the peak Ilyushin's unloading branch starts from.
std::vector<int> descent_starts(const std::vector<double>& targets);

/// One converged increment, as written to curve.csv.
struct IncrementRecord {
  int step = 0;               ///< 0 = the unloaded initial state
  double alpha = 0.0;         ///< indentation depth [m]
  double force = 0.0;         ///< P, both halves, per unit thickness [N/m]
  double half_width = 0.0;    ///< contact half-width a [m]
  int contact_nodes = 0;      ///< nodes in contact, the axis node included
  long newton_iterations = 0; ///< over every attempt of this increment, failed ones included
  long factorizations = 0;    ///< numeric LU factorizations over every attempt
  int cutbacks = 0;           ///< halvings needed to reach this increment
  long plastic_points = 0;    ///< Gauss points beyond the elastic limit
  double max_strain_intensity = 0.0;  ///< largest e_u over the Gauss points
  double wall_seconds = 0.0;  ///< wall-clock time spent on this increment
};

/// The coordinate a run's unloading branches are found in (unloading_branches): the planned
/// target of the row's step under force control (`targets` = plan_increments; a creeping
/// specimen's depth still rises as the force falls, the "nose", and a hold's forces equal their
/// target only to the Newton tolerance), else (`targets` empty) the depth.
inline double run_branch_coordinate(const std::vector<double>& targets, const IncrementRecord& r) {
  const auto step = static_cast<std::size_t>(r.step);
  return step < targets.size() ? targets[step] : r.alpha;
}

/// Secant predictor: extrapolates the last two converged states linearly in alpha.
void extrapolate(const std::vector<double>& u_previous, double alpha_previous, const std::vector<double>& u_current,
                 double alpha_current, double alpha_next, std::vector<double>& guess);

}  // namespace indentsim
