// Regression tests for the hostile inputs and faults of the robustness review (one or more per
// numbered item; items 1 and 2, the output-folder splices, are in test_run_folder.cpp).  Every
// run is small and bounded in time.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "indentsim/materials/material.hpp"
#include "indentsim/output/checkpoint.hpp"
#include "indentsim/base/error.hpp"
#include "indentsim/simulation/simulation.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using namespace indentsim;
using indentsim::testing::shipped_case;
using indentsim::testing::slurp;
using indentsim::testing::source_path;

namespace {

class Hostile : public indentsim::testing::CliTest {
protected:
  const std::string elastic = source_path("loadcases/elastic.toml");
  const std::string small = " --quiet --set mesh.contact_nodes=6 --set load.increments=4";
};

// A run's checkpoint rewritten with `edit` applied and its checksum recomputed.
fs::path edited_checkpoint(const fs::path& good, const fs::path& file, const std::function<void(Checkpoint&)>& edit) {
  Checkpoint c = read_checkpoint(good);
  edit(c);
  std::ofstream(file, std::ios::binary) << serialize(c);
  return file;
}

/// A measured load-unload curve after `header` (its lines, the column names last): loading
/// P = 2 k^2 to 100 nm, then 12 unloading rows P = 72 (k/12)^1.5, the columns split by `separator`.
void write_measured_curve(const fs::path& file, const std::string& header, char separator) {
  std::ofstream out(file);
  out << header;
  for (int k = 0; k <= 6; ++k) out << 20 * k << separator << 2.0 * k * k << "\n";
  for (int k = 11; k >= 0; --k) out << 100 + 20.0 * k / 12 << separator << 72.0 * std::pow(k / 12.0, 1.5) << "\n";
}

}  // namespace

// 3. resume DIR takes only checkpoints of the folder's own run, the newest by step, and says which.
TEST_F(Hostile, ResumeOfAFolderTakesOnlyItsOwnRunsCheckpoints) {
  const fs::path run = dir_ / "run", other = dir_ / "other";
  ASSERT_EQ(cli("run " + elastic + small + " --set output.checkpoint_every=2 --out " + run.string()), 0) << err();
  ASSERT_EQ(cli("run " + elastic + small + " --set material.E=70e9 --set load.increments=9 --set output.checkpoint_every=9 "
                "--out " + other.string()),
            0)
      << err();
  // Another case's checkpoints dropped into the folder: one under a foreign name, one named like
  // the run's own and newer by step.
  fs::copy_file(other / "checkpoints" / "checkpoint_000009.ck", run / "checkpoints" / "old.ck");
  fs::copy_file(other / "checkpoints" / "checkpoint_000009.ck", run / "checkpoints" / "checkpoint_000009.ck");
  fs::remove(run / "checkpoints" / "checkpoint_000004.ck");  // the run's newest left is step 2
  ASSERT_EQ(cli("resume " + run.string()), 0) << err();
  EXPECT_NE(out().find("checkpoint_000002.ck"), std::string::npos) << out();
  EXPECT_NE(slurp(run / "case.toml").find("E = 210000000000.0\n"), std::string::npos);
  // Without a case.toml, checkpoints of two runs cannot be told apart: refused, naming both.
  fs::remove(run / "case.toml");
  EXPECT_EQ(cli("resume " + (run / "checkpoints").string()), 2) << err();
  EXPECT_NE(err().find("different runs"), std::string::npos) << err();
}

// 4. Moduli that double precision cannot solve are refused, naming material.E, by run and check.
TEST_F(Hostile, ModuliBeyondDoublePrecisionAreRefused) {
  for (const char* E : {"1e307", "1.7e308", "4.9e-324", "1e-305"}) {
    expect_refused("run " + elastic + small + " --set material.E=" + E, "material.E");
    EXPECT_EQ(cli("check " + elastic + " --set material.E=" + std::string(E)), 2);
  }
}

// 5. Nothing depends on the units beyond the obvious scaling: E x 1e+-6 scales P, a stays.
TEST(HostileScaling, ForceScalesWithTheModulusAndTheContactWidthDoesNot) {
  for (const char* model : {"elastic", "j2"}) {
    SCOPED_TRACE(model);
    const std::vector<std::string> common = {std::string("material.model=") + model, "mesh.contact_nodes=8",
                                             "load.increments=4"};
    // x 1e+-6 as the review tried, and 2^+-290 (about 1e+-87) towards the accepted bounds.
    const double factors[] = {1.0, 1e6, 1e-6, std::ldexp(1.0, 290), std::ldexp(1.0, -290)};
    std::vector<std::vector<IncrementRecord>> curves;
    for (double factor : factors) {
      std::vector<std::string> o = common;
      o.push_back(fmt::format("material.E={:.17g}", 210e9 * factor));
      Simulation sim(shipped_case("deep_plastic.toml", o));
      std::vector<IncrementRecord> rows;
      sim.run([&](const IncrementRecord& r) { rows.push_back(r); });
      curves.push_back(rows);
    }
    for (std::size_t c = 1; c < curves.size(); ++c)
      for (std::size_t k = 0; k < curves[0].size(); ++k) {
        SCOPED_TRACE(k);
        EXPECT_NEAR(curves[c][k].force / factors[c], curves[0][k].force, 1e-8 * curves[0].back().force);
        EXPECT_NEAR(curves[c][k].half_width, curves[0][k].half_width, 1e-8 * curves[0].back().half_width);
        EXPECT_EQ(curves[c][k].contact_nodes, curves[0][k].contact_nodes);
      }
  }
}

// 6. A checkpoint whose checksum was recomputed after an edit is checked by its content.
TEST_F(Hostile, EditedCheckpointsWithAValidChecksumAreRefused) {
  const fs::path run = dir_ / "run";
  ASSERT_EQ(cli("run " + source_path("loadcases/deep_plastic.toml") +
                " --quiet --set mesh.contact_nodes=6 --set load.increments=12 --set output.checkpoint_every=12 --out " +
                run.string()),
            0)
      << err();
  const fs::path good = run / "checkpoints" / "checkpoint_000012.ck";
  const auto cut = [](std::size_t rows) {
    return [rows](Checkpoint& c) {
      c.curve.resize(rows);
      c.free_surface_depths.resize(rows);
      c.state.rows = static_cast<int>(rows);
      c.state.next_target = rows;
    };
  };
  const std::pair<const char*, std::function<void(Checkpoint&)>> edits[] = {
      {"cut1.ck", cut(1)},
      {"cut10.ck", cut(10)},
      {"cut10_alpha.ck",
       [&](Checkpoint& c) {
         cut(10)(c);
         c.state.alpha = c.curve.back().alpha;  // the counters and the depth patched as well
         c.state.deepest = c.state.alpha;
       }},
      {"nan_row.ck", [](Checkpoint& c) { c.curve[5].force = std::nan(""); }},
      {"nan_state.ck", [](Checkpoint& c) { c.state.u[3] = std::nan(""); }},
      {"zero_near_field.ck", [](Checkpoint& c) { c.state.near_field = NearField{true, 0, 0, 0}; }},
      {"force_edited.ck", [](Checkpoint& c) { c.curve.back().force *= 1.01; }},
  };
  for (const auto& [name, edit] : edits) {
    SCOPED_TRACE(name);
    const fs::path file = edited_checkpoint(good, dir_ / name, edit);
    EXPECT_EQ(cli("resume " + file.string() + " --quiet --out " + (dir_ / "never").string()), 2) << err();
    EXPECT_NE(err().find(name), std::string::npos) << err();
    EXPECT_FALSE(fs::exists(dir_ / "never"));
  }
}

// 2. A forged state, its checksum and case hash recomputed, is refused by what the state proves of
// itself: Newton's residual at its displacement, the previous state, each Gauss point's history
// within its law and consistent with the committed strain, and the last row recomputed from it.
TEST_F(Hostile, ForgedStatesWithAValidChecksumAreRefusedByWhatTheStateProves) {
  const auto run_to = [&](const std::string& name, const std::string& options) {
    const fs::path run = dir_ / name;
    EXPECT_EQ(cli("run " + options + " --quiet --set mesh.contact_nodes=6 --out " + run.string()), 0) << err();
    return run / "checkpoints";
  };
  // Ilyushin, at the end of its loading (12 increments); J2 on the unloading branch (row 14).
  const fs::path ilyushin = run_to("ilyushin", source_path("loadcases/deep_plastic.toml") +
                                                   " --set load.increments=12 --set output.checkpoint_every=12") /
                            "checkpoint_000012.ck";
  const fs::path j2 = run_to("j2", source_path("loadcases/load_unload.toml") +
                                       " --set load.increments=[8,8,4] --set output.checkpoint_every=14 "
                                       "--set output.keep_checkpoints='\"all\"'") /
                      "checkpoint_000014.ck";
  // The first Gauss point that has yielded, and where its history starts (after the bulk model's
  // yielded count and largest intensity, and Ilyushin's loading flag).
  const auto yielded_point = [](const Checkpoint& c, std::size_t head, std::size_t value) {
    const std::vector<double>& h = c.state.history;
    for (std::size_t at = head; at + 5 <= h.size(); at += 5)
      if (h[at + value] > 1e-3) return at;
    ADD_FAILURE() << "no yielded point";
    return head;
  };
  const auto ilyushin_point = [&](const Checkpoint& c) { return yielded_point(c, 3, 4); };
  const auto j2_point = [&](const Checkpoint& c) { return yielded_point(c, 2, 4); };
  // The embedded case's kappa set to `value` (its hash recomputed with the checksum).
  const auto embedded_kappa = [](std::string value) {
    return [value](Checkpoint& c) {
      const std::size_t at = c.load_case_toml.find("kappa = ");
      ASSERT_NE(at, std::string::npos);
      c.load_case_toml.replace(at, c.load_case_toml.find('\n', at) - at, "kappa = " + value);
    };
  };
  struct Forgery {
    const char* name;
    const fs::path* good;
    std::function<void(Checkpoint&)> edit;
    std::vector<const char*> says;  ///< the reason given (one of these: the first check that fails)
  };
  const Forgery forgeries[] = {
      {"kappa.ck", &ilyushin, embedded_kappa("0.9"), {"not a converged one", "contact set does not follow"}},
      {"u_node.ck", &ilyushin, [](Checkpoint& c) { c.state.u[c.state.u.size() / 2] *= 1.001; },
       {"not a converged one", "committed strain"}},
      {"u_previous_zeroed.ck", &ilyushin,
       [](Checkpoint& c) { std::fill(c.state.u_previous.begin(), c.state.u_previous.end(), 0.0); },
       {"previous displacement"}},
      {"alpha_previous.ck", &ilyushin, [](Checkpoint& c) { c.state.alpha_previous *= 0.5; }, {"previous depth"}},
      {"peak_intensity.ck", &ilyushin, [&](Checkpoint& c) { c.state.history[ilyushin_point(c) + 4] *= 2.0; },
       {"peak strain intensity"}},
      {"peak_strain.ck", &ilyushin,
       [&](Checkpoint& c) {
         const std::size_t p = ilyushin_point(c);
         std::vector<double>& h = c.state.history;
         for (std::size_t k = 0; k < 4; ++k) h[p + k] *= 1.1;
         h[p + 4] = strain_intensity(VoigtVector(h[p], h[p + 1], h[p + 2], h[p + 3]));  // kept consistent
       },
       {"committed strain"}},
      {"yielded_count.ck", &ilyushin, [](Checkpoint& c) { c.state.history[0] += 1.0; }, {"yielded Gauss points"}},
      {"contact_width.ck", &ilyushin, [](Checkpoint& c) { c.curve.back().half_width *= 3.0; }, {"last curve row"}},
      {"free_surface.ck", &ilyushin, [](Checkpoint& c) { c.free_surface_depths.back() *= 0.5; }, {"free surface"}},
      {"plastic_strain.ck", &j2, [&](Checkpoint& c) { c.state.history[j2_point(c)] *= 2.0; },
       {"not a converged one", "plastic strain"}},
      {"plastic_path_shortened.ck", &j2, [&](Checkpoint& c) { c.state.history[j2_point(c) + 4] *= 0.5; },
       {"material history"}},
      {"j2_kappa.ck", &j2, embedded_kappa("0.98"), {"not a converged one", "yield surface"}},
  };
  for (const Forgery& f : forgeries) {
    SCOPED_TRACE(f.name);
    const fs::path file = edited_checkpoint(*f.good, dir_ / f.name, f.edit);
    EXPECT_EQ(cli("resume " + file.string() + " --quiet --out " + (dir_ / "never").string()), 2) << err();
    EXPECT_NE(err().find(f.name), std::string::npos) << err();
    EXPECT_TRUE(std::any_of(f.says.begin(), f.says.end(),
                            [&](const char* reason) { return err().find(reason) != std::string::npos; }))
        << err();
    EXPECT_FALSE(fs::exists(dir_ / "never"));
  }
  // The untouched checkpoints resume.
  for (const fs::path* good : {&ilyushin, &j2})
    EXPECT_EQ(cli("resume " + good->string() + " --quiet --out " + (dir_ / good->stem()).string()), 0) << err();
}

// 2. The state check measures a checkpoint's residual as the run that converged it did: a branch
// to a path five times shallower (a force scale five times smaller) still resumes.
TEST_F(Hostile, ABranchToAShallowerPathResumesFromTheCheckpointOfADeeperRun) {
  const fs::path run = dir_ / "deep";
  ASSERT_EQ(cli("run " + source_path("loadcases/deep_plastic.toml") +
                " --quiet --set mesh.contact_nodes=6 --set load.path=[0,1e-5,5e-5] --set load.increments=[2,6] "
                "--set output.checkpoint_every=2 --set output.keep_checkpoints='\"all\"' --out " + run.string()),
            0)
      << err();
  EXPECT_EQ(cli("resume " + (run / "checkpoints" / "checkpoint_000002.ck").string() +
                " --quiet --set load.path=[0,1e-5,0] --set load.increments=[2,2] --out " + (dir_ / "branch").string()),
            0)
      << err();
}

// 7. Every key given is validated, whatever the model.
TEST_F(Hostile, PlasticKeysAreValidatedForAnElasticModel) {
  for (const char* bad : {"material.kappa=5", "material.kappa=1", "material.e0=-1", "material.n=5", "material.e0=2"})
    expect_refused("run " + elastic + small + " --set " + bad, std::string(bad).substr(0, std::string(bad).find('=')));
}

// 8, 9. A signal is honoured within an increment: the run stops at once, keeps the last converged
// increment, checkpoints it and exits 128 + signal.  One long increment (a fine plastic mesh):
// honouring the signal only after it would let this run finish with status 0.
TEST_F(Hostile, SigtermWithinALongIncrementStopsItAndKeepsTheLastConvergedOne) {
  const fs::path out = dir_ / "long";
  const std::string curve = (out / "curve.csv").string();
  const std::string command = "timeout 120 " + std::string(INDENTSIM_CLI) + " run " +
                              source_path("loadcases/deep_plastic.toml") +
                              " --quiet --set mesh.contact_nodes=30 --set load.increments=1 --out " + out.string() +
                              " 2>" + (dir_ / "err.txt").string() + " & pid=$!; for i in $(seq 1200); do [ -s " + curve +
                              " ] && [ $(wc -l < " + curve + ") -ge 2 ] && break; sleep 0.05; done; sleep 0.3; " +
                              "kill -TERM $pid; wait $pid";
  const int raw = std::system(("bash -c '" + command + "'").c_str());
  ASSERT_TRUE(WIFEXITED(raw));
  EXPECT_EQ(WEXITSTATUS(raw), 128 + SIGTERM) << err();
  std::istringstream rows(slurp(out / "curve.csv"));
  std::string line;
  int n = 0;
  while (std::getline(rows, line)) ++n;
  EXPECT_EQ(n, 2);  // the header and alpha = 0: the interrupted increment is not reported
  EXPECT_TRUE(fs::exists(out / "checkpoints" / "checkpoint_000000.ck"));
  EXPECT_NE(slurp(out / "summary.json").find("\"stopped\""), std::string::npos);
}

// 10. Inputs below what double precision resolves are refused at once, naming the key.
TEST_F(Hostile, DepthsAndTolerancesBelowDoublePrecisionAreRefused) {
  expect_refused("run " + elastic + small + " --set load.path=[0,1e-300]", "load.path");
  expect_refused("run " + elastic + small + " --set load.path=[0,5e-324]", "load.path");
  expect_refused("run " + elastic + small + " --set solver.tolerance=1e-300", "solver.tolerance");
}

// 11. Output-folder problems are found before solving, by run and by check: exit 2 naming
// output.dir and the reason.
TEST_F(Hostile, OutputFolderProblemsAreFoundBeforeSolving) {
  const fs::path blocked = dir_ / "blocked";
  fs::create_directories(blocked / "curve.csv");  // a folder where a run writes a file
  EXPECT_EQ(cli("run " + elastic + small + " --out " + blocked.string()), 2) << err();
  EXPECT_NE(err().find("output.dir"), std::string::npos) << err();
  EXPECT_EQ(cli("check " + elastic + " --set output.dir=" + blocked.string()), 2) << err();
  EXPECT_FALSE(fs::exists(blocked / "case.toml"));

  const fs::path file_in_the_way = dir_ / "filed";
  fs::create_directories(file_in_the_way);
  std::ofstream(file_in_the_way / "checkpoints") << "not a folder";
  EXPECT_EQ(cli("run " + elastic + small + " --out " + file_in_the_way.string()), 2) << err();
  EXPECT_FALSE(fs::exists(file_in_the_way / "case.toml"));
  EXPECT_FALSE(fs::exists(file_in_the_way / "curve.csv"));

  const fs::path a_file = dir_ / "a_file";
  std::ofstream(a_file) << "x";
  EXPECT_EQ(cli("check " + elastic + " --set output.dir=" + a_file.string()), 2) << err();
  EXPECT_EQ(cli("run " + elastic + small + " --out " + a_file.string()), 2) << err();

  // A folder the kernel will not let anyone write (root included).
  EXPECT_EQ(cli("run " + elastic + small + " --out /proc/sys/kernel"), 2) << err();
  EXPECT_NE(err().find("output.dir"), std::string::npos) << err();
}

// 12. Strings in messages are escaped and cut.
TEST_F(Hostile, MessagesEscapeControlCharactersAndCutLongValues) {
  const fs::path c = dir_ / "nul.toml";
  std::ofstream(c) << slurp(elastic).replace(slurp(elastic).find("model = \"elastic\""), 17, "model = \"\\u00e9lastic\\u0000\"");
  EXPECT_EQ(cli("check " + c.string()), 2);
  EXPECT_NE(err().find("lastic\\x00"), std::string::npos) << err();
  EXPECT_NE(err().find("is not one of"), std::string::npos) << err();
  const fs::path long_case = dir_ / "long.toml";
  std::ofstream(long_case) << slurp(elastic).replace(slurp(elastic).find("model = \"elastic\""), 17,
                                                     "model = \"" + std::string(1 << 20, 'x') + "\"");
  EXPECT_EQ(cli("check " + long_case.string()), 2);
  EXPECT_LT(err().size(), 2000u);
  EXPECT_NE(err().find("more bytes"), std::string::npos) << err();
}

// 13. One --set is one key and one value; --out '' is refused; a case after --set is the case.
TEST_F(Hostile, CommandLineInputIsNeverSilentlyIgnored) {
  expect_refused("run " + elastic + small + " --set $'material.E=70e9\\nnu=0.45'", "material.E");
  expect_refused("run " + elastic + small + " --set $'material.E=70e9\\n[extra]\\nx=1'", "material.E");
  EXPECT_EQ(cli("run " + elastic + small + " --out ''"), 2) << err();
  EXPECT_NE(err().find("--out"), std::string::npos) << err();
  EXPECT_EQ(cli("run --set mesh.contact_nodes=6 " + elastic + " --quiet --set load.increments=2 --out " +
                (dir_ / "ok").string()),
            0)
      << err();
}

// 14. Resolution is warned about at the peak, not at an unloaded end.
TEST_F(Hostile, NoCoarseWarningAtAnUnloadedEnd) {
  ASSERT_EQ(cli("run " + elastic + " --quiet --set mesh.contact_nodes=8 --set load.path=[0,5e-5,0] "
                "--set load.increments=6 --out " + (dir_ / "unloaded").string()),
            0)
      << err();
  EXPECT_EQ(err().find("coarse"), std::string::npos) << err();
  // and a coarse peak is still warned about.
  ASSERT_EQ(cli("run " + elastic + " --quiet --set mesh.contact_nodes=2 --set load.path=[0,5e-5,0] "
                "--set load.increments=6 --out " + (dir_ / "coarse").string()),
            0)
      << err();
  EXPECT_NE(err().find("coarse"), std::string::npos) << err();
}

// Round three of the hostile review (issue 37), in the forms the reviewer gave.

// 1. What double precision cannot resolve is refused naming the key, by check as by run.
TEST_F(Hostile, LengthsDoublePrecisionCannotResolveAreRefusedNamingTheKeyInCheckToo) {
  const std::string paper = source_path("loadcases/paper.toml") + " --set mesh.contact_nodes=8";
  for (const auto& [set, key] : std::vector<std::pair<std::string, std::string>>{
           {"geometry.lx=1e295", "geometry.lx"},
           {"geometry.lx=1e-300", "geometry.lx"},
           {"mesh.fine_depth=1e-300", "mesh.fine_depth"},
           {"mesh.fine_depth=1e-20", "mesh.fine_depth"},
           {"mesh.fine_width=1e-300", "mesh.fine_width"},
           {"mesh.contact_half_width=1e300", "mesh.contact_half_width"}}) {
    SCOPED_TRACE(set);
    EXPECT_EQ(cli("check " + paper + " --set " + set), 2) << err();
    EXPECT_NE(err().find(key), std::string::npos) << err();
    expect_refused("run " + paper + " --set " + set, key);
  }
  // A measured tip with a point closer than double precision resolves, or a height of 1e300.
  const std::string tip = "run " + source_path("loadcases/axisymmetric/measured_profile.toml") + " --set mesh.contact_nodes=6";
  expect_refused(tip + " --set 'punch.profile_points=[[0,0],[1e-300,1e-9],[2e-6,1e-6],[4e-6,4e-6]]'", "punch.profile_points");
  expect_refused(tip + " --set 'punch.profile_points=[[0,0],[1e-6,1e300],[2e-6,1e300]]'", "punch.profile_points");
  // A cone of half-angle 1e-300 plans no mesh of millions of unknowns: refused at once, naming
  // the implausible angle.
  const std::string cone = source_path("loadcases/axisymmetric/berkovich_cone.toml");
  EXPECT_EQ(cli("check " + cone + " --set punch.half_angle=1e-300"), 2) << err();
  EXPECT_NE(err().find("punch.half_angle = 1e-300"), std::string::npos) << err();
}

// Units: every dimensional key outside the magnitudes of its kind is warned about by its own
// name; a yield stress that gives no elastic-limit strain is refused under the key given.
TEST_F(Hostile, UnitSlipsAreNamedByTheKeyTheUserGave) {
  const fs::path c = dir_ / "ys.toml";
  std::string text = slurp(source_path("loadcases/paper.toml"));
  text.replace(text.find("e0 = 0.027"), 10, "yield_stress = 300e6");
  std::ofstream(c) << text;
  EXPECT_EQ(cli("check " + c.string() + " --set material.yield_stress=30"), 2) << err();  // e0 below 1e-9
  EXPECT_NE(err().find("material.yield_stress"), std::string::npos) << err();
  EXPECT_EQ(cli("check " + c.string() + " --set material.yield_stress=3e6"), 0) << err();
  EXPECT_EQ(err().find("material.yield_stress ="), std::string::npos) << err();
  EXPECT_EQ(cli("check " + c.string() + " --set material.yield_stress=3e4"), 0) << err();
  EXPECT_NE(err().find("material.yield_stress = 30000 Pa lies outside"), std::string::npos) << err();
  EXPECT_EQ(cli("check " + c.string() + " --set material.E=70"), 2) << err();  // sigma_y / 3 mu = 1e7
  EXPECT_NE(err().find("material.yield_stress"), std::string::npos) << err();
  EXPECT_NE(err().find("material.E = 70"), std::string::npos) << err();
  EXPECT_EQ(err().find("material.e0"), std::string::npos) << err();
  EXPECT_EQ(cli("check " + c.string() + " --set material.E=1e400"), 2) << err();
  EXPECT_NE(err().find("beyond double precision"), std::string::npos) << err();
  // A cone's contact too large for its specimen asks about the depth, not a radius it has not.
  EXPECT_EQ(cli("check " + source_path("loadcases/axisymmetric/berkovich_cone.toml") + " --set geometry.lx=1e-5 "
                "--set geometry.ly=1e-5"),
            0)
      << err();
  EXPECT_EQ(err().find("punch.radius"), std::string::npos) << err();
  EXPECT_NE(err().find("load.path"), std::string::npos) << err();
}

// Without output.dir a run goes to out/<case name>, so two cases run from one folder keep theirs.
TEST_F(Hostile, RunsOfDifferentCasesKeepTheirOwnFolders) {
  std::string text = slurp(elastic);
  text.erase(text.find("dir = "), text.find('\n', text.find("dir = ")) - text.find("dir = ") + 1);
  std::ofstream(dir_ / "steel.toml") << text;
  std::ofstream(dir_ / "glass.toml") << text;
  const std::string in_the_folder = "cd " + dir_.string() + " &&";
  ASSERT_EQ(cli("run steel.toml" + small, in_the_folder), 0) << err();
  ASSERT_EQ(cli("run glass.toml" + small, in_the_folder), 0) << err();
  EXPECT_TRUE(fs::is_regular_file(dir_ / "out" / "steel" / "curve.csv"));
  EXPECT_TRUE(fs::is_regular_file(dir_ / "out" / "glass" / "curve.csv"));
}

// An instrument's export: '#' comments, "Number of Points = N", a title line, tab-separated.
TEST_F(Hostile, InstrumentHeadersWithCommentsAndMetadataLinesAreRead) {
  const fs::path file = dir_ / "hysitron.txt";
  write_measured_curve(file, "# exported by the instrument\nNumber of Points = 19\nSample A\n\nDepth (nm)\tLoad (uN)\n", '\t');
  EXPECT_EQ(cli("analyze " + file.string() + " --set punch.shape=cone --set punch.half_angle=70.3"), 0) << err();
  EXPECT_EQ(err().find("error"), std::string::npos) << err();
}

// 2. A warning stored in a checkpoint is printed escaped on resume, never raw.
TEST_F(Hostile, AWarningStoredInACheckpointIsPrintedEscaped) {
  const fs::path run = dir_ / "run";
  ASSERT_EQ(cli("run " + elastic + small + " --set output.checkpoint_every=2 --out " + run.string()), 0) << err();
  const fs::path forged = edited_checkpoint(run / "checkpoints" / "checkpoint_000002.ck", dir_ / "forged.ck", [](Checkpoint& c) {
    c.state.warnings.push_back(std::string("\x1b[2J") + std::string(1, '\0') + std::string(1 << 20, 'w'));
  });
  cli("resume " + forged.string() + " --quiet --out " + (dir_ / "resumed").string());
  EXPECT_EQ(err().find('\x1b'), std::string::npos);
  EXPECT_LT(err().size() + out().size(), 20000u);
}

// 3. Resumed after the peak, summary.json keeps the peak's true contact (S_exact, true_H, ...).
TEST_F(Hostile, AResumeAfterThePeakKeepsThePeaksTrueContact) {
  const std::string cone = source_path("loadcases/axisymmetric/berkovich_cone.toml") +
                           " --quiet --set mesh.contact_nodes=8 --set output.checkpoint_every=2 "
                           "--set output.keep_checkpoints='\"all\"'";
  const fs::path whole = dir_ / "whole", resumed = dir_ / "resumed";
  ASSERT_EQ(cli("run " + cone + " --out " + whole.string()), 0) << err();
  ASSERT_EQ(cli("resume " + (whole / "checkpoints" / "checkpoint_000030.ck").string() + " --quiet --out " +
                resumed.string()),
            0)
      << err();
  const auto a = nlohmann::json::parse(slurp(whole / "summary.json"));
  const auto b = nlohmann::json::parse(slurp(resumed / "summary.json"));
  const auto& ua = a.at("unloading").at(0).at("analysis");
  const auto& ub = b.at("unloading").at(0).at("analysis");
  for (const char* key : {"S_exact", "true_H", "true_area", "true_contact_radius", "pile_up_ratio"}) {
    SCOPED_TRACE(key);
    ASSERT_TRUE(ua.at(key).is_number());
    EXPECT_EQ(ua.at(key), ub.at(key));
  }
}

// 4. A run folder moved or copied resumes where it is, keeping its files.
TEST_F(Hostile, AMovedRunFolderResumesWhereItIsAndKeepsItsFiles) {
  const fs::path a = dir_ / "A", moved = dir_ / "B2";
  ASSERT_EQ(cli("run " + elastic + small + " --set load.increments=8 --set output.fields_every=1 "
                "--set output.checkpoint_every=2 --set output.keep_checkpoints='\"all\"' --out " + a.string()),
            0)
      << err();
  fs::remove(a / "checkpoints" / "checkpoint_000008.ck");
  fs::rename(a, moved);
  ASSERT_EQ(cli("resume " + moved.string() + " --quiet"), 0) << err();
  EXPECT_FALSE(fs::exists(a));
  EXPECT_NE(slurp(moved / "summary.json").find("\"finished\""), std::string::npos);
  ASSERT_EQ(cli("resume " + (moved / "checkpoints" / "checkpoint_000004.ck").string() + " --quiet --out " + moved.string()), 0)
      << err();
  std::size_t vtus = 0, checkpoints = 0;
  for (const auto& e : fs::directory_iterator(moved / "fields")) vtus += e.path().extension() == ".vtu";
  for (const auto& e : fs::directory_iterator(moved / "checkpoints")) checkpoints += e.path().extension() == ".ck";
  EXPECT_EQ(vtus, 9u);
  EXPECT_EQ(checkpoints, 4u);
}

// 5. A branch's case.toml reproduces the branch (the pilot's measurements are in it).
TEST_F(Hostile, ABranchsCaseTomlReproducesTheBranch) {
  const std::string plastic = source_path("loadcases/load_unload.toml") + " --quiet --set mesh.contact_nodes=8";
  const fs::path run = dir_ / "R", branch = dir_ / "BR", again = dir_ / "again";
  ASSERT_EQ(cli("run " + plastic + " --out " + run.string()), 0) << err();
  ASSERT_EQ(cli("resume " + (run / "checkpoints" / "checkpoint_000010.ck").string() +
                " --quiet --set 'load.path=[0,5e-5,2e-5]' --set 'load.increments=[10,10]' --out " + branch.string()),
            0)
      << err();
  ASSERT_EQ(cli("run " + (branch / "case.toml").string() + " --quiet --out " + again.string()), 0) << err();
  // Column 2 is P; equal to the solver's tolerance (the resumed branch starts from the run's own
  // near field, the rerun from the pilot's zone: condensation is exact, round-off is not shared).
  const auto a = indentsim::testing::read_curve(branch / "curve.csv"), b = indentsim::testing::read_curve(again / "curve.csv");
  ASSERT_EQ(a.size(), b.size());
  double peak = 0.0;
  for (const auto& row : a) peak = std::max(peak, row[2]);
  for (std::size_t k = 0; k < a.size(); ++k) EXPECT_NEAR(a[k][2], b[k][2], 1e-8 * peak) << "row " << k;
}

// 8. The output tree is checked before anything is locked or removed.
TEST_F(Hostile, WhatARunCannotReplaceIsFoundBeforeItRemovesAnything) {
  const fs::path run = dir_ / "run";
  ASSERT_EQ(cli("run " + elastic + small + " --out " + run.string()), 0) << err();
  fs::create_directories(run / "fields" / "step_000050.vtu" / "x");
  EXPECT_EQ(cli("check " + elastic + " --set output.dir='\"" + run.string() + "\"'"), 2) << err();
  EXPECT_EQ(cli("run " + elastic + small + " --out " + run.string()), 2) << err();
  EXPECT_NE(err().find("step_000050.vtu"), std::string::npos) << err();
  EXPECT_TRUE(fs::exists(run / "case.toml"));
  fs::remove_all(run / "fields" / "step_000050.vtu");
  fs::remove(run / ".indentsim.lock");
  fs::create_directories(run / ".indentsim.lock");
  EXPECT_EQ(cli("check " + elastic + " --set output.dir='\"" + run.string() + "\"'"), 2) << err();
  EXPECT_NE(err().find(".indentsim.lock"), std::string::npos) << err();
  fs::remove(run / ".indentsim.lock");
  EXPECT_EQ(cli("run " + elastic + small + " --set output.dir='\"a\\u0000b\"'"), 2) << err();
  EXPECT_FALSE(fs::exists(dir_ / "a"));
}

// 11. Messages name what is wrong.
TEST_F(Hostile, MessagesNameTheKeyAndTheFieldThatAreWrong) {
  const fs::path run = dir_ / "run";
  ASSERT_EQ(cli("run " + elastic + small + " --set output.checkpoint_every=2 --out " + run.string()), 0) << err();
  EXPECT_EQ(cli("resume " + (run / "checkpoints" / "checkpoint_000002.ck").string() +
                " --set 'load.path=[0,4e-5,0]' --out " + (dir_ / "b").string()),
            2);
  EXPECT_NE(err().find("load.path"), std::string::npos) << err();
  EXPECT_EQ(cli("resume " + (run / "checkpoints" / "checkpoint_000002.ck").string() +
                " --set solver.tolerance=1e-4 --out " + (dir_ / "t").string()),
            2);
  EXPECT_NE(err().find("solver.tolerance"), std::string::npos) << err();
  EXPECT_EQ(cli("analyze " + (dir_ / "missing.csv").string()), 2);
  EXPECT_NE(err().find("does not exist"), std::string::npos) << err();
  const fs::path empty = dir_ / "empty";
  fs::create_directories(empty);
  EXPECT_EQ(cli("plot " + empty.string()), 2);
  EXPECT_NE(err().find("holds no run"), std::string::npos) << err();
  EXPECT_EQ(cli("plot " + run.string() + " --step 99999"), 2);
  EXPECT_NE(err().find("--step"), std::string::npos) << err();
  const fs::path profile = dir_ / "tip.csv";
  std::ofstream(profile) << "r,g\n0,0\n1e-6,nan\n2e-6,1e-6\n";
  std::string text = slurp(source_path("loadcases/axisymmetric/measured_profile.toml"));
  std::ofstream(dir_ / "tip.toml") << text.replace(text.find("\"tip_profile.csv\""), 17, "\"tip.csv\"");
  EXPECT_EQ(cli("check " + (dir_ / "tip.toml").string()), 2);
  EXPECT_NE(err().find("g = \"nan\""), std::string::npos) << err();
  // Depth in nm declared as m: H of no solid, warned.
  const fs::path nm = dir_ / "nm.csv";
  write_measured_curve(nm, "Depth (m),Load (mN)\n", ',');
  EXPECT_EQ(cli("analyze " + nm.string() + " --set punch.shape=cone --set punch.half_angle=70.3"), 0) << err();
  EXPECT_NE(err().find("no solid's"), std::string::npos) << err();
}
