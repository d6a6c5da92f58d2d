#pragma once
// The run's configuration: every choice a run makes before its first increment, each "auto" of
// the load case made concrete, resolved once (resolve_choices).  `check` prints it, summary.json
// records it ("configuration"), and the Simulation is built on it.
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "indentsim/geometry/element.hpp"
#include "indentsim/geometry/mesh.hpp"
#include "indentsim/input/load_case.hpp"
#include "indentsim/solvers/condensation.hpp"
#include "indentsim/solvers/solver.hpp"

namespace indentsim {

/// The mesh a run uses: planned from the Hertz estimate of the contact, or for a plastic case
/// from a coarse pilot run of the same case (its contact width and plastic zone); `check` prints
/// exactly this plan.  `planned_contact_half_width` (a resumed run) skips the pilot.
struct RunPlan {
  MeshPlan mesh;
  PlasticZoneGrowth plastic_zone;  ///< from the pilot, sizes the condensed near field as it grows
};
/// Throws std::invalid_argument for a force-controlled case without its depth estimate
/// (with_depth_estimate gives it).
RunPlan plan_run(const LoadCase& load_case, std::optional<double> planned_contact_half_width = std::nullopt);

/// Force control (docs/MODEL.md §13.1): the case with load.depth_estimate, the depth its largest
/// force reaches, measured by coarse depth-controlled pilot runs when the case does not give it;
/// any other case as it is.  The depth stays within half the block, half a sphere's radius and
/// half a profile's height, where the depth checks of the case hold (a force beyond what the
/// specimen carries there meets its limit in the run, which names it).
LoadCase with_depth_estimate(LoadCase load_case);

struct RunConfiguration {
  RunPlan plan;                        ///< the mesh (and the pilot's plastic zone)
  ElementKind element = ElementKind::q1;
  JacobianChoice jacobian = JacobianChoice::krylov;  ///< krylov, reuse or fresh: never automatic
  NearField near_field;                ///< what the first increment solves for (it may grow)
  LinearSolverKind linear_solver = LinearSolverKind::klu;  ///< for every Newton system of the run
  std::int64_t unknowns = 0;           ///< of the whole mesh
  std::int64_t system_unknowns = 0;    ///< of the first Newton system (the near field, if condensed)
  std::vector<int> companion_contact_nodes;  ///< the error estimate's companion runs (none: empty)
  StrainChoice strain = StrainChoice::small;  ///< small or finite: never automatic
  std::string strain_reason;                  ///< why, for geometry.strain = "auto" (else empty)
};

/// Every "auto" of `load_case` made concrete on `plan` (no pilot run: plan_run made the plan).
/// `near_field`, when given, is the near field to start from (a resumed run's): the run then does
/// not grow it ahead of the pilot's plastic zone (the plan's zone is dropped).
RunConfiguration resolve_choices(const LoadCase& load_case, const RunPlan& plan,
                                 const std::optional<NearField>& near_field = std::nullopt);
/// The case as it runs under `configuration`: the element and the Jacobian's "auto" replaced by
/// their choice and the pilot's measurements (contact half-width, plastic zone) written as keys.  case.toml and checkpoints
/// hold this, so that `run case.toml` plans the same mesh and makes the same choices without a
/// pilot (bit for bit), and a resumed branch's case.toml reproduces the branch.
LoadCase case_as_run(const LoadCase& load_case, const RunConfiguration& configuration);
/// The configuration as (name, value) lines, in the words of `check` and of summary.json.
std::vector<std::pair<std::string, std::string>> describe(const RunConfiguration& configuration);

/// The element a load case gets: mesh.element, or for "auto" B-bar where Q1 would lock (nu >=
/// 0.45, nearly perfect plasticity, a plastic material under a cone), the paper's Q1 elsewhere.
ElementKind choose_element(const LoadCase& load_case);

/// The kinematics a load case gets: geometry.strain, or for "auto" finite strain where its
/// geometric share of P is estimated above the accuracy the run aims at, with the reason
/// (docs/MODEL.md §12.5).  It depends on the case alone (the punch's own contact estimate at the
/// deepest point, not the mesh plan), so a resumed run or a companion chooses the same.
std::pair<StrainChoice, std::string> choose_strain(const LoadCase& load_case);
/// The estimated relative change of P from small to finite strain that choose_strain weighs: a
/// measured multiple of the mean strain alpha_max / a under the punch, an upper estimate.
double finite_strain_share(const LoadCase& load_case);
/// Makes "auto" concrete in the case itself, with its reason, for what changes the case before
/// it runs (planning for mesh.target_error drops the target; a fit moves the parameters).
void pin_kinematics(LoadCase& load_case);

/// The near field to solve for at depth `depth` while the pilot's plastic zone grows (`zone`):
/// condensed, holding the zone at twice the depth (within the load path) with its margins.
NearField near_field_for_depth(const LoadCase& load_case, const Mesh& mesh, const MeshPlan& plan,
                               const PlasticZoneGrowth& zone, double depth);
/// The near field the pilot's zone at `depth` needs (choose_near_field's margins).
NearField near_field_needed(const LoadCase& load_case, const Mesh& mesh, const MeshPlan& plan,
                            const PlasticZoneGrowth& zone, double depth);

/// Warnings (not errors) about values that run but are probably a slip: E outside 1 kPa - 2 TPa,
/// alpha / R > 0.05, an estimated contact half-width above 0.1 of lx or ly.
std::vector<std::string> plausibility_warnings(const LoadCase& load_case, const MeshPlan& plan);

}  // namespace indentsim
