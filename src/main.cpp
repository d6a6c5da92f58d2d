// indentsim: the command line.  Thin glue over the library: read a load case, run it, write
// the outputs.  Exit status: 0 success, 2 bad input (nothing written), 3 the solver could not
// converge (converged increments are kept), 1 anything else.
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "indentsim/error.hpp"
#include "indentsim/io.hpp"
#include "indentsim/load_case.hpp"
#include "indentsim/simulation.hpp"

namespace fs = std::filesystem;
using namespace indentsim;

namespace {

constexpr int exit_bad_input = 2;
constexpr int exit_not_converged = 3;

/// A TOML basic string holding `s`, for passing a path through --set.
std::string toml_string(const std::string& s) {
  std::string quoted = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') quoted += '\\';
    quoted += c;
  }
  return quoted + "\"";
}

fs::path prepare_output_dir(const LoadCase& lc) {
  const fs::path dir = lc.output.dir;
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
    throw InputError(lc.source, "output.dir", fmt::format("\"{}\" exists and is not a folder", dir.string()));
  fs::create_directories(dir, ec);
  if (ec) throw InputError(lc.source, "output.dir", fmt::format("cannot create \"{}\": {}", dir.string(), ec.message()));
  return dir;
}

void print_mesh(const Simulation& sim) {
  const auto& p = sim.plan();
  fmt::print("mesh: {} x {} nodes, {} unknowns; fine zone {:.4g} m x {:.4g} m at spacing {:.4g} m "
             "(estimated final contact half-width {:.4g} m), growth {:.3f}\n",
             p.nodes_x, p.nodes_y, sim.mesh().equations(), p.fine_width, p.fine_depth, p.fine_spacing,
             p.contact_half_width_estimate, p.growth);
}

int command_check(const std::string& file, const std::vector<std::string>& overrides) {
  const LoadCase lc = read_load_case(file, overrides);
  const MeshPlan p = plan_mesh(lc);
  fmt::print("{}: valid; model {}, depth up to {:.4g} m in {} increments; mesh {} x {} nodes ({} unknowns)\n", file,
             to_string(lc.material.model), lc.max_depth(), lc.load.increments, p.nodes_x, p.nodes_y, p.unknowns());
  return 0;
}

int command_run(const std::string& file, const std::vector<std::string>& overrides, const std::string& out,
                bool quiet) {
  std::vector<std::string> all = overrides;
  if (!out.empty()) all.push_back("output.dir=" + toml_string(out));
  LoadCase lc = read_load_case(file, all);
  Simulation sim(lc);  // validates the mesh size before anything is written
  if (!quiet) print_mesh(sim);
  const fs::path dir = prepare_output_dir(lc);
  const fs::path curve_path = dir / "curve.csv";
  CurveWriter curve(curve_path);
  std::size_t warnings_shown = 0;
  const auto show_warnings = [&] {
    for (; warnings_shown < sim.warnings().size(); ++warnings_shown)
      fmt::print(stderr, "warning: {}\n", sim.warnings()[warnings_shown]);
  };
  int exit_code = 0;
  try {
    sim.run([&](const IncrementRecord& r) {
      curve.write(r);
      show_warnings();
    });
  } catch (const SolverError& e) {
    fmt::print(stderr, "{}: {}\n", file, e.what());
    exit_code = exit_not_converged;
  }
  show_warnings();
  if (!quiet) fmt::print("P-alpha curve: {}\n", curve_path.string());
  return exit_code;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"indentsim: plane-strain indentation of an elasto-plastic block by a rigid cylindrical punch"};
  app.require_subcommand(1);
  std::string file, out;
  std::vector<std::string> overrides;
  bool quiet = false;

  CLI::App* run = app.add_subcommand("run", "solve a load case and write DIR/curve.csv");
  run->add_option("case", file, "load case (TOML)")->required();
  run->add_option("--out", out, "output folder (overrides output.dir)");
  run->add_option("--set", overrides, "override a key: section.key=value")->take_all();
  run->add_flag("--quiet,-q", quiet, "print nothing but warnings and errors");

  CLI::App* check = app.add_subcommand("check", "validate a load case without solving");
  check->add_option("case", file, "load case (TOML)")->required();
  check->add_option("--set", overrides, "override a key: section.key=value")->take_all();

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return exit_bad_input;
  }

  try {
    if (run->parsed()) return command_run(file, overrides, out, quiet);
    return command_check(file, overrides);
  } catch (const InputError& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return exit_bad_input;
  } catch (const std::exception& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return 1;
  }
}
