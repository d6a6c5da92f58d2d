#include "indentsim/simulation.hpp"

#include <chrono>
#include <cmath>

#include <fmt/format.h>

#include "indentsim/error.hpp"

namespace indentsim {

Simulation::Simulation(LoadCase load_case) : load_case_(std::move(load_case)) {
  if (load_case_.material.model != MaterialModel::elastic)
    throw InputError(load_case_.source, "material.model",
                     fmt::format("\"{}\" is not available in this version (use \"elastic\")",
                                 to_string(load_case_.material.model)));
  plan_ = plan_mesh(load_case_);
  mesh_ = std::make_unique<Mesh>(Mesh::from_plan(load_case_, plan_));
  pattern_ = std::make_unique<StiffnessPattern>(*mesh_);
  const ElasticMaterial material{load_case_.material.E, load_case_.material.nu};
  stiffness_ = std::make_unique<ElasticStiffness>(*mesh_, material, *pattern_);
  contact_ = std::make_unique<ContactBoundary>(*mesh_, CylindricalPunch{load_case_.punch.radius}, *pattern_,
                                               stiffness_->values());
  equations_ = std::make_unique<ElasticContactEquations>(*pattern_, *stiffness_, *contact_);

  NewtonSettings settings;
  settings.displacement_scale = load_case_.max_depth();
  settings.force_scale = material.plane_strain_modulus() * load_case_.max_depth();
  settings.tolerance = load_case_.solver.tolerance;
  settings.max_iterations = load_case_.solver.max_newton;
  newton_ = std::make_unique<NewtonSolver>(*equations_, settings);

  u_.assign(static_cast<std::size_t>(mesh_->equations()), 0.0);
}

Simulation::~Simulation() = default;

void Simulation::run(const std::function<void(const IncrementRecord&)>& on_increment) {
  const std::vector<double> targets = plan_increments(load_case_.load.path, load_case_.load.increments);
  for (double target : targets) {
    const IncrementRecord r = advance_to(target);
    if (on_increment) on_increment(r);
  }
  const ContactResult final_contact = contact();
  if (final_contact.force > 0.0 && final_contact.contact_nodes < 4)
    warnings_.push_back(fmt::format("the contact zone spans only {} node(s) at the final depth: the result is "
                                    "coarse; raise mesh.contact_nodes",
                                    final_contact.contact_nodes));
}

IncrementRecord Simulation::advance_to(double target) {
  const auto start = std::chrono::steady_clock::now();
  long iterations = 0, factorizations = 0;
  int cutbacks = 0;
  double step = target - alpha_;
  for (;;) {
    double trial = alpha_ + step;
    if (std::abs(target - trial) <= 1e-12 * std::abs(target)) trial = target;
    if (has_previous_) extrapolate(u_previous_, alpha_previous_, u_, alpha_, trial, guess_);
    else guess_ = u_;
    const NewtonReport report = newton_->solve(trial, guess_);
    iterations += report.iterations;
    factorizations += report.factorizations;
    if (report.converged) {
      u_previous_.swap(u_);
      u_.swap(guess_);
      alpha_previous_ = alpha_;
      alpha_ = trial;
      has_previous_ = true;
      if (trial == target) break;
      step = std::copysign(std::min(std::abs(step), std::abs(target - alpha_)), target - alpha_);
      continue;
    }
    if (cutbacks >= load_case_.solver.max_cutbacks)
      throw SolverError(fmt::format(
          "the increment from alpha = {:.6g} m to {:.6g} m did not converge after {} cutbacks (last try: "
          "alpha = {:.6g} m, {} Newton iterations, scaled residual {:.3g}, KINSOL flag {}{}{})",
          alpha_, target, cutbacks, trial, report.iterations, report.residual, report.kinsol_flag,
          report.message.empty() ? "" : ": ", report.message));
    step *= 0.5;
    ++cutbacks;
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return record(seconds, iterations, factorizations, cutbacks);
}

ContactResult Simulation::contact() const {
  std::vector<double> internal_force(u_.size());
  stiffness_->internal_force(u_.data(), internal_force.data());
  return evaluate_contact(*contact_, u_.data(), internal_force.data(), alpha_);
}

double Simulation::contact_half_width() const {
  return indentsim::contact_half_width(*contact_, contact());
}

std::vector<LayerForce> Simulation::layer_forces() const {
  return indentsim::layer_forces(*mesh_, *stiffness_, u_.data());
}

void Simulation::check_fine_zone(double half_width) {
  if (warned_fine_zone_ || half_width <= plan_.fine_width) return;
  warned_fine_zone_ = true;
  warnings_.push_back(fmt::format(
      "at alpha = {:.4g} m the contact half-width {:.4g} m left the fine mesh zone ({:.4g} m): accuracy drops; "
      "set mesh.contact_half_width or mesh.fine_width larger",
      alpha_, half_width, plan_.fine_width));
}

IncrementRecord Simulation::record(double wall_seconds, long iterations, long factorizations, int cutbacks) {
  const ContactResult c = contact();
  IncrementRecord r;
  r.step = rows_++;
  r.alpha = alpha_;
  r.force = c.force;
  r.half_width = indentsim::contact_half_width(*contact_, c);
  r.contact_nodes = c.contact_nodes;
  r.newton_iterations = iterations;
  r.factorizations = factorizations;
  r.cutbacks = cutbacks;
  r.wall_seconds = wall_seconds;
  check_fine_zone(r.half_width);
  return r;
}

}  // namespace indentsim
