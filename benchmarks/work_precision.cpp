// Work-precision benchmark (prints, not a test): error of the final force against wall time.
//
// For the elastic thick block (error: P against Hertz for the computed a), two plane-strain
// plastic cases, the paper's and a deep one, and three axisymmetric ones, an elastic sphere, a
// J2 steel sphere and the Berkovich-equivalent cone with Ilyushin's law (error: P against a
// Richardson extrapolation of the three finest meshes, whose observed order is printed), it sweeps
// mesh.contact_nodes, and for one case the number of increments, and writes a table to stdout and
// to a CSV file for plots/plot_work_precision.py.  P is N/m in plane strain, N in axisymmetry.
//
//   indentsim_work_precision [OUT.csv] [--quick] [--only CASE]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "indentsim/geometry/hertz.hpp"
#include "indentsim/simulation/simulation.hpp"

using namespace indentsim;

namespace {

struct Row {
  std::string label, linear;
  int contact_nodes = 0, increments = 0, unknowns = 0;
  double seconds = 0, force = 0, half_width = 0, error = 0;
  long factorizations = 0, newton = 0;
};

Row measure(const std::string& label, const std::string& file, int contact_nodes, int increments,
            const std::string& linear, std::vector<std::string> overrides = {}) {
  for (const std::string& key : {"mesh.contact_nodes=" + std::to_string(contact_nodes),
                                "load.increments=" + std::to_string(increments), "solver.linear=" + linear,
                                std::string("output.checkpoint_every=0")})
    overrides.push_back(key);
  const LoadCase lc = read_load_case(file, overrides);
  const auto start = std::chrono::steady_clock::now();
  Simulation sim(lc);
  Row row{label, linear, contact_nodes, increments, sim.mesh().equations()};
  sim.run([&](const IncrementRecord& r) {
    row.factorizations += r.factorizations;
    row.newton += r.newton_iterations;
    row.force = r.force;
    row.half_width = r.half_width;
  });
  row.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  std::string csv = "out/work_precision.csv";
  bool quick = false;
  std::string only;  // --only CASE: one Richardson sweep (its label), nothing else
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--quick") quick = true;
    else if (std::string(argv[i]) == "--only" && i + 1 < argc) only = argv[++i];
    else csv = argv[i];
  }
  const std::string dir = std::string(INDENTSIM_SOURCE_DIR) + "/loadcases/";
  // The finest mesh and those with a half and a quarter of its contact_nodes form the geometric
  // triple of the Richardson extrapolation.
  const std::vector<int> meshes = quick ? std::vector<int>{4, 6, 8, 16} : std::vector<int>{5, 8, 12, 16, 24, 32, 48};
  std::vector<Row> rows;
  const auto print = [](const Row& r) {
    fmt::print("{:<20} {:>7} {:>5} {:>4} {:>8} {:>9.3f} {:>7} {:>7} {:>16.9e} {:>10.3e}\n", r.label, r.linear,
               r.contact_nodes, r.increments, r.unknowns, r.seconds, r.factorizations, r.newton, r.force, r.error);
    std::fflush(stdout);
  };
  fmt::print("{:<20} {:>7} {:>5} {:>4} {:>8} {:>9} {:>7} {:>7} {:>16} {:>10}\n", "case", "linear", "nodes", "inc",
             "DOFs", "wall_s", "factor", "newton", "P [N/m or N]", "error");

  // Elastic: error of P against Hertz at the computed half-width (local, converges to 0.0x%).
  for (int n : only.empty() ? meshes : std::vector<int>{}) {
    Row r = measure("elastic_hertz", dir + "hertz_thick_block.toml", n, 4, "auto");
    const double e_star = 210e9 / (1 - 0.3 * 0.3);
    r.error = std::abs(r.force - hertz::force(r.half_width, 0.1, e_star)) / r.force;
    print(r);
    rows.push_back(r);
  }
  // Error against the Richardson extrapolation of the three finest meshes.
  struct Sweep {
    std::string label, file;
    std::vector<std::string> overrides;
    int increments = 4;  ///< monotone loading: deformation theory needs few; J2 flow theory integrates the path
  };
  const std::vector<Sweep> sweeps = {
      {"paper", "paper.toml", {}},
      {"deep_plastic", "deep_plastic.toml", {}},
      {"axi_elastic_sphere", "axisymmetric/elastic_sphere.toml", {}},
      // Loading only: the shipped cases also unload.
      {"axi_steel_sphere", "axisymmetric/steel_sphere.toml", {"load.path=[0.0, 10e-6]"}, 20},
      // Ilyushin's law: J2 under a sharp cone carries a sawtooth of about 2 dx / a (docs/verification.md, "Kick's
      // law") that no Richardson extrapolation can see through.
      {"axi_cone", "axisymmetric/berkovich_cone.toml", {"load.path=[0.0, 1e-6]", "material.model=\"ilyushin\""}},
  };
  for (const Sweep& s : sweeps) {
    const std::string& name = s.label;
    std::vector<Row> sweep;
    if (!only.empty() && name != only) continue;
    for (int n : meshes) sweep.push_back(measure(name, dir + s.file, n, s.increments, "auto", s.overrides));
    if (name == "deep_plastic")
      for (const char* linear : {"klu"})
        for (int n : meshes) sweep.push_back(measure(name + "_klu", dir + s.file, n, 4, linear, s.overrides));
    const auto force_at = [&](int n) {
      for (std::size_t i = 0; i < meshes.size(); ++i)
        if (meshes[i] == n) return sweep[i].force;
      throw std::logic_error("mesh sweep lacks the Richardson triple");
    };
    const int finest = meshes.back();
    const double p1 = force_at(finest / 4), p2 = force_at(finest / 2), p3 = force_at(finest);
    const double order = std::log2(std::abs((p1 - p2) / (p2 - p3)));
    const double limit = p3 + (p3 - p2) / (std::pow(2.0, order) - 1.0);
    fmt::print("# {}: observed order {:.2f} (contact_nodes {}, {}, {}), extrapolated P = {:.9e} {}\n", name, order,
               finest / 4, finest / 2, finest, limit, name.rfind("axi_", 0) == 0 ? "N" : "N/m");
    for (Row& r : sweep) {
      r.error = std::abs(r.force - limit) / limit;
      print(r);
      rows.push_back(r);
    }
    if (name == "deep_plastic")  // increments cost time but not accuracy on monotone loading
      for (int inc : {2, 8, 16}) {
        Row r = measure(name + "_increments", dir + s.file, 16, inc, "auto", s.overrides);
        r.error = std::abs(r.force - limit) / limit;
        print(r);
        rows.push_back(r);
      }
  }
  std::ofstream out(csv);
  out << "case,linear,contact_nodes,increments,unknowns,wall_s,factorizations,newton_iters,P,error\n";
  for (const Row& r : rows)
    out << fmt::format("{},{},{},{},{},{:.6f},{},{},{:.17g},{:.6e}\n", r.label, r.linear, r.contact_nodes, r.increments,
                       r.unknowns, r.seconds, r.factorizations, r.newton, r.force, r.error);
  fmt::print("table written to {}\n", csv);
  return 0;
}
