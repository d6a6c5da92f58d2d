#pragma once
// The model side of a fit (fit.hpp): one data set -- a measured force-depth curve, or the
// residual imprint after unloading -- and the load case that produces it, evaluated at material
// parameters theta, with d(model)/d(theta).
//
// The runs pass exactly through the data's depths: the load path is the data's own sequence of
// depths (Ilyushin's deformation theory is path independent on loading; a load-unload curve
// follows the data's own path), each step subdivided to the load case's own increment length.
// The mesh is fixed once for the whole fit (planned at one set of parameters, the element chosen
// for the whole box of bounds), so the model is a smooth function of theta: a mesh that moved
// with theta would make the curve jump.
//
// Gradients: forward sensitivities through the converged Newton system
// (Simulation::sensitivities: one factorization and one solve per parameter at each data depth,
// and at each reversal of an imprint's path) for the elastic model and Ilyushin's law -- on
// loading, and on the unloading branch through the peak strain's own sensitivity -- for any
// parameter but nu; one-sided finite differences of whole runs for J2 flow theory (its history
// would need the return map's sensitivity over every increment) and for nu.
//
// A time history (docs/MODEL.md §13.6) follows the case's own protocol in time -- force or depth
// control, holds, a creeping material -- with a waypoint at every data time; the response there
// (the depth under force control, the force under depth control) is the model.  Its history in
// time makes it differentiated by finite differences.
#include <string>
#include <utility>
#include <vector>

#include "indentsim/input/load_case.hpp"
#include "indentsim/materials/material_parameter.hpp"

namespace indentsim {

enum class FitDataKind {
  force_depth_curve,  ///< P at depths alpha (loading, or a load-unload sequence)
  imprint_profile,    ///< the residual depth of the surface at radii r after the run unloads to 0
  /// The response at times t along the case's own protocol in time (load.times): the depth under
  /// force control, the force under depth control (docs/MODEL.md §13.6).
  time_history
};

struct FitData {
  FitDataKind kind = FitDataKind::force_depth_curve;
  std::string file;    ///< where the data came from (messages, fit.json)
  LoadCase load_case;  ///< the scene; its material holds the fixed parameters and the starting values
  /// Curve: the depths alpha [m] in the order they were measured; imprint: the radii r [m]; time
  /// history: the times t [s], never decreasing.
  std::vector<double> abscissa;
  /// Curve: P [N; N/m in plane strain]; imprint: the residual depth below the original surface [m];
  /// time history: alpha [m] under force control, P under depth control.
  std::vector<double> values;
  double weight = 1.0;  ///< multiplies this data set's residuals
  /// Curve: the force column as the file names it, and the unit it was read in (for messages); a
  /// time history: the response's column and unit.
  std::string column = "P", unit = "N";
  /// The rows the file held, when reduce_to_resolution() replaced them by fewer points (else 0).
  std::size_t rows = 0;
};

/// The data's values are forces: a force-depth curve, or a time history under depth control.
bool values_are_forces(const FitData& data);

/// What reduce_to_resolution() did to a curve.
struct CurveReduction {
  bool reduced = false;
  std::size_t rows = 0, points = 0;  ///< before and after
  int branches = 0;                  ///< loading and unloading branches found
  double step = 0.0;                 ///< the load case's increment length [m]
  std::string note;                  ///< one line: what was done and why ("" when nothing was)
};

/// Refuses, naming the key, a load case whose load path the fit's forward model cannot follow: a
/// force-depth curve or an imprint is run along the data's own depths under depth control, so
/// force control and a rate-dependent material need the protocol in time (load.times) and the
/// data as a time history.  Throws InputError naming the case's file.
void refuse_unfittable_load(const LoadCase& load_case, FitDataKind kind);

/// A force-depth curve with many more rows than the model resolves, reduced to what it does.
/// Every data depth is a waypoint of the fit's forward runs, so a curve of 10^5 rows would cost
/// 10^5 increments per run where the load case asks for tens.  The curve is split into its
/// branches (loading, unloading, reloading: a reversal counts once the depth has come back by half
/// an increment and by 10 standard deviations of the depths' noise), and a branch holding more than two rows per increment of the load case (of
/// length max depth / load.increments) is replaced by one point per increment (at least 5), evenly
/// spaced from the branch's first depth to its turning point (kept exactly), each the value at that
/// depth of a least-squares quadratic through the rows within half a spacing of it (the rows' noise
/// averaged, the curve's curvature kept; linear interpolation where fewer than 5 rows lie there).
/// Branches with fewer rows, and imprints, are left as they are.  A time history of more than two
/// rows per increment of the case's protocol is replaced by one point at the end of each increment
/// (the same local quadratic, in time, within half an increment).
CurveReduction reduce_to_resolution(FitData& data);

/// The model at the data points, and its derivatives if asked.
struct ModelEvaluation {
  std::vector<double> values;
  std::vector<std::vector<double>> jacobian;  ///< [point][parameter]: d value / d theta
  int forward_runs = 0;                       ///< whole runs this evaluation took
};

class ForwardModel {
public:
  /// Fixes the mesh at `plan_at` (empty: the load case's own material; its pilot run, for a plastic
  /// case) and the element over `bounds`, and lays the load path through the data.  Throws
  /// InputError when the scene cannot produce the data (depths beyond the case's, an imprint that
  /// never unloads, radii off the surface).
  ForwardModel(FitData data, std::vector<RegionParameter> parameters,
               const std::vector<std::pair<double, double>>& bounds, bool finite_differences_only,
               const std::vector<double>& plan_at = {});

  /// The model at theta (in the order of the parameters).  Throws SolverError when a run fails
  /// even after two retries with steps a quarter as long.
  ModelEvaluation evaluate(const std::vector<double>& theta, bool with_jacobian) const;

  /// Plans the mesh afresh at theta (the fit's result), as a run of the fitted case would.
  void replan_mesh(const std::vector<double>& theta);

  /// True when the jacobian comes from forward sensitivities (else finite differences).
  bool uses_sensitivities() const { return sensitivities_; }
  /// Why it does not, or "" when it does.
  const std::string& finite_difference_reason() const { return fd_reason_; }
  const FitData& data() const { return data_; }
  /// The load case at theta, as the runs solve it (fixed mesh, the data's path).
  LoadCase case_at(const std::vector<double>& theta) const;
  /// The user's load case with the parameters at theta (own path and mesh): fitted_case.toml.
  LoadCase fitted_case(const std::vector<double>& theta) const;
  const std::vector<RegionParameter>& parameters() const { return parameters_; }
  double planned_contact_half_width() const { return prepared_.mesh.contact_half_width.value_or(0.0); }

private:
  /// A time history: the protocol with a waypoint at every data time (prepared_.load, path_,
  /// point_of_waypoint_).  Throws InputError for a time outside the protocol's.
  void lay_path_through_times();
  std::vector<double> run_once(const LoadCase& lc, int refinement, std::vector<std::vector<double>>* jacobian) const;
  std::vector<double> run(const LoadCase& lc, std::vector<std::vector<double>>* jacobian, int& runs) const;

  FitData data_;
  std::vector<RegionParameter> parameters_;
  /// The parameters as the simulation's forward sensitivities name them (a homogeneous specimen's).
  std::vector<MaterialParameter> sensitivity_parameters_;
  std::vector<std::pair<double, double>> bounds_;
  LoadCase prepared_;  ///< the data's path, the fixed mesh and element
  std::vector<double> path_;  ///< curve: the data depths without repeats, from 0; time history: the waypoint times
  std::vector<std::size_t> point_of_waypoint_;  ///< curve: data point -> index in path_
  bool sensitivities_ = false;
  std::string fd_reason_;
};

}  // namespace indentsim
