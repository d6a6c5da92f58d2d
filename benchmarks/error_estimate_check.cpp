// Error-estimate check (prints, not a test): for each load case at its mesh of N contact nodes,
// the run's own estimate of the error of the peak force (mesh.error_estimate = "richardson": a
// companion at N/2, the punch's order) next to the true error, from a reference that does not use
// the estimate: Richardson's extrapolation of runs at rN and r^2 N (r = 2 unless --ratio) with the
// order observed from the three meshes (the nominal 2 where they are not monotone, said in the
// table).  The estimate should bracket the true error within a factor 2 wherever the true error
// exceeds 0.02%.
//
//   indentsim_error_check [--nodes N] [--ratio r] [loadcase ...]
//                         (default: every shipped load case at its own N, r = 2)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "indentsim/simulation/error_estimate.hpp"
#include "indentsim/simulation/simulation.hpp"
#include "bench_support.hpp"

using namespace indentsim;

namespace {

struct Peak {
  int step = 0;
  double force = 0.0;
  double seconds = 0.0;
};

// The increment of largest force (the peak of a loading-unloading path, the end of a monotone one).
std::size_t peak_row(const std::vector<IncrementRecord>& rows) {
  std::size_t best = 0;
  for (std::size_t k = 0; k < rows.size(); ++k)
    if (rows[k].force > rows[best].force) best = k;
  return best;
}

std::vector<IncrementRecord> solve(const LoadCase& lc, double& seconds) {
  const auto t0 = std::chrono::steady_clock::now();
  Simulation sim(lc);
  std::vector<IncrementRecord> rows;
  sim.run([&](const IncrementRecord& r) { rows.push_back(r); });
  seconds = timing::seconds_since(t0);
  return rows;
}

void check(const std::string& file, int nodes_override, double r) {
  std::vector<std::string> overrides{"output.checkpoint_every=0", "mesh.error_estimate=richardson"};
  if (nodes_override > 0) overrides.push_back("mesh.contact_nodes=" + std::to_string(nodes_override));
  const LoadCase lc = read_load_case(file, overrides);
  const int n = lc.mesh.contact_nodes;
  const auto t0 = std::chrono::steady_clock::now();
  Simulation main_run(lc);
  std::vector<IncrementRecord> rows;
  main_run.run([&](const IncrementRecord& r) { rows.push_back(r); });
  const double main_seconds = timing::seconds_since(t0);
  const auto t1 = std::chrono::steady_clock::now();
  const DiscretizationErrorEstimate estimate(main_run);
  const double estimate_seconds = timing::seconds_since(t1);
  const std::size_t k = peak_row(rows);
  const auto at = estimate.at(rows[k]);

  double seconds2 = 0, seconds4 = 0;
  std::vector<IncrementRecord> rows2, rows4;
  LoadCase fine = lc;
  fine.mesh.error_estimate = ErrorEstimateChoice::off;
  const int n2 = static_cast<int>(std::lround(r * n)), n4 = static_cast<int>(std::lround(r * r * n));
  fine.mesh.contact_nodes = n2;
  rows2 = solve(fine, seconds2);
  fine.mesh.contact_nodes = n4;
  rows4 = solve(fine, seconds4);
  const double p1 = rows[k].force, p2 = rows2.at(k).force, p4 = rows4.at(k).force;
  // h ~ 1 / contact_nodes (the fine-zone spacing over the same planned contact width).
  const auto order = observed_order(p4, p2, p1, 1.0 / n4, 1.0 / n2, 1.0 / n);
  const RichardsonEstimate reference = richardson(p4, p2, static_cast<double>(n4) / n2, order.value_or(2.0));
  const double true_error = std::abs(p1 - reference.extrapolated) / std::abs(reference.extrapolated);
  const double estimated = at ? at->force_error / std::abs(p1) : std::nan("");
  const double ratio = estimated / true_error;
  const bool within = true_error <= 2e-4 || (ratio >= 0.5 && ratio <= 2.0);
  fmt::print("{:<34} {:>4} {:>5} {:>14.8e} {:>14.8e} {:>7} {:>10.3e} {:>10.3e} {:>6.2f} {:>5} {:>7.3f} {:>7.1f}%\n",
             std::filesystem::path(file).filename().string(), n, rows[k].step, p1, reference.extrapolated,
             order ? fmt::format("{:.2f}", *order) : std::string("2 (nom)"), estimated, true_error, ratio,
             within ? "yes" : "NO", main_seconds, 100.0 * estimate_seconds / main_seconds);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  int nodes = 0;
  double ratio = 2.0;
  std::vector<std::string> files;
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--nodes" && i + 1 < argc) nodes = std::atoi(argv[++i]);
    else if (std::string(argv[i]) == "--ratio" && i + 1 < argc) ratio = std::atof(argv[++i]);
    else files.emplace_back(argv[i]);
  }
  if (files.empty()) {
    const std::string dir = std::string(INDENTSIM_SOURCE_DIR) + "/loadcases";
    for (const char* sub : {"", "/axisymmetric"})
      for (const auto& entry : std::filesystem::directory_iterator(dir + sub))
        if (entry.path().extension() == ".toml") files.push_back(entry.path().string());
    std::sort(files.begin(), files.end());
  }
  fmt::print("{:<34} {:>4} {:>5} {:>14} {:>14} {:>7} {:>10} {:>10} {:>6} {:>5} {:>7} {:>8}\n", "case", "N", "peak",
             "P(N)", "P_reference", "order", "estimate", "true", "ratio", "fac2", "run_s", "cost");
  for (const auto& f : files) {
    try {
      check(f, nodes, ratio);
    } catch (const std::exception& e) {
      fmt::print("{}: {}\n", f, e.what());
    }
  }
  return 0;
}
