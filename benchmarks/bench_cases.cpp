// Benchmark (prints, not a test): load cases at three mesh sizes (contact_nodes 10, 20, 40).
// For each size: unknowns, setup time (mesh, assembly, and for plastic cases the pilot run),
// median wall time per increment, Newton iterations and numeric factorizations per increment,
// KLU symbolic analyses per run, and the final force.  Each size is run `repeats` times and
// the medians are reported (this machine is noisy); then the least-squares exponent p of the
// time per increment ~ DOFs^p over the sizes.
//
//   indentsim_bench [repeats] [--nodes 10,20,40] [loadcase ...]
//                                                (default: loadcases/elastic.toml, loadcases/paper.toml)
//   indentsim_bench --scaling [loadcase ...]      (default: loadcases/elastic.toml)
//
// --scaling: one run per mesh from 1e4 to 1.1e6 unknowns (contact_nodes 20 to 300), 3 increments,
// solver.linear = "auto", with the far field condensed and (up to `full_limit` unknowns) solved
// whole; prints setup time (mesh, assembly, condensation, pilot), median time per increment and
// factorizations per increment, and the least-squares exponent p of time ~ DOFs^p.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "indentsim/simulation/simulation.hpp"
#include "bench_support.hpp"

using namespace indentsim;

using timing::median;

double fitted_exponent(const std::vector<double>& unknowns, const std::vector<double>& seconds) {
  // Least-squares slope of log(seconds) against log(unknowns).
  double mx = 0, my = 0;
  const auto n = static_cast<double>(unknowns.size());
  for (std::size_t k = 0; k < unknowns.size(); ++k) {
    mx += std::log(unknowns[k]) / n;
    my += std::log(seconds[k]) / n;
  }
  double sxy = 0, sxx = 0;
  for (std::size_t k = 0; k < unknowns.size(); ++k) {
    sxy += (std::log(unknowns[k]) - mx) * (std::log(seconds[k]) - my);
    sxx += (std::log(unknowns[k]) - mx) * (std::log(unknowns[k]) - mx);
  }
  return sxx > 0 ? sxy / sxx : 0.0;
}

void bench(const std::string& file, int repeats, const std::vector<int>& sizes) {
  fmt::print("\n{} ({} repeats, medians)\n", file, repeats);
  fmt::print("{:>13} {:>9} {:>8} {:>10} {:>13} {:>10} {:>12} {:>9} {:>12}\n", "contact_nodes", "unknowns", "system",
             "setup_s", "s/increment", "newton/inc", "factor/inc", "symbolic", "P_final");
  std::vector<double> all_unknowns, all_per_increment;
  for (int contact_nodes : sizes) {
    std::vector<double> setup, per_increment;
    double newton = 0, factor = 0, force = 0;
    long symbolic = 0;
    int unknowns = 0;
    std::int64_t system = 0;
    for (int r = 0; r < repeats; ++r) {
      const LoadCase lc = read_load_case(file, {"mesh.contact_nodes=" + std::to_string(contact_nodes)});
      const auto t0 = std::chrono::steady_clock::now();
      Simulation sim(lc);
      setup.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      std::vector<double> times;
      long iterations = 0, factorizations = 0;
      int increments = 0;
      sim.run([&](const IncrementRecord& rec) {
        if (rec.step == 0) return;
        times.push_back(rec.wall_seconds);
        iterations += rec.newton_iterations;
        factorizations += rec.factorizations;
        ++increments;
      });
      per_increment.push_back(median(times));
      newton = static_cast<double>(iterations) / increments;
      factor = static_cast<double>(factorizations) / increments;
      symbolic = sim.symbolic_analyses();
      unknowns = sim.mesh().equations();
      system = sim.system_unknowns();
      force = sim.contact().force;
    }
    fmt::print("{:>13} {:>9} {:>8} {:>10.3f} {:>13.4f} {:>10.2f} {:>12.2f} {:>9} {:>12.6e}\n", contact_nodes, unknowns,
               system, median(setup), median(per_increment), newton, factor, symbolic, force);
    std::fflush(stdout);
    all_unknowns.push_back(unknowns);
    all_per_increment.push_back(median(per_increment));
  }
  if (all_unknowns.size() >= 2)
    fmt::print("  time per increment ~ DOFs^{:.2f} (least squares over {} sizes)\n",
               fitted_exponent(all_unknowns, all_per_increment), all_unknowns.size());
}

void scaling(const std::string& file) {
  constexpr int full_limit = 700'000;  // the whole-mesh solve beyond this takes minutes per run
  fmt::print("\n{} scaling (3 increments, solver.linear = auto)\n", file);
  fmt::print("{:>13} {:>9} {:>10} {:>10} {:>10} {:>13} {:>11} {:>12}\n", "contact_nodes", "unknowns", "far_field",
             "system", "setup_s", "s/increment", "factor/inc", "P_final");
  for (const char* far_field : {"condense", "full"}) {
    std::vector<double> unknowns, per_increment, setups;
    for (int contact_nodes : {20, 40, 80, 160, 300}) {
      const LoadCase lc = read_load_case(file, {"mesh.contact_nodes=" + std::to_string(contact_nodes),
                                                "load.increments=3", "solver.linear=auto",
                                                std::string("solver.far_field=") + far_field});
      if (std::string(far_field) == "full" && plan_mesh(lc).unknowns() > full_limit) break;
      const auto t0 = std::chrono::steady_clock::now();
      Simulation sim(lc);
      const double setup = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      std::vector<double> times;
      long factorizations = 0;
      sim.run([&](const IncrementRecord& rec) {
        if (rec.step == 0) return;
        times.push_back(rec.wall_seconds);
        factorizations += rec.factorizations;
      });
      unknowns.push_back(sim.mesh().equations());
      per_increment.push_back(median(times));
      setups.push_back(setup);
      fmt::print("{:>13} {:>9} {:>10} {:>10} {:>10.3f} {:>13.4f} {:>11.2f} {:>12.6e}\n", contact_nodes,
                 sim.mesh().equations(), far_field, sim.system_unknowns(), setup, per_increment.back(),
                 static_cast<double>(factorizations) / static_cast<double>(times.size()), sim.contact().force);
      std::fflush(stdout);
    }
    if (unknowns.size() >= 2)
      fmt::print("  {}: time per increment ~ DOFs^{:.2f}, setup ~ DOFs^{:.2f} (from {:.3g} to {:.3g} unknowns)\n",
                 far_field, fitted_exponent(unknowns, per_increment), fitted_exponent(unknowns, setups),
                 unknowns.front(), unknowns.back());
  }
}

int main(int argc, char** argv) {
  if (argc > 1 && std::string(argv[1]) == "--scaling") {
    std::vector<std::string> files;
    for (int i = 2; i < argc; ++i) files.emplace_back(argv[i]);
    if (files.empty()) files.push_back(std::string(INDENTSIM_SOURCE_DIR) + "/loadcases/elastic.toml");
    fmt::print("indentsim scaling benchmark\n");
    for (const auto& f : files) scaling(f);
    return 0;
  }
  const int repeats = argc > 1 ? std::max(1, std::atoi(argv[1])) : 3;
  std::vector<std::string> files;
  std::vector<int> sizes{10, 20, 40};
  for (int i = 2; i < argc; ++i) {
    if (std::string(argv[i]) == "--nodes" && i + 1 < argc) {
      sizes.clear();
      std::string list = argv[++i];
      for (std::size_t start = 0; start < list.size();) {
        const std::size_t comma = std::min(list.find(',', start), list.size());
        sizes.push_back(std::atoi(list.substr(start, comma - start).c_str()));
        start = comma + 1;
      }
    } else {
      files.emplace_back(argv[i]);
    }
  }
  if (files.empty())
    for (const char* name : {"elastic.toml", "paper.toml"})
      files.push_back(std::string(INDENTSIM_SOURCE_DIR) + "/loadcases/" + name);
  fmt::print("indentsim benchmark\n");
  for (const auto& f : files) bench(f, repeats, sizes);
  return 0;
}
