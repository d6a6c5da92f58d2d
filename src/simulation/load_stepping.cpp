#include "indentsim/simulation/load_stepping.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace indentsim {

std::vector<double> plan_increments(const std::vector<double>& path, int increments) {
  const std::size_t segments = path.size() - 1;
  std::vector<double> length(segments);
  std::vector<int> count(segments, 0);
  for (std::size_t s = 0; s < segments; ++s) length[s] = std::abs(path[s + 1] - path[s]);
  const double total = std::accumulate(length.begin(), length.end(), 0.0);
  const std::size_t nonempty =
      static_cast<std::size_t>(std::count_if(length.begin(), length.end(), [](double l) { return l > 0.0; }));
  const int n = std::max(increments, static_cast<int>(nonempty));
  std::vector<double> remainder(segments, -1.0);
  int assigned = 0;
  for (std::size_t s = 0; s < segments; ++s) {
    if (length[s] <= 0.0) continue;
    const double share = n * length[s] / total;
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
  std::vector<double> alphas{path.front()};
  for (std::size_t s = 0; s < segments; ++s)
    for (int k = 1; k <= count[s]; ++k)
      alphas.push_back(k == count[s] ? path[s + 1] : path[s] + (path[s + 1] - path[s]) * k / count[s]);
  return alphas;
}

std::vector<double> plan_increments(const LoadInput& load) {
  if (load.segment_increments.empty()) return plan_increments(load.path, load.increments);
  std::vector<double> alphas{load.path.front()};
  for (std::size_t s = 0; s + 1 < load.path.size(); ++s) {
    const int n = load.segment_increments[s];
    for (int k = 1; k <= n; ++k)
      alphas.push_back(k == n ? load.path[s + 1] : load.path[s] + (load.path[s + 1] - load.path[s]) * k / n);
  }
  return alphas;
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
