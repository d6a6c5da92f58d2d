#include "indentsim/simulation/error_estimate.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "indentsim/base/error.hpp"
#include "indentsim/geometry/mesh.hpp"
#include "indentsim/geometry/punch.hpp"
#include "indentsim/simulation/simulation.hpp"
#include "indentsim/solvers/solver.hpp"

namespace indentsim {

RichardsonEstimate richardson(double fine, double coarse, double ratio, double order) {
  if (!(ratio > 1.0) || !(order > 0.0)) throw std::invalid_argument("richardson: needs ratio > 1 and order > 0");
  const double extrapolated = fine + (fine - coarse) / (std::pow(ratio, order) - 1.0);
  return {extrapolated, std::abs(fine - extrapolated)};
}

std::optional<double> observed_order(double f1, double f2, double f3, double h1, double h2, double h3) {
  constexpr double lowest = 0.5, highest = 6.0;
  if (!(h1 < h2 && h2 < h3)) throw std::invalid_argument("observed_order: needs h1 < h2 < h3");
  const double d12 = f2 - f1, d23 = f3 - f2;
  // In the asymptotic range f moves monotonically with h: both differences have one sign.
  if (d12 == 0.0 || d23 == 0.0 || (d12 > 0.0) != (d23 > 0.0)) return std::nullopt;
  // (h3^p - h2^p) / (h2^p - h1^p) = d23 / d12 grows monotonically with p: bisection.
  const double target = d23 / d12;
  const auto ratio_at = [&](double p) {
    return (std::pow(h3, p) - std::pow(h2, p)) / (std::pow(h2, p) - std::pow(h1, p));
  };
  double lo = lowest, hi = highest;
  if (target < ratio_at(lo) || target > ratio_at(hi)) return std::nullopt;
  for (int i = 0; i < 100 && hi - lo > 1e-12; ++i) {
    const double mid = 0.5 * (lo + hi);
    (ratio_at(mid) < target ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

namespace {

/// The main run's case on its own plan but `contact_nodes` across the planned contact width.
CompanionRun run_companion(const LoadCase& main_case, const RunPlan& main_plan, int contact_nodes) {
  const auto start = std::chrono::steady_clock::now();
  CompanionRun companion;
  companion.contact_nodes = contact_nodes;
  LoadCase lc = main_case;
  lc.mesh.contact_nodes = contact_nodes;
  // The main run's planned contact width and its pilot's plastic zone (a resumed run has it from
  // its checkpoint, so its estimate is the original's bit for bit): the companion's near field
  // grows with the zone as the main run's does.
  const RunPlan plan{plan_mesh(lc, main_plan.mesh.contact_half_width_estimate), main_plan.plastic_zone};
  try {
    Simulation sim(lc, plan);
    sim.run([&](const IncrementRecord& r) { companion.curve.push_back(r); });
  } catch (const SolverError& e) {
    companion.failure = e.what();
  }
  companion.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return companion;
}

/// The first row of a curve at the path's deepest depth, or null.
const IncrementRecord* deepest_row(const std::vector<IncrementRecord>& curve, double deepest) {
  for (const IncrementRecord& r : curve)
    if (std::abs(r.alpha - deepest) <= 1e-12 * deepest) return &r;
  return nullptr;
}

}  // namespace

bool depends_on_the_increments(const LoadCase& load_case) {
  for (std::size_t r = 0; r < load_case.regions(); ++r)
    if (load_case.region_material(r).model == MaterialModel::j2) return true;
  return load_case.contact.friction > 0.0;
}

LoadCase with_halved_increments(const LoadCase& load_case) {
  LoadCase lc = load_case;
  if (lc.load.segment_increments.empty()) {
    lc.load.increments = std::max(1, lc.load.increments / 2);
    return lc;
  }
  lc.load.increments = 0;
  for (int& n : lc.load.segment_increments) {
    n = std::max(1, n / 2);
    lc.load.increments += n;
  }
  return lc;
}

std::optional<std::string> error_estimate_unavailable(const LoadCase& load_case) {
  const MeshInput& mesh = load_case.mesh;
  if (mesh.error_estimate == ErrorEstimateChoice::off) return std::nullopt;
  // The companions' rows are matched to the run's at the same planned depths (companion_row); under
  // force control they land on the same forces at other depths.
  if (load_case.load.control == LoadControlKind::force)
    return std::string("under load.control = \"force\" the error estimate is not built yet (its companion runs "
                       "reach the same forces at other depths, and the estimate compares forces at equal depths): "
                       "this run has no error estimate");
  const int divisor = mesh.error_estimate == ErrorEstimateChoice::observed ? 4 : 2;
  if (mesh.contact_nodes / divisor >= 2) return std::nullopt;
  return fmt::format("mesh.contact_nodes = {} is too coarse for a companion run at contact_nodes / {} (it needs at "
                     "least {}): this run has no error estimate",
                     mesh.contact_nodes, divisor, 2 * divisor);
}

std::vector<int> companion_contact_nodes(const LoadCase& load_case) {
  const MeshInput& mesh = load_case.mesh;
  if (mesh.error_estimate == ErrorEstimateChoice::off || error_estimate_unavailable(load_case)) return {};
  std::vector<int> levels{mesh.contact_nodes / 2};
  if (mesh.error_estimate == ErrorEstimateChoice::observed) levels.push_back(mesh.contact_nodes / 4);
  return levels;
}

DiscretizationErrorEstimate::DiscretizationErrorEstimate(const Simulation& main)
    : DiscretizationErrorEstimate(main.load_case(), RunPlan{main.plan(), main.plastic_zone_growth()}) {}

DiscretizationErrorEstimate::DiscretizationErrorEstimate(const LoadCase& main_case, const RunPlan& main_plan)
    : method_(main_case.mesh.error_estimate),
      force_order_(force_order_assumed(main_case)),
      contact_nodes_(main_case.mesh.contact_nodes) {
  if (method_ == ErrorEstimateChoice::off) throw std::invalid_argument("error estimate: mesh.error_estimate is off");
  if (const auto why = error_estimate_unavailable(main_case)) throw std::invalid_argument(*why);
  for (int nodes : companion_contact_nodes(main_case)) {
    companions_.push_back(run_companion(main_case, main_plan, nodes));
    const CompanionRun& c = companions_.back();
    if (!c.failure.empty())
      warnings_.push_back(fmt::format("the error estimate's companion run (contact_nodes = {}) stopped after "
                                      "increment {}: {}; later increments have no error estimate",
                                      nodes, c.curve.empty() ? -1 : c.curve.back().step, c.failure));
  }
  // The path integration's share (IncrementSensitivity): the first companion again, with half the
  // increments.  It costs about half that companion.
  if (!depends_on_the_increments(main_case) || companions_.empty()) return;
  const CompanionRun halved = run_companion(with_halved_increments(main_case), main_plan, companions_.front().contact_nodes);
  halved_wall_seconds_ = halved.wall_seconds;
  const double deepest = main_case.max_depth();
  const IncrementRecord* full = deepest_row(companions_.front().curve, deepest);
  const IncrementRecord* half = deepest_row(halved.curve, deepest);
  if (!full || !half) {
    warnings_.push_back(fmt::format("the error estimate's companion with half the increments stopped before the "
                                    "deepest point{}{}: the increments' share of the error is not measured",
                                    halved.failure.empty() ? "" : ": ", halved.failure));
    return;
  }
  increment_sensitivity_ = IncrementSensitivity{companions_.front().contact_nodes, deepest, full->force, half->force};
  if (increment_sensitivity_->relative_change() > increment_change_warning)
    warnings_.push_back(fmt::format(
        "halving the increments moves P at the deepest point by {:.2g}% (on the error estimate's mesh of {} contact "
        "nodes): the path's share of the error, at least about that, is not in P_error_estimate (the mesh's); raise "
        "load.increments",
        100.0 * increment_sensitivity_->relative_change(), companions_.front().contact_nodes));
}

double DiscretizationErrorEstimate::wall_seconds() const {
  double total = halved_wall_seconds_;
  for (const CompanionRun& c : companions_) total += c.wall_seconds;
  return total;
}

const IncrementRecord* DiscretizationErrorEstimate::companion_row(std::size_t companion,
                                                                  const IncrementRecord& row) const {
  const std::vector<IncrementRecord>& curve = companions_[companion].curve;
  if (row.step < 0 || static_cast<std::size_t>(row.step) >= curve.size()) return nullptr;
  const IncrementRecord& c = curve[static_cast<std::size_t>(row.step)];
  // Same load path, same planned depths: the rows match step for step.
  if (c.step != row.step || std::abs(c.alpha - row.alpha) > 1e-12 * std::max(std::abs(row.alpha), 1e-300))
    return nullptr;
  return &c;
}

double force_order_assumed(const LoadCase& load_case) {
  constexpr double plastic_order = 1.5;
  // A coated specimen's force converges at first order, measured (a 400 GPa film 50 um thick on a
  // 200 GPa substrate under a 1 mm sphere at 20 um: 907.86, 906.70, 906.22, 905.98 N at 10, 20, 40
  // and 80 contact nodes, differences falling by 2.7 then 1.9; a film of whole fine rows converges
  // alike, so not the interface's laying; docs/MODEL.md §14.3).
  constexpr double layered_order = 1.0;
  const double shape_order = make_punch(load_case.punch)->force_convergence_order();
  const double order = load_case.any_inelastic() ? std::min(shape_order, plastic_order) : shape_order;
  return load_case.layers.empty() ? order : std::min(order, layered_order);
}

std::optional<DiscretizationErrorEstimate::AtIncrement> DiscretizationErrorEstimate::at(
    const IncrementRecord& row) const {
  const IncrementRecord* half = companion_row(0, row);
  if (!half) return std::nullopt;
  // The fine-zone spacing is the planned contact width over contact_nodes: h ~ 1 / contact_nodes.
  const double ratio = static_cast<double>(contact_nodes_) / companions_[0].contact_nodes;
  AtIncrement estimate;
  estimate.force_order = force_order_;
  if (method_ == ErrorEstimateChoice::observed) {
    const IncrementRecord* quarter = companion_row(1, row);
    if (!quarter) return std::nullopt;
    const double h1 = 1.0 / contact_nodes_, h2 = 1.0 / companions_[0].contact_nodes,
                 h3 = 1.0 / companions_[1].contact_nodes;
    if (const auto p = observed_order(row.force, half->force, quarter->force, h1, h2, h3)) {
      estimate.force_order = *p;
      estimate.order_observed = true;
    }
  }
  const RichardsonEstimate force = richardson(row.force, half->force, ratio, estimate.force_order);
  estimate.force_error = force.error;
  estimate.force_extrapolated = force.extrapolated;
  estimate.width_error = richardson(row.half_width, half->half_width, ratio, nominal_width_order).error;
  return estimate;
}

std::optional<double> relative_force_error(const DiscretizationErrorEstimate& estimate,
                                           const std::vector<IncrementRecord>& curve) {
  if (curve.empty()) return std::nullopt;
  const IncrementRecord* row = &curve.back();
  if (row->force == 0.0)
    for (const IncrementRecord& r : curve)
      if (std::abs(r.force) > std::abs(row->force)) row = &r;
  if (row->force == 0.0) return std::nullopt;
  const auto e = estimate.at(*row);
  if (!e) return std::nullopt;
  return e->force_error / std::abs(row->force);
}

namespace {

/// One pilot of mesh.target_error: the case on `contact_nodes`, in memory, with its estimate.
TargetErrorChoice::Attempt run_pilot(const LoadCase& load_case, int contact_nodes) {
  LoadCase pilot_case = load_case;
  pilot_case.mesh.contact_nodes = contact_nodes;
  pilot_case.mesh.target_error.reset();
  Simulation pilot(pilot_case);
  const DiscretizationErrorEstimate estimate(pilot);
  std::vector<IncrementRecord> curve;
  try {
    pilot.run([&](const IncrementRecord& r) { curve.push_back(r); });
  } catch (const SolverError& e) {
    throw SolverError(fmt::format("the pilot of mesh.target_error (contact_nodes = {}) did not converge: {}",
                                  contact_nodes, e.what()));
  }
  const std::optional<double> error = relative_force_error(estimate, curve);
  if (!error)
    throw SolverError(fmt::format("the pilot of mesh.target_error (contact_nodes = {}) has no error estimate: its "
                                  "companion run stopped early or the curve has no force",
                                  contact_nodes));
  TargetErrorChoice::Attempt attempt{"pilot", contact_nodes, pilot_case.load.total_increments(), *error, std::nullopt};
  if (const auto& s = estimate.increment_sensitivity()) attempt.increment_change = s->relative_change();
  return attempt;
}

}  // namespace

LoadCase plan_case_for_target(const LoadCase& load_case, TargetErrorChoice& choice, int first_pilot_contact_nodes) {
  if (!load_case.mesh.target_error) throw std::invalid_argument("plan_case_for_target: no target");
  // A pilot is refined at most by this factor before the next one: its cost is then about an
  // eighth of the next one's (a run's cost grows about as contact_nodes^3, docs/performance.md).
  constexpr double pilot_refinement = 2.0;
  constexpr int most_increments_factor = 16;
  choice.target = *load_case.mesh.target_error;
  const double order = force_order_assumed(load_case);
  LoadCase pilot_case = load_case;
  pin_kinematics(pilot_case);  // chosen against the target, which the planned case no longer holds
  pilot_case.mesh.contact_nodes = first_pilot_contact_nodes;
  int increments_factor = 1;
  for (;;) {
    choice.attempts.push_back(run_pilot(pilot_case, pilot_case.mesh.contact_nodes));
    const TargetErrorChoice::Attempt& pilot = choice.attempts.back();
    // The path first: a mesh estimate taken on a path far from converged is the path's noise
    // (the J2 cylinder on 4 increments estimated 0.77% at 10 contact nodes and 0.005% at 20).
    if (pilot.increment_change && increments_factor < most_increments_factor) {
      const int factor = std::min(increments_factor_for_target(*pilot.increment_change, choice.target),
                                  most_increments_factor / increments_factor);
      if (factor > 1) {
        pilot_case.load.multiply_increments(factor);
        increments_factor *= factor;
        continue;
      }
    }
    const int needed = contact_nodes_for_target(pilot.relative_error, pilot.contact_nodes, choice.target, order);
    // At most five doublings (10 to 320 contact nodes): a pilot beyond is a run in itself, and an
    // estimate that keeps asking for more is better judged by the run and its retry.
    if (needed <= pilot_refinement * pilot.contact_nodes || pilot.contact_nodes >= (first_pilot_contact_nodes << 5)) break;
    pilot_case.mesh.contact_nodes = static_cast<int>(pilot_refinement * pilot.contact_nodes);
  }
  LoadCase chosen = pilot_case;
  chosen.mesh.target_error.reset();
  chosen.mesh.contact_nodes = contact_nodes_for_target(choice.attempts.back().relative_error,
                                                       choice.attempts.back().contact_nodes, choice.target, order);
  return chosen;
}

LoadCase refine_case_for_target(const LoadCase& as_run, const TargetErrorChoice::Attempt& missed, double target) {
  LoadCase lc = as_run;
  lc.mesh.target_error.reset();
  lc.mesh.contact_nodes = contact_nodes_for_target(missed.relative_error, missed.contact_nodes, target,
                                                   force_order_assumed(as_run));
  if (missed.increment_change)
    lc.load.multiply_increments(increments_factor_for_target(*missed.increment_change, target));
  return lc;
}

int increments_factor_for_target(double relative_change, double target) {
  if (!(target > 0.0)) throw std::invalid_argument("increments_factor_for_target: bad target");
  constexpr int most = 16;
  if (!(relative_change > target)) return 1;
  // First order: the error of n increments is the change from n / 2, and it falls as 1 / n.  The
  // margin of 30% on the error is the mesh's 15% on the spacing at order 2.
  return static_cast<int>(std::min<double>(most, std::ceil(1.3 * relative_change / target)));
}

int contact_nodes_for_target(double relative_error, int contact_nodes, double target, double order) {
  if (!(target > 0.0) || !(order > 0.0)) throw std::invalid_argument("contact_nodes_for_target: bad target or order");
  if (!(relative_error > target)) return contact_nodes;
  // error ~ C h^p and h ~ 1 / contact_nodes: N = N0 (e0 / target)^(1/p), 15% finer for margin.
  const double nodes = 1.15 * contact_nodes * std::pow(relative_error / target, 1.0 / order);
  return static_cast<int>(std::min(std::ceil(nodes), 1e6));
}

}  // namespace indentsim
