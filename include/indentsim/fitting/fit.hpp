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
//    errors assume independent errors of equal size within a data set (noise, not a model error);
//  - the singular values of J diag(theta): how much the residuals move per relative change of
//    each combination of parameters.  The strongest is of order one (P is nearly proportional to
//    E or sigma_y); a condition number beyond identifiability_condition_limit = 100 means a 10%
//    change of the weakest combination moves the curves by less than about 0.1% -- below the
//    model's own discretization error at the default mesh -- so no data the model is compared
//    with can pin it (measured: a sharp cone's loading curve, sigma_y with n: about 270; a
//    sphere's: 30; a sphere and a cone together: 11-13; docs/verification.md).

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "indentsim/fitting/forward_model.hpp"
#include "indentsim/materials/material_parameter.hpp"

namespace indentsim {

inline constexpr double identifiability_condition_limit = 100.0;
/// The coarse phase (FitSettings::coarse_first) runs where every data set's mesh has at least
/// this many contact nodes (half of them is then still a resolved contact).
inline constexpr int coarse_first_min_contact_nodes = 12;

struct FreeParameter {
  MaterialParameter parameter = MaterialParameter::E;
  double lower = 0.0, upper = 0.0;
};

/// One iteration of the optimiser, for the progress line.
struct FitProgress {
  int start = 0, starts = 1, iteration = 0;
  double cost = 0.0;
  std::vector<double> theta;
  int forward_runs = 0;  ///< on the data sets' own meshes
  int coarse_runs = 0;   ///< on the coarse phase's meshes
  std::string phase;     ///< StartOutcome::phase
};

struct FitSettings {
  int starts = 1;              ///< the load case's values, then points spread over the bounds
  int max_iterations = 50;     ///< Levenberg-Marquardt iterations per start
  bool finite_differences = false;  ///< force finite differences (the benchmark compares both)
  /// Levenberg-Marquardt travels on meshes with half the contact nodes, then the fine meshes are
  /// planned at its optimum and the result polished there (see fit()).
  bool coarse_first = true;
  bool replan_mesh = true;     ///< without the coarse phase: re-plan the mesh at the result and polish
  std::function<void(const FitProgress&)> on_iteration;
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

struct StartOutcome {
  std::vector<double> start, result;
  double cost = 0.0;
  int iterations = 0;
  bool converged = false;
  std::string message;  ///< Ceres' own words
  /// "coarse" (a start on the coarse phase's meshes), "fine" (a start on the data sets' own
  /// meshes), "polish" (from the coarse or first result, on meshes planned there)
  std::string phase = "fine";
};

struct FitResult {
  std::vector<double> values;      ///< in the order of problem.free
  std::vector<double> std_errors;  ///< infinite for a combination the data do not determine
  Eigen::MatrixXd covariance, correlation;
  std::vector<double> singular_values;  ///< of J diag(theta), largest first
  double condition_number = 0.0;
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
};

/// The data a measurement of `truth` would give at `abscissa` (depths of a curve, or radii of an
/// imprint), with Gaussian noise of standard deviation `noise` times the largest |value| (an
/// instrument's noise floor; seeded), computed on the mesh and element a fit of `free` would use:
/// for round trips, identifiability studies before an experiment, and the benchmark.
FitData synthetic_data(const LoadCase& truth, FitDataKind kind, const std::vector<double>& abscissa,
                       const std::vector<FreeParameter>& free, double noise, unsigned seed);

/// Checks the problem (free keys, bounds inside the physical range and around sensible values,
/// enough points) and fits.  Throws InputError for a problem that cannot be posed, SolverError when
/// no start reaches a single successful evaluation.
FitResult fit(const FitProblem& problem);

}  // namespace indentsim
