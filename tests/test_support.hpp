#pragma once
// Helpers shared by the tests: load cases from the repository, and small edits of them.
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "indentsim/base/error.hpp"
#include "indentsim/input/load_case.hpp"
#include "indentsim/geometry/mesh.hpp"
#include "indentsim/materials/material.hpp"
#include "indentsim/simulation/simulation.hpp"

namespace indentsim::testing {

/// Central differences of a stress function of the strain, column by column: what a pointwise
/// law's consistent tangent is checked against.
template <class StressOf>
ConstitutiveMatrix finite_difference_tangent(const StressOf& stress, const VoigtVector& strain) {
  ConstitutiveMatrix fd;
  const double step = 1e-7 * strain.norm();
  for (int j = 0; j < 4; ++j) {
    VoigtVector plus = strain, minus = strain;
    plus[j] += step;
    minus[j] -= step;
    fd.col(j) = (stress(plus) - stress(minus)) / (2 * step);
  }
  return fd;
}

/// A small valid load case (the paper's block, elastic) for tests that edit one key.
inline const std::string small_case_toml = R"(
[geometry]
lx = 15e-3
ly = 10e-3
[punch]
radius = 2e-3
[material]
model = "elastic"
E = 210e9
nu = 0.3
[load]
path = [0.0, 2e-5]
increments = 3
[mesh]
contact_nodes = 8
)";

/// A sphere of radius 1 mm pressed 20 um into a 10 mm steel-like block (E 200 GPa, nu 0.3; e0
/// 1.5e-3, kappa 0.8, n 0.2 for a plastic model) on a pinned mesh (10 contact nodes across
/// a* = 150 um, Q1): the small scene the sensitivity and fit tests vary.
inline LoadCase small_sphere_case(SceneKind scene, MaterialModel model, HardeningLaw law) {
  LoadCase lc;
  lc.geometry.kind = scene;
  lc.geometry.lx = lc.geometry.ly = 10e-3;
  lc.punch.radius = 1e-3;
  lc.material.model = model;
  lc.material.E = 200e9;
  lc.material.nu = 0.3;
  lc.material.hardening = law;
  lc.material.e0 = 1.5e-3;
  lc.material.kappa = 0.8;
  lc.material.n = 0.2;
  lc.load.path = {0.0, 20e-6};
  lc.load.increments = 5;
  lc.mesh.contact_nodes = 10;
  lc.mesh.contact_half_width = 150e-6;
  lc.mesh.element = ElementChoice::q1;
  validate(lc);
  return lc;
}

/// A fresh folder per test, removed afterwards.
class TempDirTest : public ::testing::Test {
protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("indentsim_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
            std::to_string(::getpid()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::filesystem::path dir_;
};

inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// Writes `text` to `p` as it is (binary: a CRLF stays CRLF).
inline void write_text(const std::filesystem::path& p, const std::string& text) {
  std::ofstream(p, std::ios::binary) << text;
}

/// curve.csv without its wall-clock column (the last one): what must agree between two runs.
inline std::string curve_without_timing(const std::filesystem::path& file) {
  std::istringstream in(slurp(file));
  std::string line, out;
  while (std::getline(in, line)) out += line.substr(0, line.rfind(',')) + "\n";
  return out;
}

/// curve.csv's rows as numbers (header skipped), in its column order.
inline std::vector<std::vector<double>> read_curve(const std::filesystem::path& file) {
  std::istringstream in(slurp(file));
  std::string line;
  std::getline(in, line);
  std::vector<std::vector<double>> rows;
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::istringstream cells(line);
    for (std::string cell; std::getline(cells, cell, ',');)
      row.push_back(cell.empty() ? std::nan("") : std::stod(cell));  // empty: no error estimate there
    rows.push_back(row);
  }
  return rows;
}

/// A temporary folder and the CLI run in it: cli() returns the exit status (128 + signal when a
/// signal ended it), out() and err() what it printed.  `environment` is prefixed to the command
/// (e.g. "INDENTSIM_FAULT=write:5").
class CliTest : public TempDirTest {
protected:
  int cli(const std::string& args, const std::string& environment = "") {
    const std::string command = (environment.empty() ? "" : environment + " ") + std::string(INDENTSIM_CLI) + " " +
                                args + " >" + (dir_ / "out.txt").string() + " 2>" + (dir_ / "err.txt").string() +
                                " </dev/null";
    const int raw = std::system(command.c_str());
    if (WIFEXITED(raw)) return WEXITSTATUS(raw);
    return WIFSIGNALED(raw) ? 128 + WTERMSIG(raw) : -1;
  }
  std::string out() const { return slurp(dir_ / "out.txt"); }
  std::string err() const { return slurp(dir_ / "err.txt"); }
  /// Bad input: exit 2, the message names the key, and the output folder is never created.
  void expect_refused(const std::string& args, const std::string& key) {
    SCOPED_TRACE(args);
    const std::filesystem::path never = dir_ / "never";
    EXPECT_EQ(cli(args + " --quiet --out " + never.string()), 2) << err();
    EXPECT_NE(err().find(key), std::string::npos) << err();
    EXPECT_FALSE(std::filesystem::exists(never));
  }
};

/// The rows of a whole run of `lc`, one per increment.
inline std::vector<IncrementRecord> run_rows(const LoadCase& lc) {
  Simulation sim(lc);
  std::vector<IncrementRecord> rows;
  sim.run([&](const IncrementRecord& r) { rows.push_back(r); });
  return rows;
}

inline std::string source_path(const std::string& relative) { return std::string(INDENTSIM_SOURCE_DIR) + "/" + relative; }

/// E* = E / (1 - nu^2), the plane-strain (contact) modulus of a rigid-indenter contact.
inline double contact_modulus(const LoadCase& lc) { return lc.material.E / (1.0 - lc.material.nu * lc.material.nu); }

inline LoadCase shipped_case(const std::string& name, const std::vector<std::string>& overrides = {}) {
  return read_load_case(source_path("loadcases/" + name), overrides);
}

/// The key a shipped case read with `overrides` is refused by, or "" when it is taken.
inline std::string refused_key(const std::string& name, const std::vector<std::string>& overrides) {
  try {
    shipped_case(name, overrides);
  } catch (const InputError& e) {
    return e.key();
  }
  return "";
}

/// A lx x ly block (or cylinder) graded towards the loaded corner, of the given element kind and scene.
inline Mesh graded_block(double lx, double ly, ElementKind kind, SceneKind scene = SceneKind::plane_strain) {
  const auto depth = graded_axis(ly, 1e-3, 2e-4, 1.25);
  std::vector<double> y(depth.size());
  for (std::size_t k = 0; k < depth.size(); ++k) y[k] = -depth[depth.size() - 1 - k];
  Mesh mesh(graded_axis(lx, 2e-3, 2.5e-4, 1.3), y);
  mesh.set_element_kind(kind);
  mesh.set_scene(scene);
  return mesh;
}

}  // namespace indentsim::testing
