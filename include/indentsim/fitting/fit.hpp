#pragma once
// Material parameters from measured data (`indentsim fit`): weighted nonlinear least squares over
// one or more data sets (force-depth curves, residual imprints), each with its own load case,
// solved by Ceres Solver's Levenberg-Marquardt with bounds from several starts, and an honest
// report of what the data determine.
//
// Residuals: r_i = w (model_i - data_i) / (s sqrt(N)) for each data set of N points, s its largest
// |value| and w its weight, so every data set counts by its weight, not by its number of points.
// Statistics at the optimum (the Jacobian J of r in theta):
//  - covariance s2 (J^T J)^-1 with s2 = sum r^2 / (m - p), the residuals' own scatter: standard
//    errors of the noise, assuming independent errors of equal size within a data set;
//  - the model's own discretization error, estimated at the optimum (each data set with twice its
//    contact nodes, Richardson) and carried along the sensitivities into a shift of each
//    parameter; a 0.3% systematic difference moves a parameter along a flat valley by many
//    standard errors of the noise, so the interval must hold it (ParameterDetermination);
//  - per parameter a 95% interval of both, and a verdict from it: determined to +-x%, or not
//    determined by this data, with the parameter it trades against;
//  - the singular values of J diag(theta): how much the residuals move per relative change of
//    each combination of parameters (reported, and the weakest combination in words where a
//    parameter is not determined; measured: a sharp cone's loading curve, sigma_y with n: a
//    condition number about 270; a sphere's: 30; a sphere and a cone together: 11-13).
// The fit's quality is judged too (FitResult::quality): a fit whose rms misfit exceeds
// poor_fit_rms_limit of a data set's largest value, or that ends with a parameter at one of its
// bounds, is a poor fit -- its values are no answer, whatever the intervals say -- and is
// never called identifiable.

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "indentsim/base/interruption.hpp"
#include "indentsim/fitting/forward_model.hpp"
#include "indentsim/materials/material_parameter.hpp"

namespace indentsim {

/// A parameter is called determined when its 95% interval (noise and the model's own error) lies
/// within the bounds and within this fraction of its value either side: the accuracy at which
/// material parameters are compared between laboratories and with handbooks; a wider interval
/// is reported as it is, with the parameter it trades against.
inline constexpr double determination_limit = 0.05;
/// A fit whose rms misfit exceeds this fraction of a data set's largest value (the peak force, the
/// deepest imprint depth) is a poor fit.  The model's own discretization error is 0.1-1% of P at
/// the default mesh and instruments' noise a few percent: a tenth of the peak left unexplained
/// means the model, its case or the data are wrong (a unit, a sign, the scene), not the noise.
inline constexpr double poor_fit_rms_limit = 0.10;
/// A parameter within this fraction of its bound (of the bound's magnitude, or of the box's
/// width when smaller) ends "at" it: the optimum lies beyond the bounds, and the value is no answer.
inline constexpr double at_bound_tolerance = 1e-3;
/// A data set's largest force beyond this factor of the model's at the start values (either way)
/// is a wrong unit most likely (mN read as N gives 1000): the fit warns before it starts.
inline constexpr double unit_slip_factor = 100.0;
/// The coarse phase (FitSettings::coarse_first) runs where every data set's mesh has at least
/// this many contact nodes (half of them is then still a resolved contact).
inline constexpr int coarse_first_min_contact_nodes = 12;

struct FreeParameter {
  RegionParameter parameter;  ///< which parameter, of which region (a layer's or [material]'s)
  double lower = 0.0, upper = 0.0;
  FreeParameter() = default;
  FreeParameter(RegionParameter p, double low, double high) : parameter(p), lower(low), upper(high) {}
  /// A parameter of [material] (the whole specimen's, or a coated one's substrate).
  FreeParameter(MaterialParameter p, double low, double high) : parameter{p, 0}, lower(low), upper(high) {}
};

/// One iteration of the optimiser, for the progress line.
struct FitProgress {
  int start = 0, starts = 1, iteration = 0;
  double cost = 0.0;
  std::vector<double> theta;
  int forward_runs = 0;  ///< on the data sets' own meshes
  int coarse_runs = 0;   ///< on the coarse phase's meshes
  std::string phase;     ///< StartOutcome::phase
  double elapsed_seconds = 0.0;
  /// A forecast of the fit's remaining wall time (fit()'s FitForecast): the runs each phase still
  /// needs, at the time per run measured on its meshes; NaN before a run has been timed.
  double remaining_seconds = 0.0;
};

struct StartOutcome {
  int index = 0;  ///< the start's number within its phase (1, 2, ...; 0 a polish; K the K-th refinement)
  std::vector<double> start, result;
  double cost = 0.0;
  int iterations = 0;
  bool converged = false;
  std::string message;  ///< Ceres' own words
  /// "coarse" (a start on the coarse phase's meshes), "fine" (a start on the data sets' own
  /// meshes), "polish" (from the coarse or first result, on meshes planned there), "refined"
  /// (the polish repeated on meshes with twice the contact nodes, for the model's own error)
  std::string phase = "fine";
};

/// Where a fit stood after its last accepted iteration: the solves it had finished, those in
/// progress (starts run side by side: each one's `result` the point reached, `iterations` those
/// done), and its counters (`iterations`: of the finished solves).  A fit started with it
/// (FitSettings::resume_from) takes the finished solves as they were and continues those in
/// progress from their points; the decisions that follow (the best start, the meshes planned at
/// it) are the same, so it ends where the uninterrupted fit would, to the optimiser's tolerance
/// (its trust region starts afresh).
struct FitCheckpoint {
  std::vector<StartOutcome> finished;
  std::vector<StartOutcome> in_progress;
  int forward_runs = 0, coarse_runs = 0, iterations = 0, failed_runs = 0, refused_evaluations = 0;
};

struct FitSettings {
  /// The load case's values, then Halton points spread over the bounds: several by default, so
  /// that a flat valley or a second minimum is seen, not returned as the answer.
  int starts = 4;
  int max_iterations = 50;     ///< Levenberg-Marquardt iterations per start
  bool finite_differences = false;  ///< force finite differences (the benchmark compares both)
  /// Levenberg-Marquardt travels on meshes with half the contact nodes, then the fine meshes are
  /// planned at its optimum and the result polished there (see fit()).
  bool coarse_first = true;
  bool replan_mesh = true;     ///< without the coarse phase: re-plan the mesh at the result and polish
  /// Where the model's own error moves a parameter by more than the noise's standard error, the
  /// forward meshes are refined (twice the contact nodes each time) and the optimum polished, at
  /// most this many times.
  int mesh_refinements = 1;
  /// The starts of a phase run side by side on this many threads (0: the cores this process may
  /// use), each run single-threaded; the outcomes do not depend on it.
  int threads = 0;
  /// Called after every iteration of any solve, one call at a time (from the thread of the solve).
  std::function<void(const FitProgress&)> on_iteration;
  /// Called with each warning as it arises (FitResult::warnings keeps them too).
  std::function<void(const std::string&)> on_warning;
  /// Called after every accepted iteration and every finished solve (fit_files.hpp writes it).
  std::function<void(const FitCheckpoint&)> on_checkpoint;
  /// After the fit: the table of candidate additions to the data (one forward run with
  /// sensitivities each, p + 1 with finite differences).
  bool design_experiments = true;
  /// After the fit: each parameter's profile-likelihood interval (a few optimisations of the others
  /// with it held at trial values, on the meshes before any refinement; ParameterDetermination).
  bool profile = true;
  /// A checkpoint of the same problem to continue from (nullptr: from the start).
  const FitCheckpoint* resume_from = nullptr;
};

struct FitProblem {
  std::vector<FitData> data;
  std::vector<FreeParameter> free;
  FitSettings settings;
};

/// A data set at the fitted parameters.
struct DataSetFit {
  std::vector<double> model;     ///< the model at the data points
  double rms_residual = 0.0;     ///< in the data's unit (N, N/m or m)
  double rms_relative = 0.0;     ///< over the data set's largest |value|
  std::string gradients;         ///< "forward sensitivities" or "finite differences (<why>)"
  LoadCase fitted_case;          ///< the data set's load case with the fitted values
  double contact_half_width_planned = 0.0;  ///< the fixed mesh's a* [m]
};


/// What the fit can say of one parameter (FitResult::determination).
struct ParameterDetermination {
  /// The shift of the optimum that the forward model's own discretization error causes: the
  /// error estimated at the optimum (Richardson, from the data sets with twice their contact nodes
  /// on the same meshes' plan -- half where twice exceeds mesh.max_unknowns -- error_estimate.hpp's order) carried along the sensitivities,
  /// -(J^T J)^+ J^T e.  The fit's value minus it is the fit a converged model would give, to the
  /// estimate's accuracy.  0 where no estimate could be made (model_error_estimated).
  double model_shift = 0.0;
  /// The increments' share of model_shift, for a path-dependent model (J2, friction): estimated
  /// from the same mesh with four times the increments (Richardson, order 1); 0 for the others.
  double model_shift_increments = 0.0;
  /// The standard error of noise and model together: sqrt(std_error^2 + model_shift^2).
  double total_std_error = 0.0;
  /// The 95% interval of the noise from the profile likelihood (FitSettings::profile): the values
  /// of this parameter at which the cost, minimized over the others, has risen by t^2 s2 / 2 from
  /// the optimum's (the linearized interval where the model is linear in the parameters; on a
  /// curved valley it is not symmetric).  `profiled` false where it was not computed.
  bool profiled = false;
  double profile_lower = 0.0, profile_upper = 0.0;
  /// The profile's cost stayed within the noise up to a bound on one side: the data do not close
  /// the interval there.
  bool profile_open = false;
  /// The 95% interval: value -+ t(0.975, m - p) total_std_error (m points, p parameters); where the
  /// profile was computed, its distances from the value on each side combined with t model_shift
  /// in quadrature (and widened to hold other starts' ends of similar cost).
  double lower = 0.0, upper = 0.0;
  double relative_half_width = 0.0;  ///< (upper - lower) / 2 / |value|
  /// Within the bounds and within +-determination_limit of the value.
  bool determined = false;
  std::string verdict;  ///< "determined to +-1.8% (95%)" or "not determined by this data: ..."
};

/// One measurement that could be added to the fit's data (FitResult::experiment_design): what its
/// sensitivities at the fitted parameters would do to each parameter's interval, from the Fisher
/// information of the data and the addition together (noise alone, the same relative noise as
/// the data's, 20 points).
struct CandidateExperiment {
  std::string name;         ///< "unloading branch", "deeper indent", "sphere", "cone", "sharper cone", "imprint profile"
  std::string description;  ///< what exactly: "unloading from 1 um to 0.9 um, 20 points"
  std::vector<double> relative_half_width;  ///< the predicted noise-only 95% half-width over |value|, per parameter
  std::vector<double> shrink;               ///< today's noise-only half-width over the predicted one
  std::string failure;                      ///< why it could not be evaluated ("" when it was)
};

struct FitResult {
  std::vector<double> values;      ///< in the order of problem.free
  std::vector<double> std_errors;  ///< of the noise alone; infinite for a combination the data do not determine
  std::vector<ParameterDetermination> determination;  ///< in the order of problem.free
  /// The noise-only 95% half-width over |value| today, per parameter (the design's reference).
  std::vector<double> noise_relative_half_width;
  /// The experiment that would determine what this data does not (FitSettings::design_experiments).
  std::vector<CandidateExperiment> experiment_design;
  /// The model's error was estimated (every data set had a companion with twice its contact nodes).
  bool model_error_estimated = false;
  /// The largest ratio, over the parameters, of the model's shift to the noise's standard error:
  /// beyond 1 the forward mesh, not the data, limits what the fit can say.
  double model_to_noise = 0.0;
  /// The same for the increments' share of the shift (path-dependent models; else 0).
  double increments_to_noise = 0.0;
  /// The final forward model's increments over the load cases' own (refined for the model's error).
  int increments_factor = 1;
  /// Where the model's shift exceeded the noise: the optimum of the model with its estimated error
  /// taken off (the converged model's, to the estimate's accuracy); each model_shift is the
  /// distance from it.  Empty otherwise (the shift is then the linearized one).
  std::vector<double> corrected_values;
  Eigen::MatrixXd covariance, correlation;
  std::vector<double> singular_values;  ///< of J diag(theta), largest first
  double condition_number = 0.0;
  /// Every parameter is determined (ParameterDetermination) and the fit is good: a poor fit is
  /// never called identifiable (its statistics describe a wrong optimum).
  bool identifiable = false;
  std::vector<double> weakest_direction;  ///< d ln theta of the weakest combination (unit norm)
  std::string poorly_determined;          ///< the weakest combination in words ("" if identifiable)
  double cost = 0.0;                      ///< 1/2 sum r^2
  double rms_relative = 0.0;              ///< sqrt(sum r^2 / sum w^2): the weighted relative misfit
  std::vector<DataSetFit> data;
  int forward_runs = 0;  ///< runs on the data sets' own meshes
  int coarse_runs = 0;   ///< runs on the coarse phase's meshes (contact_nodes / 2)
  int iterations = 0;    ///< Levenberg-Marquardt iterations over every start and phase
  double wall_seconds = 0.0;
  std::vector<StartOutcome> starts;  ///< in the order run: coarse starts, then fine starts or the polish
  std::size_t selected_start = 0;    ///< the outcome the values come from
  bool mesh_replanned = false;  ///< the meshes were planned at a (coarse) result, not at the start
  int mesh_refinements = 0;     ///< times the forward meshes were refined for the model's error
  /// The verdict: "good", or "poor fit: " and the problems joined by "; ".
  std::string quality = "good";
  /// What makes it poor, one phrase each: "rms 64% of the peak force", "material.n at its upper
  /// bound 0.9" (with "data set K (file): " before a misfit when there are several data sets).
  std::vector<std::string> quality_problems;
  bool good() const { return quality_problems.empty(); }
  std::vector<std::string> warnings;  ///< before the fit (a unit that looks wrong), in order
  /// Forward runs that failed even with steps a sixteenth as long (each counted once, its retries
  /// not), and evaluations at parameters the model refuses (Ilyushin's admissibility): the
  /// optimiser shortened its step each time.
  int failed_runs = 0;
  int refused_evaluations = 0;
};

/// A fit stopped by SIGINT or SIGTERM (interruption.hpp): what it had found until then.
class FitInterrupted : public Interrupted {
public:
  FitInterrupted(int signal, std::vector<double> best, double cost, std::string phase, int forward_runs, int coarse_runs)
      : Interrupted(signal),
        best_(std::move(best)),
        cost_(cost),
        phase_(std::move(phase)),
        forward_runs_(forward_runs),
        coarse_runs_(coarse_runs) {}
  /// The parameters of the lowest cost reached so far (in the order of problem.free), empty when no
  /// start had reached a successful forward run.
  const std::vector<double>& best() const { return best_; }
  double cost() const { return cost_; }
  /// Where that cost was reached: "coarse" (on the coarse phase's meshes), "fine", "polish" or
  /// "refined" (StartOutcome::phase; costs of different meshes are compared as they are).
  const std::string& phase() const { return phase_; }
  int forward_runs() const { return forward_runs_; }
  int coarse_runs() const { return coarse_runs_; }

private:
  std::vector<double> best_;
  double cost_;
  std::string phase_;
  int forward_runs_, coarse_runs_;
};

/// The data a measurement of `truth` would give at `abscissa` (depths of a curve, or radii of an
/// imprint), with Gaussian noise of standard deviation `noise` times the largest |value| (an
/// instrument's noise floor; seeded), computed on the mesh and element a fit of `free` would use:
/// for round trips, identifiability studies before an experiment, and the benchmark.
FitData synthetic_data(const LoadCase& truth, FitDataKind kind, const std::vector<double>& abscissa,
                       const std::vector<FreeParameter>& free, double noise, unsigned seed);

/// Checks the problem (free keys; bounds inside each key's declared interval and plausible range;
/// the start inside the bounds; enough points; forces that push, not pull) and fits.  Throws
/// InputError for a problem that cannot be posed, SolverError when no start reaches a single
/// successful evaluation, FitInterrupted when SIGINT or SIGTERM stops it (interruption.hpp: the
/// run in progress is abandoned within a Newton iteration).  Ceres' and glog's own logging is
/// silenced (a failed run is counted in FitResult::failed_runs instead).
FitResult fit(const FitProblem& problem);

}  // namespace indentsim
