#include "indentsim/input/load_case.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "indentsim/base/error.hpp"
#include "key_declarations.hpp"

namespace indentsim {

using namespace input_detail;

/// A tip profile: r from 0 strictly increasing, g from 0 not decreasing, all finite; with a load
/// path (`within_run`), high enough that the deepest depth stays on it and within the specimen.
void validate_profile(const LoadCase& lc, bool within_run) {
  const auto& points = lc.punch.profile;
  const bool from_file = !lc.punch.profile_file.empty();
  const std::string key = from_file ? "punch.profile" : "punch.profile_points";
  const auto fail = [&](std::size_t k, const std::string& problem) {
    throw InputError(lc.source, key,
                     fmt::format("{}point {} {}", from_file ? printable(lc.punch.profile_file, 200) + ": " : "", k + 1,
                                 problem));
  };
  if (points.size() < 2) throw InputError(lc.source, key, "a profile needs at least 2 points (r, g)");
  for (std::size_t k = 0; k < points.size(); ++k) {
    const auto [r, g] = points[k];
    if (!std::isfinite(r) || !std::isfinite(g)) fail(k, "is not finite");
    if (k == 0 && (r != 0.0 || g != 0.0))
      fail(k, fmt::format("is ({}, {}): the profile must start at the tip, r = 0, g = 0", r, g));
    if (k > 0 && !(r > points[k - 1].first))
      fail(k, fmt::format("has r = {} after r = {}: r must increase", r, points[k - 1].first));
    if (k > 0 && g < points[k - 1].second)
      fail(k, fmt::format("has g = {} after g = {}: the profile must not descend (not monotone)", g,
                          points[k - 1].second));
  }
  // Double precision: a point closer to its neighbour than 1e-9 of the profile's reach, or a
  // height a million times that reach, is beyond what the contact gap can resolve.
  const double reach = points.back().first;
  for (std::size_t k = 1; k < points.size(); ++k) {
    if (points[k].first - points[k - 1].first < 1e-9 * reach)
      fail(k, fmt::format("has r = {} m, {} m from the point before it: closer than 1e-9 of the profile's reach "
                          "(r = {} m), which double precision cannot resolve",
                          points[k].first, points[k].first - points[k - 1].first, reach));
    if (points[k].second > 1e6 * reach)
      fail(k, fmt::format("has g = {} m, over a million times the profile's reach (r = {} m): not a tip", points[k].second,
                          reach));
  }
  if (!within_run) return;
  if (!(points.back().second > lc.max_depth()))
    throw InputError(lc.source, key,
                     fmt::format("the profile rises only {} m, not above the deepest depth {} m: the specimen would "
                                 "reach beyond the measured tip",
                                 points.back().second, lc.max_depth()));
  if (!(points.back().first < lc.geometry.lx))
    throw InputError(lc.source, key, fmt::format("reaches r = {} m, beyond the specimen (geometry.lx = {} m)",
                                                 points.back().first, lc.geometry.lx));
}

/// A calibrated tip's area function (docs/MODEL.md §13.5): one to nine finite coefficients; within
/// a run, A(h_c) positive and increasing over the depths the contact can reach (to twice the deepest
/// depth, where pile-up takes it), sampled at 400 depths log-spaced over six decades below that --
/// else its profile of equal area, g = A^-1(pi r^2), does not exist, and the coefficient whose term
/// pulls the area down most there is named.
void validate_area_function(const LoadCase& lc, bool within_run) {
  const auto& c = lc.punch.area_coefficients;
  const auto fail = [&](const std::string& problem) { throw InputError(lc.source, "punch.area_coefficients", problem); };
  if (c.empty() || c.size() > max_area_coefficients)
    fail(fmt::format("gives {} coefficients: an area function takes C0 to C8 (1 to {})", c.size(),
                     max_area_coefficients));
  for (std::size_t k = 0; k < c.size(); ++k)
    if (!std::isfinite(c[k])) fail(fmt::format("C{} = {} is not a finite number", k, c[k]));
  if (!within_run || !(lc.max_depth() > 0.0)) return;
  const double reach = 2.0 * lc.max_depth();
  for (int i = 0; i <= 400; ++i) {
    const double h = reach * std::pow(10.0, -6.0 + 6.0 * i / 400.0);
    const double area = area_function_area(c, h), slope = area_function_slope(c, h);
    if (area > 0.0 && slope > 0.0) continue;
    // The term that pulls A (or dA/dh) down most at h.
    std::size_t worst = 0;
    double most = 0.0;
    for (std::size_t k = 0; k < c.size(); ++k) {
      const double e = area_function_exponent(k);
      const double term = area > 0.0 ? c[k] * e * std::pow(h, e - 1.0) : c[k] * std::pow(h, e);
      if (term < most) most = term, worst = k;
    }
    fail(fmt::format("the area function {} at h_c = {:.4g} m (A = {:.4g} m^2, dA/dh_c = {:.4g} m): C{} = {:g} "
                     "pulls it down there; the area must be positive and grow with the depth over the depths the "
                     "contact reaches (to {:.4g} m, twice the deepest depth)",
                     area > 0.0 ? "does not increase" : "is not positive", h, area, slope, worst, c[worst], reach));
  }
}

/// A hardening law's parameters (docs/MODEL.md §12.1): each law's own keys given, what the law
/// cannot take refused, a table's flow curve from eps_p = 0, increasing, sigma not falling.
static void validate_hardening(const LoadCase& lc) {
  const auto& m = lc.material;
  if (m.model == MaterialModel::elastic) return;
  const auto fail = [&](const std::string& key, const std::string& problem) { throw InputError(lc.source, key, problem); };
  const std::string law = to_string(m.hardening);
  if (m.flow_stress_law() && m.model != MaterialModel::j2)
    fail("material.hardening",
         fmt::format("\"{}\" is a tensile test's flow stress sigma(eps_p), a hardening curve of J2 flow theory: "
                     "set material.model = \"j2\", or give Ilyushin's deformation theory \"linear\" or \"power\"",
                     law));
  const auto require = [&](const std::optional<double>& value, const char* key) {
    if (!value) fail(key, fmt::format("missing key (material.hardening = \"{}\" needs it)", law));
  };
  switch (m.hardening) {
    case HardeningLaw::linear:
    case HardeningLaw::power_law: break;
    case HardeningLaw::power:
    case HardeningLaw::ludwik:
      // omega = 1 - (e0/e_u)^(1-n) with n = 0 leaves Ilyushin's conditions; K eps_p^0 jumps at yield.
      if (!(m.n > 0.0))
        fail("material.n", fmt::format("must be > 0 for material.hardening = \"{}\" (got {}){}", law, m.n,
                                       m.hardening == HardeningLaw::ludwik ? ": K eps_p^0 jumps by K at yield" : ""));
      if (m.hardening == HardeningLaw::ludwik) require(m.K, "material.K");
      break;
    case HardeningLaw::swift:
      require(m.K, "material.K");
      require(m.prestrain, "material.prestrain");
      break;
    case HardeningLaw::voce:
      require(m.Q, "material.Q");
      require(m.b, "material.b");
      break;
    case HardeningLaw::table: {
      const auto& points = m.hardening_points;
      const bool from_file = !m.hardening_table_file.empty();
      const std::string key = from_file ? "material.hardening_table" : "material.hardening_points";
      const auto fail_point = [&](std::size_t k, const std::string& problem) {
        fail(key, fmt::format("{}point {} {}", from_file ? printable(m.hardening_table_file, 200) + ": " : "", k + 1,
                              problem));
      };
      if (points.size() < 2)
        fail(key, fmt::format("a hardening table needs at least 2 points (eps_p, sigma), got {}", points.size()));
      for (std::size_t k = 0; k < points.size(); ++k) {
        const auto [eps_p, sigma] = points[k];
        if (!(std::isfinite(eps_p) && std::isfinite(sigma))) fail_point(k, "is not two finite numbers");
        if (k == 0 && eps_p != 0.0)
          fail_point(k, fmt::format("has eps_p = {}: the table starts at yield, eps_p = 0", eps_p));
        if (!(sigma > 0.0)) fail_point(k, fmt::format("has sigma = {} Pa: a flow stress is > 0", sigma));
        if (k > 0 && !(eps_p > points[k - 1].first))
          fail_point(k, fmt::format("has eps_p = {} after {}: eps_p must increase", eps_p, points[k - 1].first));
        if (k > 0 && sigma < points[k - 1].second)
          fail_point(k, fmt::format("has sigma = {} Pa after {} Pa: the flow stress must not fall (softening "
                                    "localizes; J2 flow theory with a falling curve has no unique solution)",
                                    sigma, points[k - 1].second));
      }
      break;
    }
  }
}

namespace input_detail {

/// The indenter on its own: what its shape needs, whatever specimen it meets.
/// A rate-dependent flow rule (docs/MODEL.md §13.3): J2's, with its parameters, on a load path in
/// time (the increments' durations are what it integrates over).
static void validate_rate(const LoadCase& lc) {
  const auto& m = lc.material;
  if (m.rate == RateLaw::none) return;
  const auto fail = [&](const std::string& key, const std::string& problem) { throw InputError(lc.source, key, problem); };
  const std::string rule = to_string(m.rate);
  if (m.model != MaterialModel::j2)
    fail("material.rate", fmt::format("\"{}\" is a flow rule of J2 flow theory: set material.model = \"j2\"", rule));
  const auto require = [&](const std::optional<double>& value, const char* key) {
    if (!value) fail(key, fmt::format("missing key (material.rate = \"{}\" needs it)", rule));
  };
  if (m.rate == RateLaw::perzyna) require(m.reference_strain_rate, "material.reference_strain_rate");
  if (m.rate == RateLaw::norton) {
    require(m.creep_coefficient, "material.creep_coefficient");
    require(m.reference_stress, "material.reference_stress");
  }
  require(m.rate_exponent, "material.rate_exponent");
  if (lc.load.times.empty())
    fail("material.rate", fmt::format("\"{}\" flows at a rate: give load.times, the time [s] of each waypoint of "
                                      "load.path (e.g. path = [0, 0.05, 0.05, 0], times = [0, 10, 20, 30] for a "
                                      "10 s loading, a 10 s hold and a 10 s unloading)",
                                      rule));
  // Creep flows wherever the stress is not zero: there is no elastic far field to condense.
  if (m.rate == RateLaw::norton && lc.solver.far_field == FarFieldChoice::condense)
    fail("solver.far_field", "\"condense\" takes the far field to be linear elastic, and under material.rate = "
                             "\"norton\" every stressed element creeps: use \"auto\" or \"full\"");
}

/// The layers (docs/MODEL.md §14.2): each thickness a length > 0, the stack thinner than the
/// specimen, and each layer's material valid as [material] is (checked by the same functions on a
/// scratch case whose material is the layer's; its messages name layer[k]).
static void validate_layers(const LoadCase& lc) {
  // Each layer is at least 4 rows of elements and an interface laid into the mesh; a stack of
  // more is a graded material, which wants its own model.
  if (lc.layers.size() > max_layers)
    throw InputError(lc.source, "layer",
                     fmt::format("{} layers: at most {} (a finer stack is a graded material, not built)",
                                 lc.layers.size(), max_layers));
  double depth = 0.0;
  for (std::size_t k = 0; k < lc.layers.size(); ++k) {
    const std::string name = fmt::format("layer[{}]", k + 1);
    const LayerInput& layer = lc.layers[k];
    if (!(std::isfinite(layer.thickness) && layer.thickness > 0.0))
      throw InputError(lc.source, name + ".thickness",
                       fmt::format("must be a finite length > 0 (got {})", layer.thickness));
    // Each interface a mesh line (MODEL.md §14.3), resolved in double precision against the block
    // (as the depths are: 1e-9 of it), and so is the substrate below the last.
    const double resolvable = 1e-9 * lc.geometry.ly;
    if (!(layer.thickness >= resolvable))
      throw InputError(lc.source, name + ".thickness",
                       fmt::format("{:g} m is below what double precision resolves against the specimen's depth "
                                   "(1e-9 of geometry.ly = {:g} m)",
                                   layer.thickness, lc.geometry.ly));
    depth += layer.thickness;
    if (!(lc.geometry.ly - depth >= resolvable))
      throw InputError(lc.source, name + ".thickness",
                       fmt::format("the layers reach {} m below the surface, the specimen's depth (geometry.ly = {} m) "
                                   "or within 1e-9 of it: the substrate must lie below them",
                                   depth, lc.geometry.ly));
    const LoadCase scratch = with_material(lc, layer.material);
    try {
      check_declared_ranges(scratch, "material");
      validate_hardening(scratch);
      validate_rate(scratch);
    } catch (const InputError& e) {
      // The layer's own keys are named as the layer's; a key of another section (the far field
      // a creeping layer cannot have condensed) keeps its name.
      const bool own = e.key().rfind("material", 0) == 0;
      throw InputError(e.file(), own ? name + "." + e.key() : e.key(),
                       own ? e.problem() : fmt::format("{} (in {})", e.problem(), name));
    }
  }
  // Ilyushin's deformation theory makes the whole body's state a function of the load and its
  // unloading theorem unloads the whole body from the path's deepest point (docs/MODEL.md §5);
  // a region that creeps at a held load has no such state (measured: an Ilyushin film on a Norton
  // substrate finds no first increment).
  if (lc.any_rate_dependent())
    for (std::size_t r = 0; r < lc.regions(); ++r)
      if (lc.region_material(r).model == MaterialModel::ilyushin)
        throw InputError(lc.source, (r == 0 ? std::string() : fmt::format("layer[{}].", r)) + "material.model",
                         "\"ilyushin\" (deformation theory: the state of the whole specimen follows the load) cannot "
                         "share a specimen with a region whose material.rate flows in time: use \"j2\"");
}

void validate_punch_shape(const LoadCase& lc) {
  const auto& punch = lc.punch;
  if ((punch.shape == PunchShapeKind::sphere || punch.shape == PunchShapeKind::flat) && !(punch.radius > 0.0))
    throw InputError(lc.source, "punch.radius", fmt::format("must be > 0 (got {})", punch.radius));
  if (punch.shape == PunchShapeKind::cone) {
    if (!(punch.half_angle > 0.0 && punch.half_angle < 90.0))
      throw InputError(lc.source, "punch.half_angle",
                       fmt::format("must lie in (0, 90) degrees, the angle between axis and face (got {})",
                                   punch.half_angle));
    if (!(punch.tip_radius >= 0.0))
      throw InputError(lc.source, "punch.tip_radius", fmt::format("must be >= 0 (got {})", punch.tip_radius));
  }
  if (punch.shape == PunchShapeKind::profile) validate_profile(lc, false);
  if (punch.shape == PunchShapeKind::area_function) {
    if (lc.geometry.kind != SceneKind::axisymmetric)
      throw InputError(lc.source, "punch.shape",
                       "\"area_function\" is the projected area of a tip of revolution (or a pyramid's equal-area "
                       "cone): plane strain has no such profile; use geometry.kind = \"axisymmetric\", or a profile");
    validate_area_function(lc, false);
  }
}

void validate_analysis(const LoadCase& lc) {
  const auto fail = [&](const std::string& key, const std::string& problem) {
    throw InputError(lc.source, key, problem);
  };
  check_declared_ranges(lc, "analysis");
  const auto& fit = lc.analysis.fit_range;
  if (fit.size() != 2 || !(fit[0] >= 0.0 && fit[0] < fit[1] && fit[1] <= 1.0))
    fail("analysis.fit_range", "must be two fractions of P_max, 0 <= lower < upper <= 1 (for example [0.2, 0.98])");
}

}  // namespace input_detail

void validate(const LoadCase& lc) {
  const auto fail = [&](const std::string& key, const std::string& problem) {
    throw InputError(lc.source, key, problem);
  };
  // Each key's own interval, where it is declared (key_declarations.cpp); here what involves
  // several keys.  The [analysis] keys are validate_analysis'.  Every key given is checked,
  // whatever the model uses: a case switched to another model later must not carry a value that
  // was never valid.
  for (const std::string& section : section_names(key_declarations()))
    if (section != "analysis") check_declared_ranges(lc, section);
  const auto& punch = lc.punch;
  const bool has_radius = punch.shape == PunchShapeKind::sphere || punch.shape == PunchShapeKind::flat;
  validate_punch_shape(lc);
  if (punch.shape == PunchShapeKind::flat && !(punch.radius < lc.geometry.lx))
    fail("punch.radius", fmt::format("the flat punch ({} m) is not narrower than the specimen (geometry.lx = {} m)",
                                     punch.radius, lc.geometry.lx));
  if (punch.shape == PunchShapeKind::cone) {
    const double cap = punch.tip_radius * std::cos(punch.half_angle * std::acos(-1.0) / 180.0);
    if (!(cap < lc.geometry.lx))
      fail("punch.tip_radius", fmt::format("the spherical cap of radius {} m meets the face at r = {:.4g} m, beyond "
                                           "the specimen (geometry.lx = {} m): it does not fit",
                                           punch.tip_radius, cap, lc.geometry.lx));
  }
  if (punch.shape == PunchShapeKind::profile && !lc.load.path.empty()) validate_profile(lc, true);
  if (punch.shape == PunchShapeKind::area_function) validate_area_function(lc, true);
  // Friction's rows are written beside node-to-rigid's normal rows (docs/MODEL.md §3.3); a finite
  // coefficient's slip rows are unsymmetric, which CHOLMOD's Cholesky cannot factor.
  if (lc.contact.friction > 0.0 && lc.contact.discretization != ContactDiscretizationChoice::node_to_rigid)
    fail("contact.friction", "Coulomb friction is implemented with contact.discretization = \"node_to_rigid\" only");
  // A sticking node keeps its tangential force until it separates, where that force would have to
  // vanish at once: the increment that releases it has no solution (measured: the shipped steel
  // sphere's first unloading increment cycles between contact sets through 10 cutbacks).  A finite
  // coefficient releases it by sliding as the normal force vanishes.
  if (std::isinf(lc.contact.friction))
    for (std::size_t i = 1; i < lc.load.path.size(); ++i)
      if (lc.load.path[i] < lc.load.path[i - 1])
        fail("contact.friction",
             fmt::format("\"sticking\" cannot release a node's tangential force as it separates, so the load path's "
                         "unloading (waypoint {}) has no solution: give a finite coefficient (mu = 10 slides only "
                         "where the normal force nearly vanishes)",
                         i));
  // Finite strain is built on node-to-rigid's rows, with or without friction (docs/MODEL.md
  // §12.3); its contact rows and F-bar's tangent are unsymmetric.
  if (lc.geometry.strain == StrainChoice::finite) {
    if (lc.contact.discretization != ContactDiscretizationChoice::node_to_rigid)
      fail("geometry.strain", "\"finite\" is built with contact.discretization = \"node_to_rigid\" only (the "
                              "integrated gap on the current surface is not built yet)");
    if (lc.solver.linear == LinearSolverChoice::cholmod)
      fail("solver.linear", "\"cholmod\" cannot factor finite strain's unsymmetric rows (the contact on the current "
                            "surface, F-bar): use \"klu\" or \"auto\"");
  }
  if (lc.contact.friction > 0.0 && std::isfinite(lc.contact.friction) && lc.solver.linear == LinearSolverChoice::cholmod)
    fail("solver.linear", fmt::format("\"cholmod\" cannot factor the unsymmetric rows of sliding friction "
                                      "(contact.friction = {}): use \"klu\" or \"auto\"",
                                      lc.contact.friction));

  validate_hardening(lc);
  validate_rate(lc);
  validate_layers(lc);

  const auto& path = lc.load.path;
  if (path.size() < 2) fail("load.path", "needs at least two waypoints, starting at 0");
  if (path.front() != 0.0) fail("load.path", fmt::format("must start at 0 (got {})", path.front()));
  const bool force_control = lc.load.control == LoadControlKind::force;
  const char* quantity = force_control ? "force" : "depth";
  for (std::size_t i = 0; i < path.size(); ++i)
    if (!(path[i] >= 0.0) || !std::isfinite(path[i]))
      fail("load.path", fmt::format("waypoint {} is not a {} >= 0 ({})", i, quantity, path[i]));
  if (!(lc.load.largest_target() > 0.0))
    fail("load.path", force_control ? "never loads: every waypoint is 0" : "never indents: every waypoint is 0");
  if (lc.load.depth_estimate && !force_control)
    fail("load.depth_estimate", "is the depth pilot's measurement under load.control = \"force\"; under depth "
                                "control the deepest waypoint is the depth");
  if (force_control) {
    // The bordered Newton system (docs/MODEL.md §13.1) has a row and a column CHOLMOD's symmetric
    // factorization cannot take.
    if (lc.solver.linear == LinearSolverChoice::cholmod)
      fail("solver.linear", "\"cholmod\" cannot factor the force-controlled Newton system (its force row and depth "
                            "column are not symmetric): use \"klu\" or \"auto\"");
    if (lc.contact.discretization == ContactDiscretizationChoice::integrated_gap)
      fail("load.control", "\"force\" is built with contact.discretization = \"node_to_rigid\" only (the integrated "
                           "gap's penalty force is not yet a row of the force-controlled system)");
  }
  // Depth checks: on the deepest waypoint, or on the depth pilot's estimate once it is measured.
  const char* depth_key = force_control ? "load.depth_estimate" : "load.path";
  if (lc.max_depth() > 0.0) {
    // The gap g(x) = R - sqrt(R^2 - x^2) and the displacements are resolved against R and the
    // block in double precision: a depth below 1e-9 of them is round-off, not an indentation.
    const double resolvable = 1e-9 * std::max(has_radius ? lc.punch.radius : 0.0, lc.geometry.ly);
    if (lc.max_depth() < resolvable)
      fail(depth_key, fmt::format("the deepest depth {:g} m is below what double precision resolves against the "
                                  "punch radius and the block ({:g} m, 1e-9 of them)",
                                  lc.max_depth(), resolvable));
    if (punch.shape == PunchShapeKind::sphere && lc.max_depth() >= lc.punch.radius)
      fail(depth_key, fmt::format("depth {} reaches the punch radius {}: no circular contact possible",
                                  lc.max_depth(), lc.punch.radius));
    if (lc.max_depth() >= lc.geometry.ly)
      fail(depth_key, fmt::format("depth {} is not small against the block depth {}", lc.max_depth(),
                                  lc.geometry.ly));
  }
  if (!lc.load.segment_increments.empty() && lc.load.segment_increments.size() + 1 != path.size())
    fail("load.path", fmt::format("has {} segments, but load.increments gives {} per-segment counts: set the two "
                                  "together (or load.increments as one total, spread by path length)",
                                  path.size() - 1, lc.load.segment_increments.size()));
  if (const auto& times = lc.load.times; !times.empty()) {
    if (times.size() != path.size())
      fail("load.times", fmt::format("gives {} times for the {} waypoints of load.path: one time per waypoint",
                                     times.size(), path.size()));
    if (times.front() != 0.0) fail("load.times", fmt::format("must start at 0 (got {})", times.front()));
    for (std::size_t i = 1; i < times.size(); ++i)
      if (!std::isfinite(times[i]) || !(times[i] > times[i - 1]))
        fail("load.times", fmt::format("time {} ({} s) does not come after time {} ({} s): every segment of the "
                                       "path needs a positive duration",
                                       i, times[i], i - 1, times[i - 1]));
  }
  if (lc.load.increments < 1) fail("load.increments", fmt::format("must be >= 1 (got {})", lc.load.increments));
  if (lc.load.increments > 10'000'000)
    fail("load.increments", fmt::format("{} is more than 1e7 increments", lc.load.increments));

  if (lc.mesh.contact_half_width && !(*lc.mesh.contact_half_width < std::min(lc.geometry.lx, lc.geometry.ly)))
    fail("mesh.contact_half_width",
         fmt::format("{} m is not smaller than the specimen (geometry.lx = {} m, geometry.ly = {} m): a contact wider "
                     "than the specimen is no indentation",
                     *lc.mesh.contact_half_width, lc.geometry.lx, lc.geometry.ly));
  if (!lc.mesh.plastic_zone.empty()) {
    // (A flat punch's contact half-width is its radius: case.toml records the zone alone.)
    if (!lc.mesh.contact_half_width && punch.shape != PunchShapeKind::flat)
      fail("mesh.plastic_zone", "is the pilot's and comes with its contact half-width: give mesh.contact_half_width too");
    for (std::size_t i = 0; i < lc.mesh.plastic_zone.size(); ++i) {
      const auto& z = lc.mesh.plastic_zone[i];
      if (!(std::isfinite(z[0]) && std::isfinite(z[1]) && std::isfinite(z[2]) && z[0] >= 0.0 && z[1] >= 0.0 && z[2] >= 0.0))
        fail("mesh.plastic_zone", fmt::format("element {} must be three finite lengths >= 0", i));
      if (i > 0 && !(z[0] > lc.mesh.plastic_zone[i - 1][0]))
        fail("mesh.plastic_zone", fmt::format("element {}: the depths h must increase", i));
    }
  }
  if (lc.mesh.contact_half_width && punch.shape == PunchShapeKind::flat)
    fail("mesh.contact_half_width", "a flat punch's contact radius is punch.radius: the mesh is sized from it");
  if (lc.mesh.target_error && force_control)
    fail("mesh.target_error", "needs an error estimate, which load.control = \"force\" does not have yet");
  if (lc.mesh.target_error && lc.mesh.error_estimate == ErrorEstimateChoice::off)
    fail("mesh.target_error", "needs an error estimate: mesh.error_estimate = \"off\" cannot check a target");

  validate_analysis(lc);
  if (lc.output.dir.empty()) fail("output.dir", "must not be empty");
  // A NUL would cut the path short at the system call ("a\u0000b" creates a); other control
  // characters make folders no shell command can name.
  if (std::any_of(lc.output.dir.begin(), lc.output.dir.end(), [](char c) { return static_cast<unsigned char>(c) < 0x20 || c == 0x7f; }))
    fail("output.dir", fmt::format("\"{}\" holds a control character (NUL, a newline, ...): not a folder name",
                                   printable(lc.output.dir, 80)));
  for (std::size_t i = 0; i < lc.output.profile_depths.size(); ++i) {
    const double d = lc.output.profile_depths[i];
    if (!(d >= 0.0 && d <= lc.geometry.ly))
      fail("output.profile_depths", fmt::format("element {} = {} is not a depth within the block [0, {}]", i, d, lc.geometry.ly));
  }
}

}  // namespace indentsim
