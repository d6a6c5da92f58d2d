// The load path in time (docs/MODEL.md §13.2): load.times gives each waypoint its time, a repeated
// waypoint is a hold, the increments are spread by duration and curve.csv carries each row's time.
// Every material model is rate-independent so far: a hold must repeat its state exactly, under
// depth control and under force control alike.
#include <cmath>
#include <csignal>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "indentsim/base/error.hpp"
#include "indentsim/fitting/forward_model.hpp"
#include "indentsim/input/load_case.hpp"
#include "indentsim/simulation/load_stepping.hpp"
#include "indentsim/simulation/simulation.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using namespace indentsim;
using indentsim::testing::shipped_case;

// "Load in 10 s, hold 20 s, unload in 10 s" with 8 increments: by duration 2, 4 and 2, each at
// its place in time; by the path's length alone the hold would get none.
TEST(LoadTimes, IncrementsAreSpreadByDurationSoThatAHoldGetsItsShareOfTime) {
  LoadInput load;
  load.path = {0.0, 1e-6, 1e-6, 0.0};
  load.increments = 8;
  EXPECT_EQ(segment_increments(load), (std::vector<int>{4, 0, 4}));
  EXPECT_TRUE(plan_times(load).empty());

  load.times = {0.0, 10.0, 30.0, 40.0};
  EXPECT_EQ(segment_increments(load), (std::vector<int>{2, 4, 2}));
  const std::vector<double> times = plan_times(load), targets = plan_increments(load);
  ASSERT_EQ(times.size(), 9u);
  ASSERT_EQ(targets.size(), 9u);
  for (std::size_t k = 0; k < times.size(); ++k) EXPECT_DOUBLE_EQ(times[k], 5.0 * static_cast<double>(k)) << k;
  for (std::size_t k = 2; k <= 6; ++k) EXPECT_EQ(targets[k], 1e-6) << k;  // the hold, at the peak
  EXPECT_EQ(targets.back(), 0.0);

  // Per-segment counts are the user's, with or without times.
  load.segment_increments = {1, 2, 3};
  EXPECT_EQ(segment_increments(load), (std::vector<int>{1, 2, 3}));
  EXPECT_DOUBLE_EQ(plan_times(load)[2], 20.0);
}

// J2 plasticity has no rate: through a hold at the peak depth (depth control) or the peak force
// (force control) the force and the depth stay those of the peak, and Newton starts converged.
TEST(LoadTimes, ARateIndependentSpecimenRepeatsItsStateThroughAHold) {
  const std::vector<std::string> common{"mesh.contact_nodes=8", "mesh.contact_half_width=3.2e-6",
                                        "mesh.error_estimate=off", "load.times=[0, 10, 20, 25]",
                                        "load.increments=[5, 3, 2]"};
  for (const bool force_control : {false, true}) {
    SCOPED_TRACE(force_control ? "force control" : "depth control");
    std::vector<std::string> overrides = common;
    if (force_control) {
      overrides.insert(overrides.end(), {"load.control=force", "load.path=[0, 0.02, 0.02, 0.01]",
                                         "load.depth_estimate=1e-6"});
    } else {
      overrides.push_back("load.path=[0, 1e-6, 1e-6, 0.8e-6]");
    }
    const LoadCase lc = shipped_case("axisymmetric/berkovich_cone.toml", overrides);
    Simulation sim(lc);
    std::vector<IncrementRecord> rows;
    sim.run([&](const IncrementRecord& r) { rows.push_back(r); });
    ASSERT_EQ(rows.size(), 11u);  // step 0 and 10 increments
    const IncrementRecord& peak = rows[5];
    EXPECT_GT(peak.plastic_points, 0);
    for (std::size_t k = 6; k <= 8; ++k) {
      SCOPED_TRACE(k);
      EXPECT_NEAR(rows[k].force, peak.force, 1e-10 * peak.force);
      EXPECT_NEAR(rows[k].alpha, peak.alpha, 1e-10 * peak.alpha);
      EXPECT_EQ(rows[k].plastic_points, peak.plastic_points);
      EXPECT_LE(rows[k].newton_iterations, 1);
    }
    EXPECT_LT(rows.back().force, peak.force);  // and the unloading after it unloads
  }
}

TEST(LoadTimes, TimesThatDoNotFitThePathAreRefusedByName) {
  const auto refused = [](const std::vector<std::string>& overrides) {
    std::vector<std::string> all{"load.path=[0, 1e-6, 1e-6, 0]"};
    all.insert(all.end(), overrides.begin(), overrides.end());
    return indentsim::testing::refused_key("axisymmetric/elastic_sphere.toml", all);
  };
  EXPECT_EQ(refused({"load.times=[0, 10, 20]"}), "load.times");         // one time short
  EXPECT_EQ(refused({"load.times=[1, 10, 20, 30]"}), "load.times");     // not from 0
  EXPECT_EQ(refused({"load.times=[0, 10, 10, 30]"}), "load.times");     // a segment of no duration
  EXPECT_EQ(refused({"load.times=[0, 10, 5, 30]"}), "load.times");      // time running back
  EXPECT_EQ(refused({"load.times=[0, 10, 20, 30]"}), "");
  // A force-depth curve is fitted along the data's depths; with its time column, as a time history
  // along the protocol.
  const LoadCase timed = shipped_case("axisymmetric/elastic_sphere.toml",
                                      {"load.path=[0, 1e-6, 1e-6, 0]", "load.times=[0, 10, 20, 30]"});
  try {
    refuse_unfittable_load(timed, FitDataKind::force_depth_curve);
    FAIL() << "the fit took a case with load.times for a curve without time";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "load.times");
  }
  EXPECT_NO_THROW(refuse_unfittable_load(timed, FitDataKind::time_history));
}

class LoadTimesCli : public indentsim::testing::CliTest {};

// curve.csv gains each row's time after its step, the run warns that time reaches no law, and a
// run killed in its hold resumes to the same curve, times included; a resume that moves the
// times of rows already written is refused by name.  The analysis reads the run's time: its hold
// has crept by nothing, and Feng and Ngan's correction leaves the stiffness as it is.
// A dense time history is fitted at the ends of the protocol's increments, each point from the
// rows of its own segment: the corner where the ramp meets the hold is kept sharp.  Rows on the
// exact piecewise-linear response reduce to it exactly (a quadratic through a line), also at the
// corner, where a window across it would round the corner off by a tenth of an increment's rise.
TEST(LoadTimes, ADenseTimeHistoryIsReducedToTheProtocolsIncrementsWithoutRoundingItsCorners) {
  FitData data;
  data.kind = FitDataKind::time_history;
  data.file = "dense.csv";
  data.load_case = shipped_case("axisymmetric/elastic_sphere.toml",
                                {"load.path=[0, 1e-6, 1e-6]", "load.times=[0, 1, 2]", "load.increments=[4, 4]"});
  const auto response = [](double t) { return t < 1.0 ? 0.5 * t : 0.5 + 0.1 * (t - 1.0); };
  for (int k = 1; k <= 2000; ++k) {
    data.abscissa.push_back(2.0 * k / 2000.0);
    data.values.push_back(response(data.abscissa.back()));
  }
  const CurveReduction r = reduce_to_resolution(data);
  ASSERT_TRUE(r.reduced);
  ASSERT_EQ(data.abscissa.size(), 8u);
  for (std::size_t i = 0; i < 8; ++i) {
    EXPECT_NEAR(data.abscissa[i], 0.25 * static_cast<double>(i + 1), 1e-12);
    EXPECT_NEAR(data.values[i], response(data.abscissa[i]), 1e-12) << "t = " << data.abscissa[i];
  }
}

TEST_F(LoadTimesCli, CurveRowsCarryTheirTimeThroughAKillAndAResume) {
  const std::string source = indentsim::testing::source_path("loadcases/axisymmetric/berkovich_cone.toml");
  const std::string args = " --set mesh.contact_nodes=8 --set load.path=[0,1e-6,1e-6,0.96e-6] "
                           "--set load.times=[0,10,20,30] --set load.increments=12 "
                           "--set output.checkpoint_every=2";
  ASSERT_EQ(cli("run " + source + args + " --out " + (dir_ / "full").string()), 0) << err();
  EXPECT_NE(err().find("load.times only labels the increments"), std::string::npos) << err();
  const std::string expected = indentsim::testing::curve_without_timing(dir_ / "full" / "curve.csv");
  EXPECT_EQ(expected.substr(0, expected.find('\n')).rfind("step,time,alpha,P,", 0), 0u) << expected;
  // 12 increments by duration: 4 loading, 4 holding, 4 unloading; every row at its planned time.
  const std::vector<std::vector<double>> rows = indentsim::testing::read_curve(dir_ / "full" / "curve.csv");
  ASSERT_EQ(rows.size(), 13u);
  for (std::size_t k = 0; k < rows.size(); ++k) EXPECT_NEAR(rows[k][1], 2.5 * static_cast<double>(k), 1e-12 * 30.0) << k;

  ASSERT_EQ(cli("analyze " + (dir_ / "full").string()), 0) << err();
  const auto json = nlohmann::json::parse(indentsim::testing::slurp(dir_ / "full" / "analysis.json"));
  const auto& hold = json["branches"][0]["hold"];
  ASSERT_TRUE(hold.is_object()) << json["branches"][0].dump();
  EXPECT_DOUBLE_EQ(hold["duration_s"].get<double>(), 10.0);
  EXPECT_NEAR(hold["creep_depth"].get<double>(), 0.0, 1e-12 * 1e-6);
  EXPECT_NEAR(hold["S_corrected"].get<double>() / json["branches"][0]["S_fit"].get<double>(), 1.0, 1e-9);

  const fs::path out = dir_ / "killed";
  EXPECT_EQ(cli("run " + source + args + " --quiet --out " + out.string(), "INDENTSIM_FAULT=increment:7"),
            128 + SIGKILL);
  EXPECT_EQ(cli("resume " + (out / "checkpoints").string() + " --quiet --set load.times=[0,10,30,40]"), 2);
  EXPECT_NE(err().find("load.times"), std::string::npos) << err();
  ASSERT_EQ(cli("resume " + (out / "checkpoints").string() + " --quiet"), 0) << err();
  EXPECT_EQ(indentsim::testing::curve_without_timing(out / "curve.csv"), expected);
}
