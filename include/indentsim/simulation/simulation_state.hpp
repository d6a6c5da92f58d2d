#pragma once
// The run state: everything that changes while a run goes on.  With the load case (and the mesh
// plan) it is all a checkpoint needs to continue the run bit for bit.  Simulation owns one of
// these; the checkpoint writes, reads and checks it through visit_fields, its one list of fields.
//
// Adding a field: declare it below, add one line to visit_fields (its place there is its place in
// the checkpoint file), and bump checkpoint_format_version with a note (output/checkpoint.hpp).
#include <cstdint>
#include <string>
#include <vector>

#include "indentsim/solvers/condensation.hpp"

namespace indentsim {

struct SimulationState {
  double alpha = 0.0;           ///< the converged depth [m]
  double alpha_previous = 0.0;  ///< the one before (the predictor's)
  double deepest = 0.0;         ///< the largest converged depth so far (the load path's peak)
  bool has_previous = false;    ///< alpha_previous and u_previous hold a converged state
  /// Force control (load_control.hpp): the target force the state converged to, the one before
  /// and the largest so far [N or N/m]; 0 under depth control.
  double force = 0.0, force_previous = 0.0, largest_force = 0.0;
  /// The force scale Newton measured the residual on when u (u_previous) converged: a resumed
  /// run checks the state against it (a branch to a shallower path scales its own increments
  /// smaller).
  double residual_scale = 0.0, residual_scale_previous = 0.0;
  int rows = 0;                 ///< increments reported so far
  std::uint64_t next_target = 0;  ///< index of the next planned depth
  bool warned_fine_zone = false;
  std::vector<std::string> warnings;  ///< raised so far, each once
  std::vector<double> u, u_previous;  ///< displacement and the previous one (the predictor's)
  /// The bulk model's carried material state.  The bulk model holds the live one: this field is
  /// filled by Simulation::state() and read by restore().
  std::vector<double> history;
  /// The active contact set at u: implied by u, kept as a check on restore (filled by state()).
  std::vector<char> in_contact;
  NearField near_field;                   ///< what the Newton iterations solve for (it may have grown)
  PlasticZoneGrowth plastic_zone_growth;  ///< the pilot's, which grows near_field ahead (empty: none)
};

/// Calls visit(name, field, what) for every field of the state, in the checkpoint's order; `what`
/// names the part of the file it belongs to, for messages about a damaged file.  `State` is
/// SimulationState or const SimulationState.
template <class State, class Visitor>
void visit_fields(State& s, Visitor&& visit) {
  visit("alpha", s.alpha, "the state");
  visit("alpha_previous", s.alpha_previous, "the state");
  visit("deepest", s.deepest, "the state");
  visit("has_previous", s.has_previous, "the state");
  visit("force", s.force, "the state");
  visit("force_previous", s.force_previous, "the state");
  visit("largest_force", s.largest_force, "the state");
  visit("residual_scale", s.residual_scale, "the state");
  visit("residual_scale_previous", s.residual_scale_previous, "the state");
  visit("rows", s.rows, "the state");
  visit("next_target", s.next_target, "the state");
  visit("warned_fine_zone", s.warned_fine_zone, "the state");
  visit("warnings", s.warnings, "the warnings");
  visit("u", s.u, "the displacement");
  visit("u_previous", s.u_previous, "the previous displacement");
  visit("history", s.history, "the material history");
  visit("in_contact", s.in_contact, "the contact set");
  visit("near_field", s.near_field, "the near field");
  visit("plastic_zone_growth", s.plastic_zone_growth, "the plastic zone growth");
}

}  // namespace indentsim
