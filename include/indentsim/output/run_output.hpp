#pragma once
// Output files of a run.
#include <cstdio>
#include <filesystem>
#include <string>

#include <memory>
#include <optional>

#include <nlohmann/json.hpp>

#include "indentsim/simulation/error_estimate.hpp"
#include "indentsim/output/fields.hpp"
#include "indentsim/analysis/indentation_analysis.hpp"
#include "indentsim/base/file_system.hpp"
#include "indentsim/simulation/increment_snapshot.hpp"
#include "indentsim/simulation/load_stepping.hpp"
#include "indentsim/simulation/run_configuration.hpp"
#include "indentsim/base/phase_times.hpp"

namespace indentsim {

/// DIR/curve.csv: the P-alpha curve, one row per converged increment, written and flushed as
/// the run goes so that a stopped run keeps every converged increment.
/// With an error estimate (mesh.error_estimate, error_estimate.hpp) three more columns before
/// wall_s: P_error_estimate, a_error_estimate and P_extrapolated (empty where a companion run
/// has no such increment).  An estimate still being computed (`estimate_pending`: the companions
/// run beside the first increments) leaves the rows' estimate cells empty until
/// set_error_estimate, which rewrites the file with them (atomically) and appends from then on.
class CurveWriter {
public:
  /// `times`: the time of each planned increment (plan_times; empty when the path has no time), a
  /// `time` column after `step` when given.
  CurveWriter(const std::filesystem::path& file, const DiscretizationErrorEstimate* error_estimate = nullptr,
              bool estimate_pending = false, std::vector<double> times = {});

  void write(const IncrementRecord& record);
  /// The estimate has come (null: it will not, its cells stay empty): rewrites the file with
  /// `rows_written`, the rows written so far (RunOutput keeps them), its cells filled in.
  void set_error_estimate(const DiscretizationErrorEstimate* error_estimate,
                          const std::vector<IncrementRecord>& rows_written);
  static std::string header(bool with_error_estimate = false, bool with_time = false);

private:
  /// A row, with the estimate's cells when the file has them (empty where it has nothing for the row).
  std::string format(const IncrementRecord& record) const;

  AppendedFile file_;
  const DiscretizationErrorEstimate* error_estimate_;
  bool estimate_columns_ = false;
  std::vector<double> times_;
};

/// How a run ended, as summary.json says in "status": "running" from its first write until it
/// ends (so a folder whose run was killed says "running" while no process holds its lock),
/// then "finished", "not_converged" (exit 3), "stopped" (a signal; resumable) or "failed" (an
/// I/O or other error, with the message).
enum class RunStatus { running, finished, not_converged, stopped, failed };
std::string to_string(RunStatus status);


/// What indentation users read off a load history (DIR/summary.json): the peak, and for every
/// unloading branch the unloading stiffness S = dP/dalpha at its start, the residual depth
/// where the punch leaves the surface, and its Oliver-Pharr analysis next to the true contact
/// (indentation_analysis.hpp).
class LoadHistorySummary {
public:
  /// `load_case` gives the indenter, the scene and the analysis settings (none: no analysis).
  explicit LoadHistorySummary(const LoadCase* load_case = nullptr);

  struct Unloading {
    int step = 0;                       ///< the increment where unloading starts (the reversal)
    double depth = 0.0, force = 0.0;    ///< state at the reversal
    double stiffness = 0.0;             ///< S: secant of the first unloading increment [N/m per m] (NaN: the depth did not fall)
    double loading_stiffness = 0.0;     ///< secant of the last loading increment before it
    bool separated = false;             ///< the punch left the surface on this branch
    double residual_depth = 0.0;        ///< depth where it left: max_k(-v_k - g_k) once P = 0 [m]
    int separation_step = -1;
  };

  /// Feed every converged increment in order, with Simulation::free_surface_depth() at it.
  void add(const IncrementRecord& record, double free_surface_depth);
  /// The live state's exact unloading stiffness and contact radius at a peak `step`.
  void set_true_contact(int step, const TrueContact& truth);
  /// summary.json's text.  `run_fields`: members about the run itself (after the status);
  /// `result_fields`: members about the results, after the unloading branches.
  std::string json(const nlohmann::ordered_json& run_fields, RunStatus status, const std::string& message,
                   const PhaseTimes& times = PhaseTimes{},
                   const nlohmann::ordered_json& result_fields = nlohmann::ordered_json::object()) const;
  /// Every unloading branch of the rows fed so far (unloading_branches, load_stepping.hpp, in the
  /// controlled quantity) whose peak carries a force.
  std::vector<Unloading> unloadings() const;
  double peak_depth() const { return peak_depth_; }
  double peak_force() const { return peak_force_; }
  /// The true contacts recorded so far, by peak step (a checkpoint keeps them for a resume).
  const std::vector<std::pair<int, TrueContact>>& true_contacts() const { return truths_; }

private:
  std::shared_ptr<const PunchShape> punch_;  // the indenter's area function (null: no analysis)
  AnalysisContext context_;
  std::vector<double> depths_, forces_;
  /// The controlled quantity's planned targets (empty: the depths), and each row's: the branches
  /// are found in it (run_branch_coordinate).
  std::vector<double> targets_, controlled_;
  std::vector<int> steps_, contact_nodes_;
  std::vector<double> free_surface_depths_;
  std::vector<std::pair<int, TrueContact>> truths_;
  double peak_depth_ = 0.0, peak_force_ = 0.0;
};

/// Everything a run writes into its output folder, as the run goes:
///   case.toml      the load case as run (every key explicit);
///   curve.csv      one row per converged increment (CurveWriter);
///   fields.pvd, fields/step_*.vtu   every output.fields_every increments and the final state;
///   layers.csv, profiles.csv        the paper's layer view of the deepest state (the peak of the
///                  load path) and of the final state, one block each (columns step, alpha);
///   summary.json   the run's status; peak, unloading stiffness and residual depth of each
///                  unloading branch; the error estimate at the final and the peak increment,
///                  and how a target error chose the mesh.
/// The folder is expected to be held (RunFolder) and cleared of an earlier run's files.
class RunOutput {
public:
  /// `error_estimate` (may be null; must outlive this object) adds its columns and figures;
  /// `replay_curve`/`replay_depths`: the rows of a run being resumed, written again first.
  RunOutput(const std::filesystem::path& dir, const LoadCase& load_case,
            const DiscretizationErrorEstimate* error_estimate = nullptr,
            const std::vector<IncrementRecord>& replay_curve = {}, const std::vector<double>& replay_depths = {});
  /// A new run whose estimate is still being computed: curve.csv has its columns, left empty in
  /// the rows until set_error_estimate fills them in, which must come before a checkpoint (a
  /// resume keeps the rows up to it as they are on disk) and before finish().
  RunOutput(const std::filesystem::path& dir, const LoadCase& load_case, bool error_estimate_pending);
  /// The estimate of a run built with error_estimate_pending (null: none after all, e.g. its
  /// companions were stopped by a signal).  Must outlive this object.
  void set_error_estimate(const DiscretizationErrorEstimate* error_estimate);
  /// The run's configuration, every "auto" resolved (summary.json "configuration").
  void set_configuration(const RunConfiguration& configuration);
  /// How mesh.target_error chose this run's mesh (summary.json "target_error").
  void set_target_choice(const TargetErrorChoice& choice) { target_choice_ = choice; }
  /// A converged increment (Simulation::snapshot): its row, and its fields and tables when due.
  void increment(const IncrementSnapshot& state);
  /// A resumed run's live state, restored at the last replayed increment: a peak's exact
  /// unloading stiffness is taken from it when the run resumes exactly there.
  void resumed(const IncrementSnapshot& state) {
    if (!records_.empty()) record_true_contact(state, records_.back().step);
  }
  /// The true contacts a resumed run recorded at its peaks before the checkpoint (the live states
  /// that gave them are gone): its summary.json then holds what the uninterrupted run's does.
  void restore_true_contacts(const std::vector<std::pair<int, TrueContact>>& truths) {
    for (const auto& [step, truth] : truths) summary_.set_true_contact(step, truth);
  }
  const std::vector<std::pair<int, TrueContact>>& true_contacts() const { return summary_.true_contacts(); }
  /// Writes the final state's fields, the layer view and summary.json with `status` (not
  /// "failed": use fail()).
  /// `final_state`: the state the run ends in (the last row's).
  void finish(const IncrementSnapshot& final_state, RunStatus status, const std::string& message = "",
              const PhaseTimes& times = PhaseTimes{});
  /// Marks the folder as a failed run (summary.json "failed" with `message`), as far as the file
  /// system still allows; never throws.
  void fail(const std::string& message) noexcept;
  std::filesystem::path curve_path() const { return dir_ / "curve.csv"; }
  const std::vector<IncrementRecord>& records() const { return records_; }
  const std::vector<double>& free_surface_depths() const { return depths_; }

private:
  RunOutput(const std::filesystem::path& dir, const LoadCase& load_case,
            const DiscretizationErrorEstimate* error_estimate, const std::vector<IncrementRecord>& replay_curve,
            const std::vector<double>& replay_depths, bool error_estimate_pending);
  void write_fields(const IncrementSnapshot& state, int step);
  /// At a peak of the load path: the exact unloading stiffness and the true contact radius.
  void record_true_contact(const IncrementSnapshot& state, int step);
  /// The layer view of a state: {layers.csv rows, profiles.csv rows}.
  std::pair<std::string, std::string> layer_tables(const IncrementSnapshot& state, int step, bool header) const;

  /// summary.json's "error_estimate" and "target_error" members.
  nlohmann::ordered_json error_fields(const PhaseTimes& times) const;

  std::filesystem::path dir_;
  nlohmann::ordered_json run_fields_;
  const DiscretizationErrorEstimate* error_estimate_ = nullptr;
  std::optional<TargetErrorChoice> target_choice_;
  LoadHistorySummary summary_;
  std::vector<IncrementRecord> records_;
  std::vector<double> depths_;
  int fields_every_ = 0;
  std::vector<double> profile_depths_;
  CurveWriter curve_;
  FieldSeries fields_;
  int last_step_ = -1, last_fields_step_ = -1;
  int deepest_step_ = 0;  ///< the end of the first stay at the load path's largest target (its deepest state)
  int increments_ = 0;          ///< the path's, as run
  int peak_step_ = -1;          ///< the increment that reached it (its fields and tables are kept)
  std::vector<int> peak_steps_;  ///< the planned increments where an unloading branch starts
  std::pair<std::string, std::string> peak_tables_;
};

}  // namespace indentsim
