// Static condensation of the elastic far field (docs/DESIGN.md, section 7): the Schur complement is
// exact, the condensed and full solves give the same curve to solver tolerance, a near field too
// small is detected and grown, and chord steps change the work, not the answer.
#include <algorithm>
#include <cmath>
#include <random>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "indentsim/driver/resume.hpp"
#include "indentsim/solvers/condensation.hpp"
#include "indentsim/simulation/simulation.hpp"
#include "indentsim/solvers/solver.hpp"
#include "test_support.hpp"

using namespace indentsim;
using indentsim::testing::shipped_case;

namespace {

struct Outcome {
  std::vector<IncrementRecord> rows;
  std::vector<double> u;
  NearField near;
  int growths = 0;
  long factorizations = 0;
};

Outcome solve(const LoadCase& lc, std::optional<NearField> near = std::nullopt) {
  Simulation sim(lc, std::nullopt, near);
  Outcome r;
  sim.run([&](const IncrementRecord& rec) {
    r.rows.push_back(rec);
    r.factorizations += rec.factorizations;
  });
  r.u = sim.displacement();
  r.near = sim.near_field();
  r.growths = sim.near_field_growths();
  return r;
}

double largest_magnitude(const std::vector<double>& v) {
  double m = 0.0;
  for (double x : v) m = std::max(m, std::abs(x));
  return m;
}

void expect_same_curve(const Outcome& a, const Outcome& b, double relative) {
  ASSERT_EQ(a.rows.size(), b.rows.size());
  double peak = 0.0;
  for (const auto& r : a.rows) peak = std::max(peak, r.force);
  for (std::size_t k = 0; k < a.rows.size(); ++k) {
    EXPECT_NEAR(a.rows[k].force, b.rows[k].force, relative * peak) << "step " << k;
    EXPECT_EQ(a.rows[k].contact_nodes, b.rows[k].contact_nodes) << "step " << k;
    EXPECT_EQ(a.rows[k].plastic_points, b.rows[k].plastic_points) << "step " << k;
  }
  ASSERT_EQ(a.u.size(), b.u.size());
  const double scale = largest_magnitude(a.u);
  for (std::size_t i = 0; i < a.u.size(); ++i) ASSERT_NEAR(a.u[i], b.u[i], relative * scale) << "unknown " << i;
}

}  // namespace

// The condensed operator is the Schur complement of K_FF: for any near-field displacement, the
// expanded displacement satisfies the far-field equations (K u)_F = 0, and (K u)_R = K_red u_R.
TEST(FarFieldCondensation, SchurComplementIsExact) {
  for (const char* name : {"elastic.toml", "paper.toml"}) {
    SCOPED_TRACE(name);
    const LoadCase lc = shipped_case(name, {"mesh.contact_nodes=6"});
    const MeshPlan plan = plan_mesh(lc);
    Mesh mesh = Mesh::from_plan(lc, plan);
    const StiffnessPattern pattern(mesh);
    const ElasticStiffness k(mesh, ElasticMaterial{lc.material.E, lc.material.nu}, pattern);
    const NodeToRigidContact contact(mesh, make_punch(lc.punch), pattern, k.values());
    const NearField near{true, 8, name == std::string("paper.toml") ? 6 : 0, name == std::string("paper.toml") ? 5 : 0};
    const FarFieldCondensation condensation(k, contact, near);
    ASSERT_LT(condensation.size(), mesh.equations() / 4);
    ASSERT_GT(condensation.interface_size(), 0);

    std::mt19937 random(7);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    std::vector<double> u_near(static_cast<std::size_t>(condensation.size())), u, f(u_near.size()), ku(mesh.equations());
    for (double& x : u_near) x = 1e-6 * unit(random);
    condensation.expand(u_near, u);
    k.multiply(u.data(), ku.data());
    condensation.pattern().multiply(condensation.values(), u_near.data(), f.data());

    const double force_scale = largest_magnitude(ku);
    std::vector<char> is_near(static_cast<std::size_t>(mesh.equations()), 0);
    for (int e : condensation.near_equations()) is_near[e] = 1;
    for (int e = 0; e < mesh.equations(); ++e) {
      if (is_near[e]) continue;
      ASSERT_NEAR(ku[e], 0.0, 1e-11 * force_scale) << "far equation " << e;
    }
    for (std::size_t r = 0; r < u_near.size(); ++r)
      ASSERT_NEAR(f[r], ku[condensation.near_equations()[r]], 1e-11 * force_scale) << "near unknown " << r;
    // The Schur complement of an SPD matrix is SPD: its diagonal stays positive (and softer).
    for (std::int64_t r = 0; r < condensation.size(); ++r)
      EXPECT_GT(condensation.values()[condensation.pattern().diagonal_position(static_cast<int>(r))], 0.0);
  }
}

namespace {

// K_red u = f: the condensed system's own linear equations, its matrix the Jacobian and the
// pivot reference (so KLU analyses the pattern it is given, dense block and all).
class CondensedLinearEquations : public IncrementEquations {
public:
  CondensedLinearEquations(const StiffnessPattern& pattern, const std::vector<double>& values, std::vector<double> load)
      : pattern_(pattern), values_(values), load_(std::move(load)) {}
  const StiffnessPattern& pattern() const override { return pattern_; }
  void residual(const double* u, double, double* f) override {
    pattern_.multiply(values_, u, f);
    for (std::size_t i = 0; i < load_.size(); ++i) f[i] -= load_[i];
  }
  void jacobian(const double*, double, double* values) override { std::copy(values_.begin(), values_.end(), values); }
  bool pivot_reference(double* values) override {
    std::copy(values_.begin(), values_.end(), values);
    return true;
  }

private:
  const StiffnessPattern& pattern_;
  const std::vector<double>& values_;
  std::vector<double> load_;
};

}  // namespace

// K_red's interface unknowns are coupled all to all.  The condensed pattern says so
// (dense_block), and both direct solvers then try that block last, after a nested dissection of
// the rest, against a dissection of the whole graph (METIS then cuts through the clique), and
// keep the order with the smaller factor.  Solved in both orders, the solution is the same; on a
// near field like a plastic run's the block-last order leaves fewer entries in the factors than
// the same pattern ordered as a whole, and on one little wider than its interface, where the
// whole graph's dissection wins, no more.
TEST(FarFieldCondensation, TheDenseInterfaceBlockIsFactoredLastWhereThatLeavesLessFill) {
  struct Scene {
    int contact_nodes;
    NearField near;
    bool block_last_wins;
  };
  for (const Scene& scene : {Scene{20, NearField{true, 30, 40, 30}, true}, Scene{16, NearField{true, 24, 30, 26}, false}}) {
    SCOPED_TRACE(fmt::format("contact_nodes {}, near field {} x {} elements", scene.contact_nodes, scene.near.elements_x,
                             scene.near.elements_y));
    const LoadCase lc = shipped_case("paper.toml", {fmt::format("mesh.contact_nodes={}", scene.contact_nodes)});
    const MeshPlan plan = plan_mesh(lc);
    Mesh mesh = Mesh::from_plan(lc, plan);
    const StiffnessPattern pattern(mesh);
    const ElasticStiffness k(mesh, ElasticMaterial{lc.material.E, lc.material.nu}, pattern);
    const NodeToRigidContact contact(mesh, make_punch(lc.punch), pattern, k.values());
    const FarFieldCondensation condensation(k, contact, scene.near);
    const StiffnessPattern& with_block = condensation.pattern();
    ASSERT_EQ(static_cast<std::int64_t>(with_block.dense_block().size()), condensation.interface_size());
    ASSERT_GT(condensation.interface_size(), 100);
    const StiffnessPattern as_a_whole(with_block.column_start(), with_block.row_index());
    ASSERT_TRUE(as_a_whole.dense_block().empty());

    std::vector<double> load(static_cast<std::size_t>(condensation.size()), 0.0);
    load[static_cast<std::size_t>(condensation.contact().candidates().front().equation)] = -1e3;
    for (LinearSolverKind linear : {LinearSolverKind::klu, LinearSolverKind::cholmod}) {
      SCOPED_TRACE(linear == LinearSolverKind::klu ? "KLU" : "CHOLMOD");
      NewtonSettings settings;
      settings.linear = linear;
      settings.displacement_scale = 1e-6;
      settings.force_scale = 1e3;
      auto solve_with = [&](const StiffnessPattern& p, long& factor_nonzeros) {
        CondensedLinearEquations equations(p, condensation.values(), load);
        NewtonSolver solver(equations, settings);
        std::vector<double> u(load.size(), 0.0);
        const NewtonReport report = solver.solve(0.0, u);
        EXPECT_TRUE(report.converged) << report.message;
        factor_nonzeros = solver.factor_nonzeros();
        return u;
      };
      long block_last = 0, whole = 0;
      const std::vector<double> u_block_last = solve_with(with_block, block_last);
      const std::vector<double> u_whole = solve_with(as_a_whole, whole);
      const double scale = largest_magnitude(u_whole);
      ASSERT_GT(scale, 0.0);
      for (std::size_t i = 0; i < u_whole.size(); ++i) ASSERT_NEAR(u_block_last[i], u_whole[i], 1e-9 * scale) << i;
      ASSERT_GT(block_last, 0);
      if (scene.block_last_wins)
        EXPECT_LT(block_last, whole);
      else if (linear == LinearSolverKind::klu)  // the same dissection of the whole graph either way
        EXPECT_EQ(block_last, whole);
    }
  }
}

TEST(FarFieldCondensation, ElasticSceneSolvesOnlyForTheContactCandidates) {
  Simulation sim(shipped_case("elastic.toml", {"mesh.contact_nodes=10"}));
  ASSERT_TRUE(sim.near_field().condensed);
  EXPECT_EQ(sim.near_field().elements_x, 0);
  EXPECT_EQ(sim.system_unknowns(), sim.near_field().contact_nodes);
  EXPECT_LT(sim.system_unknowns(), sim.mesh().equations() / 50);
}

TEST(FarFieldCondensation, CondensedAndFullSolvesGiveTheSameCurve) {
  for (const char* name : {"elastic.toml", "paper.toml", "load_unload.toml", "power_law.toml"}) {
    SCOPED_TRACE(name);
    auto with = [&](const char* far_field) {
      return solve(shipped_case(name, {"mesh.contact_nodes=8", std::string("solver.far_field=") + far_field}));
    };
    const Outcome condensed = with("condense"), full = with("full");
    ASSERT_TRUE(condensed.near.condensed);
    ASSERT_FALSE(full.near.condensed);
    expect_same_curve(condensed, full, 1e-9);
  }
}

TEST(FarFieldCondensation, TooSmallANearFieldGrowsAndGivesTheSameCurve) {
  // Elastic: 3 contact candidates for a contact of about 8 nodes.
  const LoadCase elastic = shipped_case("elastic.toml", {"mesh.contact_nodes=8", "solver.far_field=full"});
  const Outcome small_elastic = solve(elastic, NearField{true, 3, 0, 0});
  EXPECT_GE(small_elastic.growths, 1);
  EXPECT_GT(small_elastic.near.contact_nodes, 8);
  expect_same_curve(small_elastic, solve(elastic), 1e-9);

  // Plastic: a 2 x 2 block of near elements under a plastic zone several times larger.
  const LoadCase plastic = shipped_case("paper.toml", {"mesh.contact_nodes=8", "solver.far_field=full"});
  const Outcome small_plastic = solve(plastic, NearField{true, 3, 2, 2});
  EXPECT_GE(small_plastic.growths, 1);
  EXPECT_GT(small_plastic.near.elements_x, 2);
  EXPECT_GT(small_plastic.near.elements_y, 2);
  expect_same_curve(small_plastic, solve(plastic), 1e-9);
}

TEST(FarFieldCondensation, AResumedRunContinuesOnTheGrownNearField) {
  const LoadCase lc = shipped_case("paper.toml", {"mesh.contact_nodes=8"});
  Simulation first(lc, std::nullopt, NearField{true, 3, 2, 2});
  first.run();
  ASSERT_GE(first.near_field_growths(), 1);
  const SimulationState state = first.state();
  EXPECT_EQ(state.near_field, first.near_field());
  Simulation second(lc, first.plan().contact_half_width_estimate);
  second.restore(state);
  EXPECT_EQ(second.near_field(), first.near_field());
  EXPECT_EQ(second.system_unknowns(), first.system_unknowns());
  // A near field that does not fit the mesh is refused.
  SimulationState broken = state;
  broken.near_field.elements_x = second.mesh().elements_x() + 1;
  EXPECT_THROW(second.restore(broken), std::invalid_argument);
}

// With a pilot, the near field starts as large as the first increments' plastic zone and grows
// ahead of it: smaller Newton systems early, no increment repeated, the same curve as the whole
// mesh, and a run resumed between two growths grows at the same increments (bit for bit).
TEST(FarFieldCondensation, TheNearFieldGrowsAheadOfThePilotsPlasticZone) {
  for (const char* name : {"deep_plastic.toml", "power_law.toml"}) {
    SCOPED_TRACE(name);
    const LoadCase lc = shipped_case(name, {"mesh.contact_nodes=10", "solver.far_field=condense"});
    Simulation run(lc);
    const NearField first = run.near_field();
    std::vector<IncrementRecord> rows;
    std::vector<SimulationState> states;
    run.run([&](const IncrementRecord& r) {
      rows.push_back(r);
      states.push_back(run.state());
    });
    EXPECT_GE(run.near_field_rebuilds(), 1);
    EXPECT_EQ(run.near_field_growths(), 0) << "the pilot's zone (with its margin) should hold the plastic zone";
    EXPECT_LT(first.elements_x * first.elements_y, run.near_field().elements_x * run.near_field().elements_y);
    ASSERT_FALSE(states.front().plastic_zone_growth.empty());

    Outcome grown{rows, run.displacement(), run.near_field(), 0, 0};
    LoadCase whole = lc;
    whole.solver.far_field = FarFieldChoice::full;
    expect_same_curve(grown, solve(whole), 1e-9);

    // Resume from the first increment (before the later growths): the same rows, bit for bit.
    Simulation resumed(lc, run.plan().contact_half_width_estimate, states[1].near_field);
    resumed.restore(states[1]);
    std::vector<IncrementRecord> rest;
    resumed.run([&](const IncrementRecord& r) { rest.push_back(r); });
    ASSERT_EQ(rest.size() + 2, rows.size());
    for (std::size_t k = 0; k < rest.size(); ++k) EXPECT_EQ(rest[k].force, rows[k + 2].force) << "step " << k + 2;
    EXPECT_EQ(resumed.near_field(), run.near_field());
    EXPECT_EQ(resumed.displacement(), run.displacement());
  }
}

TEST(ChordSteps, KeepTheCurveAndSaveFactorizations) {
  for (const char* name : {"paper.toml", "deep_plastic.toml"}) {
    SCOPED_TRACE(name);
    const Outcome reuse = solve(shipped_case(name, {"mesh.contact_nodes=10", "solver.jacobian=reuse"}));
    const Outcome fresh = solve(shipped_case(name, {"mesh.contact_nodes=10", "solver.jacobian=fresh"}));
    // Both converge to the same tolerance on the same equations; the iterates differ.
    expect_same_curve(reuse, fresh, 1e-8);
    EXPECT_LE(reuse.factorizations, fresh.factorizations);
    RecordProperty(std::string("factorizations_") + name, fmt::format("{} reuse, {} fresh", reuse.factorizations,
                                                                      fresh.factorizations));
  }
}

// solver.jacobian = "krylov" (the default for plastic specimens and for finite strain): GMRES on
// the exact Jacobian, preconditioned by a factorization kept across the Newton iterations of an
// increment.  The same equations to the same tolerance as a factorization every iteration -- both
// plastic models, both scenes, a load path that unloads, both sparse direct solvers as the
// preconditioner, an elastic near field in finite strain -- with fewer factorizations than even
// the chord steps of "reuse".
TEST(KrylovSolves, KeepTheCurveWithFewerFactorizations) {
  struct Scene {
    const char* label;
    const char* name;
    std::vector<std::string> overrides;
  };
  const std::vector<Scene> scenes{
      {"Ilyushin, plane strain", "deep_plastic.toml", {"mesh.contact_nodes=10"}},
      {"J2, unloading", "load_unload.toml", {"mesh.contact_nodes=8"}},
      {"J2, axisymmetric", "axisymmetric/steel_sphere.toml", {"mesh.contact_nodes=8", "load.increments=[6, 3, 1]"}},
      {"CHOLMOD preconditions", "deep_plastic.toml", {"mesh.contact_nodes=8", "solver.linear=cholmod"}},
      {"elastic, finite strain", "axisymmetric/elastic_sphere.toml",
       {"mesh.contact_nodes=8", "geometry.strain=\"finite\"", "mesh.error_estimate=\"off\""}},
  };
  for (const Scene& scene : scenes) {
    SCOPED_TRACE(fmt::format("{} ({})", scene.name, scene.label));
    // What "auto" chooses: every one of these bulks is nonlinear.
    EXPECT_EQ(Simulation(shipped_case(scene.name, scene.overrides)).configuration().jacobian, JacobianChoice::krylov);
    auto with = [&](const char* jacobian) {
      std::vector<std::string> o = scene.overrides;
      o.push_back(std::string("solver.jacobian=") + jacobian);
      return shipped_case(scene.name, o);
    };
    Simulation krylov_run(with("krylov"));
    long linear_iterations = 0;
    Outcome krylov;
    krylov_run.run([&](const IncrementRecord& rec) {
      krylov.rows.push_back(rec);
      krylov.factorizations += rec.factorizations;
      linear_iterations += krylov_run.last_newton_report().linear_iterations;
    });
    krylov.u = krylov_run.displacement();
    const Outcome fresh = solve(with("fresh")), reuse = solve(with("reuse"));
    expect_same_curve(krylov, fresh, 1e-8);
    EXPECT_GT(linear_iterations, 0);  // GMRES did the solving
    EXPECT_LT(krylov.factorizations, reuse.factorizations);
    RecordProperty(fmt::format("factorizations_{}_{}", scene.name, scene.label),
                   fmt::format("{} krylov, {} reuse, {} fresh", krylov.factorizations, reuse.factorizations,
                               fresh.factorizations));
  }
}

// The configuration a run is built on (resolve_choices, what `check` prints) counts the near
// field's unknowns from the mesh alone, as the condensation then builds them: the linear solver
// "auto" is decided on that count.
TEST(FarFieldCondensation, TheConfigurationCountsTheNearFieldAsTheCondensationBuildsIt) {
  for (const char* name : {"elastic.toml", "deep_plastic.toml", "paper.toml", "axisymmetric/steel_sphere.toml",
                           "axisymmetric/berkovich_cone.toml", "axisymmetric/flat_punch.toml"}) {
    SCOPED_TRACE(name);
    const Simulation sim(shipped_case(name, {"mesh.contact_nodes=8", "solver.linear=\"auto\""}));
    const RunConfiguration& c = sim.configuration();
    EXPECT_EQ(c.near_field, sim.near_field());
    EXPECT_EQ(c.system_unknowns, sim.system_unknowns());
    EXPECT_EQ(c.unknowns, sim.mesh().equations());
    EXPECT_EQ(c.element, sim.mesh().element_kind());
  }
}
