// What plastic runs report: the contact half-width a of every increment, and the outputs of a
// load path that unloads to separation (curve.csv and summary.json, as a user reads them).
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include <gtest/gtest.h>

#include "indentsim/simulation/simulation.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using namespace indentsim;
using indentsim::testing::shipped_case;
using indentsim::testing::slurp;
using indentsim::testing::source_path;

TEST(PlasticContactWidth, LiesBetweenTheNeighboursOfTheOutermostContactNode) {
  // a is resolved from the opening gap next to the edge (docs/DESIGN.md §4); whatever the estimate, the
  // edge of the discrete contact zone lies between the last node but one in contact and the first
  // open node.  Checked on both plastic models, from the mesh coordinates and the contact count.
  for (const char* model : {"ilyushin", "j2"}) {
    SCOPED_TRACE(model);
    Simulation sim(shipped_case("deep_plastic.toml", {std::string("material.model=") + model, "mesh.contact_nodes=8",
                                                      "load.increments=6"}));
    const Mesh& mesh = sim.mesh();
    int checked = 0;
    sim.run([&](const IncrementRecord& r) {
      if (r.step == 0) {
        EXPECT_EQ(r.half_width, 0.0);  // alpha = 0: no force, no contact zone
        return;
      }
      ASSERT_GT(r.force, 0.0);
      ASSERT_GE(r.contact_nodes, 2);
      // contact_nodes counts the axis node: the outermost contact node is node contact_nodes - 1.
      const int outermost = r.contact_nodes - 1;
      EXPECT_GE(r.half_width, mesh.x(outermost - 1)) << "step " << r.step;
      EXPECT_LE(r.half_width, mesh.x(outermost + 1)) << "step " << r.step;
      EXPECT_LE(r.half_width, sim.plan().fine_width) << "step " << r.step;
      ++checked;
    });
    EXPECT_EQ(checked, 6);
  }
}

namespace {

class UnloadingOutputs : public indentsim::testing::CliTest {};

using indentsim::testing::read_curve;

double json_number(const std::string& json, const std::string& key) {
  std::smatch m;
  if (!std::regex_search(json, m, std::regex("\"" + key + "\": ([-0-9.eE+]+)"))) return std::nan("");
  return std::stod(m.str(1));
}

}  // namespace

TEST_F(UnloadingOutputs, ALoadUnloadRunReportsItsPeakStiffnessAndImprint) {
  // J2, loaded to 50 um in 5 increments and unloaded to 0 in 5: the punch separates on the way up.
  const fs::path out = dir_ / "history";
  ASSERT_EQ(cli("run " + source_path("loadcases/load_unload.toml") +
                " --quiet --set mesh.contact_nodes=6 --set load.path=[0,5e-5,0] --set load.increments=[5,5] --out " +
                out.string()),
            0)
      << err();
  const auto rows = read_curve(out / "curve.csv");  // step, alpha, P, a, contact_nodes, ...
  ASSERT_EQ(rows.size(), 11u);
  for (std::size_t k = 0; k < rows.size(); ++k) {
    SCOPED_TRACE(k);
    const double planned = k <= 5 ? 1e-5 * k : 1e-5 * (10 - k);
    EXPECT_NEAR(rows[k][1], planned, 1e-18);  // the path, loading then unloading
    EXPECT_GE(rows[k][2], 0.0);               // never a tensile punch force
    if (rows[k][2] == 0.0 && k > 0) {
      EXPECT_EQ(rows[k][4], 0.0);  // no force: no node in contact
      EXPECT_EQ(rows[k][3], 0.0);
    }
  }
  EXPECT_GT(rows[5][2], rows[4][2]);       // the peak is at the deepest point
  EXPECT_EQ(rows.back()[2], 0.0);          // separated at alpha = 0: plastic imprint
  const std::string summary = slurp(out / "summary.json");
  EXPECT_NE(summary.find("\"status\": \"finished\""), std::string::npos);
  EXPECT_EQ(json_number(summary, "peak_depth"), rows[5][1]);
  EXPECT_EQ(json_number(summary, "peak_force"), rows[5][2]);
  EXPECT_EQ(json_number(summary, "step"), 5.0);
  const double stiffness = json_number(summary, "stiffness"), loading = json_number(summary, "loading_stiffness");
  EXPECT_NEAR(stiffness, (rows[5][2] - rows[6][2]) / (rows[5][1] - rows[6][1]), 1e-9 * stiffness);
  EXPECT_GT(stiffness, loading);  // unloading is steeper than the loading that made the imprint
  EXPECT_GT(loading, 0.0);
  EXPECT_NE(summary.find("\"separated\": true"), std::string::npos);
  const double residual = json_number(summary, "residual_depth");
  EXPECT_GT(residual, 0.0);
  EXPECT_LT(residual, rows[5][1]);
}
