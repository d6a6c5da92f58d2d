// Coated and layered specimens (docs/MODEL.md §14): the material-region seam is bit for bit on
// one material, a coated specimen tends to its film's Hertz force as the film thickens and to its
// substrate's as a compliant film thins, tractions are continuous across an interface while the
// in-plane stress jumps, and every bad layer is refused naming the layer and the key.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "indentsim/analysis/coating_analysis.hpp"
#include "indentsim/analysis/curve_analysis.hpp"
#include "indentsim/base/error.hpp"
#include "indentsim/fitting/fit.hpp"
#include "indentsim/geometry/mesh.hpp"
#include "indentsim/input/load_case.hpp"
#include "indentsim/simulation/simulation.hpp"
#include "indentsim/solvers/line_forces.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using namespace indentsim;
using indentsim::testing::small_sphere_case;

namespace {

/// The forces at every increment of a run.
std::vector<double> forces_of(const LoadCase& lc) {
  std::vector<double> forces;
  for (const IncrementRecord& r : indentsim::testing::run_rows(lc)) forces.push_back(r.force);
  return forces;
}

/// The depth of the k-th node row below the surface of the case's own (homogeneous) mesh.
double node_depth(const LoadCase& lc, std::size_t k) {
  const MeshPlan plan = plan_mesh(lc);
  return graded_axis(lc.geometry.ly, plan.fine_depth, plan.fine_spacing, plan.growth).at(k);
}

/// A layer of `material` and `thickness` on the case's substrate.
LoadCase with_layer(LoadCase lc, double thickness, const MaterialInput& material) {
  lc.layers.push_back({thickness, material});
  validate(lc);
  return lc;
}

MaterialInput elastic(double E, double nu) {
  MaterialInput m;
  m.model = MaterialModel::elastic;
  m.E = E;
  m.nu = nu;
  return m;
}

/// Hertz's force of a rigid sphere of radius R at depth h on a half-space of modulus E*.
double hertz_force(double E_star, double R, double h) { return 4.0 / 3.0 * E_star * std::sqrt(R) * std::pow(h, 1.5); }

/// The axisymmetric elastic sphere of loadcases/axisymmetric/elastic_sphere.toml (a/lx < 0.004).
LoadCase sphere_on(const MaterialInput& substrate) {
  LoadCase lc = indentsim::testing::shipped_case("axisymmetric/elastic_sphere.toml", {"load.increments=2"});
  lc.material = substrate;
  return lc;
}

const std::string& layer_case = indentsim::testing::small_case_toml;

/// The key a load case of `layers` (TOML appended to layer_case) is refused by, or "" when taken.
std::string refused_key(const std::string& layers, const std::vector<std::string>& overrides = {}) {
  try {
    parse_load_case(layer_case + layers, "layers.toml", overrides);
  } catch (const InputError& e) {
    return e.key();
  }
  return "";
}

}  // namespace

TEST(Layers, ALayerOfTheSubstratesOwnMaterialOnAMeshLineIsTheHomogeneousSpecimenBitForBit) {
  // The seam (docs/MODEL.md §14.1): the element matrices, the point laws and the history by
  // region give exactly one material's run when every region holds that material and the
  // interface lies on a line of the homogeneous mesh.
  for (const SceneKind scene : {SceneKind::plane_strain, SceneKind::axisymmetric})
    for (const MaterialModel model : {MaterialModel::elastic, MaterialModel::ilyushin, MaterialModel::j2}) {
      SCOPED_TRACE(fmt::format("{} {}", to_string(scene), to_string(model)));
      LoadCase homogeneous = small_sphere_case(scene, model, HardeningLaw::linear);
      homogeneous.load.path = {0.0, 20e-6, 8e-6};
      homogeneous.load.segment_increments = {4, 2};
      const LoadCase coated = with_layer(homogeneous, node_depth(homogeneous, 6), homogeneous.material);
      EXPECT_EQ(Mesh::from_plan(coated, plan_mesh(coated)).y(), Mesh::from_plan(homogeneous, plan_mesh(homogeneous)).y());
      const std::vector<double> expected = forces_of(homogeneous), got = forces_of(coated);
      ASSERT_EQ(got.size(), expected.size());
      for (std::size_t k = 0; k < got.size(); ++k) EXPECT_EQ(got[k], expected[k]) << "increment " << k;
    }
}

TEST(Layers, ALayersImplausibleValueIsWarnedNamingTheLayer) {
  LoadCase lc = small_sphere_case(SceneKind::axisymmetric, MaterialModel::elastic, HardeningLaw::linear);
  lc = with_layer(lc, 1e-5, elastic(400, 0.25));  // GPa meant, Pa written
  const std::vector<std::string> warnings = implausible_values(lc);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0].rfind("layer[1].material.E = 400", 0), 0u) << warnings[0];
}

TEST(Layers, InterfacesAreMeshLinesAndEveryLayerHasItsRows) {
  // docs/MODEL.md §14.3: every interface a node row; at least 4 rows per layer however thin; no
  // element more than twice its neighbour once a thin film refined the rows near it.
  LoadCase lc = small_sphere_case(SceneKind::axisymmetric, MaterialModel::elastic, HardeningLaw::linear);
  const double spacing = plan_mesh(lc).fine_spacing;
  lc = with_layer(lc, 0.013 * spacing, elastic(400e9, 0.25));          // far thinner than an element
  lc = with_layer(lc, 2.37 * spacing, elastic(100e9, 0.3));            // between lines
  lc = with_layer(lc, 40.0 * spacing, elastic(150e9, 0.3));            // into the graded zone
  const Mesh mesh = Mesh::from_plan(lc, plan_mesh(lc));
  const std::vector<double> interfaces = lc.interface_depths();
  std::vector<int> rows(lc.regions(), 0);
  for (int ej = 0; ej < mesh.elements_y(); ++ej) {
    ++rows[static_cast<std::size_t>(mesh.region(ej))];
    const double top = -mesh.y(ej + 1), bottom = -mesh.y(ej);
    EXPECT_EQ(static_cast<int>(lc.region_at_depth(0.5 * (top + bottom))), mesh.region(ej));
    const double size = bottom - top;
    if (ej > 0) EXPECT_LE(size, 2.0 * (mesh.y(ej) - mesh.y(ej - 1)) * (1 + 1e-12)) << "row " << ej;
    if (ej + 1 < mesh.elements_y()) EXPECT_LE(size, 2.0 * (mesh.y(ej + 2) - mesh.y(ej + 1)) * (1 + 1e-12)) << "row " << ej;
  }
  for (const double depth : interfaces) {
    bool on_a_line = false;
    for (const double y : mesh.y()) on_a_line = on_a_line || y == -depth;
    EXPECT_TRUE(on_a_line) << "interface at " << depth;
  }
  for (std::size_t k = 1; k < lc.regions(); ++k) EXPECT_GE(rows[k], min_rows_per_layer) << "layer " << k;
  EXPECT_EQ(plan_mesh(lc).nodes_y, mesh.nodes_y());
}

TEST(Layers, AnElasticFilmThickAgainstTheContactGivesTheFilmsHertzForce) {
  // A stiff film (210 GPa) on a compliant substrate (100 GPa) under a sphere: the substrate's
  // share falls as a/t (Gao, Chiu and Lee, Int. J. Solids Struct. 29, 1992, eq. 20's first order),
  // so P(t) and P(2t) extrapolate to the infinitely thick film, whose force is Hertz's.
  const MaterialInput film = elastic(210e9, 0.3);
  const LoadCase homogeneous = sphere_on(film);
  const double R = homogeneous.punch.radius, h = homogeneous.max_depth(), a = std::sqrt(R * h);
  const double thin = forces_of(with_layer(sphere_on(elastic(100e9, 0.3)), 20 * a, film)).back();
  const double thick = forces_of(with_layer(sphere_on(elastic(100e9, 0.3)), 40 * a, film)).back();
  const double own = forces_of(homogeneous).back();
  const double hertz = hertz_force(film.E / (1 - film.nu * film.nu), R, h);
  const double extrapolated = 2.0 * thick - thin;
  std::cout << fmt::format("P(t = 20 a) = {:.5g} N, P(40 a) = {:.5g} N -> {:.5g} N at t -> infinity; the film's own "
                           "{:.5g} N, Hertz {:.5g} N\n",
                           thin, thick, extrapolated, own, hertz);
  EXPECT_LT(thin, thick);
  EXPECT_LT(thick, own);
  EXPECT_NEAR(extrapolated / own, 1.0, 5e-3);     // the film's own run on the same mesh
  EXPECT_NEAR(extrapolated / hertz, 1.0, 1e-2);   // and Hertz, as the homogeneous scenes agree with it
}

TEST(Layers, AThinCompliantFilmGivesTheSubstratesForce) {
  // A compliant film (50 GPa) on steel (210 GPa): its extra compliance grows as its thickness t,
  // so P(t) and P(t/4) extrapolate to t = 0, the bare substrate's force.
  const MaterialInput substrate = elastic(210e9, 0.3);
  const LoadCase bare = sphere_on(substrate);
  const double a = std::sqrt(bare.punch.radius * bare.max_depth());
  const double p_t = forces_of(with_layer(bare, a / 100, elastic(50e9, 0.3))).back();
  const double p_quarter = forces_of(with_layer(bare, a / 400, elastic(50e9, 0.3))).back();
  const double own = forces_of(bare).back();
  std::cout << fmt::format("P(t = a/100) = {:.5g} N, P(a/400) = {:.5g} N, the bare substrate's {:.5g} N\n", p_t, p_quarter, own);
  EXPECT_LT(p_t, p_quarter);
  EXPECT_LT(p_quarter, own);
  // First order in t: the deviation falls by 4 from t to t/4, and the extrapolation is the substrate.
  EXPECT_NEAR((own - p_t) / (own - p_quarter), 4.0, 0.5);
  EXPECT_NEAR((4.0 * p_quarter - p_t) / 3.0 / own, 1.0, 2e-3);
}

TEST(Layers, TractionsAreContinuousAcrossAnInterfaceAndTheLayersAreInEquilibrium) {
  // A film four times stiffer than its substrate, its interface at 0.7 a*, near the depth of the
  // largest shear: sigma_22 and sigma_12 extrapolated to the interface from the rows above and
  // below differ by a discretization error, which halves as the mesh does; sigma_11 jumps by the
  // physics (the film carries the bending), whatever the mesh; and the force across every line is
  // P to round-off.
  for (const SceneKind scene : {SceneKind::plane_strain, SceneKind::axisymmetric}) {
    std::vector<double> traction_jumps, in_plane_jumps;
    for (const int nodes : {20, 40}) {
      SCOPED_TRACE(fmt::format("{}, {} contact nodes", to_string(scene), nodes));
      LoadCase lc = small_sphere_case(scene, MaterialModel::elastic, HardeningLaw::linear);
      lc.mesh.contact_nodes = nodes;
      lc.material = elastic(100e9, 0.3);
      lc = with_layer(lc, 0.7 * *lc.mesh.contact_half_width, elastic(400e9, 0.25));
      Simulation sim(lc);
      sim.run();
      const Mesh& mesh = sim.mesh();
      const double force = sim.contact().force;
      for (const LineForce& line : line_forces(mesh, sim.bulk())) {
        if (!std::isnan(line.below)) EXPECT_NEAR(line.below, force, 1e-8 * force);
        if (!std::isnan(line.above)) EXPECT_NEAR(line.above, force, 1e-8 * force);
      }
      int below = 0;
      while (mesh.region(below + 1) == 0) ++below;  // the substrate's top row; the film's first is below + 1
      const int above = below + 1;
      // Linear extrapolation in the element's height from its two Gauss rows (at 1/2 -+ 1/(2 sqrt 3)
      // of it) to its edge on the interface (1 from below, 0 from above).
      const double lo = 0.5 - 0.5 / std::sqrt(3.0), hi = 0.5 + 0.5 / std::sqrt(3.0);
      const auto at_interface = [&](int ej, int ei, int component, double t) {
        const auto s = sim.bulk().gauss_point_states(ei, ej);  // vertex order: (i, j), (i, j+1), (i+1, j), (i+1, j+1)
        const double bottom = 0.5 * (s[0].stress[component] + s[2].stress[component]);
        const double top = 0.5 * (s[1].stress[component] + s[3].stress[component]);
        return bottom + (top - bottom) * (t - lo) / (hi - lo);
      };
      double p0 = 0.0, traction_jump = 0.0, in_plane_jump = 0.0;
      for (int ei = 0; mesh.x(ei) < 1.5 * sim.contact().half_width; ++ei) {
        p0 = std::max(p0, std::abs(at_interface(below, ei, 1, 1.0)));
        for (const int c : {1, 2})
          traction_jump = std::max(traction_jump, std::abs(at_interface(below, ei, c, 1.0) - at_interface(above, ei, c, 0.0)));
        in_plane_jump = std::max(in_plane_jump, std::abs(at_interface(below, ei, 0, 1.0) - at_interface(above, ei, 0, 0.0)));
      }
      std::cout << fmt::format("{}, {} contact nodes: at the interface |sigma_22| up to {:.4g} Pa; the tractions jump "
                               "by up to {:.3g} of it, sigma_11 by {:.3g} of it\n",
                               to_string(scene), nodes, p0, traction_jump / p0, in_plane_jump / p0);
      traction_jumps.push_back(traction_jump / p0);
      in_plane_jumps.push_back(in_plane_jump / p0);
    }
    EXPECT_LT(traction_jumps[1], 0.6 * traction_jumps[0]);  // first order: halves with the mesh
    EXPECT_LT(traction_jumps[1], 0.05);
    EXPECT_GT(in_plane_jumps[1], 0.8 * in_plane_jumps[0]);  // the physics: stays
    EXPECT_GT(in_plane_jumps[1], 10.0 * traction_jumps[1]);
  }
}

TEST(Layers, ACoatedCaseWritesItsLayersBackAndAResumeComparesThem) {
  const std::string toml = layer_case + R"(
[[layer]]
thickness = 1e-5
[layer.material]
model = "j2"
E = 400e9
nu = 0.25
yield_stress = 5e9
[[layer]]
thickness = 2e-5
[layer.material]
model = "elastic"
E = 150e9
nu = 0.3
)";
  const LoadCase lc = parse_load_case(toml, "coated.toml");
  ASSERT_EQ(lc.layers.size(), 2u);
  EXPECT_EQ(lc.layers[0].material.model, MaterialModel::j2);
  EXPECT_DOUBLE_EQ(lc.layers[0].material.e0, e0_of_yield_stress(5e9, 400e9, 0.25));
  const LoadCase back = parse_load_case(to_toml(lc), "case.toml");
  EXPECT_EQ(first_physics_difference(lc, back), "");
  ASSERT_EQ(back.layers.size(), 2u);
  EXPECT_EQ(back.layers[1].thickness, 2e-5);
  // --set addresses a layer's keys; a resumed run may not change them.
  const LoadCase changed = parse_load_case(toml, "coated.toml", {"layer.2.material.E=160e9"});
  EXPECT_EQ(changed.layers[1].material.E, 160e9);
  EXPECT_EQ(first_physics_difference(lc, changed), "layer[2].material.E");
  EXPECT_EQ(first_physics_difference(lc, parse_load_case(toml, "coated.toml", {"layer.1.thickness=1.5e-5"})),
            "layer[1].thickness");
}

TEST(Layers, BadLayersAreRefusedNamingTheLayerAndTheKey) {
  // A layer of `thickness` (TOML text) whose material has the required keys and `extra` lines.
  const auto layer = [](const std::string& thickness, const std::string& extra = "") {
    return "\n[[layer]]\nthickness = " + thickness + "\n[layer.material]\nmodel = \"elastic\"\nE = 1e9\nnu = 0.3\n" + extra;
  };
  const std::string film = layer("1e-5");
  EXPECT_EQ(refused_key(film), "");
  EXPECT_EQ(refused_key(layer("0.0")), "layer[1].thickness");
  EXPECT_EQ(refused_key(film + layer("-1e-6")), "layer[2].thickness");
  EXPECT_EQ(refused_key(layer("0.02")), "layer[1].thickness");            // deeper than geometry.ly
  EXPECT_EQ(refused_key(film + layer("0.99999e-2")), "layer[2].thickness");  // the stack reaches geometry.ly
  // Interfaces double precision cannot tell apart (1e-4 + 1e-21 == 1e-4), or a film of a denormal's
  // thickness, would give rows of no height: refused below 1e-9 of the specimen's depth.
  EXPECT_EQ(refused_key(layer("1e-4") + layer("1e-21")), "layer[2].thickness");
  EXPECT_EQ(refused_key(layer("1e-323")), "layer[1].thickness");
  EXPECT_EQ(refused_key(layer("2e-11")), "");  // twice 1e-9 of ly = 10 mm: a film of 0.02 nm still runs
  EXPECT_EQ(refused_key(layer("0.9999999999e-2")), "layer[1].thickness");     // the substrate within 1e-9 of it
  EXPECT_EQ(refused_key(layer("\"thin\"")), "layer[1].thickness");
  EXPECT_EQ(refused_key("\n[[layer]]\nmaterial = { model = \"elastic\", E = 1e9, nu = 0.3 }\n"), "layer[1].thickness");
  EXPECT_EQ(refused_key("\n[[layer]]\nthickness = 1e-5\n"), "layer[1].material");
  EXPECT_EQ(refused_key("\n[[layer]]\nthickness = 1e-5\nmaterial = 3\n"), "layer[1].material");
  EXPECT_EQ(refused_key("\n[[layer]]\nthickness = 1e-5\ncolour = 3\n"), "layer[1].colour");
  EXPECT_EQ(refused_key(film + layer("1e-5", "Young = 1e9\n")), "layer[2].material.Young");
  EXPECT_EQ(refused_key("\n[[layer]]\nthickness = 1e-5\n[layer.material]\nmodel = \"elastic\"\nnu = 0.3\n"),
            "layer[1].material.E");  // a required key missing
  EXPECT_EQ(refused_key("\n[[layer]]\nthickness = 1e-5\n[layer.material]\nmodel = \"elastic\"\nE = -1e9\nnu = 0.3\n"),
            "layer[1].material.E");
  EXPECT_EQ(refused_key("\n[[layer]]\nthickness = 1e-5\n[layer.material]\nmodel = \"elastic\"\nE = 1e9\nnu = 0.5\n"),
            "layer[1].material.nu");
  EXPECT_EQ(refused_key("\n[[layer]]\nthickness = 1e-5\n[layer.material]\nmodel = \"plastic\"\nE = 1e9\nnu = 0.3\n"),
            "layer[1].material.model");
  // A model, law or rule the scene does not allow, as [material] would refuse it.
  const std::string ilyushin = "\n[[layer]]\nthickness = 1e-5\n[layer.material]\nmodel = \"ilyushin\"\nE = 1e9\nnu = 0.3\n";
  EXPECT_EQ(refused_key(ilyushin + "hardening = \"voce\"\nQ = 1e8\nb = 10\n"), "layer[1].material.hardening");
  EXPECT_EQ(refused_key(layer("1e-5", "elastic_stress = \"kirchhoff\"\n")), "layer[1].material.elastic_stress");
  const std::string j2 = "\n[[layer]]\nthickness = 1e-5\n[layer.material]\nmodel = \"j2\"\nE = 1e9\nnu = 0.3\n";
  EXPECT_EQ(refused_key(j2 + "rate = \"norton\"\ncreep_coefficient = 1e-3\nreference_stress = 1e8\nrate_exponent = 3\n"),
            "layer[1].material.rate");  // creep needs load.times
  EXPECT_EQ(refused_key(j2 + "kappa = 0.5\nQ = 1e8\n"), "layer[1].material.Q");  // another law's key
  // Deformation theory beside a region that creeps.
  EXPECT_EQ(refused_key(ilyushin + "\n[[layer]]\nthickness = 1e-5\n[layer.material]\nmodel = \"j2\"\nE = 1e9\nnu = "
                        "0.3\nrate = \"norton\"\ncreep_coefficient = 1e-3\nreference_stress = 1e8\nrate_exponent = 3\n",
                        {"load.times=[0, 10]"}),
            "layer[1].material.model");
  try {
    parse_load_case("layer = 3\n" + layer_case, "layers.toml");
    ADD_FAILURE() << "layer = 3 was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "layer");
  }
  EXPECT_EQ(refused_key("\n[layer]\nthickness = 1e-5\n"), "layer");
  std::string stack;
  for (std::size_t k = 0; k <= max_layers; ++k) stack += layer("1e-6");
  EXPECT_EQ(refused_key(stack), "layer");
  // --set names a layer that is there, and its keys are checked as the layer's.
  EXPECT_EQ(refused_key(film, {"layer.2.material.E=1e9"}), "layer.2.material.E");
  EXPECT_EQ(refused_key(film, {"layer.1.material.E=-1"}), "layer[1].material.E");
  EXPECT_EQ(refused_key(film, {"layer.1.thickness=0"}), "layer[1].thickness");
  EXPECT_EQ(refused_key(film, {"layer.x.thickness=1"}), "layer.x.thickness");
  EXPECT_EQ(refused_key(film, {"layer.1.material=1"}), "layer.1.material");
}

TEST(Layers, AFilmsModulusIsFittedFromACoatedCurveWithTheSubstrateKnown) {
  // docs/MODEL.md §14.5: a 50 um film of 400 GPa on a 200 GPa substrate under a 1 mm sphere
  // (contact radius 140 um: the substrate carries most of the load), its loading curve made on a
  // mesh twice as fine with 0.3% noise; the fit frees layer.1.material.E from 250 GPa.
  LoadCase truth = small_sphere_case(SceneKind::axisymmetric, MaterialModel::elastic, HardeningLaw::linear);
  truth.mesh.contact_nodes = 20;
  truth = with_layer(truth, 50e-6, elastic(400e9, 0.25));
  const RegionParameter film_modulus{MaterialParameter::E, 1};
  FitProblem problem;
  problem.free = {FreeParameter(film_modulus, 50e9, 2000e9)};
  problem.settings.design_experiments = false;
  std::vector<double> depths;
  for (int k = 1; k <= 8; ++k) depths.push_back(4e-6 + 2e-6 * k);  // 6 to 20 um: a at least 7 contact nodes
  LoadCase finer = truth;
  finer.mesh.contact_nodes *= 2;
  FitData d = synthetic_data(finer, FitDataKind::force_depth_curve, depths, problem.free, 0.003, 3);
  d.load_case = truth;
  set_value(d.load_case, film_modulus, 250e9);
  problem.data.push_back(d);
  const FitResult r = fit(problem);
  const ParameterDetermination& pd = r.determination[0];
  std::cout << fmt::format("layer.1.material.E = {:.5g} Pa, 95% [{:.5g}, {:.5g}] ({} forward runs; the model's shift "
                           "{:.3g} Pa, estimated: {}): {}\n",
                           r.values[0], pd.lower, pd.upper, r.forward_runs, pd.model_shift, r.model_error_estimated,
                           pd.verdict);
  EXPECT_TRUE(r.good()) << r.quality;
  EXPECT_LE(pd.lower, 400e9);
  EXPECT_GE(pd.upper, 400e9);
  EXPECT_TRUE(pd.determined);
  EXPECT_NEAR(r.values[0] / 400e9, 1.0, 0.03);
}

/// The axisymmetric flat punch of loadcases/axisymmetric/flat_punch.toml (radius 50 um, 0.5 um
/// deep) on a specimen 400 radii across, so that the specimen's own size is no part of its
/// stiffness, in one increment.
LoadCase flat_punch_on(const MaterialInput& substrate) {
  LoadCase lc = indentsim::testing::shipped_case("axisymmetric/flat_punch.toml",
                                                 {"load.increments=1", "geometry.lx=20e-3", "geometry.ly=20e-3"});
  lc.material = substrate;
  return lc;
}

TEST(Layers, AFlatPunchFeelsItsFilmByGaosWeightToFirstOrder) {
  // Gao, Chiu and Lee (1992): to first order in the film's mismatch, a flat punch of radius a on a
  // film of thickness t feels E* = E*_s + (E*_f - E*_s) I0(t/a) (equal Poisson's ratios).  A film
  // 2% stiffer than its substrate: the force's relative rise over 2% is I0.
  const MaterialInput substrate = elastic(70e9, 0.2);
  const double own = forces_of(flat_punch_on(substrate)).back();
  for (const double t_over_a : {0.25, 1.0, 4.0}) {
    const LoadCase coated = with_layer(flat_punch_on(substrate), t_over_a * 50e-6, elastic(70e9 * 1.02, 0.2));
    const double share = (forces_of(coated).back() / own - 1.0) / 0.02;
    const double I0 = gao_weights(t_over_a, 0.2).I0;
    std::cout << fmt::format("t/a = {}: the film's share {:.4f}, Gao's I0 {:.4f}\n", t_over_a, share, I0);
    EXPECT_NEAR(share / I0, 1.0, 0.03);
  }
  // The weights' limits: a film of no thickness is the substrate, an infinitely thick one the film.
  EXPECT_NEAR(gao_weights(1e-9, 0.3).I0, 0.0, 1e-7);
  EXPECT_NEAR(gao_weights(1e9, 0.3).I0, 1.0, 1e-8);
  EXPECT_NEAR(gao_weights(1e9, 0.3).I1, 1.0, 1e-8);
  // The inversion returns the film it was given.
  const double apparent = gao_contact_modulus(400e9, 0.25, 200e9, 0.3, 0.7);
  EXPECT_NEAR(*gao_film_modulus(apparent, 0.25, 200e9, 0.3, 0.7) / 400e9, 1.0, 1e-12);
}

class LayersCli : public indentsim::testing::CliTest {};

TEST_F(LayersCli, ABadLayerExitsWith2NamingItAndWritesNothing) {
  const fs::path file = dir_ / "coated.toml";
  std::ofstream(file) << layer_case << "\n[[layer]]\nthickness = 1e-5\n[layer.material]\nmodel = \"plastic\"\nE = 1e9\nnu = 0.3\n";
  expect_refused("run " + file.string(), "layer[1].material.model");
}

TEST_F(LayersCli, ACoatedRunWritesItsLayersAndRegionsAndResumesToTheSameCurve) {
  // A J2 film on an elastic substrate under force control, checkpointed and resumed: the curve
  // is the uninterrupted run's, summary.json lists the layers, the fields carry the regions.
  const fs::path file = dir_ / "coated.toml";
  std::ofstream(file) << R"(
[geometry]
kind = "axisymmetric"
lx = 0.3e-3
ly = 0.3e-3
[punch]
shape = "sphere"
radius = 20e-6
[material]
model = "elastic"
E = 200e9
nu = 0.3
[[layer]]
thickness = 0.5e-6
[layer.material]
model = "j2"
E = 70e9
nu = 0.33
yield_stress = 300e6
hardening = "power"
n = 0.1
[load]
control = "force"
path = [0.0, 2e-3, 0.2e-3]
increments = [8, 8]
[mesh]
contact_nodes = 10
[output]
checkpoint_every = 3
fields_every = 0
)";
  ASSERT_EQ(cli("run " + file.string() + " --quiet --out " + (dir_ / "full").string()), 0) << err();
  const auto summary = nlohmann::json::parse(indentsim::testing::slurp(dir_ / "full" / "summary.json"));
  ASSERT_TRUE(summary.contains("layers")) << summary.dump(2);
  EXPECT_EQ(summary["layers"][0]["model"], "j2");
  EXPECT_EQ(summary["layers"][0]["thickness"], 0.5e-6);
  EXPECT_EQ(summary["material"]["E"], 200e9);
  // The analysis of its unloading knows the coating (docs/MODEL.md §14.4).
  ASSERT_FALSE(summary["unloading"].empty()) << summary.dump(2);
  const auto& coating = summary["unloading"][0]["analysis"]["coating"];
  ASSERT_TRUE(coating.is_object()) << summary["unloading"][0].dump(2);
  EXPECT_DOUBLE_EQ(coating["h_max_over_t"].get<double>(), summary["unloading"][0]["depth"].get<double>() / 0.5e-6);
  EXPECT_EQ(coating["film_E_true"], 70e9);
  EXPECT_NEAR(coating["film_share_gao_I0"].get<double>(),
              gao_weights(0.5e-6 / summary["unloading"][0]["analysis"]["contact_radius"].get<double>(), 0.3).I0, 1e-12);
  bool region_field = false;
  for (const auto& entry : fs::recursive_directory_iterator(dir_ / "full"))
    if (entry.path().extension() == ".vtu")
      region_field = region_field || indentsim::testing::slurp(entry.path()).find("Name=\"region\"") != std::string::npos;
  EXPECT_TRUE(region_field);
  ASSERT_EQ(cli("run " + file.string() + " --quiet --out " + (dir_ / "killed").string(), "INDENTSIM_FAULT=increment:7"),
            128 + SIGKILL);
  ASSERT_EQ(cli("resume " + (dir_ / "killed" / "checkpoints").string() + " --quiet"), 0) << err();
  EXPECT_EQ(indentsim::testing::curve_without_timing(dir_ / "killed" / "curve.csv"),
            indentsim::testing::curve_without_timing(dir_ / "full" / "curve.csv"));
}

TEST_F(LayersCli, AnalyzeWarnsWhereTheSubstrateMovesTheFilmsResultsAndNotUnderAThickFilm) {
  // A flat punch (radius a = 50 um) on a film twice as stiff as its substrate: at t = a the
  // substrate takes a third of the apparent modulus away (Gao's weight 0.48); at t = 40 a about
  // 1.5%, inside the default 2%.  Measured against the film alone's companion run.
  for (const double t_over_a : {1.0, 40.0}) {
    SCOPED_TRACE(t_over_a);
    const fs::path file = dir_ / "coated_flat.toml";
    std::ofstream(file) << fmt::format(R"(
[geometry]
kind = "axisymmetric"
lx = 20e-3
ly = 20e-3
[punch]
shape = "flat"
radius = 50e-6
[material]
model = "elastic"
E = 70e9
nu = 0.2
[[layer]]
thickness = {}
[layer.material]
model = "elastic"
E = 140e9
nu = 0.2
[load]
path = [0.0, 0.5e-6, 0.3e-6]
increments = [5, 10]
[mesh]
contact_nodes = 10
error_estimate = "off"
)",
                                       t_over_a * 50e-6);
    const fs::path out = dir_ / fmt::format("t{}", t_over_a);
    ASSERT_EQ(cli("run " + file.string() + " --quiet --out " + out.string()), 0) << err();
    ASSERT_EQ(cli("analyze " + out.string()), 0) << err();
    EXPECT_EQ(err().find("the substrate moves") != std::string::npos, t_over_a < 10.0) << err();
    const auto analysis = nlohmann::json::parse(indentsim::testing::slurp(out / "analysis.json"));
    const auto& coating = analysis["branches"][0]["coating"];
    ASSERT_TRUE(coating["film_alone_E_r"].is_number()) << analysis["branches"][0].dump(2);
    const double change = analysis["branches"][0]["E_r"].get<double>() / coating["film_alone_E_r"].get<double>() - 1.0;
    // Between Gao's weight applied to the moduli (his first order: E* = E*_s + (E*_f - E*_s) I0)
    // and the same weight applied to the compliances (1/E* = I0/E*_f + (1 - I0)/E*_s): a stiff
    // film's modulus falls faster than linearly as the substrate's share grows.
    const double I0 = gao_weights(t_over_a, 0.2).I0;
    const double in_moduli = -0.5 * (1.0 - I0), in_compliances = 1.0 / (2.0 - I0) - 1.0;
    std::cout << fmt::format("t/a = {}: E_r moved by {:.4f} from the film alone's; Gao's weight on the moduli {:.4f}, "
                             "on the compliances {:.4f}\n",
                             t_over_a, change, in_moduli, in_compliances);
    EXPECT_LT(change, in_moduli);
    EXPECT_GT(change, in_compliances);
  }
}
