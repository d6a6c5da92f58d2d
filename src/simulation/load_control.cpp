#include "indentsim/simulation/load_control.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "indentsim/geometry/kinematics.hpp"
#include "indentsim/solvers/force_controlled_equations.hpp"

namespace indentsim {

namespace {

class DepthControl final : public LoadControl {
public:
  LoadControlKind kind() const override { return LoadControlKind::depth; }
  std::string describe(double value) const override { return fmt::format("alpha = {:.6g} m", value); }
  double committed(const SimulationState& s) const override { return s.alpha; }
  double previous(const SimulationState& s) const override { return s.alpha_previous; }
  bool loads(const SimulationState& s, double trial) const override { return trial >= s.deepest; }
  double predictor_coordinate(double value) const override { return value; }
  void commit(SimulationState&, double) const override {}
  bool at_target(const IncrementRecord& row, double target, double, double) const override {
    return row.alpha == target;
  }
  std::unique_ptr<IncrementEquations> system_equations(ContactEquations&, const ContactDiscretization&,
                                                       double) const override {
    return nullptr;
  }
};

class ForceControl final : public LoadControl {
public:
  ForceControl(double largest_force, std::string unit, double exponent)
      : largest_force_(largest_force), unit_(std::move(unit)), exponent_(exponent) {}
  LoadControlKind kind() const override { return LoadControlKind::force; }
  std::string describe(double value) const override { return fmt::format("P = {:.6g} {}", value, unit_); }
  double committed(const SimulationState& s) const override { return s.force; }
  double previous(const SimulationState& s) const override { return s.force_previous; }
  bool loads(const SimulationState& s, double trial) const override { return trial >= s.largest_force; }
  double predictor_coordinate(double value) const override { return std::pow(std::max(0.0, value), 1.0 / exponent_); }
  void commit(SimulationState& s, double trial) const override {
    s.force_previous = s.force;
    s.force = trial;
    s.largest_force = std::max(s.largest_force, trial);
  }
  bool at_target(const IncrementRecord& row, double target, double largest, double tolerance) const override {
    // ForceControlledEquations lands P within the tolerance of force_control_reference; the
    // factor 2 leaves room for the rounding of the force recomputed from the state.
    return std::abs(row.force - target) <= 2.0 * tolerance * force_control_reference(target, largest);
  }
  std::unique_ptr<IncrementEquations> system_equations(ContactEquations& equations,
                                                       const ContactDiscretization& contact,
                                                       double force_scale) const override {
    return std::make_unique<ForceControlledEquations>(equations, contact, force_scale, largest_force_);
  }

private:
  double largest_force_;
  std::string unit_;
  double exponent_;
};

}  // namespace

double force_exponent(PunchShapeKind shape) {
  switch (shape) {
    case PunchShapeKind::flat: return 1.0;
    case PunchShapeKind::cone:
    case PunchShapeKind::area_function: return 2.0;  // a calibrated sharp tip: A ~ h^2 beyond its rounding
    case PunchShapeKind::sphere:
    case PunchShapeKind::profile: break;
  }
  return 1.5;
}

double expected_depth(const LoadCase& lc, double target) {
  if (lc.load.control != LoadControlKind::force) return target;
  return lc.max_depth() *
         std::pow(std::max(0.0, target) / lc.load.largest_target(), 1.0 / force_exponent(lc.punch.shape));
}

std::unique_ptr<LoadControl> LoadControl::of(const LoadCase& load_case) {
  if (load_case.load.control == LoadControlKind::force)
    return std::make_unique<ForceControl>(load_case.load.largest_target(),
                                          make_kinematics(load_case.geometry.kind)->force_unit(),
                                          force_exponent(load_case.punch.shape));
  return std::make_unique<DepthControl>();
}

}  // namespace indentsim
