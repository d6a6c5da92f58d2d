#include "indentsim/simulation/load_stepping.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace indentsim {

namespace {

// `increments` spread over segments of the given weights (lengths or durations) in proportion,
// largest-remainder rounding, at least one per segment of positive weight (none to the others).
std::vector<int> spread(const std::vector<double>& weight, int increments) {
  const std::size_t segments = weight.size();
  std::vector<int> count(segments, 0);
  const double total = std::accumulate(weight.begin(), weight.end(), 0.0);
  const std::size_t nonempty =
      static_cast<std::size_t>(std::count_if(weight.begin(), weight.end(), [](double l) { return l > 0.0; }));
  const int n = std::max(increments, static_cast<int>(nonempty));
  std::vector<double> remainder(segments, -1.0);
  int assigned = 0;
  for (std::size_t s = 0; s < segments; ++s) {
    if (weight[s] <= 0.0) continue;
    const double share = n * weight[s] / total;
    count[s] = std::max(1, static_cast<int>(std::floor(share)));
    remainder[s] = share - std::floor(share);
    assigned += count[s];
  }
  while (assigned < n) {
    const auto s = static_cast<std::size_t>(std::max_element(remainder.begin(), remainder.end()) - remainder.begin());
    ++count[s];
    remainder[s] = -1.0;
    ++assigned;
  }
  while (assigned > n) {  // only when the "at least one" rule overshot: take from the largest
    const auto s = static_cast<std::size_t>(std::max_element(count.begin(), count.end()) - count.begin());
    --count[s];
    --assigned;
  }
  return count;
}

std::vector<double> segment_lengths(const std::vector<double>& waypoints) {
  std::vector<double> length(waypoints.size() - 1);
  for (std::size_t s = 0; s < length.size(); ++s) length[s] = std::abs(waypoints[s + 1] - waypoints[s]);
  return length;
}

// The values at the end of each increment along piecewise-linear `waypoints`, `count[s]` uniform
// increments in segment s, each segment ending exactly on its waypoint.
std::vector<double> along(const std::vector<double>& waypoints, const std::vector<int>& count) {
  std::vector<double> values{waypoints.front()};
  for (std::size_t s = 0; s + 1 < waypoints.size(); ++s)
    for (int k = 1; k <= count[s]; ++k)
      values.push_back(k == count[s] ? waypoints[s + 1]
                                     : waypoints[s] + (waypoints[s + 1] - waypoints[s]) * k / count[s]);
  return values;
}

}  // namespace

std::vector<double> plan_increments(const std::vector<double>& path, int increments) {
  return along(path, spread(segment_lengths(path), increments));
}

std::vector<int> segment_increments(const LoadInput& load) {
  if (!load.segment_increments.empty()) return load.segment_increments;
  return spread(segment_lengths(load.times.empty() ? load.path : load.times), load.increments);
}

std::vector<double> plan_increments(const LoadInput& load) { return along(load.path, segment_increments(load)); }

std::vector<double> plan_times(const LoadInput& load) {
  if (load.times.empty()) return {};
  return along(load.times, segment_increments(load));
}

std::vector<CurveBranch> unloading_branches(const std::vector<double>& depth) {
  std::vector<CurveBranch> branches;
  const std::size_t n = depth.size();
  std::size_t loading_start = 0;
  bool risen = false;  // the depth rose since the last branch ended (holds do not count)
  for (std::size_t i = 0; i + 1 < n;) {
    if (depth[i + 1] > depth[i]) risen = true;
    if (depth[i + 1] < depth[i] && risen) {
      // Down to the valley: through holds, until the depth rises again.
      CurveBranch b{loading_start, i, i};
      while (b.end + 1 < n && depth[b.end + 1] <= depth[b.end]) ++b.end;
      branches.push_back(b);
      loading_start = b.end;
      risen = false;
      i = b.end;
    } else {
      if (depth[i + 1] < depth[i]) loading_start = i + 1;  // a fall before any rise: loading starts below it
      ++i;
    }
  }
  return branches;
}

std::vector<int> reversal_steps(const std::vector<double>& targets) {
  std::vector<int> steps;
  for (const CurveBranch& b : unloading_branches(targets)) {
    steps.push_back(static_cast<int>(b.peak));
    if (b.end + 1 < targets.size()) steps.push_back(static_cast<int>(b.end));
  }
  return steps;
}

std::vector<int> descent_starts(const std::vector<double>& targets) {
  std::vector<int> steps;
  for (std::size_t k = 0; k + 1 < targets.size(); ++k)
    if (targets[k + 1] < targets[k]) steps.push_back(static_cast<int>(k));
  return steps;
}

void extrapolate(const std::vector<double>& u_previous, double alpha_previous, const std::vector<double>& u_current,
                 double alpha_current, double alpha_next, std::vector<double>& guess) {
  guess = u_current;
  const double span = alpha_current - alpha_previous;
  if (span == 0.0 || u_previous.size() != u_current.size()) return;
  const double t = (alpha_next - alpha_current) / span;
  for (std::size_t i = 0; i < guess.size(); ++i) guess[i] += t * (u_current[i] - u_previous[i]);
}

}  // namespace indentsim
