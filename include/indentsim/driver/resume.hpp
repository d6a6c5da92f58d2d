#pragma once
// Checkpoints of a running simulation, and a simulation continuing one: the two places where a
// run state meets the Simulation that owns it.
#include <memory>
#include <string>
#include <vector>

#include "indentsim/input/load_case.hpp"
#include "indentsim/output/checkpoint.hpp"
#include "indentsim/simulation/simulation.hpp"

namespace indentsim {

/// Builds a checkpoint of a running simulation, the rows it has reported and the true contacts
/// recorded at the peaks passed (RunOutput::true_contacts).
Checkpoint make_checkpoint(const Simulation& sim, const std::vector<IncrementRecord>& curve,
                           const std::vector<double>& free_surface_depths,
                           const std::vector<std::pair<int, TrueContact>>& true_contacts = {});

/// A simulation continuing a checkpoint, with `overrides` (--set) applied to its load case:
/// validates everything (throws InputError naming the file and the problem) before returning.
struct ResumedRun {
  LoadCase load_case;
  std::unique_ptr<Simulation> simulation;
};
ResumedRun resume_from(const Checkpoint& checkpoint, const std::string& source, const std::vector<std::string>& overrides);

}  // namespace indentsim
