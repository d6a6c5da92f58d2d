// Benchmark (prints, not a test): load cases at three mesh sizes (contact_nodes 10, 20, 40).
// For each size: unknowns, setup time (mesh, assembly, and for plastic cases the pilot run),
// median wall time per increment, Newton iterations and numeric factorizations per increment,
// KLU symbolic analyses per run, and the final force.  Each size is run `repeats` times and
// the medians are reported (this machine is noisy).
//
//   indentsim_bench [repeats] [loadcase ...]     (default: loadcases/elastic.toml, loadcases/paper.toml)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "indentsim/simulation.hpp"

using namespace indentsim;

namespace {
double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}
}  // namespace

void bench(const std::string& file, int repeats) {
  fmt::print("\n{} ({} repeats, medians)\n", file, repeats);
  fmt::print("{:>13} {:>9} {:>10} {:>13} {:>10} {:>12} {:>9} {:>12}\n", "contact_nodes", "unknowns", "setup_s",
             "s/increment", "newton/inc", "factor/inc", "symbolic", "P_final");
  for (int contact_nodes : {10, 20, 40}) {
    std::vector<double> setup, per_increment;
    double newton = 0, factor = 0, force = 0;
    long symbolic = 0;
    int unknowns = 0;
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
      force = sim.contact().force;
    }
    fmt::print("{:>13} {:>9} {:>10.3f} {:>13.4f} {:>10.2f} {:>12.2f} {:>9} {:>12.6e}\n", contact_nodes, unknowns,
               median(setup), median(per_increment), newton, factor, symbolic, force);
    std::fflush(stdout);
  }
}

int main(int argc, char** argv) {
  const int repeats = argc > 1 ? std::max(1, std::atoi(argv[1])) : 3;
  std::vector<std::string> files;
  for (int i = 2; i < argc; ++i) files.emplace_back(argv[i]);
  if (files.empty())
    for (const char* name : {"elastic.toml", "paper.toml"})
      files.push_back(std::string(INDENTSIM_SOURCE_DIR) + "/loadcases/" + name);
  fmt::print("indentsim benchmark\n");
  for (const auto& f : files) bench(f, repeats);
  return 0;
}
