// Benchmark (prints, not a test): the cost of `indentsim fit` (fit.hpp) in forward runs and in
// wall time, with forward sensitivities and with finite differences.
//
// The scene is the shipped steel ball (loadcases/axisymmetric/steel_sphere.toml) with Ilyushin's
// law, at its own mesh (contact_nodes = 20): a 20-point load-unload curve (14 depths on loading
// to 10 um, 6 on unloading to 8.5 um) made by indentsim at the truth (sigma_y 500 MPa, n 0.15,
// E 210 GPa) with 0.5% noise, fitted from starts a factor 2 away: sigma_y and n (E known), then
// E, sigma_y and n; each with forward sensitivities (coarse phase first, and on the fine mesh
// alone) and with finite differences (coarse phase first).  A "forward-run time" is the median wall time of one run of the model along
// the data's path at the truth, without sensitivities: the unit the goal is stated in (a
// three-parameter fit in under 15 of them).
//
//   indentsim_fit_bench [repeats] [--runs-only] [--threads]
//     repeats: forward runs are timed `repeats` times (default 3), medians; each fit is run once
//     (its run count is deterministic).  --runs-only: the forward-run timings alone (profiling).
//     --threads: instead of the table, the sigma_y, n fit with the defaults (4 starts, profiles,
//     design) on 1 thread and on the cores this process may use: the wall times, their ratio, and
//     the progress line's forecast of the remaining time against the time that remained, at a
//     quarter, half and three quarters of the fit.
#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstdio>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "indentsim/base/worker_threads.hpp"
#include "indentsim/fitting/fit.hpp"
#include "indentsim/input/load_case.hpp"
#include "bench_support.hpp"

using namespace indentsim;

namespace {

using timing::median;
using timing::seconds_since;

std::vector<FreeParameter> free_parameters(const LoadCase& truth, const std::vector<MaterialParameter>& keys) {
  std::vector<FreeParameter> free;
  for (MaterialParameter p : keys) {
    const auto [lower, upper] = default_bounds(p, value_of(truth.material, p));
    free.push_back({p, lower, upper});
  }
  return free;
}

}  // namespace

int main(int argc, char** argv) {
  int repeats = 3;
  bool runs_only = false, threads_only = false;
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--runs-only") runs_only = true;
    else if (std::string(argv[i]) == "--threads") threads_only = true;
    else repeats = std::max(1, std::atoi(argv[i]));
  }
  const LoadCase truth = read_load_case(std::string(INDENTSIM_SOURCE_DIR) + "/loadcases/axisymmetric/steel_sphere.toml",
                                        {"material.model=ilyushin"});
  std::vector<double> depths;
  for (int k = 1; k <= 14; ++k) depths.push_back(10e-6 * k / 14);
  for (int k = 1; k <= 6; ++k) depths.push_back(10e-6 - 1.5e-6 * k / 6);

  const std::vector<MaterialParameter> all{MaterialParameter::E, MaterialParameter::yield_stress, MaterialParameter::n};
  const std::vector<FreeParameter> free_all = free_parameters(truth, all);
  fmt::print("indentsim fit benchmark: {} (Ilyushin), 20-point load-unload curve, 0.5% noise\n", truth.source);
  const auto t_data = std::chrono::steady_clock::now();
  const FitData data = synthetic_data(truth, FitDataKind::force_depth_curve, depths, free_all, 0.005, 7);
  fmt::print("data made in {:.2f} s (the mesh's pilot run and one forward run)\n", seconds_since(t_data));

  // The unit: one forward run along the data's path at the truth, with and without sensitivities.
  {
    std::vector<std::pair<double, double>> bounds;
    std::vector<double> theta;
    for (const auto& f : free_all) {
      bounds.emplace_back(f.lower, f.upper);
      theta.push_back(value_of(truth, f.parameter));
    }
    std::vector<RegionParameter> parameters;
    for (const auto& f : free_all) parameters.push_back(f.parameter);
    const ForwardModel model(data, parameters, bounds, false);
    std::vector<double> plain, with_sensitivities;
    for (int r = 0; r < repeats; ++r) {
      auto t0 = std::chrono::steady_clock::now();
      (void)model.evaluate(theta, false);
      plain.push_back(seconds_since(t0));
      t0 = std::chrono::steady_clock::now();
      (void)model.evaluate(theta, true);
      with_sensitivities.push_back(seconds_since(t0));
    }
    const double unit = median(plain);
    fmt::print("forward run: {:.3f} s (median of {}); with sensitivities of 3 parameters: {:.3f} s ({:.2f}x)\n\n", unit,
               repeats, median(with_sensitivities), median(with_sensitivities) / unit);
    if (runs_only) return 0;
    if (threads_only) {
      const int cores = usable_cores();
      fmt::print("sigma_y, n with the defaults (4 starts, profiles, design), forward sensitivities\n");
      fmt::print("{:>7} {:>8} {:>6} {:>7}  {}\n", "threads", "wall_s", "runs", "coarse",
                 "forecast of the remaining time / the time that remained, at 1/4, 1/2, 3/4 of the fit");
      double one_thread = 0.0;
      for (const int threads : {1, cores}) {
        FitProblem problem;
        problem.free = free_parameters(truth, {MaterialParameter::yield_stress, MaterialParameter::n});
        FitData started = data;
        for (const auto& f : problem.free)
          set_value(started.load_case, f.parameter, 2.0 * value_of(truth, f.parameter));
        validate(started.load_case);
        problem.data.push_back(started);
        problem.settings.threads = threads;
        std::vector<std::pair<double, double>> forecasts;  // (elapsed, remaining forecast)
        problem.settings.on_iteration = [&](const FitProgress& p) {
          forecasts.emplace_back(p.elapsed_seconds, p.remaining_seconds);
        };
        const FitResult r = fit(problem);
        std::string ratios;
        for (const double fraction : {0.25, 0.5, 0.75}) {
          const double at = fraction * r.wall_seconds;
          const auto f = std::find_if(forecasts.begin(), forecasts.end(), [&](const auto& e) { return e.first >= at; });
          if (f == forecasts.end()) continue;
          ratios += fmt::format("  {:.0f}/{:.0f} s ({:.2f})", f->second, r.wall_seconds - f->first,
                                f->second / (r.wall_seconds - f->first));
        }
        if (threads == 1) one_thread = r.wall_seconds;
        fmt::print("{:>7} {:>8.1f} {:>6} {:>7} {}\n", threads, r.wall_seconds, r.forward_runs, r.coarse_runs, ratios);
        std::fflush(stdout);
        if (threads == cores && cores > 1)
          fmt::print("{} threads: {:.2f}x faster than 1\n", cores, one_thread / r.wall_seconds);
        if (cores == 1) break;
      }
      return 0;
    }

    fmt::print("{:<16} {:<14} {:<13} {:>5} {:>7} {:>5} {:>8} {:>9} {:>6}  {}\n", "free", "gradients", "levels", "runs",
               "coarse", "iter", "wall_s", "wall/run", "cond", "result (+- standard error; truth 210 GPa, 500 MPa, 0.15)");
    struct Variant {
      bool finite_differences, coarse_first;
    };
    for (const std::vector<MaterialParameter>& keys :
         {std::vector<MaterialParameter>{MaterialParameter::yield_stress, MaterialParameter::n}, all}) {
      for (const Variant v : {Variant{false, true}, Variant{false, false}, Variant{true, true}}) {
        FitProblem problem;
        problem.free = free_parameters(truth, keys);
        FitData started = data;
        for (const auto& f : problem.free)
          set_value(started.load_case, f.parameter, 2.0 * value_of(truth, f.parameter));
        validate(started.load_case);
        problem.data.push_back(started);
        problem.settings.finite_differences = v.finite_differences;
        problem.settings.coarse_first = v.coarse_first;
        const FitResult r = fit(problem);
        std::string names, values;
        for (std::size_t j = 0; j < keys.size(); ++j) {
          if (j) names += ",";
          names += key_of(keys[j]).substr(9);  // without "material."
          values += fmt::format("{}{:.5g} +- {:.2g}", j ? ", " : "", r.values[j], r.std_errors[j]);
        }
        fmt::print("{:<16} {:<14} {:<13} {:>5} {:>7} {:>5} {:>8.1f} {:>9.1f} {:>6.3g}  {}\n", names,
                   v.finite_differences ? "finite diff." : "sensitivities", v.coarse_first ? "coarse, fine" : "fine only",
                   r.forward_runs, r.coarse_runs, r.iterations, r.wall_seconds, r.wall_seconds / unit,
                   r.condition_number, values);
        std::fflush(stdout);
      }
    }
  }
  fmt::print("\nruns: forward runs on the case's own mesh; coarse: on half its contact nodes.\n"
             "goal: a 3-parameter fit in under 15 forward-run times (wall/run column)\n");
  return 0;
}
