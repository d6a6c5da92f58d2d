#pragma once
// What the benchmark programs share: the median of noisy timings (this machine has 2 cores and
// neighbours; medians, not means, are quoted) and a wall clock.
#include <algorithm>
#include <chrono>
#include <vector>

namespace indentsim::timing {

inline double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace indentsim::timing
