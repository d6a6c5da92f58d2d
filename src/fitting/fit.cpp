#include "indentsim/fitting/fit.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <future>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <set>

#include <Eigen/QR>
#include <Eigen/SVD>
#include <ceres/ceres.h>
#include <fmt/format.h>
#include <glog/logging.h>

#include "indentsim/base/error.hpp"
#include "indentsim/base/interruption.hpp"
#include "indentsim/base/worker_threads.hpp"
#include "indentsim/simulation/error_estimate.hpp"

namespace indentsim {

namespace {

/// Evaluations that failed, over every data set's cost function (starts run side by side).
struct EvaluationFailures {
  std::atomic<int> runs{0};     ///< forward runs that failed even with their retries
  std::atomic<int> refused{0};  ///< parameter combinations the model refuses
};

/// Ceres reports through glog, which writes to stderr whatever the caller asked for: a start
/// whose first evaluation fails is an ERROR line ("Terminating: Residual and Jacobian evaluation
/// failed.", after "Logging before InitGoogleLogging() is written to STDERR").  The fit counts
/// failures and reports them in its own words, so glog is held to fatal errors while it works
/// (messages below FLAGS_minloglevel are dropped before anything is written) and restored after.
class QuietCeresLogging {
public:
  QuietCeresLogging() : previous_(FLAGS_minloglevel) { FLAGS_minloglevel = std::max<int>(previous_, google::GLOG_FATAL); }
  ~QuietCeresLogging() { FLAGS_minloglevel = previous_; }
  QuietCeresLogging(const QuietCeresLogging&) = delete;
  QuietCeresLogging& operator=(const QuietCeresLogging&) = delete;

private:
  int previous_;
};

/// The residuals of one data set as a Ceres cost function of the scaled parameters x = theta / scale.
/// Ceres asks for the residuals at a trial point and, once the point is accepted, for the
/// Jacobian at the same point: the last evaluation is kept, and with forward sensitivities it
/// always carries its Jacobian (one factorization per data depth, far cheaper than a second run).
/// One solve at a time evaluates it (the kept evaluation is its own); starts side by side each
/// have their own over the same ForwardModel, whose evaluate() is const.
class DataSetResiduals : public ceres::CostFunction {
public:
  DataSetResiduals(const ForwardModel& model, std::vector<double> scale, std::atomic<int>& forward_runs,
                   EvaluationFailures& failures)
      : model_(model), scale_(std::move(scale)), forward_runs_(forward_runs), failures_(failures) {
    const FitData& d = model.data();
    set_num_residuals(static_cast<int>(d.values.size()));
    mutable_parameter_block_sizes()->push_back(static_cast<int>(scale_.size()));
    double largest = 0.0;
    for (double v : d.values) largest = std::max(largest, std::abs(v));
    factor_ = d.weight / (largest * std::sqrt(static_cast<double>(d.values.size())));
  }

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    if (interruption_requested()) return false;  // the fit is stopping: no new run (fit() throws)
    std::vector<double> theta(scale_.size());
    for (std::size_t j = 0; j < theta.size(); ++j) theta[j] = parameters[0][j] * scale_[j];
    const bool want_jacobian = jacobians && jacobians[0];
    if (failed_ && theta == failed_theta_) return false;  // the same run on the same mesh fails again
    if (!(cached_ && theta == cached_theta_ && (!want_jacobian || !cached_.jacobian.empty()))) {
      try {
        ModelEvaluation e = model_.evaluate(theta, want_jacobian || model_.uses_sensitivities());
        forward_runs_ += e.forward_runs;
        own_runs_ += e.forward_runs;
        cached_ = std::move(e);
        cached_theta_ = theta;
      } catch (const SolverError&) {
        forward_runs_ += 3;
        own_runs_ += 3;
        ++failures_.runs;
        remember_failure(theta);
        return false;  // the optimiser shortens its step
      } catch (const InputError&) {
        ++failures_.refused;
        remember_failure(theta);
        return false;  // a parameter combination the model refuses (Ilyushin's admissibility)
      } catch (const Interrupted&) {
        return false;  // SIGINT or SIGTERM within the run: the callback ends the solve, fit() throws
      }
    }
    const FitData& d = model_.data();
    for (std::size_t i = 0; i < d.values.size(); ++i)
      residuals[i] = factor_ * (cached_.values[i] - d.values[i]) - (offset_.empty() ? 0.0 : offset_[i]);
    if (want_jacobian)
      for (std::size_t i = 0; i < d.values.size(); ++i)
        for (std::size_t j = 0; j < scale_.size(); ++j)
          jacobians[0][i * scale_.size() + j] = factor_ * cached_.jacobian[i][j] * scale_[j];
    return true;
  }

  /// Forgets the kept evaluation and failure: the model changed (its mesh was re-planned).
  void forget() {
    cached_.valid = false;
    failed_ = false;
  }
  /// The model's values at the scaled parameters x, evaluated as Ceres' first evaluation of a start
  /// at x evaluates them (with the Jacobian), and kept for it; nullptr when the evaluation failed.
  const std::vector<double>* values_at(const std::vector<double>& x) const {
    std::vector<double> residuals(static_cast<std::size_t>(num_residuals()));
    std::vector<double> jacobian(residuals.size() * scale_.size());
    const double* parameters[] = {x.data()};
    double* jacobians[] = {jacobian.data()};
    if (!Evaluate(parameters, residuals.data(), jacobians)) return nullptr;
    return &cached_.values;
  }
  /// The last evaluation (model values and Jacobian in theta) if it was at theta with its Jacobian.
  const ModelEvaluation* evaluated_at(const std::vector<double>& theta) const {
    return cached_ && theta == cached_theta_ && !cached_.jacobian.empty() ? &cached_ : nullptr;
  }
  double factor() const { return factor_; }
  /// The forward runs evaluated through this cost function.
  int own_runs() const { return own_runs_; }
  /// Subtracted from the residuals (in their units), or nothing when empty: the model's own error
  /// e, so that the optimum found is the converged model's (fit()'s corrected optimum).
  void set_offset(std::vector<double> offset) { offset_ = std::move(offset); }

private:
  struct Cache : ModelEvaluation {
    bool valid = false;
    explicit operator bool() const { return valid; }
    Cache& operator=(ModelEvaluation&& e) {
      ModelEvaluation::operator=(std::move(e));
      valid = true;
      return *this;
    }
  };
  void remember_failure(const std::vector<double>& theta) const {
    failed_ = true;
    failed_theta_ = theta;
  }
  const ForwardModel& model_;
  std::vector<double> scale_;
  std::atomic<int>& forward_runs_;
  EvaluationFailures& failures_;
  double factor_ = 1.0;
  mutable int own_runs_ = 0;
  std::vector<double> offset_;
  mutable Cache cached_;
  mutable std::vector<double> cached_theta_;
  mutable bool failed_ = false;  ///< the last failed evaluation was at failed_theta_
  mutable std::vector<double> failed_theta_;
};

/// After each iteration of a solve: the checkpoint (after an accepted step) and the progress
/// line, one solve at a time (`fit_mutex`: starts run side by side).
class ProgressReporter : public ceres::IterationCallback {
public:
  ProgressReporter(const FitSettings& settings, FitProgress progress, const std::vector<double>& x,
                   const std::vector<double>& scale, std::mutex& fit_mutex,
                   std::function<void(FitProgress&)> fill_counters,
                   std::function<void(const ceres::IterationSummary&)> after_accepted_step)
      : settings_(settings),
        progress_(std::move(progress)),
        x_(x),
        scale_(scale),
        fit_mutex_(fit_mutex),
        fill_counters_(std::move(fill_counters)),
        after_accepted_step_(std::move(after_accepted_step)) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
    // SIGINT or SIGTERM: end the solve at the point reached (its cost stays usable); fit() throws.
    if (interruption_requested()) return ceres::SOLVER_TERMINATE_SUCCESSFULLY;
    const std::lock_guard<std::mutex> lock(fit_mutex_);
    if (s.step_is_successful && after_accepted_step_) after_accepted_step_(s);
    if (!settings_.on_iteration) return ceres::SOLVER_CONTINUE;
    progress_.iteration = s.iteration;
    progress_.cost = s.cost;
    progress_.theta.resize(x_.size());
    for (std::size_t j = 0; j < x_.size(); ++j) progress_.theta[j] = x_[j] * scale_[j];
    fill_counters_(progress_);
    settings_.on_iteration(progress_);
    return ceres::SOLVER_CONTINUE;
  }

private:
  const FitSettings& settings_;
  FitProgress progress_;
  const std::vector<double>& x_;
  const std::vector<double>& scale_;
  std::mutex& fit_mutex_;
  std::function<void(FitProgress&)> fill_counters_;
  std::function<void(const ceres::IterationSummary&)> after_accepted_step_;
};

/// The forecast of a fit's remaining wall time, for its progress line.  Each solve's runs are
/// timed on the meshes they ran on ("coarse", "fine" -- the data sets' own, which polishes and
/// profiles use -- and "refined"); a run on meshes not yet timed is taken as 6 on meshes with
/// half their contact nodes (a quarter of the unknowns; docs/performance.md).  What is still to
/// come is counted in runs: a start as many as the finished starts of its phase took (10 before
/// one has finished); a polish 4 iterations, each side of a profile 3, at the runs per iteration
/// measured (before any: 1 with sensitivities, p + 1 with finite differences); starts and
/// profile sides shared among the threads; the model's own error one run per data set with
/// twice its contact nodes; the design table 5 candidates of one run (p + 1 with finite
/// differences).  A refinement for the model's error is
/// counted once it is decided.  A solve's remaining runs are not known before it converges: the
/// forecast is a guide, measured against the actual remaining time in docs/performance.md.
class FitForecast {
public:
  FitForecast(int starts, int threads, std::size_t parameters, std::size_t data_sets, bool coarse_first, bool profile,
              bool design, bool sensitivities)
      : starts_(starts),
        threads_(threads),
        parameters_(static_cast<double>(parameters)),
        data_sets_(static_cast<double>(data_sets)),
        coarse_first_(coarse_first),
        profile_(profile),
        design_runs_(design ? 5.0 * (sensitivities ? 1.0 : static_cast<double>(parameters) + 1.0) : 0.0),
        runs_per_iteration_prior_(sensitivities ? 1.0 : static_cast<double>(parameters) + 1.0) {}

  /// A solve ended: its runs, iterations and wall seconds, on the meshes of its phase.
  void solve_ended(const std::string& phase, int runs, int iterations, double seconds) {
    Pace& pace = paces_[level_of(phase)];
    pace.runs += runs;
    pace.seconds += seconds;
    runs_of_solves_ += runs;
    iterations_of_solves_ += iterations;
    if (phase == "coarse" || phase == "fine") {
      ++finished_starts_;
      runs_of_finished_starts_ += runs;
    }
  }

  /// The remaining seconds while `phase`'s solve number `index` has taken `runs` runs in
  /// `seconds`; NaN before any run has been timed.
  double remaining(const std::string& phase, int index, int runs, double seconds) const {
    Pace now = paces_.count(level_of(phase)) ? paces_.at(level_of(phase)) : Pace{};
    now.runs += runs;
    now.seconds += seconds;
    std::map<std::string, double> per_run;
    for (const auto& [level, pace] : paces_)
      if (pace.runs > 0) per_run[level] = pace.seconds / pace.runs;
    if (now.runs > 0) per_run[level_of(phase)] = now.seconds / now.runs;
    if (per_run.empty()) return std::numeric_limits<double>::quiet_NaN();
    const auto known = [&](const char* level) { return per_run.count(level) ? per_run.at(level) : 0.0; };
    // The unknown levels from the known ones: 6 times per doubling of the contact nodes.
    double coarse = known("coarse"), fine = known("fine"), refined = known("refined");
    if (fine == 0.0) fine = coarse > 0.0 ? 6.0 * coarse : refined / 6.0;
    if (coarse == 0.0) coarse = fine / 6.0;
    if (refined == 0.0) refined = 6.0 * fine;
    const double on_level = phase == "coarse" ? coarse : phase == "refined" ? refined : fine;
    const double per_iteration = iterations_of_solves_ > 0 ? std::max(1.0, static_cast<double>(runs_of_solves_) / iterations_of_solves_)
                                                           : runs_per_iteration_prior_;
    const double side_runs = 3.0 * per_iteration, polish_runs = 4.0 * per_iteration;
    const double profile_threads = std::min(static_cast<double>(threads_), 2.0 * parameters_);
    const double left_of_solve = [&] {
      if (phase == "coarse" || phase == "fine") {
        // The phase's starts not yet finished (this one among them), their runs so far subtracted.
        const double per_start = finished_starts_ > 0 ? static_cast<double>(runs_of_finished_starts_) / finished_starts_
                                                      : std::max(10.0, runs + 2.0);
        const double starts_left = std::max(1.0, static_cast<double>(starts_ - finished_starts_));
        const double parallel = std::min(static_cast<double>(threads_), starts_left);
        return std::max(1.0, starts_left * per_start - runs * parallel) / parallel;
      }
      if (phase == "profile") {  // the sides after this one, shared among the threads
        const int side = (index / 100) % 10, parameter = index / 1000 - 1;
        const double sides_after = std::max(0.0, 2.0 * parameters_ - (2.0 * parameter + side) - profile_threads);
        return std::max(1.0, side_runs - runs) + side_runs * sides_after / profile_threads;
      }
      return std::max(1.0, polish_runs - runs);  // a polish, here or refined, or the corrected optimum
    }();
    double later = 0.0;
    const double profiles = profile_ ? 2.0 * parameters_ * side_runs / profile_threads * fine : 0.0;
    const double polish = polish_runs * fine;
    // The model's own error: one run per data set with twice the contact nodes of the meshes.
    if (phase == "coarse") later = polish + data_sets_ * refined + profiles + design_runs_ * fine;
    else if (phase == "fine") later = (coarse_first_ ? 0.0 : polish) + data_sets_ * refined + profiles + design_runs_ * fine;
    else if (phase == "polish") later = data_sets_ * refined + profiles + design_runs_ * fine;
    else if (phase == "profile") later = design_runs_ * fine;
    else if (phase == "refined") later = data_sets_ * 6.0 * refined + design_runs_ * refined;
    else if (phase == "corrected") later = design_runs_ * fine;
    return left_of_solve * on_level + later;
  }

private:
  struct Pace {
    int runs = 0;
    double seconds = 0.0;
  };
  static std::string level_of(const std::string& phase) {
    return phase == "coarse" || phase == "refined" ? phase : "fine";
  }
  int starts_, threads_;
  double parameters_, data_sets_;
  bool coarse_first_, profile_;
  double design_runs_, runs_per_iteration_prior_;
  std::map<std::string, Pace> paces_;
  int runs_of_solves_ = 0, iterations_of_solves_ = 0;
  int finished_starts_ = 0, runs_of_finished_starts_ = 0;
};

/// The radical inverse of k in base b: the k-th point of van der Corput's sequence.
double radical_inverse(int k, int base) {
  double result = 0.0, f = 1.0 / base;
  for (; k > 0; k /= base, f /= base) result += f * (k % base);
  return result;
}

/// Start k >= 1: the k-th Halton point of the box, log-uniform for a parameter whose bounds are
/// both positive and a decade or more apart (E, e0, sigma_y), uniform otherwise.
std::vector<double> spread_start(int k, const std::vector<FreeParameter>& free) {
  static constexpr int primes[] = {2, 3, 5, 7, 11, 13};
  std::vector<double> theta;
  for (std::size_t j = 0; j < free.size(); ++j) {
    const double u = radical_inverse(k, primes[j % 6]);
    const auto& f = free[j];
    if (f.lower > 0.0 && f.upper >= 10.0 * f.lower) theta.push_back(f.lower * std::pow(f.upper / f.lower, u));
    else theta.push_back(f.lower + u * (f.upper - f.lower));
  }
  return theta;
}

/// The unit of a curve's forces in SI: N, or N/m in plane strain.
const char* si_force_unit(const FitData& d) { return d.load_case.geometry.kind == SceneKind::plane_strain ? "N/m" : "N"; }

/// The key's unit for messages (" Pa" for the stresses, " 1/s" for the rates).
std::string unit_suffix(MaterialParameter p) {
  using P = MaterialParameter;
  if (p == P::E || p == P::yield_stress || p == P::K || p == P::Q || p == P::reference_stress) return " Pa";
  if (p == P::reference_strain_rate || p == P::creep_coefficient) return " 1/s";
  return "";
}

void check_problem(const FitProblem& problem) {
  if (problem.data.empty()) throw InputError("fit", "data", "no data to fit");
  if (problem.free.empty()) throw InputError("fit", "--free", "no parameter to fit");
  // Forces push the punch in: P > 0.  A curve whose largest force is negative was exported with
  // the other sign convention (or the column is another one); fitted, it ends at a bound.
  for (const auto& d : problem.data) {
    if (!values_are_forces(d) || d.values.empty()) continue;
    const double peak = *std::max_element(d.values.begin(), d.values.end(),
                                          [](double a, double b) { return std::abs(a) < std::abs(b); });
    if (peak < 0.0)
      throw InputError(d.file, fmt::format("column \"{}\"", d.column),
                       fmt::format("the force column is negative (its largest force is {:.4g} {}): indentsim's P is the "
                                   "force pushing the punch in, positive; negate the column",
                                   peak, si_force_unit(d)));
  }
  const LoadCase& first = problem.data.front().load_case;
  std::set<RegionParameter> seen;
  std::size_t points = 0;
  for (const auto& d : problem.data) points += d.values.size();
  for (const auto& f : problem.free) {
    const std::string key = key_of(f.parameter);
    // A layer's key has the declared interval and magnitudes of [material]'s.
    const std::string declared_key = key_of(f.parameter.which);
    const MaterialParameter which = f.parameter.which;
    const std::string unit = unit_suffix(which);
    // Every data set's case has the layer (the fit frees one parameter of all of them).
    for (const auto& d : problem.data)
      if (f.parameter.region > d.load_case.layers.size())
        throw InputError(d.load_case.source, key,
                         fmt::format("names layer {}, but the case has {} layer(s) ([[layer]] tables)", f.parameter.region,
                                     d.load_case.layers.size()));
    if (!seen.insert(f.parameter).second) throw InputError("fit", key, "is listed twice among the free parameters");
    if ((which == MaterialParameter::e0 && seen.count({MaterialParameter::yield_stress, f.parameter.region})) ||
        (which == MaterialParameter::yield_stress && seen.count({MaterialParameter::e0, f.parameter.region})))
      throw InputError("fit", key, "material.e0 and material.yield_stress are one parameter: free one of them");
    // The start: the first data set's value, within the magnitudes the key declares plausible
    // (the default bounds are clipped to them) -- otherwise a unit slip is fitted.
    const double start = value_of(first, f.parameter);
    const MaterialInput& first_material = first.region_material(f.parameter.region);
    const auto plausible = plausible_magnitudes(declared_key);
    if (plausible && !(start >= plausible->low && start <= plausible->high))
      throw InputError(first.source, key,
                       fmt::format("starts at {:g}{} (the load case's value), outside {}, {:g} to {:g}{}: a fit "
                                   "starts and stays within them (is the unit right?)",
                                   start, unit, plausible->of_what, plausible->low, plausible->high, unit));
    const auto [low, high] = physical_range(which);
    if (!(f.lower < f.upper))
      throw InputError("fit", key, fmt::format("bounds {}:{} are reversed or empty (lower < upper needed)", f.lower, f.upper));
    // Open ends but kappa's 0 and the rate exponent's [1, 100] (the key accepts both ends).
    if (!(f.lower >= low && f.upper <= high) || (f.lower == low && low == 0.0 && which != MaterialParameter::kappa) ||
        (f.upper == high && which != MaterialParameter::rate_exponent))
      throw InputError("fit", key,
                       fmt::format("bounds {}:{} leave the physical range ({}, {})", f.lower, f.upper, low, high));
    // Each bound a value the key accepts (its declared interval) and a solid plausibly has.
    for (const auto& [bound_name, bound] : {std::pair{"lower", f.lower}, std::pair{"upper", f.upper}}) {
      if (const auto words = declared_interval_problem(declared_key, bound))
        throw InputError("fit", key,
                         fmt::format("bounds {:g}:{:g}: the {} bound {}, as {} declares", f.lower, f.upper, bound_name, *words, declared_key));
      if (plausible && !(bound >= plausible->low && bound <= plausible->high))
        throw InputError("fit", key,
                         fmt::format("bounds {:g}:{:g}: the {} bound lies outside {}, {:g} to {:g}{} (is the unit "
                                     "right?)",
                                     f.lower, f.upper, bound_name, plausible->of_what, plausible->low, plausible->high, unit));
      // sigma_y is e0 = sigma_y / (3 mu) to the law: a bound must give an elastic-limit strain.
      if (which == MaterialParameter::yield_stress) {
        const double e0 = e0_of_yield_stress(bound, first_material.E, first_material.nu);
        if (const auto e0_words = declared_interval_problem("material.e0", e0))
          throw InputError("fit", key,
                           fmt::format("bounds {:g}:{:g}: the {} bound gives the elastic-limit strain e0 = sigma_y / "
                                       "(3 mu) = {:.3g} with material.E = {:g} Pa and material.nu = {:g}, but material.e0 {}",
                                       f.lower, f.upper, bound_name, e0, first_material.E, first_material.nu, *e0_words));
      }
    }
    // A start outside the bounds is refused, never moved: the fit would start elsewhere than told.
    if (!(start >= f.lower && start <= f.upper))
      throw InputError(first.source, key,
                       fmt::format("starts at {:g}{} (the load case's value), outside its bounds [{:g}, {:g}]{}: set a start "
                                   "inside them (in the load case, or with --set) or widen them (--bounds {}=lower:upper)",
                                   start, unit, f.lower, f.upper, unit, key));
    for (const auto& d : problem.data) {
      if (const auto why = inapplicable(d.load_case.region_material(f.parameter.region), which))
        throw InputError(d.load_case.source, key, *why);
    }
  }
  if (points < problem.free.size())
    throw InputError(problem.data.front().file, "data",
                     fmt::format("{} point(s) for {} free parameters: a fit needs at least as many points", points,
                                 problem.free.size()));
}

/// The index of the lowest finite cost among the outcomes on the coarse meshes ("coarse") or on
/// the data sets' own ("fine": fine starts and polishes), or outcomes.size() if there is none.
std::size_t best_start(const std::vector<StartOutcome>& outcomes, const std::string& meshes) {
  std::size_t chosen = outcomes.size();
  for (std::size_t k = 0; k < outcomes.size(); ++k) {
    const StartOutcome& o = outcomes[k];
    if ((o.phase == "coarse") != (meshes == "coarse") || !std::isfinite(o.cost)) continue;
    if (chosen == outcomes.size() || o.cost < outcomes[chosen].cost) chosen = k;
  }
  return chosen;
}

/// The free parameters' keys and bounds, as the forward models take them.
std::pair<std::vector<RegionParameter>, std::vector<std::pair<double, double>>> split(
    const std::vector<FreeParameter>& free) {
  std::vector<RegionParameter> parameters;
  std::vector<std::pair<double, double>> bounds;
  for (const FreeParameter& f : free) {
    parameters.push_back(f.parameter);
    bounds.emplace_back(f.lower, f.upper);
  }
  return {parameters, bounds};
}

std::string percent(double fraction) { return fmt::format("{:.3g}%", 100.0 * fraction); }

/// Student's t at 0.975 for `dof` degrees of freedom: exact for 1 and 2, else the Cornish-Fisher
/// expansion about the normal quantile (Abramowitz and Stegun 26.7.5; within 4e-3 at 3 degrees,
/// closer beyond).
double student_t975(double dof) {
  if (!(dof >= 1.0)) return std::numeric_limits<double>::infinity();
  if (dof < 2.0) return 12.706204736;
  if (dof < 3.0) return 4.302652730;
  const double z = 1.959963984540054, z2 = z * z, z3 = z2 * z, z5 = z3 * z2, z7 = z5 * z2, z9 = z7 * z2;
  const double g1 = (z3 + z) / 4.0, g2 = (5.0 * z5 + 16.0 * z3 + 3.0 * z) / 96.0,
               g3 = (3.0 * z7 + 19.0 * z5 + 17.0 * z3 - 15.0 * z) / 384.0,
               g4 = (79.0 * z9 + 776.0 * z7 + 1482.0 * z5 - 1920.0 * z3 - 945.0 * z) / 92160.0;
  return z + g1 / dof + g2 / (dof * dof) + g3 / std::pow(dof, 3) + g4 / std::pow(dof, 4);
}

}  // namespace

FitData synthetic_data(const LoadCase& truth, FitDataKind kind, const std::vector<double>& abscissa,
                       const std::vector<FreeParameter>& free, double noise, unsigned seed) {
  FitData d;
  d.kind = kind;
  d.file = "synthetic";
  d.load_case = truth;
  d.abscissa = abscissa;
  d.values.assign(abscissa.size(), 0.0);
  const auto [parameters, bounds] = split(free);
  std::vector<double> theta;
  for (const RegionParameter& p : parameters) theta.push_back(value_of(truth, p));
  const ForwardModel model(d, parameters, bounds, false);
  d.values = model.evaluate(theta, false).values;
  double largest = 0.0;
  for (double v : d.values) largest = std::max(largest, std::abs(v));
  std::mt19937 random(seed);
  std::normal_distribution<double> gauss(0.0, noise * largest);
  for (double& v : d.values) v += gauss(random);
  return d;
}

FitResult fit(const FitProblem& problem) {
  const auto start_time = std::chrono::steady_clock::now();
  const QuietCeresLogging quiet_logging;
  check_problem(problem);
  const std::size_t p = problem.free.size();
  // Named variables, not a structured binding: clang 14 cannot capture bindings in lambdas.
  const auto free_split = split(problem.free);
  const std::vector<RegionParameter>& parameters = free_split.first;
  const auto& bounds = free_split.second;
  // The parameters Ceres sees, x = theta / scale, are of order one.
  const LoadCase& first = problem.data.front().load_case;
  std::vector<double> scale, case_start;
  for (const auto& f : problem.free) {
    const double v = std::clamp(value_of(first, f.parameter), f.lower, f.upper);
    case_start.push_back(v);
    scale.push_back(v != 0.0 ? std::abs(v) : std::max(std::abs(f.lower), std::abs(f.upper)));
  }

  FitResult result;
  std::atomic<int> forward_runs{0}, coarse_runs{0};
  EvaluationFailures failures;
  // Starts run side by side (FitSettings::threads); the fit's shared state -- its outcomes, the
  // checkpoint, the progress line -- is changed under this lock.
  std::mutex fit_mutex;
  const int starts = std::max(1, problem.settings.starts);
  const int threads = std::max(1, problem.settings.threads > 0 ? problem.settings.threads : usable_cores());
  const auto warn = [&](std::string warning) {
    if (problem.settings.on_warning) problem.settings.on_warning(warning);
    result.warnings.push_back(std::move(warning));
  };
  // SIGINT or SIGTERM: the run in progress throws Interrupted (caught by the cost function, whose
  // later evaluations fail at once), the callback ends the solve, and the fit stops between solves
  // with the lowest cost found so far (on the data sets' own meshes if any, else the coarse ones).
  const auto interrupted_fit = [&](int signal) {
    std::size_t k = best_start(result.starts, "fine");
    if (k == result.starts.size()) k = best_start(result.starts, "coarse");
    if (k == result.starts.size())
      return FitInterrupted(signal, {}, std::numeric_limits<double>::quiet_NaN(), "", forward_runs, coarse_runs);
    const StartOutcome& o = result.starts[k];
    return FitInterrupted(signal, o.result, o.cost, o.phase, forward_runs, coarse_runs);
  };
  const auto stop_if_interrupted = [&] {
    if (const int signal = interruption_requested()) throw interrupted_fit(signal);
  };
  // The data sets' models on meshes with contact_nodes / divisor, planned at plan_at (empty:
  // at each case's own values), and their cost functions counting runs in `runs`.
  // (a path-dependent case's increments multiplied by increments_factor: its increments refined).
  struct Level {
    std::vector<std::unique_ptr<ForwardModel>> models;
    std::vector<std::unique_ptr<DataSetResiduals>> costs;
    int increments_factor = 1;
  };
  const auto make_level = [&](double nodes_factor, const std::vector<double>& plan_at, std::atomic<int>& runs,
                              int increments_factor = 1) {
    Level level;
    level.increments_factor = increments_factor;
    for (const auto& d : problem.data) {
      FitData data = d;
      data.load_case.mesh.contact_nodes =
          std::max(2, static_cast<int>(d.load_case.mesh.contact_nodes * nodes_factor + 1e-9));
      if (increments_factor > 1) data.load_case.load.multiply_increments(increments_factor);
      try {  // a plastic case's mesh is planned from a pilot run
        level.models.push_back(std::make_unique<ForwardModel>(std::move(data), parameters, bounds,
                                                              problem.settings.finite_differences, plan_at));
      } catch (const Interrupted& e) {
        throw interrupted_fit(e.signal());
      }
      level.costs.push_back(std::make_unique<DataSetResiduals>(*level.models.back(), scale, runs, failures));
    }
    return level;
  };

  // Before the first start: a curve whose forces are orders of magnitude off the model's at the
  // start values was read in the wrong unit, most likely (mN written as N).  The evaluation is the
  // first start's own first one (kept for it), so the check costs no run.
  bool magnitudes_checked = false;
  const auto check_magnitudes = [&](const Level& level) {
    if (magnitudes_checked) return;
    magnitudes_checked = true;
    std::vector<double> x(p);
    for (std::size_t j = 0; j < p; ++j) x[j] = case_start[j] / scale[j];
    for (std::size_t d = 0; d < problem.data.size(); ++d) {
      const FitData& data = problem.data[d];
      if (!values_are_forces(data)) continue;
      const std::vector<double>* model = level.costs[d]->values_at(x);
      if (!model) continue;
      double data_peak = 0.0, model_peak = 0.0;
      for (double v : data.values) data_peak = std::max(data_peak, std::abs(v));
      for (double v : *model) model_peak = std::max(model_peak, std::abs(v));
      if (!(data_peak > 0.0 && model_peak > 0.0)) continue;
      const double ratio = data_peak / model_peak;
      if (ratio <= unit_slip_factor && ratio >= 1.0 / unit_slip_factor) continue;
      warn(fmt::format("{}: its largest force, {:.4g} {}, is {} the model's at the start values ({:.4g} {}): the force "
                       "unit is probably wrong (column \"{}\" was read in {}; mN written as N gives 1000 times the "
                       "force): give the right one (--force-unit, or force_unit in the fit file)",
                       data.file, data_peak, si_force_unit(data),
                       ratio > 1.0 ? fmt::format("{:.3g} times", ratio) : fmt::format("1/{:.3g} of", 1.0 / ratio),
                       model_peak, si_force_unit(data), data.column, data.unit));
    }
  };

  // Checkpoints (FitSettings::on_checkpoint): every solve finished (those of the checkpoint
  // resumed from among them, whether or not this process has come to them yet), those in progress
  // at their last accepted step, and the resumed ones in progress not yet taken up again.  The
  // iterations counted are the finished solves'; those in progress carry their own.
  const FitCheckpoint* resume = problem.settings.resume_from;
  std::vector<StartOutcome> solved;                              // finished solves
  std::map<std::pair<std::string, int>, StartOutcome> running;  // (phase, index) -> last accepted point
  std::vector<StartOutcome> waiting;                             // resumed, in progress, not yet taken up
  int finished_iterations = 0;
  if (resume) {
    forward_runs = resume->forward_runs;
    coarse_runs = resume->coarse_runs;
    finished_iterations = resume->iterations;
    failures.runs = resume->failed_runs;
    failures.refused = resume->refused_evaluations;
    solved = resume->finished;
    waiting = resume->in_progress;
  }
  const auto emit_checkpoint = [&] {  // with fit_mutex held
    if (!problem.settings.on_checkpoint) return;
    FitCheckpoint c;
    c.finished = solved;
    for (const auto& entry : running) c.in_progress.push_back(entry.second);
    c.in_progress.insert(c.in_progress.end(), waiting.begin(), waiting.end());
    c.forward_runs = forward_runs;
    c.coarse_runs = coarse_runs;
    c.iterations = finished_iterations;
    c.failed_runs = failures.runs;
    c.refused_evaluations = failures.refused;
    problem.settings.on_checkpoint(c);
  };
  const auto same_solve = [](const StartOutcome& o, const std::string& phase, int index, const std::vector<double>& start) {
    return o.phase == phase && o.index == index && o.start == start;
  };
  const auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count(); };
  const bool coarse_first =
      problem.settings.coarse_first &&
      std::all_of(problem.data.begin(), problem.data.end(),
                  [](const FitData& d) { return d.load_case.mesh.contact_nodes >= coarse_first_min_contact_nodes; });
  FitForecast forecast(starts, threads, p, problem.data.size(), coarse_first, problem.settings.profile,
                       problem.settings.design_experiments, !problem.settings.finite_differences);

  using Costs = std::vector<std::unique_ptr<DataSetResiduals>>;
  const auto solve_from = [&](const Costs& costs, const std::string& phase, const std::vector<double>& start,
                              int start_index, int max_iterations, int held = -1) {
    // Resumed: a solve the checkpoint finished is taken as it was; one in progress continues.
    std::vector<double> from = start;
    int done_iterations = 0;
    if (resume) {
      const std::lock_guard<std::mutex> lock(fit_mutex);
      for (const StartOutcome& f : resume->finished)
        if (same_solve(f, phase, start_index, start)) return f;
      for (auto w = waiting.begin(); w != waiting.end(); ++w)
        if (same_solve(*w, phase, start_index, start)) {
          from = w->result;
          done_iterations = w->iterations;
          running[{phase, start_index}] = *w;
          waiting.erase(w);
          break;
        }
    }
    const auto runs_of = [&costs] {
      int runs = 0;
      for (const auto& c : costs) runs += c->own_runs();
      return runs;
    };
    const int runs_before = runs_of();
    const auto solve_began = std::chrono::steady_clock::now();
    const auto seconds_of_solve = [&] {
      return std::chrono::duration<double>(std::chrono::steady_clock::now() - solve_began).count();
    };
    std::vector<double> x(p);
    for (std::size_t j = 0; j < p; ++j) x[j] = from[j] / scale[j];
    ceres::Problem::Options problem_options;
    problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    ceres::Problem ceres_problem(problem_options);
    for (const auto& c : costs) ceres_problem.AddResidualBlock(c.get(), nullptr, x.data());
    for (std::size_t j = 0; j < p; ++j) {
      ceres_problem.SetParameterLowerBound(x.data(), static_cast<int>(j), problem.free[j].lower / scale[j]);
      ceres_problem.SetParameterUpperBound(x.data(), static_cast<int>(j), problem.free[j].upper / scale[j]);
    }
    // A profile holds one parameter at its trial value and optimises the others.
    if (held >= 0 && p > 1) ceres_problem.SetManifold(x.data(), new ceres::SubsetManifold(static_cast<int>(p), {held}));
    if (held >= 0 && p == 1) ceres_problem.SetParameterBlockConstant(x.data());  // the cost at x alone
    FitProgress progress;
    progress.start = start_index;
    progress.starts = starts;
    progress.phase = phase;
    const auto checkpoint_step = [&](const ceres::IterationSummary& step) {  // fit_mutex held
      StartOutcome reached;
      reached.index = start_index;
      reached.start = start;
      for (std::size_t j = 0; j < p; ++j) reached.result.push_back(x[j] * scale[j]);
      reached.cost = step.cost;
      reached.iterations = done_iterations + step.iteration;
      reached.phase = phase;
      running[{phase, start_index}] = std::move(reached);
      emit_checkpoint();
    };
    const auto fill_counters = [&](FitProgress& now) {  // fit_mutex held
      now.forward_runs = forward_runs;
      now.coarse_runs = coarse_runs;
      now.elapsed_seconds = elapsed();
      now.remaining_seconds = forecast.remaining(phase, start_index, runs_of() - runs_before, seconds_of_solve());
    };
    ProgressReporter reporter(problem.settings, progress, x, scale, fit_mutex, fill_counters, checkpoint_step);
    ceres::Solver::Options options;
    options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
    options.linear_solver_type = ceres::DENSE_QR;
    options.max_num_iterations = std::max(0, max_iterations - done_iterations);
    // Stop when a step changes the cost by less than 1e-6 of itself: moving by k standard errors
    // changes the cost by about k^2 / (m - p) of itself (m points, p parameters), so with tens of
    // points the optimum is then found to a few thousandths of a standard error, and every
    // further iteration would cost a run for nothing.  Noise-free data (cost -> 0) stop on the
    // parameters instead, at 1e-7 relative.
    options.parameter_tolerance = 1e-7;
    options.function_tolerance = 1e-6;
    options.gradient_tolerance = 1e-14;
    options.logging_type = ceres::SILENT;
    options.minimizer_progress_to_stdout = false;
    options.num_threads = 1;
    options.update_state_every_iteration = true;
    options.callbacks.push_back(&reporter);
    ceres::Solver::Summary summary;
    ceres::Solve(options, &ceres_problem, &summary);
    StartOutcome outcome;
    outcome.index = start_index;
    outcome.start = start;
    for (std::size_t j = 0; j < p; ++j) outcome.result.push_back(x[j] * scale[j]);
    // A start whose very first evaluation failed has no usable solution (its cost is not one).
    outcome.cost = summary.IsSolutionUsable() ? summary.final_cost : std::numeric_limits<double>::infinity();
    const int iterations = std::max(0, static_cast<int>(summary.iterations.size()) - 1);
    outcome.iterations = done_iterations + iterations;
    outcome.converged = summary.termination_type == ceres::CONVERGENCE;
    outcome.message = summary.message;
    outcome.phase = phase;
    // A solve a stop request ended is not finished: the checkpoint keeps its last accepted point.
    if (!interruption_requested()) {
      const std::lock_guard<std::mutex> lock(fit_mutex);
      forecast.solve_ended(phase, runs_of() - runs_before, iterations, seconds_of_solve());
      running.erase({phase, start_index});
      solved.push_back(outcome);
      finished_iterations += outcome.iterations;
      emit_checkpoint();
    }
    return outcome;
  };

  // Coarse first: the starts run on meshes with half the contact nodes (a quarter of the unknowns,
  // about a sixth of the time), where Levenberg-Marquardt does its travelling; the fine meshes are
  // then planned at the coarse optimum -- the mesh a run of the fitted case would use, to the
  // coarse answer's accuracy -- and the result polished there (5-6 runs in the benchmark: the
  // optimum moves by the coarse mesh's discretization error, which along a poorly determined
  // combination is a few standard errors).  Should the coarse phase or the polish find nothing
  // (every run refused or failed), the starts run on the fine meshes as without it.
  // Independent solves (the starts of a phase, the sides of the profiles) run side by side on
  // `threads` threads, each thread with its own cost functions over the level's forward models
  // (ForwardModel::evaluate is const; each run is its own single-threaded Simulation:
  // worker_threads.hpp).  Task k goes to thread k mod threads, task 0 to this thread with the
  // level's own cost functions (which hold the magnitude check's evaluation), and each task's
  // solves depend on the task alone: the outcomes do not depend on the threads.
  // Tasks 0..tasks-1 on `threads` threads, task k on thread k mod threads (0: this one), and
  // the first exception of any rethrown here once all have ended.
  const auto parallel_for = [&](int tasks, const std::function<void(int thread, int task)>& task) {
    const int used = std::clamp(threads, 1, std::max(1, tasks));
    const auto run_share = [&](int w) {
      for (int k = w; k < tasks && !interruption_requested(); k += used) task(w, k);
    };
    std::vector<std::future<void>> others;
    for (int w = 1; w < used; ++w) others.push_back(std::async(std::launch::async, run_share, w));
    std::exception_ptr failure;
    try {
      run_share(0);
    } catch (...) {
      failure = std::current_exception();
    }
    for (auto& other : others) {
      try {
        other.get();
      } catch (...) {
        if (!failure) failure = std::current_exception();
      }
    }
    if (failure) std::rethrow_exception(failure);
  };
  const auto side_by_side = [&](const Level& level, std::atomic<int>& runs, int tasks,
                                const std::function<void(int, const Costs&)>& task) {
    std::vector<Costs> own(static_cast<std::size_t>(std::clamp(threads, 1, std::max(1, tasks))));
    for (std::size_t w = 1; w < own.size(); ++w)
      for (const auto& model : level.models)
        own[w].push_back(std::make_unique<DataSetResiduals>(*model, scale, runs, failures));
    parallel_for(tasks, [&](int w, int k) { task(k, w == 0 ? level.costs : own[static_cast<std::size_t>(w)]); });
  };
  const auto run_starts = [&](const Level& level, const std::string& phase, std::atomic<int>& runs) {
    std::vector<std::optional<StartOutcome>> outcomes(static_cast<std::size_t>(starts));
    side_by_side(level, runs, starts, [&](int k, const Costs& costs) {
      const std::vector<double> start = k == 0 ? case_start : spread_start(k, problem.free);
      outcomes[static_cast<std::size_t>(k)] = solve_from(costs, phase, start, k + 1, problem.settings.max_iterations);
    });
    for (auto& o : outcomes)
      if (o) result.starts.push_back(std::move(*o));
    stop_if_interrupted();
  };
  std::optional<Level> fine;
  if (coarse_first) {
    const Level coarse = make_level(0.5, {}, coarse_runs);
    check_magnitudes(coarse);
    run_starts(coarse, "coarse", coarse_runs);
    const std::size_t best = best_start(result.starts, "coarse");
    if (best < result.starts.size()) {
      const std::vector<double> coarse_optimum = result.starts[best].result;
      fine = make_level(1.0, coarse_optimum, forward_runs);
      result.starts.push_back(solve_from(fine->costs, "polish", coarse_optimum, 0, problem.settings.max_iterations));
      stop_if_interrupted();
      if (std::isfinite(result.starts.back().cost)) result.mesh_replanned = true;
      else fine.reset();
    }
  }
  bool replan = false;
  if (!fine) {
    fine = make_level(1.0, {}, forward_runs);
    check_magnitudes(*fine);
    run_starts(*fine, "fine", forward_runs);
    replan = problem.settings.replan_mesh;
  }
  // The best outcome on the fine meshes (coarse costs are on other meshes: not comparable).
  result.selected_start = best_start(result.starts, "fine");
  if (result.selected_start == result.starts.size())
    throw SolverError("no start of the fit reached a successful forward run");
  std::vector<double> theta = result.starts[result.selected_start].result;

  // Without the coarse phase the mesh was planned at the load case's own parameters.  A run of
  // the fitted case plans it at the fitted ones (for a plastic case from its pilot's contact
  // width): re-plan there and polish, so the answer is that of the mesh its own case would use.
  if (replan) {
    bool changed = false;
    for (const auto& m : fine->models) {
      const double before = m->planned_contact_half_width();
      try {
        m->replan_mesh(theta);
      } catch (const Interrupted& e) {
        throw interrupted_fit(e.signal());
      }
      changed = changed || m->planned_contact_half_width() != before;
    }
    if (changed) {
      result.mesh_replanned = true;
      for (const auto& c : fine->costs) c->forget();  // evaluations on the old mesh
      StartOutcome polished = solve_from(fine->costs, "polish", theta, 0, problem.settings.max_iterations);
      if (std::isfinite(polished.cost)) {
        theta = polished.result;
        result.selected_start = result.starts.size();
      }
      result.starts.push_back(std::move(polished));
      stop_if_interrupted();
    }
  }
  // Statistics at the optimum theta on a level's meshes: FitResult's data sets, covariance,
  // the model's own error and each parameter's interval and verdict (recomputed from scratch).
  std::size_t m_total = 0;
  for (const auto& d : problem.data) m_total += d.values.size();
  bool all_determined = false;
  Eigen::VectorXd last_model_error;  // e at the last assessment, in residual units (model - converged)
  Eigen::MatrixXd fisher_jacobian;  // J at the last assessment (the design's reference)
  std::string weakest_in_words;     // the weakest combination at the last assessment
  double fisher_s2 = std::numeric_limits<double>::quiet_NaN();
  // A parameter's verdict from its interval (ParameterDetermination): determined within the
  // bounds and +-determination_limit, else not, with the interval, the parameter it trades
  // against and whether the forward mesh (the model's shift) or the data limit it.
  const auto judge = [&](std::size_t j, ParameterDetermination& pd) {
    const FreeParameter& f = problem.free[j];
    const double value = result.values.empty() ? 0.0 : result.values[j];
    const double half = (pd.upper - pd.lower) / 2.0;
    pd.relative_half_width = value != 0.0 ? half / std::abs(value) : std::numeric_limits<double>::infinity();
    const bool inside = pd.lower >= f.lower && pd.upper <= f.upper && !pd.profile_open;
    pd.determined = std::isfinite(pd.relative_half_width) && pd.relative_half_width <= determination_limit && inside;
    if (pd.determined) {
      pd.verdict = fmt::format("determined to +-{} (95%)", percent(pd.relative_half_width));
      return;
    }
    std::string reach;
    if (pd.lower < f.lower) reach += fmt::format(", below the lower bound {:g}", f.lower);
    if (pd.upper > f.upper) reach += fmt::format("{} above the upper bound {:g}", reach.empty() ? "," : " and", f.upper);
    if (pd.profile_open) reach += ", the data's misfit staying within noise up to a bound";
    const bool model_limited = !pd.profile_open && std::abs(pd.model_shift) > result.std_errors[j];
    pd.verdict = fmt::format("not determined {}: the 95% interval is [{:.4g}, {:.4g}] (+-{}){}",
                             model_limited ? "at this forward mesh" : "by this data", pd.lower, pd.upper,
                             percent(pd.relative_half_width), reach);
    // The parameter it trades against: the strongest correlation.
    std::size_t partner = j;
    for (std::size_t k = 0; k < p; ++k)
      if (k != j && (partner == j || std::abs(result.correlation(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(k))) >
                                         std::abs(result.correlation(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(partner)))))
        partner = k;
    if (partner != j) {
      const double c = result.correlation(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(partner));
      if (std::abs(c) >= 0.5)
        pd.verdict += fmt::format("; it trades against {} (correlation {:.3f})", key_of(problem.free[partner].parameter), c);
    }
    if (model_limited)
      pd.verdict += "; the forward model's own discretization error is most of it (a finer mesh.contact_nodes narrows it)";
  };
  const auto assess = [&](const Level& level, const std::vector<double>& theta) {
    const auto& models = level.models;
    const auto& costs = level.costs;
    result.data.clear();
    result.std_errors.clear();
    result.singular_values.clear();
    result.weakest_direction.clear();
    result.determination.clear();
    result.poorly_determined.clear();
    result.model_to_noise = 0.0;
    // Statistics at the optimum: residuals r and J = dr/d(theta).
    Eigen::VectorXd r(static_cast<Eigen::Index>(m_total));
    Eigen::MatrixXd jacobian(static_cast<Eigen::Index>(m_total), static_cast<Eigen::Index>(p));
    double weight_sum = 0.0;
    Eigen::Index row = 0;
    for (std::size_t d = 0; d < models.size(); ++d) {
      const FitData& data = problem.data[d];
      // Ceres' last Jacobian is usually at the optimum already (sensitivities come with every run).
      const ModelEvaluation* kept = costs[d]->evaluated_at(theta);
      const ModelEvaluation e = kept ? *kept : [&] {
        try {
          return models[d]->evaluate(theta, true);
        } catch (const Interrupted& stop) {
          throw interrupted_fit(stop.signal());
        }
      }();
      if (!kept) forward_runs += e.forward_runs;
      const double factor = costs[d]->factor();
      DataSetFit out;
      out.model = e.values;
      double sum2 = 0.0, largest = 0.0;
      for (std::size_t i = 0; i < data.values.size(); ++i, ++row) {
        const double diff = e.values[i] - data.values[i];
        sum2 += diff * diff;
        largest = std::max(largest, std::abs(data.values[i]));
        r[row] = factor * diff;
        for (std::size_t j = 0; j < p; ++j) jacobian(row, static_cast<Eigen::Index>(j)) = factor * e.jacobian[i][j];
      }
      out.rms_residual = std::sqrt(sum2 / static_cast<double>(data.values.size()));
      out.rms_relative = out.rms_residual / largest;
      out.gradients = models[d]->uses_sensitivities() ? "forward sensitivities"
                                                       : "finite differences (" + models[d]->finite_difference_reason() + ")";
      out.fitted_case = models[d]->fitted_case(theta);
      out.contact_half_width_planned = models[d]->planned_contact_half_width();
      result.data.push_back(std::move(out));
      weight_sum += data.weight * data.weight;
    }
    result.values = theta;
    result.cost = 0.5 * r.squaredNorm();
    result.rms_relative = std::sqrt(r.squaredNorm() / weight_sum);

    // Relative sensitivities J diag(theta): what a 100% change of each combination does.
    Eigen::MatrixXd relative = jacobian;
    for (std::size_t j = 0; j < p; ++j) relative.col(static_cast<Eigen::Index>(j)) *= theta[j];
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(relative, Eigen::ComputeThinU | Eigen::ComputeThinV);
    const Eigen::VectorXd sigma = svd.singularValues();
    const Eigen::MatrixXd v = svd.matrixV();
    for (Eigen::Index k = 0; k < sigma.size(); ++k) result.singular_values.push_back(sigma[k]);
    const double smallest = sigma[sigma.size() - 1];
    result.condition_number = smallest > 0.0 ? sigma[0] / smallest : std::numeric_limits<double>::infinity();

    // Covariance s2 (J^T J)^-1, through the SVD: cov(ln theta) = s2 V S^-2 V^T.
    const double dof = static_cast<double>(m_total) - static_cast<double>(p);
    const double s2 = dof > 0.0 ? r.squaredNorm() / dof : std::numeric_limits<double>::quiet_NaN();
    fisher_jacobian = jacobian;
    fisher_s2 = s2;
    const Eigen::Index pp = static_cast<Eigen::Index>(p);
    Eigen::MatrixXd cov_log = Eigen::MatrixXd::Zero(pp, pp);
    for (Eigen::Index k = 0; k < sigma.size(); ++k) {
      const double inv2 = sigma[k] > 1e-14 * sigma[0] ? 1.0 / (sigma[k] * sigma[k]) : std::numeric_limits<double>::infinity();
      cov_log += s2 * inv2 * v.col(k) * v.col(k).transpose();
    }
    result.covariance = cov_log;
    for (Eigen::Index a = 0; a < pp; ++a)
      for (Eigen::Index b = 0; b < pp; ++b) result.covariance(a, b) *= theta[static_cast<std::size_t>(a)] * theta[static_cast<std::size_t>(b)];
    result.correlation = Eigen::MatrixXd::Identity(pp, pp);
    for (Eigen::Index a = 0; a < pp; ++a) {
      result.std_errors.push_back(std::sqrt(result.covariance(a, a)));
      for (Eigen::Index b = 0; b < pp; ++b)
        if (a != b) result.correlation(a, b) = result.covariance(a, b) / std::sqrt(result.covariance(a, a) * result.covariance(b, b));
    }

    // The model's own discretization error at the optimum: each data set again with twice its
    // contact nodes on the same planned contact width and element (one run, no gradients, at the
    // fitted parameters), Richardson's estimate e = P - P* at every data point, P* extrapolated
    // from the two.  Twice, not half (the runs' own companions): a fit's meshes are often coarse,
    // and below them the force is out of the asymptotic range (under a J2 cone at 10 contact
    // nodes the force at 5 lay nearer the converged one than at 10: Richardson on them said 0.6%
    // where the error was 4%; docs/verification.md).  Where the case cannot take twice the nodes
    // (mesh.max_unknowns), half is used.  The data are nature's (or a finer model's), so the
    // fit's optimum is shifted by what e does along the sensitivities:
    // theta_fit - theta_true = -(J^T J)^+ J^T e.
    // A path-dependent model (J2's flow history, friction's slip: depends_on_the_increments) also
    // carries the error of its increments: the same mesh with four times the increments,
    // Richardson of order 1 (the return map and the slip are backward Euler).  Four, not two:
    // under a J2 cone at 30 contact nodes the force at 0.75 um moved by 1.4%, 2.6% and 1.0% from
    // 20 to 40, 80 and 160 loading increments -- not yet first order, a doubling saw half the
    // error of 20 (docs/verification.md).  e is the sum of both shares; each is kept for the
    // refinement below.
    Eigen::VectorXd model_error = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(m_total));
    Eigen::VectorXd increments_error = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(m_total));
    result.model_error_estimated = true;
    row = 0;
    for (std::size_t d = 0; d < models.size(); ++d) {
      const std::size_t n = problem.data[d].values.size();
      const LoadCase fine_case = models[d]->case_at(theta);
      const int nodes = fine_case.mesh.contact_nodes;
      const auto companion = [&](int companion_nodes, int increments_factor) {
        FitData other = problem.data[d];
        other.load_case.mesh.contact_nodes = companion_nodes;
        other.load_case.load.multiply_increments(increments_factor);
        if (models[d]->planned_contact_half_width() > 0.0)  // a flat punch's is its radius
          other.load_case.mesh.contact_half_width = models[d]->planned_contact_half_width();
        other.load_case.mesh.element = fine_case.mesh.element;
        const ForwardModel model(std::move(other), parameters, bounds, true, theta);
        ModelEvaluation e = model.evaluate(theta, false);
        forward_runs += e.forward_runs;
        return e.values;
      };
      try {
        const double order = force_order_assumed(fine_case);
        std::vector<double> extrapolated(n);
        try {
          const std::vector<double> twice = companion(2 * nodes, level.increments_factor);
          for (std::size_t i = 0; i < n; ++i)
            extrapolated[i] = richardson(twice[i], result.data[d].model[i], 2.0, order).extrapolated;
        } catch (const InputError&) {  // twice the nodes exceed the case's mesh.max_unknowns
          if (nodes / 2 < 2) throw;
          const std::vector<double> half = companion(nodes / 2, level.increments_factor);
          const double ratio = static_cast<double>(nodes) / (nodes / 2);
          for (std::size_t i = 0; i < n; ++i)
            extrapolated[i] = richardson(result.data[d].model[i], half[i], ratio, order).extrapolated;
        }
        const Eigen::Index first_row = row;
        for (std::size_t i = 0; i < n; ++i, ++row)
          model_error[row] = costs[d]->factor() * (result.data[d].model[i] - extrapolated[i]);
        if (depends_on_the_increments(fine_case)) {
          const std::vector<double> finer = companion(nodes, 4 * level.increments_factor);
          for (std::size_t i = 0; i < n; ++i) {
            const double model_value = result.data[d].model[i];
            const Eigen::Index k = first_row + static_cast<Eigen::Index>(i);
            increments_error[k] =
                costs[d]->factor() * (model_value - richardson(finer[i], model_value, 4.0, 1.0).extrapolated);
            model_error[k] += increments_error[k];
          }
        }
      } catch (const Interrupted& stop) {
        throw interrupted_fit(stop.signal());
      } catch (const std::exception&) {
        result.model_error_estimated = false;  // no companion ran: the noise alone is reported
        row = 0;
        for (std::size_t k = 0; k <= d; ++k) row += static_cast<Eigen::Index>(problem.data[k].values.size());
      }
    }
    if (!result.model_error_estimated) {
      model_error.setZero();
      increments_error.setZero();
    }
    last_model_error = model_error;
    // -(J^T J)^+ J^T e in ln theta, through the SVD of J diag(theta): -V S^-1 U^T e.
    const auto shift_of = [&](const Eigen::VectorXd& error) {
      Eigen::VectorXd shift = Eigen::VectorXd::Zero(pp);
      const Eigen::MatrixXd u = svd.matrixU();
      for (Eigen::Index k = 0; k < sigma.size(); ++k)
        if (sigma[k] > 1e-14 * sigma[0]) shift -= (u.col(k).dot(error) / sigma[k]) * v.col(k);
      return shift;
    };
    const Eigen::VectorXd shift_log = shift_of(model_error);
    const Eigen::VectorXd increments_shift_log = shift_of(increments_error);
    result.increments_to_noise = 0.0;

    // Per parameter: the 95% interval of noise and model together, and the verdict.
    const double t = student_t975(dof);
    all_determined = true;
    for (std::size_t j = 0; j < p; ++j) {
      ParameterDetermination pd;
      pd.model_shift = shift_log[static_cast<Eigen::Index>(j)] * theta[j];
      pd.model_shift_increments = increments_shift_log[static_cast<Eigen::Index>(j)] * theta[j];
      if (result.std_errors[j] > 0.0)
        result.increments_to_noise =
            std::max(result.increments_to_noise, std::abs(pd.model_shift_increments) / result.std_errors[j]);
      pd.total_std_error = std::hypot(result.std_errors[j], pd.model_shift);
      pd.lower = theta[j] - t * pd.total_std_error;
      pd.upper = theta[j] + t * pd.total_std_error;
      pd.relative_half_width = theta[j] != 0.0 ? t * pd.total_std_error / std::abs(theta[j])
                                               : std::numeric_limits<double>::infinity();
      judge(j, pd);
      all_determined = all_determined && pd.determined;
      result.model_to_noise = std::max(result.model_to_noise, result.std_errors[j] > 0.0
                                                                  ? std::abs(pd.model_shift) / result.std_errors[j]
                                                                  : 0.0);
      result.determination.push_back(std::move(pd));
    }

    // The weakest combination, in words: scaled so that its largest component is 1%.
    const Eigen::VectorXd weak = v.col(pp - 1);
    for (Eigen::Index j = 0; j < pp; ++j) result.weakest_direction.push_back(weak[j]);
    weakest_in_words.clear();
    if (p > 1) {
      const Eigen::Index lead = [&] {
        Eigen::Index k = 0;
        weak.cwiseAbs().maxCoeff(&k);
        return k;
      }();
      const Eigen::VectorXd step = 0.01 * weak / weak[lead];
      std::string parts;
      for (Eigen::Index j = 0; j < pp; ++j) {
        if (j == lead || std::abs(step[j]) < 1e-4) continue;
        parts += fmt::format("{} {} {} by {}", parts.empty() ? "while" : " and", step[j] > 0 ? "raising" : "lowering",
                             key_of(problem.free[static_cast<std::size_t>(j)].parameter), percent(std::abs(step[j])));
      }
      std::string names = key_of(problem.free[static_cast<std::size_t>(lead)].parameter);
      for (Eigen::Index j = 0; j < pp; ++j)
        if (j != lead && std::abs(step[j]) >= 1e-4) names += " and " + key_of(problem.free[static_cast<std::size_t>(j)].parameter);
      weakest_in_words = fmt::format(
          "{} trade off: raising {} by 1% {} changes the fit to the data by only {} (weighted rms, relative to each data "
          "set's largest value); condition number {:.3g}",
          names, key_of(problem.free[static_cast<std::size_t>(lead)].parameter), parts.empty() ? "alone" : parts,
          percent((relative * step).norm() / std::sqrt(weight_sum)), result.condition_number);
    }

  };
  assess(*fine, theta);

  struct Profile {
    bool found = false;
    std::vector<std::pair<double, double>> samples[2];  // (distance, cost - best) below and above
    double bound[2] = {0.0, 0.0};                       // the bounds below and above
    double room[2] = {0.0, 0.0};                        // their distances from the optimum sampled about
  };
  std::vector<Profile> profiles(p);
  // The profile likelihood of each parameter, on the fit's own meshes before any refinement for
  // the model's error (the noise's profile hardly depends on the mesh; there a run costs a fifth
  // to an eighth): held at trial values on each side, the others optimised, until the cost has
  // risen by t^2 s2 / 2 (the likelihood ratio at 95%; the linearized interval where the model is
  // linear).  Trials are placed by the profile's quadratic growth, (cost - best) ~ h^2.  The
  // samples are kept; the crossings are found from them with the final meshes' s2 (the misfit of
  // the meshes before refinement holds more of the model's error than the noise's) and applied
  // about the final optimum, combined with t model_shift in quadrature.  A fit that is poor
  // already (misfit, a parameter at a bound) is not profiled.
  const bool poor_already = [&] {
    for (const DataSetFit& d : result.data)
      if (!(d.rms_relative <= poor_fit_rms_limit)) return true;
    for (std::size_t j = 0; j < p; ++j)
      if (theta[j] <= problem.free[j].lower || theta[j] >= problem.free[j].upper) return true;
    return false;
  }();
  if (problem.settings.profile && !poor_already) {
    const double dof = static_cast<double>(m_total) - static_cast<double>(p);
    const double best_cost = result.cost;
    const double s2 = dof > 0.0 ? 2.0 * best_cost / dof : 0.0;
    const double t = student_t975(dof);
    const double rise = 0.5 * t * t * s2;
    const std::vector<double> optimum = theta;
    constexpr int profile_iterations = 20;
    if (rise > 0.0 && std::isfinite(rise)) {
      // The 2p sides are independent (each starts from the optimum): they run side by side.
      struct Side {
        std::vector<std::pair<double, double>> samples;
        double bound = 0.0, room = 0.0;
        bool failed = false;
      };
      std::vector<Side> sides(2 * p);
      const auto trace_side = [&](std::size_t j, int side, const Costs& costs) {
        const FreeParameter& f = problem.free[j];
        Side& found = sides[2 * j + static_cast<std::size_t>(side)];
        const double sign = side == 0 ? -1.0 : 1.0;
        const double bound = side == 0 ? f.lower : f.upper;
        const double room = std::abs(bound - optimum[j]);
        found.bound = bound;
        found.room = room;
        double h = t * result.std_errors[j];
        if (!(h > 0.0) || !std::isfinite(h)) h = 0.1 * std::abs(optimum[j]);
        if (!(h > 0.0)) {
          found.failed = true;  // nothing to scale a trial by: the linearized interval stands
          return;
        }
        int trial = 0;
        // Each trial starts where the linearized model puts the others for that value of this
        // one (the conditional mean, theta_k + cov_kj / cov_jj delta): on the valley, so that
        // Levenberg-Marquardt needs an iteration or two.  A trial that does not converge is no
        // profile value (its cost is above the profile's) and is not kept.
        const auto profile_at = [&](double distance) {
          std::vector<double> start = optimum;
          const double delta = sign * distance;
          const double cjj = result.covariance(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(j));
          for (std::size_t k = 0; k < p; ++k) {
            if (k == j || !(cjj > 0.0) || !std::isfinite(cjj)) continue;
            const double ckj = result.covariance(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(j));
            if (std::isfinite(ckj))
              start[k] = std::clamp(optimum[k] + ckj / cjj * delta, problem.free[k].lower, problem.free[k].upper);
          }
          start[j] = distance >= room ? bound : optimum[j] + delta;  // exactly on the bound: feasible
          ++trial;
          const int index = 1000 * static_cast<int>(j + 1) + 100 * side + trial;
          const StartOutcome o = solve_from(costs, "profile", start, index, profile_iterations, static_cast<int>(j));
          if (interruption_requested() || !std::isfinite(o.cost) || !o.converged)
            return std::numeric_limits<double>::quiet_NaN();
          found.samples.emplace_back(distance, o.cost - best_cost);
          return o.cost - best_cost;
        };
        // With p = 1 the "profile" is the cost itself: a solve with its only parameter held
        // evaluates it.  A trial's excess predicts the crossing at distance sqrt(rise / excess).
        double distance = std::min(h, room), excess = profile_at(distance);
        for (int widening = 0; std::isfinite(excess) && excess < rise && distance < room && widening < 4; ++widening) {
          distance = std::min(room, excess > 0.0 ? 1.2 * distance * std::sqrt(rise / excess) : 2.0 * distance);
          excess = profile_at(distance);
        }
        if (!std::isfinite(excess)) {
          found.failed = true;
          return;
        }
        if (excess > 2.0 * rise)  // far past the crossing: a trial at the prediction brackets it
          profile_at(distance * std::sqrt(rise / excess));
      };
      side_by_side(*fine, forward_runs, static_cast<int>(2 * p), [&](int k, const Costs& costs) {
        trace_side(static_cast<std::size_t>(k) / 2, k % 2, costs);
      });
      stop_if_interrupted();
      for (std::size_t j = 0; j < p; ++j) {
        const Side& below = sides[2 * j];
        const Side& above = sides[2 * j + 1];
        if (below.failed || above.failed) continue;  // the linearized interval stands
        Profile found;
        found.found = true;
        found.samples[0] = below.samples;
        found.samples[1] = above.samples;
        found.bound[0] = below.bound;
        found.bound[1] = above.bound;
        found.room[0] = below.room;
        found.room[1] = above.room;
        profiles[j] = std::move(found);
      }
    }
  }

  // The model's error beyond the noise's: the forward meshes refined (twice the contact nodes,
  // planned at the optimum) and the optimum polished there, up to settings.mesh_refinements times.
  // A path-dependent model's increments are doubled instead, or as well, where their share of the
  // shift is at least half of it (the mesh likewise).
  double nodes_factor = 1.0;
  while (result.model_to_noise > 1.0 && result.mesh_refinements < problem.settings.mesh_refinements) {
    double mesh_to_noise = 0.0;
    for (std::size_t j = 0; j < p; ++j)
      if (result.std_errors[j] > 0.0)
        mesh_to_noise = std::max(mesh_to_noise, std::abs(result.determination[j].model_shift -
                                                         result.determination[j].model_shift_increments) /
                                                    result.std_errors[j]);
    const bool finer_mesh = mesh_to_noise >= 0.5 * result.model_to_noise;
    const bool more_increments = result.increments_to_noise >= 0.5 * result.model_to_noise;
    const double factor = finer_mesh ? 2.0 * nodes_factor : nodes_factor;
    const int increments = more_increments ? 2 * fine->increments_factor : fine->increments_factor;
    const std::string what = fmt::format("{}{}{}", finer_mesh ? fmt::format("{} times the contact nodes", factor) : "",
                                         finer_mesh && more_increments ? ", " : "",
                                         more_increments ? fmt::format("{} times the increments", increments) : "");
    std::optional<Level> refined;
    try {
      refined = make_level(factor, theta, forward_runs, increments);
    } catch (const InputError& e) {  // a refinement the case cannot take (mesh.max_unknowns): the answer stands
      warn(fmt::format("the forward model could not be refined for its own error ({}): {}", what, e.what()));
      break;
    } catch (const SolverError& e) {
      warn(fmt::format("the forward model could not be refined for its own error (its planning run with {} failed): {}",
                       what, e.what()));
      break;
    }
    StartOutcome polished =
        solve_from(refined->costs, "refined", theta, result.mesh_refinements + 1, problem.settings.max_iterations);
    stop_if_interrupted();
    const bool usable = std::isfinite(polished.cost);
    result.starts.push_back(std::move(polished));
    if (!usable) {  // the refined meshes found nothing: the last level's answer stands
      warn(fmt::format("the polish on the forward model refined for its own error ({}) found no successful run: the "
                       "answer of the model before stands",
                       what));
      break;
    }
    ++result.mesh_refinements;
    nodes_factor = factor;
    result.increments_factor = increments;
    theta = result.starts.back().result;
    result.selected_start = result.starts.size() - 1;
    fine = std::move(*refined);
    assess(*fine, theta);
  }
  // Where the model's error still exceeds the noise, its shift along the sensitivities is a
  // linearization far from where it holds: along a curved valley (a J2 cone's sigma_y against n)
  // a shift of several standard errors bends with it.  The converged model's optimum, to the
  // estimate's accuracy, is found instead: the same fit with e taken off the model (residuals
  // r - e, e held at its value at the optimum), started from the optimum; each parameter's
  // model_shift is then its distance from there (the increments' share scaled with it).
  if (result.model_error_estimated && result.model_to_noise > 1.0 &&
      last_model_error.size() == static_cast<Eigen::Index>(m_total)) {
    Eigen::Index first = 0;
    for (std::size_t d = 0; d < fine->costs.size(); ++d) {
      const Eigen::Index n = static_cast<Eigen::Index>(problem.data[d].values.size());
      fine->costs[d]->set_offset(std::vector<double>(last_model_error.data() + first, last_model_error.data() + first + n));
      first += n;
    }
    const StartOutcome corrected = solve_from(fine->costs, "corrected", theta, 0, problem.settings.max_iterations);
    for (const auto& c : fine->costs) c->set_offset({});
    stop_if_interrupted();
    if (std::isfinite(corrected.cost)) {
      const double t = student_t975(static_cast<double>(m_total) - static_cast<double>(p));
      result.corrected_values = corrected.result;
      result.model_to_noise = 0.0;
      for (std::size_t j = 0; j < p; ++j) {
        ParameterDetermination& pd = result.determination[j];
        const double linearized = pd.model_shift;
        pd.model_shift = theta[j] - corrected.result[j];
        pd.model_shift_increments = linearized != 0.0 ? pd.model_shift_increments * pd.model_shift / linearized : 0.0;
        pd.total_std_error = std::hypot(result.std_errors[j], pd.model_shift);
        pd.lower = theta[j] - t * pd.total_std_error;
        pd.upper = theta[j] + t * pd.total_std_error;
        judge(j, pd);
        if (result.std_errors[j] > 0.0)
          result.model_to_noise = std::max(result.model_to_noise, std::abs(pd.model_shift) / result.std_errors[j]);
      }
    }
  }
  // The crossings at the final s2, between the farthest sample within the noise (the optimum
  // itself, (0, 0), at least) and the nearest beyond it, where sqrt(cost - best) grows about
  // linearly with the distance; none beyond: open at the bound if a sample reached it, else
  // extrapolated from the farthest one.
  {
    const double dof = static_cast<double>(m_total) - static_cast<double>(p);
    const double t = student_t975(dof);
    const double rise = dof > 0.0 ? 0.5 * t * t * (2.0 * result.cost / dof) : 0.0;
    for (std::size_t j = 0; j < p && rise > 0.0 && std::isfinite(rise); ++j) {
      if (!profiles[j].found) continue;
      double reach[2] = {0.0, 0.0};
      bool open_side[2] = {false, false};
      for (int side = 0; side < 2; ++side) {
        std::pair<double, double> within{0.0, 0.0};
        const std::pair<double, double>* beyond = nullptr;
        for (const auto& sample : profiles[j].samples[side]) {
          if (sample.second < rise && sample.first > within.first) within = sample;
          if (sample.second >= rise && (!beyond || sample.first < beyond->first)) beyond = &sample;
        }
        const double room = std::abs(profiles[j].bound[side] - theta[j]);
        if (beyond && beyond->first > within.first) {
          const double a = std::sqrt(std::max(within.second, 0.0)), b = std::sqrt(beyond->second);
          const double crossing = within.first + (std::sqrt(rise) - a) / (b - a) * (beyond->first - within.first);
          reach[side] = std::min(room, std::clamp(crossing, within.first, beyond->first));
        } else {
          // Within the noise as far as sampled: open if that reached the bound the profile had.
          const bool reached_bound = within.first > 0.0 && within.first >= 0.999 * profiles[j].room[side];
          if (reached_bound || !(within.second > 0.0)) {
            reach[side] = room;
            open_side[side] = true;
          } else {
            reach[side] = std::min(room, within.first * std::sqrt(rise / within.second));
            open_side[side] = reach[side] >= room;
          }
        }
      }
      ParameterDetermination& pd = result.determination[j];
      pd.profiled = true;
      pd.profile_open = open_side[0] || open_side[1];
      pd.profile_lower = open_side[0] ? problem.free[j].lower : theta[j] - reach[0];
      pd.profile_upper = open_side[1] ? problem.free[j].upper : theta[j] + reach[1];
      const double model = t * std::abs(pd.model_shift);
      // An open side ends at its bound: the data say nothing of what lies beyond it.
      pd.lower = open_side[0] ? problem.free[j].lower : theta[j] - std::hypot(reach[0], model);
      pd.upper = open_side[1] ? problem.free[j].upper : theta[j] + std::hypot(reach[1], model);
      judge(j, pd);
    }
  }
  all_determined = std::all_of(result.determination.begin(), result.determination.end(),
                               [](const ParameterDetermination& d) { return d.determined; });

  // Other starts that ended elsewhere at a cost the data cannot tell from the best's (a
  // likelihood-ratio test at 95% on their own meshes: 2 (cost - best) / s2 below chi2(p)) belong to
  // the answer: a flat valley, or a second minimum.  Each parameter's interval is widened to hold
  // them, and a warning names them.
  {
    const double chi2_95[] = {3.841, 5.991, 7.815, 9.488, 11.07, 12.59};
    const double chi2 = chi2_95[std::min<std::size_t>(p, 6) - 1];
    const double dof_points = static_cast<double>(m_total) - static_cast<double>(p);
    std::vector<std::string> others;
    std::vector<bool> widened(p, false);
    for (const std::string phase : {"coarse", "fine"}) {
      // The best of this very phase: its starts ran on the same meshes (a polish or a refinement
      // did not).
      std::size_t best = result.starts.size();
      for (std::size_t k = 0; k < result.starts.size(); ++k)
        if (result.starts[k].phase == phase && std::isfinite(result.starts[k].cost) &&
            (best == result.starts.size() || result.starts[k].cost < result.starts[best].cost))
          best = k;
      if (best == result.starts.size() || !(dof_points > 0.0)) continue;
      const StartOutcome& b = result.starts[best];
      const double s2 = 2.0 * b.cost / dof_points;
      for (const StartOutcome& o : result.starts) {
        if (&o == &b || o.phase != b.phase || !std::isfinite(o.cost)) continue;
        if (!(2.0 * (o.cost - b.cost) <= chi2 * s2)) continue;
        // Elsewhere: outside the best's own 95% interval in some parameter (on its own meshes the
        // same offset; the offset is what matters).
        bool elsewhere = false;
        for (std::size_t j = 0; j < p; ++j) {
          const ParameterDetermination& pd = result.determination[j];
          if (std::abs(o.result[j] - b.result[j]) > (pd.upper - pd.lower) / 2.0) elsewhere = true;
        }
        if (!elsewhere) continue;
        std::string values;
        for (std::size_t j = 0; j < p; ++j) {
          // The other end, moved by the offset between the two phases' optima, within the bounds.
          const double other = std::clamp(theta[j] + (o.result[j] - b.result[j]), problem.free[j].lower,
                                          problem.free[j].upper);
          ParameterDetermination& pd = result.determination[j];
          if (other < pd.lower || other > pd.upper) {
            pd.lower = std::min(pd.lower, other);
            pd.upper = std::max(pd.upper, other);
            widened[j] = true;
          }
          values += fmt::format("{}{} = {:.4g}", values.empty() ? "" : ", ", key_of(problem.free[j].parameter), o.result[j]);
        }
        others.push_back(fmt::format("{} (cost {:.4g} against {:.4g}, on the {} meshes)", values, o.cost, b.cost, phase));
      }
    }
    if (!others.empty()) {
      for (std::size_t j = 0; j < p; ++j) {
        if (!widened[j]) continue;
        ParameterDetermination& pd = result.determination[j];
        judge(j, pd);
        pd.verdict += "; distinct starts end within noise of the best cost across it";
      }
      all_determined = std::all_of(result.determination.begin(), result.determination.end(),
                                   [](const ParameterDetermination& d) { return d.determined; });
      std::string list;
      for (const auto& o : others) list += "; " + o;
      warn(fmt::format("distinct starts ended at distinct points of a cost the data cannot tell from the best's{}: the "
                       "valley between them is part of the answer (the intervals are widened to hold it)",
                       list));
    }
  }
  result.poorly_determined = all_determined ? std::string() : weakest_in_words;

  if (result.model_to_noise > 1.0) {
    int nodes = 0;
    for (const auto& m : fine->models) nodes = std::max(nodes, m->case_at(theta).mesh.contact_nodes);
    warn(fmt::format("the forward model's own discretization error moves the fitted parameters by up to {:.2g} times "
                     "their noise's standard error (its increments' share {:.2g}) after {} refinement(s) of the forward "
                     "model (now {} contact nodes{}; fit.mesh_refinements allows {}): the intervals include it",
                     result.model_to_noise, result.increments_to_noise, result.mesh_refinements, nodes,
                     result.increments_factor > 1 ? fmt::format(", {} times the increments", result.increments_factor) : "",
                     problem.settings.mesh_refinements));
  }

  // The experiment that would determine what this data does not: candidate additions to the
  // data, each evaluated once with its sensitivities at the optimum, and the noise-only interval
  // of the data and the addition together, s2 (J^T J + Ja^T Ja)^-1 (the addition's rows scaled
  // as a data set's, 20 points, with the data's relative noise).  Fisher's information adds.
  const auto design_experiments = [&](const std::vector<std::unique_ptr<ForwardModel>>& models, bool additions) {
    const double dof = static_cast<double>(m_total) - static_cast<double>(p);
    if (!(fisher_s2 > 0.0) || !(dof > 0.0)) return;
    const double t_now = student_t975(dof);
    // In ln theta (J diag(theta)): the parameters' scales differ by 1e9 (sigma_y against n), which
    // a rank-revealing inverse would read as a rank deficiency.
    Eigen::MatrixXd relative_jacobian = fisher_jacobian;
    for (std::size_t j = 0; j < p; ++j) relative_jacobian.col(static_cast<Eigen::Index>(j)) *= theta[j];
    const Eigen::MatrixXd information = relative_jacobian.transpose() * relative_jacobian;
    const Eigen::MatrixXd today = information.completeOrthogonalDecomposition().pseudoInverse();
    for (std::size_t j = 0; j < p; ++j) {
      const double var = fisher_s2 * today(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(j));
      result.noise_relative_half_width.push_back(t_now * std::sqrt(std::max(var, 0.0)));
    }
    if (!additions) return;
    // The reference data set: the first force-depth curve.
    std::size_t base = problem.data.size();
    for (std::size_t d = 0; d < problem.data.size(); ++d)
      if (problem.data[d].kind == FitDataKind::force_depth_curve) {
        base = d;
        break;
      }
    if (base == problem.data.size()) return;
    const FitData& data = problem.data[base];
    const double deepest = *std::max_element(data.abscissa.begin(), data.abscissa.end());
    bool unloads = false, has_imprint = false;
    double reached = 0.0;
    for (double a : data.abscissa) {
      unloads = unloads || a < reached * (1.0 - 1e-9);
      reached = std::max(reached, a);
    }
    std::set<PunchShapeKind> shapes;
    for (const FitData& d : problem.data) {
      has_imprint = has_imprint || d.kind == FitDataKind::imprint_profile;
      shapes.insert(d.load_case.punch.shape);
    }
    LoadCase at = data.load_case;
    for (std::size_t j = 0; j < p; ++j) set_value(at, parameters[j], theta[j]);
    const int points = 20;
    const auto spaced = [&](double from, double to, int n) {
      std::vector<double> x;
      for (int k = 0; k < n; ++k) x.push_back(from + (to - from) * (n == 1 ? 1.0 : static_cast<double>(k) / (n - 1)));
      return x;
    };
    const auto loading = [&](double depth) { return spaced(depth / points, depth, points); };
    struct Candidate {
      CandidateExperiment report;
      FitData data;
    };
    std::vector<Candidate> candidates;
    const auto add = [&](std::string name, std::string description, LoadCase lc, FitDataKind kind,
                         std::vector<double> abscissa, bool replan) {
      Candidate c;
      c.report.name = std::move(name);
      c.report.description = std::move(description);
      if (replan) lc.mesh.contact_half_width.reset();
      c.data.kind = kind;
      c.data.file = c.report.name;
      c.data.load_case = std::move(lc);
      c.data.abscissa = std::move(abscissa);
      c.data.values.assign(c.data.abscissa.size(), 0.0);
      candidates.push_back(std::move(c));
    };
    const double step = at.max_depth() / std::max(1, at.load.total_increments());
    const auto with_path = [&](LoadCase lc, std::vector<double> path) {
      double length = 0.0;
      for (std::size_t k = 1; k < path.size(); ++k) length += std::abs(path[k] - path[k - 1]);
      lc.load.path = std::move(path);
      lc.load.segment_increments.clear();
      lc.load.increments = std::max(1, static_cast<int>(std::ceil(length / step - 1e-9)));
      return lc;
    };
    if (!unloads)
      add("unloading branch", fmt::format("unloading from the deepest depth {:.3g} m to {:.3g} m, {} points", deepest,
                                          0.9 * deepest, points),
          with_path(at, {0.0, deepest, 0.9 * deepest}), FitDataKind::force_depth_curve,
          spaced(deepest, 0.9 * deepest, points), false);
    add("deeper indent", fmt::format("the same indenter to {:.3g} m (twice as deep), {} points", 2.0 * deepest, points),
        with_path(at, {0.0, 2.0 * deepest}), FitDataKind::force_depth_curve, loading(2.0 * deepest), true);
    if (!shapes.count(PunchShapeKind::sphere)) {
      LoadCase sphere = with_path(at, {0.0, deepest});
      sphere.punch = PunchInput{};
      sphere.punch.shape = PunchShapeKind::sphere;
      sphere.punch.radius = 20.0 * deepest;  // the depth 5% of the radius: small strain's range
      add("sphere", fmt::format("a sphere of radius {:.3g} m to {:.3g} m, {} points", sphere.punch.radius, deepest, points),
          sphere, FitDataKind::force_depth_curve, loading(deepest), true);
    }
    // A calibrated tip's area function is a cone beyond its rounding (sharp_tip): a sharper cone adds more.
    if (!shapes.count(PunchShapeKind::cone) && !shapes.count(PunchShapeKind::area_function)) {
      LoadCase cone = with_path(at, {0.0, deepest});
      cone.punch = PunchInput{};
      cone.punch.shape = PunchShapeKind::cone;
      cone.punch.half_angle = 70.3;  // the Berkovich pyramid's equivalent cone
      add("cone", fmt::format("a 70.3 degree cone (Berkovich's equivalent) to {:.3g} m, {} points", deepest, points), cone,
          FitDataKind::force_depth_curve, loading(deepest), true);
    } else {
      LoadCase sharp = with_path(at, {0.0, deepest});
      sharp.punch = PunchInput{};
      sharp.punch.shape = PunchShapeKind::cone;
      sharp.punch.half_angle = 42.3;  // the cube corner's equivalent cone
      add("sharper cone", fmt::format("a 42.3 degree cone (the cube corner's equivalent) to {:.3g} m, {} points", deepest,
                                      points),
          sharp, FitDataKind::force_depth_curve, loading(deepest), true);
    }
    if (!has_imprint) {
      const double a = models[base]->planned_contact_half_width();
      std::vector<double> radii = spaced(0.0, std::min(2.0 * a, 0.9 * at.geometry.lx), 12);
      add("imprint profile",
          fmt::format("the residual imprint after unloading from {:.3g} m to 0, 12 radii to {:.3g} m", deepest, radii.back()),
          with_path(at, {0.0, deepest, 0.0}), FitDataKind::imprint_profile, radii, false);
    }
    // The candidates are independent runs: side by side, reported in their order.
    parallel_for(static_cast<int>(candidates.size()), [&](int, int k) {
      Candidate& c = candidates[static_cast<std::size_t>(k)];
      try {
        const ForwardModel model(c.data, parameters, bounds, problem.settings.finite_differences, theta);
        const ModelEvaluation e = model.evaluate(theta, true);
        forward_runs += e.forward_runs;
        double peak = 0.0;
        for (double v : e.values) peak = std::max(peak, std::abs(v));
        if (!(peak > 0.0)) throw SolverError("the addition measures nothing at the fitted parameters");
        // Rows scaled as the reference data set's (weight over sqrt of its points), so that each
        // carries the same noise in residual units and s2 applies: the addition is measured with
        // the data's relative noise, row for row.
        const double factor =
            data.weight / (peak * std::sqrt(static_cast<double>(data.values.size())));
        Eigen::MatrixXd added(static_cast<Eigen::Index>(e.values.size()), static_cast<Eigen::Index>(p));
        for (std::size_t i = 0; i < e.values.size(); ++i)
          for (std::size_t j = 0; j < p; ++j)
            added(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = factor * e.jacobian[i][j] * theta[j];
        const Eigen::MatrixXd inverse =
            (information + added.transpose() * added).completeOrthogonalDecomposition().pseudoInverse();
        const double t_then = student_t975(dof + static_cast<double>(e.values.size()));
        for (std::size_t j = 0; j < p; ++j) {
          const double var = fisher_s2 * inverse(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(j));
          const double predicted = t_then * std::sqrt(std::max(var, 0.0));
          c.report.relative_half_width.push_back(predicted);
          c.report.shrink.push_back(predicted > 0.0 ? result.noise_relative_half_width[j] / predicted
                                                    : std::numeric_limits<double>::infinity());
        }
      } catch (const Interrupted& stop) {
        throw interrupted_fit(stop.signal());
      } catch (const std::exception& failure) {  // a candidate the scene cannot make: said, not fatal
        c.report.failure = failure.what();
      }
    });
    stop_if_interrupted();
    for (Candidate& c : candidates) result.experiment_design.push_back(std::move(c.report));
  };

  // The verdict: a misfit beyond poor_fit_rms_limit, or a parameter at a bound, is a poor fit.
  for (std::size_t d = 0; d < result.data.size(); ++d) {
    const double misfit = result.data[d].rms_relative;
    if (misfit <= poor_fit_rms_limit) continue;  // NaN (no data) fails too
    const FitData& data = problem.data[d];
    result.quality_problems.push_back(
        fmt::format("{}rms {} of the {}",
                    problem.data.size() > 1 ? fmt::format("data set {} ({}): ", d + 1, data.file) : "",
                    percent(misfit),
                    values_are_forces(data)                       ? "peak force"
                    : data.kind == FitDataKind::imprint_profile ? "deepest imprint depth"
                                                                : "largest depth"));
  }
  for (std::size_t j = 0; j < p; ++j) {
    const FreeParameter& f = problem.free[j];
    const auto at = [&](double bound) {
      const double width = f.upper - f.lower;
      const double measure = bound != 0.0 ? std::min(std::abs(bound), width) : width;
      return std::abs(theta[j] - bound) <= at_bound_tolerance * measure;
    };
    if (at(f.lower) || at(f.upper))
      result.quality_problems.push_back(fmt::format("{} at its {} bound {:g}", key_of(f.parameter),
                                                    at(f.lower) ? "lower" : "upper", at(f.lower) ? f.lower : f.upper));
  }
  if (!result.good()) {
    result.quality = "poor fit";
    for (std::size_t k = 0; k < result.quality_problems.size(); ++k)
      result.quality += (k == 0 ? ": " : "; ") + result.quality_problems[k];
  }
  result.identifiable = all_determined && result.good();
  design_experiments(fine->models, problem.settings.design_experiments && result.good());
  result.failed_runs = failures.runs;
  result.refused_evaluations = failures.refused;
  result.forward_runs = forward_runs;
  result.coarse_runs = coarse_runs;
  result.iterations = finished_iterations;
  result.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count();
  return result;
}

}  // namespace indentsim
