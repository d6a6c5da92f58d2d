#include "indentsim/simulation/run_configuration.hpp"

#include <algorithm>
#include <tuple>
#include <cmath>

#include <fmt/format.h>

#include "indentsim/base/error.hpp"
#include "indentsim/geometry/punch.hpp"
#include "indentsim/simulation/error_estimate.hpp"
#include "indentsim/simulation/load_control.hpp"
#include "indentsim/simulation/load_stepping.hpp"
#include "indentsim/simulation/simulation.hpp"
#include "indentsim/solvers/contact.hpp"

namespace indentsim {

namespace {

// Measured (CHANGELOG, with Debian's OpenBLAS): CHOLMOD is faster than KLU from the smallest
// meshes tried (1.6x at 684 unknowns, 2.1x at 1860, 6.2x at 40k); below ~1000 unknowns both take
// milliseconds and KLU, the user's default, is kept.
constexpr int cholmod_crossover_unknowns = 1000;
constexpr double max_relative_contact = 0.1;  // a / lx and a / ly beyond which the run warns

// Plastic scenes spread their contact wider than the elastic Hertz estimate, up to the punch's
// chord sqrt(2 R alpha) when the material flows freely.  A coarse pilot run of the same load
// case (8 elements across the chord, 4 increments) measures the final contact half-width and
// how far the plastic zone reaches at each of its increments; the real mesh is planned from the
// first with a 5% margin, the condensed near field from the second, as it grows with the depth.
// The pilot sets mesh.contact_half_width itself, so it never runs a pilot of its own, and solves
// its small mesh whole.  Should it fail, the chord is a safe upper bound and the near field falls
// back to its default.
struct PilotResult {
  double contact_half_width = 0.0;
  PlasticZoneGrowth plastic_zone;
};

// The coarse pilot of both pilots below: the case pressed to `depth` under depth control in 4
// increments, on a default mesh with 8 elements across the punch's chord (where the punch meets
// the undeformed surface: the sphere's sqrt(2 R alpha - alpha^2); a flat punch's own half-width
// is its mesh's), solved whole, without an error estimate, to a tolerance no finer than 1e-9.
LoadCase coarse_pilot_case(const LoadCase& lc, double depth) {
  LoadCase pilot = lc;
  pilot.load.control = LoadControlKind::depth;  // under force control too: to the depth estimate
  pilot.load.depth_estimate.reset();
  pilot.load.path = {0.0, depth};
  pilot.load.increments = 4;
  pilot.load.segment_increments.clear();
  pilot.load.times.clear();
  // A rate-dependent law flows over time (docs/MODEL.md §13.3): the pilot presses in the time the
  // case takes to its largest waypoint.
  if (lc.any_rate_dependent() && !lc.load.times.empty()) {
    const auto& path = lc.load.path;
    const auto peak = static_cast<std::size_t>(std::max_element(path.begin(), path.end()) - path.begin());
    pilot.load.times = {0.0, lc.load.times[peak]};
  }
  pilot.mesh = MeshInput{};
  pilot.mesh.contact_nodes = 8;
  pilot.mesh.error_estimate = ErrorEstimateChoice::off;
  if (const double chord = make_punch(lc.punch)->geometric_contact_radius(depth);
      lc.punch.shape != PunchShapeKind::flat && chord > 0.0)  // (a calibration's A may not be positive yet)
    pilot.mesh.contact_half_width = chord;
  pilot.solver.tolerance = std::max(lc.solver.tolerance, 1e-9);
  pilot.solver.far_field = FarFieldChoice::full;
  return pilot;
}

PilotResult pilot_run(const LoadCase& lc) {
  const double depth = lc.max_depth();
  const double chord = make_punch(lc.punch)->geometric_contact_radius(depth);
  LoadCase pilot = coarse_pilot_case(lc, depth);
  pilot.mesh.contact_half_width = chord;  // a flat punch's too: the pilot plans no pilot of its own
  double widest = 0.0;
  try {
    Simulation sim(pilot);
    PlasticZoneGrowth growth;
    sim.run([&](const IncrementRecord& r) {
      widest = std::max(widest, r.half_width);
      if (r.step == 0 || !sim.plasticity()) return;  // an elastic coated specimen's pilot measures its contact
      const Mesh& mesh = sim.mesh();
      PlasticExtent zone;
      for (int ei = 0; ei < mesh.elements_x(); ++ei)
        for (int ej = 0; ej < mesh.elements_y(); ++ej)
          for (std::size_t g = 0; g < 4; ++g)
            if (sim.plasticity()->has_yielded(4 * static_cast<std::size_t>(mesh.element(ei, ej)) + g)) {
              zone.width = std::max(zone.width, mesh.x(ei + 1));
              zone.depth = std::max(zone.depth, -mesh.y(ej));
            }
      growth.depths.push_back(r.alpha);
      growth.extents.push_back(zone);
    });
    return {widest > 0.0 ? std::min(chord, 1.05 * widest) : chord, growth};
  } catch (const SolverError&) {
    return {chord, {}};
  }
}

// The depth pilot of force control.  P(alpha) is measured on a coarse mesh (coarse_pilot_case) up
// to a trial depth, and the depth is
// rescaled along the curve's own power law at its end, alpha <- alpha (P_max / P)^(1/m) with
// m = d ln P / d ln alpha from its last two increments, until it moves by less than 2%.  It starts
// from a depth of the punch's own scale and moves by a factor 10 at most per pilot; near a limit
// load (m -> 0) it stops at the depth bounds of the case (half the block, half a sphere's radius),
// where the run itself meets the limit and says so -- or earlier, once d ln P / d ln alpha has
// fallen below 0.2: the force has stopped rising with the depth.
constexpr double depth_pilot_tolerance = 0.02;
constexpr int depth_pilot_runs = 10;
constexpr double depth_pilot_limit_exponent = 0.2;

struct DepthPilot {
  double force = 0.0;     ///< P at the pilot's depth
  double exponent = 0.0;  ///< d ln P / d ln alpha over its last increment
};

DepthPilot depth_pilot(const LoadCase& lc, double depth) {
  LoadCase pilot = coarse_pilot_case(lc, depth);
  pilot.solver.linear = LinearSolverChoice::klu;
  Simulation sim(pilot);
  std::vector<IncrementRecord> rows;
  sim.run([&](const IncrementRecord& r) { rows.push_back(r); });
  DepthPilot result;
  result.force = rows.back().force;
  const IncrementRecord& before = rows[rows.size() - 2];
  if (before.force > 0.0 && result.force > 0.0)
    result.exponent = std::log(result.force / before.force) / std::log(rows.back().alpha / before.alpha);
  return result;
}

// The creep pilot of force control (docs/MODEL.md §13.1): a creeping specimen goes on sinking
// while the force holds -- at the largest force, and at any force held long enough after it -- so
// the deepest depth is not where the largest force is first reached.  A coarse force-controlled
// run of the whole protocol (at most 4 increments a segment, 8 contact nodes over twice `depth`),
// its deepest depth returned; `depth` when it fails.
double creep_pilot_depth(const LoadCase& lc, double depth) {
  LoadCase pilot = coarse_pilot_case(lc, 2.0 * depth);
  pilot.load = lc.load;
  pilot.load.depth_estimate = 2.0 * depth;
  const std::vector<int> per_segment = segment_increments(lc.load);
  pilot.load.segment_increments.clear();
  for (const int n : per_segment) pilot.load.segment_increments.push_back(std::min(4, n));
  pilot.load.increments = pilot.load.total_increments();
  double deepest = depth;
  try {
    Simulation sim(pilot);
    sim.run([&](const IncrementRecord& r) { deepest = std::max(deepest, r.alpha); });
  } catch (const SolverError&) {
    return depth;  // the run itself meets what stopped the pilot, and says so
  }
  return deepest;
}

}  // namespace

LoadCase with_depth_estimate(LoadCase lc) {
  if (lc.load.control != LoadControlKind::force || lc.load.depth_estimate) return lc;
  const double target = lc.load.largest_target();
  double bound = 0.5 * lc.geometry.ly;
  if (lc.punch.shape == PunchShapeKind::sphere) bound = std::min(bound, 0.5 * lc.punch.radius);
  if (lc.punch.shape == PunchShapeKind::profile && !lc.punch.profile.empty())
    bound = std::min(bound, 0.5 * lc.punch.profile.back().second);
  // The punch's own scale: a thousandth of its radius, or of the block under a cone.
  const bool has_radius = lc.punch.shape == PunchShapeKind::sphere || lc.punch.shape == PunchShapeKind::flat;
  double depth = std::min(bound, 1e-3 * (has_radius ? lc.punch.radius : lc.geometry.ly));
  for (int run = 0; run < depth_pilot_runs; ++run) {
    DepthPilot pilot;
    try {
      pilot = depth_pilot(lc, depth);
    } catch (const SolverError&) {
      break;  // the run itself meets what stopped the pilot, and says so
    }
    // A force that has stopped rising with the depth lies at a limit load below the target: the
    // run meets it at about this depth and names it (Simulation::limit_load_note).
    if (pilot.force < target && pilot.exponent > 0.0 && pilot.exponent < depth_pilot_limit_exponent) break;
    double factor = 10.0;
    if (pilot.force > 0.0) {
      const double exponent = pilot.exponent > 0.0 ? pilot.exponent : force_exponent(lc.punch.shape);
      factor = std::clamp(std::pow(target / pilot.force, 1.0 / exponent), 0.1, 10.0);
    }
    const double next = std::min(bound, depth * factor);
    const bool settled = std::abs(next / depth - 1.0) < depth_pilot_tolerance || next == depth;
    depth = next;
    if (settled) break;
  }
  if (lc.any_rate_dependent() && !lc.load.times.empty()) depth = creep_pilot_depth(lc, depth);
  lc.load.depth_estimate = depth;
  validate(lc);  // what depends on the deepest depth (a tip's area function over it) is checked now
  return lc;
}

namespace {

// "auto": KLU below the measured crossover, CHOLMOD's supernodal Cholesky above it.
LinearSolverKind choose_linear_solver(LinearSolverChoice choice, int unknowns) {
  switch (choice) {
    case LinearSolverChoice::klu: return LinearSolverKind::klu;
    case LinearSolverChoice::cholmod: return LinearSolverKind::cholmod;
    case LinearSolverChoice::automatic: break;
  }
  return unknowns >= cholmod_crossover_unknowns ? LinearSolverKind::cholmod : LinearSolverKind::klu;
}

// Every surface node within 1.3 a + 2 h of the axis may touch (a the planned final contact
// half-width, h the fine spacing); every element within 1.3 times the pilot's plastic zone plus
// 2 h (or, without a pilot, within 2.5 a) may yield.  Generous on purpose: a near field too
// small is detected after the increment and grown (Simulation::grow_near_field), which costs a
// new condensation; one too large only costs unknowns.  "auto" solves the whole mesh only when the
// near field would hold more than 80% of its unknowns: measured on deep_plastic.toml, a near field
// of 55% of the unknowns still cut the time per increment by 40% (docs/DESIGN.md, section 7).
NearField choose_near_field(const LoadCase& lc, const Mesh& mesh, const MeshPlan& plan, bool plastic,
                            const std::optional<PlasticExtent>& plastic_zone) {
  NearField near;
  // Norton's creep has no yield surface: every stressed element flows, and no far field is elastic
  // (a creeping layer reaches the far field too: docs/MODEL.md §14.1).
  if (lc.solver.far_field == FarFieldChoice::full || lc.any_rate(RateLaw::norton)) return near;
  const double a = plan.contact_half_width_estimate, h = plan.fine_spacing;
  const double contact_width = 1.3 * a + 2.0 * h;
  while (near.contact_nodes < mesh.nodes_x() && mesh.x(near.contact_nodes) <= contact_width) ++near.contact_nodes;
  near.contact_nodes = std::min(mesh.nodes_x(), near.contact_nodes + 1);
  if (plastic) {
    const double width = plastic_zone ? std::max(1.3 * plastic_zone->width, contact_width) + 2.0 * h : 2.5 * a;
    const double depth = plastic_zone ? 1.3 * plastic_zone->depth + 2.0 * h : 2.5 * a;
    while (near.elements_x < mesh.elements_x() && mesh.x(near.elements_x) < width) ++near.elements_x;
    while (near.elements_y < mesh.elements_y() && -mesh.y(mesh.top_row() - near.elements_y) < depth) ++near.elements_y;
    near.contact_nodes = std::max(near.contact_nodes, near.elements_x + 1);
  }
  const double near_unknowns = 2.0 * (near.elements_x + 1) * (near.elements_y + 1) + near.contact_nodes;
  near.condensed = lc.solver.far_field == FarFieldChoice::condense || near_unknowns <= 0.8 * mesh.equations();
  return near;
}

}  // namespace

// "auto": the paper's exact Q1 element unless the scene locks it -- nearly incompressible
// elasticity (nu >= 0.45), nearly perfect plasticity (isochoric flow with kappa > 0.95 or
// n < 0.1, or any tensile-test flow curve), or a plastic material under a cone, whose strain is set by the angle and not by the
// depth, so the flow under it is fully plastic and isochoric from the first increment (Q1 locks:
// on berkovich_cone with Ilyushin's law it overestimates P/h^2 by 1%, with a sawtooth 1.5x as
// large) -- where mean dilatation (B-bar) is used.
ElementKind choose_element(const LoadCase& lc) {
  switch (lc.mesh.element) {
    case ElementChoice::q1: return ElementKind::q1;
    case ElementChoice::bbar: return ElementKind::bbar;
    case ElementChoice::automatic: break;
  }
  // One element kind per mesh: B-bar when any region needs it (docs/MODEL.md §14.1).
  const auto needs_bbar = [&](const MaterialInput& m) {
    const bool near_incompressible = m.nu >= 0.45;
    const bool plastic = m.model != MaterialModel::elastic;
    // A tensile test's flow curve (power_law, ludwik, swift, voce, table) flattens as eps_p grows
    // (saturates, or is flat beyond a table): the flow under an indenter is nearly perfectly plastic.
    const bool near_perfect_plasticity =
        plastic && (m.flow_stress_law() || (m.hardening == HardeningLaw::linear ? m.kappa > 0.95 : m.n < 0.1));
    const bool sharp_plastic_indentation = plastic && sharp_tip(lc.punch.shape);
    // Norton's creep flows isochorically everywhere, and in a hold it is all the specimen does.
    const bool creeping = m.rate == RateLaw::norton;
    return near_incompressible || near_perfect_plasticity || sharp_plastic_indentation || creeping;
  };
  for (std::size_t r = 0; r < lc.regions(); ++r)
    if (needs_bbar(lc.region_material(r))) return ElementKind::bbar;
  return ElementKind::q1;
}

/// The keys that set a contact's size, for a warning that it is too large: a sphere's and a flat
/// punch's radius, a cone's depth, a profile's points.
static std::string contact_size_question(const LoadCase& lc) {
  switch (lc.punch.shape) {
    case PunchShapeKind::sphere: return "are punch.radius and load.path in metres?";
    case PunchShapeKind::flat: return "is punch.radius in metres?";
    case PunchShapeKind::cone: return "is load.path in metres?";
    case PunchShapeKind::profile: return "are the profile's points and load.path in metres?";
    case PunchShapeKind::area_function:
      return "are punch.area_coefficients in SI (A in m^2 for h_c in m) and load.path in metres?";
  }
  return "";
}

std::vector<std::string> plausibility_warnings(const LoadCase& lc, const MeshPlan& plan) {
  // Unit slips: a modulus in GPa instead of Pa, a depth in nm written as m, run and give results
  // 1e3 to 1e9 off; each value outside the magnitudes of its kind is named by its key.
  std::vector<std::string> warnings = implausible_values(lc);
  // The model is small-strain with the gap measured vertically (docs/MODEL.md §3): both need slopes
  // and depths small against the punch's size.
  if (auto slope = make_punch(lc.punch)->slope_warning(lc.max_depth())) warnings.push_back(*slope);
  // Time reaches only a rate-dependent flow rule (docs/MODEL.md §13.3).
  if (!lc.load.times.empty() && !lc.any_rate_dependent())
    warnings.push_back("load.times only labels the increments: the material of this case does not depend on the rate "
                       "of loading (material.rate = \"none\"), so the loading rate changes nothing and a hold repeats "
                       "its state (no creep)");
  // A contact that is not small against the specimen: its edges and base shape P well beyond the
  // discretization error (docs/user-guide.md, "Choosing the specimen").
  const double a = plan.contact_half_width_estimate;
  for (const auto& [key, size] : {std::pair<const char*, double>{"geometry.lx", lc.geometry.lx}, {"geometry.ly", lc.geometry.ly}})
    if (a > max_relative_contact * size)
      warnings.push_back(fmt::format("the contact half-width (about {:.3g} m) is {:.2g} of {} = {:.3g} m: the "
                                     "specimen's edges change P far beyond the discretization error (keep a / {} "
                                     "below {:g}; {})",
                                     a, a / size, key, size, key, max_relative_contact, contact_size_question(lc)));
  return warnings;
}

RunPlan plan_run(const LoadCase& load_case, std::optional<double> planned_contact_half_width) {
  if (load_case.load.control == LoadControlKind::force && !load_case.load.depth_estimate)
    throw std::invalid_argument("plan_run: a force-controlled case needs its depth estimate (with_depth_estimate)");
  RunPlan plan{plan_mesh(load_case), {}};  // also refuses a mesh too large before any work
  if (planned_contact_half_width) {
    plan.mesh = plan_mesh(load_case, planned_contact_half_width);
  } else if (!load_case.mesh.plastic_zone.empty()) {
    // The pilot's measurements as case.toml recorded them: the same plan without the pilot.
    for (const auto& z : load_case.mesh.plastic_zone) {
      plan.plastic_zone.depths.push_back(z[0]);
      plan.plastic_zone.extents.push_back(PlasticExtent{z[1], z[2]});
    }
  } else if ((load_case.any_inelastic() || !load_case.layers.empty()) && !load_case.mesh.contact_half_width) {
    // A plastic specimen's contact, and a coated one's (a thin film's substrate is felt before the
    // mesh is planned, docs/MODEL.md §14.1), are measured by a coarse pilot run.
    LoadCase pinned = load_case;  // the pilot drops mesh.target_error: it runs the kinematics chosen with it
    pin_kinematics(pinned);
    const PilotResult pilot = pilot_run(pinned);
    plan.mesh = plan_mesh(load_case, pilot.contact_half_width);
    plan.plastic_zone = pilot.plastic_zone;
  }
  return plan;
}


NearField near_field_for_depth(const LoadCase& lc, const Mesh& mesh, const MeshPlan& plan, const PlasticZoneGrowth& zone,
                               double depth) {
  const double ahead = std::min(lc.max_depth(), 2.0 * depth);
  NearField near = choose_near_field(lc, mesh, plan, true, zone.at(ahead));
  near.condensed = true;
  return near;
}

NearField near_field_needed(const LoadCase& lc, const Mesh& mesh, const MeshPlan& plan, const PlasticZoneGrowth& zone,
                            double depth) {
  return choose_near_field(lc, mesh, plan, true, zone.at(std::min(depth, lc.max_depth())));
}

// How much finite strain moves P, per unit of the mean strain alpha / a under the punch
// (docs/MODEL.md §12.5): measured 0.20 on elastic spheres (alpha / R from 1e-4 to 1e-2), 0.155 on
// the elastic Berkovich cone, 0.084 under a flat punch; 0.052 and 0.049 on J2 under a sphere and
// the cone.  The largest of each kind, rounded up, so that "auto" errs toward finite strain.
constexpr double elastic_geometric_share = 0.25;
constexpr double plastic_geometric_share = 0.06;
// The accuracy a run aims at without mesh.target_error: the default mesh's discretization error
// (docs/verification.md: the shipped plastic cases within 0.2% of their converged force).
constexpr double default_accuracy = 2e-3;

// The mean strain alpha / a under the punch at the deepest point, with a the punch's own estimate
// of the contact radius (Sneddon's, the mesh plan's first guess), which the case alone decides.
double mean_strain_at_max_depth(const LoadCase& lc) {
  const double a =
      make_punch(lc.punch)->contact_estimate(lc.geometry.kind, lc.max_depth(), lc.geometry.ly, lc.surface_material().nu);
  return lc.max_depth() / a;
}

double geometric_share_per_strain(const LoadCase& lc) {
  return lc.any_inelastic() ? plastic_geometric_share : elastic_geometric_share;
}

double finite_strain_share(const LoadCase& lc) { return geometric_share_per_strain(lc) * mean_strain_at_max_depth(lc); }

std::pair<StrainChoice, std::string> choose_strain(const LoadCase& lc) {
  if (lc.geometry.strain != StrainChoice::automatic) return {lc.geometry.strain, lc.geometry.strain_reason};
  if (lc.contact.discretization != ContactDiscretizationChoice::node_to_rigid)
    return {StrainChoice::small, "auto: small, as finite strain is not built with the integrated gap"};
  if (lc.solver.linear == LinearSolverChoice::cholmod)
    return {StrainChoice::small, "auto: small, as solver.linear = \"cholmod\" cannot factor finite strain's rows"};
  const double per_strain = geometric_share_per_strain(lc);
  const double mean_strain = mean_strain_at_max_depth(lc);
  const double share = per_strain * mean_strain;
  const double accuracy = lc.mesh.target_error.value_or(default_accuracy);
  const bool finite = share > accuracy;
  return {finite ? StrainChoice::finite : StrainChoice::small,
          fmt::format("auto: {}, as finite strain's share of P, about {:g} alpha / a = {:.2g} at alpha / a = {:.3g}, is "
                      "{} {} = {:g}",
                      finite ? "finite" : "small", per_strain, share,
                      mean_strain, finite ? "above" : "within",
                      lc.mesh.target_error ? "mesh.target_error" : "the default mesh's accuracy", accuracy)};
}

void pin_kinematics(LoadCase& lc) {
  if (lc.geometry.strain != StrainChoice::automatic) return;
  std::tie(lc.geometry.strain, lc.geometry.strain_reason) = choose_strain(lc);
}

RunConfiguration resolve_choices(const LoadCase& lc, const RunPlan& plan, const std::optional<NearField>& near_field) {
  RunConfiguration c;
  c.plan = plan;
  std::tie(c.strain, c.strain_reason) = choose_strain(lc);
  const bool finite_strain = c.strain == StrainChoice::finite;
  c.element = choose_element(lc);
  const bool plastic = lc.any_inelastic();
  // Plastic Newton iterations contract linearly (each moves the yield front across Gauss points
  // where the tangent jumps), so a factorization kept as GMRES's preconditioner serves several of
  // them; so it does for an elastic near field in finite strain, nonlinear and thousands of
  // unknowns large (docs/DESIGN.md §8).  Elastic contact in small strain converges in two or three
  // exact steps on a small condensed system.
  const bool nonlinear_bulk = plastic || finite_strain;
  c.jacobian = lc.solver.jacobian == JacobianChoice::automatic
                   ? (nonlinear_bulk ? JacobianChoice::krylov : JacobianChoice::reuse)
                   : lc.solver.jacobian;
  const Mesh mesh = Mesh::from_plan(lc, plan.mesh);  // coordinates and numbering only: cheap
  if (near_field) {
    c.near_field = *near_field;
    c.plan.plastic_zone = {};
  } else if (plan.plastic_zone.empty()) {
    // Finite strain integrates the near elements nonlinearly even when elastic: they are planned
    // as a plastic zone's would be (2.5 a), so that the run does not grow them increment by increment.
    c.near_field = choose_near_field(lc, mesh, plan.mesh, nonlinear_bulk, std::nullopt);
  } else {
    // Whether to condense is decided on the zone of the deepest point; the near field starts as
    // large as the first increments need and grows with the zone (Simulation::anticipate_plastic_zone).
    c.near_field = choose_near_field(lc, mesh, plan.mesh, true, plan.plastic_zone.at(lc.max_depth()));
    if (c.near_field.condensed) {
      const std::vector<double> targets = plan_increments(lc.load);
      const auto first = std::find_if(targets.begin(), targets.end(), [](double t) { return t > 0.0; });
      if (first != targets.end())
        c.near_field = near_field_for_depth(lc, mesh, plan.mesh, plan.plastic_zone, expected_depth(lc, *first));
    }
  }
  c.unknowns = mesh.equations();
  std::vector<int> candidate_equations, tangential_equations;
  const int candidates = contact_candidate_count(mesh, *make_punch(lc.punch));
  for (int i = 0; i < candidates; ++i) {
    candidate_equations.push_back(mesh.equation(Mesh::dof_v(mesh.node(i, mesh.top_row()))));
    // Friction and the contact on the current surface write rows on the horizontal unknowns too.
    if (lc.contact.friction > 0.0 || finite_strain)
      tangential_equations.push_back(mesh.equation(Mesh::dof_u(mesh.node(i, mesh.top_row()))));
  }
  const auto unknowns_of = [&](const NearField& near) -> std::int64_t {
    if (!near.condensed) return c.unknowns;
    const std::vector<char> is_near = near_field_equations(mesh, candidate_equations, near, tangential_equations);
    return std::count(is_near.begin(), is_near.end(), char{1});
  };
  c.system_unknowns = unknowns_of(c.near_field);
  // The linear solver serves every Newton system of the run: it is chosen on the largest, the
  // near field the run grows to at its deepest point (Simulation::anticipate_plastic_zone).
  std::int64_t largest = c.system_unknowns;
  if (c.near_field.condensed && !c.plan.plastic_zone.empty()) {
    NearField deepest = near_field_needed(lc, mesh, plan.mesh, c.plan.plastic_zone, lc.max_depth());
    deepest.condensed = true;
    deepest.elements_x = std::max(deepest.elements_x, c.near_field.elements_x);
    deepest.elements_y = std::max(deepest.elements_y, c.near_field.elements_y);
    deepest.contact_nodes = std::max(deepest.contact_nodes, c.near_field.contact_nodes);
    largest = unknowns_of(deepest);
  }
  c.linear_solver = choose_linear_solver(lc.solver.linear, static_cast<int>(largest));
  // Sliding friction's rows are unsymmetric (docs/MODEL.md §3.3): only KLU factors them.
  if (lc.contact.friction > 0.0 && std::isfinite(lc.contact.friction)) c.linear_solver = LinearSolverKind::klu;
  // So are the rows of finite strain's contact and F-bar's tangent (docs/MODEL.md §12), and force
  // control's border (docs/MODEL.md §13.1).
  if (finite_strain || lc.load.control == LoadControlKind::force) c.linear_solver = LinearSolverKind::klu;
  c.companion_contact_nodes = companion_contact_nodes(lc);
  return c;
}

LoadCase case_as_run(const LoadCase& lc, const RunConfiguration& c) {
  LoadCase as_run = lc;
  auto& mesh = as_run.mesh;
  mesh.element = c.element == ElementKind::bbar ? ElementChoice::bbar : ElementChoice::q1;
  // A flat punch's contact radius is its own (the key is refused for it).
  if (lc.punch.shape != PunchShapeKind::flat) mesh.contact_half_width = c.plan.mesh.contact_half_width_estimate;
  // A resumed run's configuration has dropped the zone (it starts from its own near field): the
  // case keeps the one it was planned with.
  if (!c.plan.plastic_zone.empty()) mesh.plastic_zone.clear();
  for (std::size_t k = 0; k < c.plan.plastic_zone.depths.size(); ++k)
    mesh.plastic_zone.push_back(
        {c.plan.plastic_zone.depths[k], c.plan.plastic_zone.extents[k].width, c.plan.plastic_zone.extents[k].depth});
  as_run.solver.jacobian = c.jacobian;
  // solver.linear and solver.far_field stay as given: their "auto" is chosen on each mesh (the
  // error estimate's companions are smaller), and summary.json's configuration says what it chose.
  // So does geometry.strain: its "auto" depends on the case alone (choose_strain).
  return as_run;
}

std::vector<std::pair<std::string, std::string>> describe(const RunConfiguration& c) {
  const MeshPlan& p = c.plan.mesh;
  std::string companions = "none";
  for (std::size_t k = 0; k < c.companion_contact_nodes.size(); ++k)
    companions = (k ? companions + ", " : std::string()) + std::to_string(c.companion_contact_nodes[k]);
  const auto jacobian = [&] {
    switch (c.jacobian) {
      case JacobianChoice::krylov: return "krylov";
      case JacobianChoice::reuse: return "reuse";
      case JacobianChoice::fresh: return "fresh";
      case JacobianChoice::automatic: break;
    }
    return "auto";
  };
  return {
      {"mesh", fmt::format("{} x {} nodes, {} unknowns", p.nodes_x, p.nodes_y, c.unknowns)},
      {"contact_half_width", fmt::format("{:.6g} m{}", p.contact_half_width_estimate,
                                         c.plan.plastic_zone.empty() ? "" : " (from the pilot run)")},
      {"strain", c.strain_reason.empty() ? to_string(c.strain) : c.strain_reason},
      {"element", c.element == ElementKind::bbar ? "bbar" : "q1"},
      {"far_field", c.near_field.condensed
                        ? fmt::format("condensed: near field of {} contact nodes, {} x {} elements, {} unknowns",
                                      c.near_field.contact_nodes, c.near_field.elements_x, c.near_field.elements_y,
                                      c.system_unknowns)
                        : std::string("full (the whole mesh is solved)")},
      {"linear_solver", c.linear_solver == LinearSolverKind::cholmod ? "cholmod" : "klu"},
      {"jacobian", jacobian()},
      {"companion_runs", companions == "none" ? companions : "contact_nodes = " + companions},
  };
}

}  // namespace indentsim
