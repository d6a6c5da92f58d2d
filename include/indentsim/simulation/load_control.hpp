#pragma once
// Load control: what the load path steps, between the run and the increment's Newton solve
// (docs/MODEL.md §13.1).  Everything the run does with a waypoint goes through it: the trial
// value of a (sub-)increment, Ilyushin's loading branch, the predictor's secant, the Newton
// system (the depth a parameter, or one more unknown), the resume check, the messages.
//
//   DepthControl  the depth alpha is stepped; P is the result (the seed paper's scheme).
//   ForceControl  the force P is stepped; alpha is solved for with u in one bordered Newton
//                 system (force_controlled_equations.hpp).
#include <memory>
#include <string>

#include "indentsim/input/load_case.hpp"
#include "indentsim/simulation/load_stepping.hpp"
#include "indentsim/simulation/simulation_state.hpp"
#include "indentsim/solvers/solver.hpp"

namespace indentsim {

/// The exponent m of P ~ alpha^m on an elastic half-space (Sneddon 1965): 1 under a flat punch,
/// 3/2 under a sphere (and a measured profile, taken as round), 2 under a cone.  Force control's
/// first guess of a depth, and the depth pilot's, go through it.
double force_exponent(PunchShapeKind shape);
/// The depth a target of the load path is expected to reach before it is solved: a depth is
/// itself; a force P, the case's depth estimate scaled as (P / P_max)^(1/m).
double expected_depth(const LoadCase& load_case, double target);

class LoadControl {
public:
  virtual ~LoadControl() = default;
  /// The control `load_case` asks for (load.control).
  static std::unique_ptr<LoadControl> of(const LoadCase& load_case);

  virtual LoadControlKind kind() const = 0;
  /// A value of the controlled quantity for a message: "alpha = 1.2e-06 m", "P = 0.003 N".
  virtual std::string describe(double value) const = 0;
  /// The controlled quantity at the committed state, and at the one before (the predictor's).
  virtual double committed(const SimulationState& state) const = 0;
  virtual double previous(const SimulationState& state) const = 0;
  /// Whether a trial loads the specimen beyond every state before it (Ilyushin's loading branch):
  /// a depth beyond the deepest, a force beyond the largest.
  virtual bool loads(const SimulationState& state, double trial) const = 0;
  /// The coordinate the predictor's secant is linear in: the depth itself; for a force
  /// P^(1/m) (force_exponent), in which an elastic contact's depth and displacements are linear.
  virtual double predictor_coordinate(double value) const = 0;
  /// The control's own part of a committed trial: the force and the largest force so far.
  virtual void commit(SimulationState& state, double trial) const = 0;
  /// Whether a row lies at its planned target: bit for bit for a depth (it is the target); for
  /// a force to the Newton tolerance relative to `largest` (the path's largest force).
  virtual bool at_target(const IncrementRecord& row, double target, double largest, double tolerance) const = 0;
  /// The Newton system's equations for the depth-controlled `equations` of contact `contact`, or
  /// nullptr when they are those equations themselves (the depth is then the solver's parameter
  /// and not an unknown).
  virtual std::unique_ptr<IncrementEquations> system_equations(ContactEquations& equations,
                                                               const ContactDiscretization& contact,
                                                               double force_scale) const = 0;
};

}  // namespace indentsim
