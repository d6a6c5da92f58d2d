#include "indentsim/fitting/forward_model.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include <Eigen/QR>
#include <fmt/format.h>

#include "indentsim/base/error.hpp"
#include "indentsim/base/file_system.hpp"
#include "indentsim/simulation/load_stepping.hpp"
#include "indentsim/simulation/run_configuration.hpp"
#include "indentsim/simulation/simulation.hpp"

namespace indentsim {

namespace {

// Relative step of the one-sided finite differences: large against the Newton tolerance's noise
// in P (1e-11 of the scene's forces), small against the curvature of P(theta).  A Gauss point
// crossing the elastic limit inside the step changes d ln P / d ln theta by about 1e-5 at a step
// of 1e-4 (tests/test_sensitivity.cpp): negligible for the optimiser.
constexpr double finite_difference_step = 1e-5;

/// Where x0 falls in x (increasing): y(x0) = (1 - t) y[lower] + t y[lower + 1] (t = 0 at the last
/// point), or nullopt outside [x.front(), x.back()].
struct Bracket {
  std::size_t lower = 0;
  double t = 0.0;
  template <class Values>
  double operator()(const Values& y) const {
    return t == 0.0 ? y[lower] : (1.0 - t) * y[lower] + t * y[lower + 1];
  }
};

std::optional<Bracket> bracket(const std::vector<double>& x, double x0) {
  if (x.empty() || x0 < x.front() || x0 > x.back()) return std::nullopt;
  const auto it = std::upper_bound(x.begin(), x.end(), x0);
  if (it == x.end()) return Bracket{x.size() - 1, 0.0};
  const std::size_t k = static_cast<std::size_t>(it - x.begin());
  if (k == 0) return Bracket{0, 0.0};
  return Bracket{k - 1, (x0 - x[k - 1]) / (x[k] - x[k - 1])};
}

/// The value at x0 of a curve given by rows (x, y) sorted by x, as reduce_to_resolution() takes
/// it: a least-squares quadratic through the rows within `half_width` of x0 where there are at
/// least 5 (linear, or their mean, should their depths not span one), else linear interpolation
/// between the rows around x0; nullopt when x0 lies outside the rows' depths.
std::optional<double> local_value(const std::vector<double>& x, const std::vector<double>& y, double x0,
                                  double half_width) {
  if (x.empty() || x0 < x.front() || x0 > x.back()) return std::nullopt;
  const auto first = std::lower_bound(x.begin(), x.end(), x0 - half_width);
  const auto last = std::upper_bound(x.begin(), x.end(), x0 + half_width);
  const auto m = static_cast<Eigen::Index>(last - first);
  if (m >= 5) {
    const auto offset = static_cast<std::size_t>(first - x.begin());
    Eigen::MatrixXd A(m, 3);
    Eigen::VectorXd b(m);
    for (Eigen::Index i = 0; i < m; ++i) {
      const double u = (x[offset + static_cast<std::size_t>(i)] - x0) / half_width;
      A(i, 0) = 1.0;
      A(i, 1) = u;
      A(i, 2) = u * u;
      b[i] = y[offset + static_cast<std::size_t>(i)];
    }
    for (const Eigen::Index columns : {3, 2}) {
      Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A.leftCols(columns));
      qr.setThreshold(1e-10);
      if (qr.rank() == columns) return qr.solve(b)[0];
    }
    return b.mean();  // a hold: the rows at one depth
  }
  if (x0 == x.back()) return y.back();
  const std::size_t k = static_cast<std::size_t>(std::upper_bound(x.begin(), x.end(), x0) - x.begin());
  const double t = x[k] > x[k - 1] ? (x0 - x[k - 1]) / (x[k] - x[k - 1]) : 0.5;
  return (1.0 - t) * y[k - 1] + t * y[k];
}

}  // namespace

bool values_are_forces(const FitData& data) {
  return data.kind == FitDataKind::force_depth_curve ||
         (data.kind == FitDataKind::time_history && data.load_case.load.control == LoadControlKind::depth);
}

void refuse_unfittable_load(const LoadCase& lc, FitDataKind kind) {
  if (kind == FitDataKind::time_history) {
    if (lc.load.times.empty())
      throw InputError(lc.source, "load.times",
                       "a time history (a curve read with its time column) is fitted along the case's protocol in "
                       "time: give load.times beside load.path");
    return;
  }
  // A curve is run along the data's own depths under depth control, an imprint after the case's
  // path without time (docs/MODEL.md §13.6).
  if (kind == FitDataKind::imprint_profile) {
    const char* key = lc.load.control == LoadControlKind::force ? "load.control"
                      : lc.material.rate != RateLaw::none     ? "material.rate"
                      : !lc.load.times.empty()                ? "load.times"
                                                              : nullptr;
    if (key)
      throw InputError(lc.source, key,
                       "an imprint is fitted after the case's depth-controlled path without time (an imprint after a "
                       "protocol in time is not built): fit the protocol's curve as a time history instead");
    return;
  }
  const char* as_history = "give the curve's time column (--time-column, or time_column in [[data]]) and load.times "
                           "beside load.path: the fit then follows the protocol in time";
  if (lc.load.control == LoadControlKind::force)
    throw InputError(lc.source, "load.control",
                     fmt::format("a force-depth curve without time is fitted along the data's depths under depth "
                                 "control: {} (a rate-independent material's P(alpha) does not depend on the control, "
                                 "so load.control = \"depth\" fits the same curve)",
                                 as_history));
  if (lc.material.rate != RateLaw::none)
    throw InputError(lc.source, "material.rate",
                     fmt::format("a rate-dependent material's response depends on time, not on the depth alone: {}",
                                 as_history));
  if (!lc.load.times.empty())
    throw InputError(lc.source, "load.times",
                     "a force-depth curve without time is fitted along the data's depths, not along the case's path "
                     "in time: give the curve's time column (--time-column, or time_column in [[data]]) to fit it as "
                     "a time history, or leave load.times out");
}

namespace {

/// A time history of more than two rows per increment of the case's protocol, as one point at the
/// end of each increment within the data's times (reduce_to_resolution).
CurveReduction reduce_time_history(FitData& data) {
  CurveReduction r;
  r.rows = r.points = data.abscissa.size();
  const LoadInput& load = data.load_case.load;
  const std::vector<double> times = plan_times(load);
  if (times.size() < 2 || data.abscissa.size() <= 2 * (times.size() - 1)) return r;
  // Each increment's point from the rows of its own protocol segment: a window across a corner of
  // the protocol (the peak, a hold's start) would round the corner off.
  const std::vector<int> per_segment = segment_increments(load);
  std::vector<double> t, value;
  std::size_t k = 0;
  for (std::size_t s = 0; s < per_segment.size(); ++s) {
    const auto first = std::lower_bound(data.abscissa.begin(), data.abscissa.end(), load.times[s]);
    const auto last = std::upper_bound(data.abscissa.begin(), data.abscissa.end(), load.times[s + 1]);
    const std::vector<double> x(first, last);
    const std::vector<double> y(data.values.begin() + (first - data.abscissa.begin()),
                                data.values.begin() + (last - data.abscissa.begin()));
    for (int i = 0; i < per_segment[s]; ++i) {
      ++k;
      const double half_width = 0.5 * (times[k] - times[k - 1]);
      if (const auto v = local_value(x, y, times[k], half_width)) {
        t.push_back(times[k]);
        value.push_back(*v);
      }
    }
  }
  if (t.empty() || t.size() >= data.abscissa.size()) return r;
  r.reduced = true;
  r.points = t.size();
  r.branches = static_cast<int>(load.path.size()) - 1;
  data.rows = data.abscissa.size();
  data.abscissa = std::move(t);
  data.values = std::move(value);
  r.note = fmt::format(
      "{}: {} rows of the time history fitted as {} points, one at the end of each increment of the case's protocol "
      "({} increments over {:.4g} s), each a local quadratic in time through the rows within half an increment; raise "
      "load.increments to fit more points",
      data.file, r.rows, r.points, times.size() - 1, load.times.back() - load.times.front());
  return r;
}

/// The protocol's target at time t (linear in time along each segment, as the run steps it).
double target_at(const LoadInput& load, double t) {
  const auto it = std::upper_bound(load.times.begin(), load.times.end(), t);
  if (it == load.times.begin()) return load.path.front();
  if (it == load.times.end()) return load.path.back();
  const auto k = static_cast<std::size_t>(it - load.times.begin());
  const double s = (t - load.times[k - 1]) / (load.times[k] - load.times[k - 1]);
  return load.path[k - 1] + s * (load.path[k] - load.path[k - 1]);
}

}  // namespace

CurveReduction reduce_to_resolution(FitData& data) {
  if (data.kind == FitDataKind::time_history) return reduce_time_history(data);
  CurveReduction r;
  r.rows = r.points = data.abscissa.size();
  if (data.kind != FitDataKind::force_depth_curve || data.abscissa.empty() || data.abscissa.size() != data.values.size())
    return r;
  const LoadCase& lc = data.load_case;
  const int increments = std::max(1, lc.load.total_increments());
  r.step = lc.max_depth() / increments;
  if (!(r.step > 0.0)) return r;
  const std::vector<double>& a = data.abscissa;

  // The branches [begin, end) and their turning points: a reversal counts once the depth has come
  // back from the branch's extreme by half an increment (finer wiggles the model does not resolve)
  // and by 10 standard deviations of the depth's noise (the extremes of 10^5 noisy rows lie some
  // 4.5 of them either side of the trend).  The noise from the steps between rows: a curve this
  // dense moves little from one row to the next, so their spread about the median step is noise
  // (1.4826 MAD / sqrt 2 for one depth).
  struct Branch {
    std::size_t begin = 0, end = 0, turn = 0;
  };
  std::vector<Branch> branches;
  double noise = 0.0;
  if (a.size() > 2) {
    std::vector<double> steps(a.size() - 1);
    for (std::size_t i = 1; i < a.size(); ++i) steps[i - 1] = a[i] - a[i - 1];
    const auto middle = steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2);
    std::nth_element(steps.begin(), middle, steps.end());
    const double median = *middle;
    for (double& d : steps) d = std::abs(d - median);
    std::nth_element(steps.begin(), middle, steps.end());
    noise = 1.4826 * *middle / std::sqrt(2.0);
  }
  const double tolerance = std::max(0.5 * r.step, 10.0 * noise);
  std::size_t begin = 0, extreme = 0;
  double direction = 1.0;  // a curve starts by loading from 0
  for (std::size_t i = 1; i < a.size(); ++i) {
    if (direction * (a[i] - a[extreme]) >= 0.0) {
      extreme = i;
    } else if (direction * (a[extreme] - a[i]) > tolerance) {
      branches.push_back({begin, extreme + 1, extreme});
      begin = extreme + 1;
      direction = -direction;
      extreme = i;  // the rows since the turning point all lie within the tolerance of it
    }
  }
  branches.push_back({begin, a.size(), extreme});
  r.branches = static_cast<int>(branches.size());

  std::vector<double> depth, force;
  double from = 0.0;  // the path starts at 0; each later branch at the turning point before it
  for (const Branch& b : branches) {
    const double to = a[b.turn];
    const std::size_t rows = b.end - b.begin;
    const int n = std::max(5, static_cast<int>(std::ceil(std::abs(to - from) / r.step - 1e-9)));
    if (rows <= 2 * static_cast<std::size_t>(n) || to == from) {
      depth.insert(depth.end(), a.begin() + static_cast<std::ptrdiff_t>(b.begin), a.begin() + static_cast<std::ptrdiff_t>(b.end));
      force.insert(force.end(), data.values.begin() + static_cast<std::ptrdiff_t>(b.begin),
                   data.values.begin() + static_cast<std::ptrdiff_t>(b.end));
    } else {
      std::vector<std::size_t> order(rows);
      std::iota(order.begin(), order.end(), b.begin);
      std::stable_sort(order.begin(), order.end(), [&](std::size_t i, std::size_t j) { return a[i] < a[j]; });
      std::vector<double> x, y;
      for (std::size_t i : order) {
        x.push_back(a[i]);
        y.push_back(data.values[i]);
      }
      const double half_width = 0.5 * std::abs(to - from) / n;
      for (int k = 1; k <= n; ++k) {
        const double target = k == n ? to : from + (to - from) * k / n;
        if (const auto value = local_value(x, y, target, half_width)) {
          depth.push_back(target);
          force.push_back(*value);
        }
      }
    }
    from = to;
  }
  if (depth.size() >= a.size()) return r;
  r.reduced = true;
  r.points = depth.size();
  data.rows = a.size();
  data.abscissa = std::move(depth);
  data.values = std::move(force);
  r.note = fmt::format(
      "{}: {} rows fitted as {} points ({} branch{}): one per increment of the load case where a branch had more "
      "than two rows per increment ({} increments to {:.4g} m: the model resolves {:.3g} m), each a local quadratic "
      "fit of the rows around it; raise load.increments to fit more points",
      data.file, r.rows, r.points, r.branches, r.branches == 1 ? "" : "es", increments, lc.max_depth(), r.step);
  return r;
}

ForwardModel::ForwardModel(FitData data, std::vector<RegionParameter> parameters,
                           const std::vector<std::pair<double, double>>& bounds, bool finite_differences_only,
                           const std::vector<double>& plan_at)
    : data_(std::move(data)), parameters_(std::move(parameters)), bounds_(bounds) {
  const LoadCase& user = data_.load_case;
  const std::string& file = data_.file;
  refuse_unfittable_load(user, data_.kind);
  prepared_ = user;
  // One kinematics for every forward run: "auto" chosen once on the user's case, so that a step
  // of the parameters or a replanned mesh never switches it (the cost stays smooth).
  pin_kinematics(prepared_);
  if (data_.abscissa.empty() || data_.abscissa.size() != data_.values.size())
    throw InputError(file, "data", "holds no points");

  if (data_.kind == FitDataKind::force_depth_curve) {
    // The load path through the data's depths, each step no longer than the case's own.
    const double step = user.max_depth() / std::max(1, user.load.total_increments());
    path_ = {0.0};
    for (std::size_t i = 0; i < data_.abscissa.size(); ++i) {
      const double depth = data_.abscissa[i];
      if (!(depth >= 0.0))
        throw InputError(file, fmt::format("row {}", i + 1), fmt::format("depth {} m is negative", depth));
      if (depth > user.max_depth() * (1.0 + 1e-12))
        throw InputError(file, fmt::format("row {}", i + 1),
                         fmt::format("depth {:.6g} m is beyond the load case's deepest depth {:.6g} m ({}): the "
                                     "mesh is planned for the case's load path; deepen load.path",
                                     depth, user.max_depth(), user.source));
      if (depth != path_.back()) path_.push_back(depth);
      point_of_waypoint_.push_back(path_.size() - 1);
    }
    prepared_.load.path = path_;
    prepared_.load.segment_increments.clear();
    for (std::size_t s = 1; s < path_.size(); ++s)
      prepared_.load.segment_increments.push_back(
          std::max(1, static_cast<int>(std::ceil(std::abs(path_[s] - path_[s - 1]) / step - 1e-9))));
    prepared_.load.increments = prepared_.load.total_increments();
  } else if (data_.kind == FitDataKind::time_history) {
    lay_path_through_times();
  } else {
    const auto& path = user.load.path;
    if (path.back() != 0.0 || !std::any_of(path.begin(), path.end(), [](double a) { return a > 0.0; }))
      throw InputError(user.source, "load.path",
                       fmt::format("an imprint ({}) is measured after the punch has left: the load path must end "
                                   "at 0 (it ends at {} m)",
                                   file, path.back()));
    for (std::size_t i = 0; i < data_.abscissa.size(); ++i)
      if (!(data_.abscissa[i] >= 0.0 && data_.abscissa[i] < user.geometry.lx))
        throw InputError(file, fmt::format("row {}", i + 1),
                         fmt::format("radius {} m is off the specimen's surface [0, {}) m", data_.abscissa[i],
                                     user.geometry.lx));
  }

  // The element, chosen once for the whole box: B-bar if the automatic choice picks it anywhere
  // in it (its conditions are monotone in each parameter, so the corners decide).
  if (user.mesh.element == ElementChoice::automatic) {
    bool bbar = false;
    const std::size_t corners = std::size_t{1} << parameters_.size();
    for (std::size_t c = 0; c < corners && !bbar; ++c) {
      LoadCase corner = user;
      for (std::size_t j = 0; j < parameters_.size(); ++j)
        set_value(corner, parameters_[j], (c >> j) & 1 ? bounds_[j].second : bounds_[j].first);
      bbar = choose_element(corner) == ElementKind::bbar;
    }
    prepared_.mesh.element = bbar ? ElementChoice::bbar : ElementChoice::q1;
  }
  std::vector<double> start = plan_at;
  if (start.empty())
    for (const RegionParameter& p : parameters_) start.push_back(value_of(user, p));
  replan_mesh(start);

  // Forward sensitivities where the state is a function of depth and theta alone.
  for (const RegionParameter& p : parameters_) sensitivity_parameters_.push_back(p.which);
  if (finite_differences_only) fd_reason_ = "finite differences asked for";
  else if (!user.layers.empty()) fd_reason_ = "a coated specimen's force is not homogeneous in one E (MODEL.md §14.1)";
  else if (data_.kind == FitDataKind::time_history) fd_reason_ = "a protocol in time carries its history";
  else if (user.material.model == MaterialModel::j2) fd_reason_ = "J2 flow theory carries its history";
  else if (user.contact.friction > 0.0) fd_reason_ = "friction carries its slip history";
  else if (std::count(sensitivity_parameters_.begin(), sensitivity_parameters_.end(), MaterialParameter::nu))
    fd_reason_ = "nu also shapes the condensed far field";
  sensitivities_ = fd_reason_.empty();
}

void ForwardModel::replan_mesh(const std::vector<double>& theta) {
  LoadCase lc = data_.load_case;
  for (std::size_t j = 0; j < parameters_.size(); ++j) set_value(lc, parameters_[j], theta[j]);
  validate(lc);
  // Force control: the depth the largest force reaches sizes the mesh; fixed with it for every run.
  lc = with_depth_estimate(std::move(lc));
  prepared_.load.depth_estimate = lc.load.depth_estimate;
  const RunPlan plan = plan_run(lc);
  // A flat punch's mesh is sized from its radius, fixed already.
  if (lc.punch.shape != PunchShapeKind::flat) prepared_.mesh.contact_half_width = plan.mesh.contact_half_width_estimate;
}

void ForwardModel::lay_path_through_times() {
  // Every data time a waypoint of the protocol (whose targets are linear in time along each
  // segment, so the protocol is unchanged), each piece stepped at its segment's own increment.
  const LoadCase& user = data_.load_case;
  const LoadInput& load = user.load;
  const std::vector<int> per_segment = segment_increments(load);
  const double start = load.times.front(), end = load.times.back();
  const double tolerance = 1e-12 * (end - start);
  std::vector<double> times = load.times;
  for (std::size_t i = 0; i < data_.abscissa.size(); ++i) {
    const double t = data_.abscissa[i];
    if (!(t > start && t <= end + tolerance))
      throw InputError(data_.file, fmt::format("data point {}", i + 1),
                       fmt::format("time {:.6g} s is outside the protocol's times ({:.6g}, {:.6g}] s ({}: load.times)", t,
                                   start, end, user.source));
    times.push_back(std::min(t, end));
  }
  std::sort(times.begin(), times.end());
  path_.clear();
  for (double t : times)
    if (path_.empty() || t - path_.back() > tolerance) path_.push_back(t);
  prepared_.load.times = path_;
  prepared_.load.path.clear();
  prepared_.load.segment_increments.clear();
  for (std::size_t k = 0; k < path_.size(); ++k) {
    prepared_.load.path.push_back(target_at(load, path_[k]));
    if (k == 0) continue;
    // The protocol's segment holding this piece, and its own increment length.
    const double middle = 0.5 * (path_[k - 1] + path_[k]);
    const auto s = static_cast<std::size_t>(
        std::min<std::ptrdiff_t>(std::upper_bound(load.times.begin(), load.times.end(), middle) - load.times.begin(),
                                 static_cast<std::ptrdiff_t>(load.times.size()) - 1) - 1);
    const double step = (load.times[s + 1] - load.times[s]) / std::max(1, per_segment[s]);
    prepared_.load.segment_increments.push_back(
        std::max(1, static_cast<int>(std::ceil((path_[k] - path_[k - 1]) / step - 1e-9))));
  }
  prepared_.load.increments = prepared_.load.total_increments();
  point_of_waypoint_.clear();
  for (double t : data_.abscissa) {
    const auto it = std::lower_bound(path_.begin(), path_.end(), std::min(t, end) - tolerance);
    point_of_waypoint_.push_back(static_cast<std::size_t>(it - path_.begin()));
  }
}

LoadCase ForwardModel::case_at(const std::vector<double>& theta) const {
  LoadCase lc = prepared_;
  for (std::size_t j = 0; j < parameters_.size(); ++j) set_value(lc, parameters_[j], theta[j]);
  validate(lc);
  return lc;
}

LoadCase ForwardModel::fitted_case(const std::vector<double>& theta) const {
  LoadCase lc = data_.load_case;
  for (std::size_t j = 0; j < parameters_.size(); ++j) set_value(lc, parameters_[j], theta[j]);
  return lc;
}

std::vector<double> ForwardModel::run_once(const LoadCase& base, int refinement,
                                           std::vector<std::vector<double>>* jacobian) const {
  LoadCase lc = base;
  lc.load.multiply_increments(refinement);
  Simulation sim(lc);
  const std::size_t points = data_.abscissa.size();
  std::vector<double> values(points, 0.0);
  if (data_.kind == FitDataKind::force_depth_curve || data_.kind == FitDataKind::time_history) {
    // The increments that end a waypoint of the path (the data depths, or times), and the response
    // recorded there: the force, or the depth under force control.
    const bool depth_response = lc.load.control == LoadControlKind::force;
    std::vector<std::size_t> waypoint_of_step{0};
    for (std::size_t s = 0; s < lc.load.segment_increments.size(); ++s)
      for (int k = 1; k <= lc.load.segment_increments[s]; ++k) waypoint_of_step.push_back(k == lc.load.segment_increments[s] ? s + 1 : 0);
    bool available = true;  // sensitivities at every data depth (else the jacobian stays empty)
    std::vector<double> force_at(path_.size(), 0.0);
    std::vector<std::vector<double>> sensitivity_at(path_.size());
    sim.run([&](const IncrementRecord& r) {
      const auto step = static_cast<std::size_t>(r.step);
      const std::size_t waypoint = step < waypoint_of_step.size() ? waypoint_of_step[step] : 0;
      if (waypoint == 0) return;
      force_at[waypoint] = depth_response ? r.alpha : r.force;
      if (jacobian && available) {
        auto s = sim.force_sensitivities(sensitivity_parameters_);
        available = s.has_value();
        if (available) sensitivity_at[waypoint] = std::move(*s);
      }
    });
    for (std::size_t i = 0; i < points; ++i) values[i] = force_at[point_of_waypoint_[i]];
    if (jacobian) jacobian->clear();
    if (jacobian && available) {
      jacobian->assign(points, std::vector<double>(parameters_.size(), 0.0));
      for (std::size_t i = 0; i < points; ++i)
        if (point_of_waypoint_[i] > 0) (*jacobian)[i] = sensitivity_at[point_of_waypoint_[i]];
    }
    return values;
  }
  // The imprint.  With derivatives: the sensitivities before every descent of the path record the
  // peak's d eps*/d theta for Ilyushin's unloading branch (Simulation::sensitivities), those at
  // the end give d v/d theta.  Should they be unavailable after all, the jacobian is left empty
  // and evaluate() differentiates this evaluation by finite differences.
  const std::vector<double> targets = plan_increments(lc.load);
  std::vector<char> descent(targets.size(), 0);
  if (jacobian)
    for (int step : descent_starts(targets)) descent[static_cast<std::size_t>(step)] = 1;
  bool available = jacobian != nullptr;
  sim.run([&](const IncrementRecord& r) {
    const auto step = static_cast<std::size_t>(r.step);
    if (available && step < descent.size() && descent[step]) available = sim.sensitivities(sensitivity_parameters_).has_value();
  });
  std::optional<Simulation::Sensitivities> end;
  if (available) end = sim.sensitivities(sensitivity_parameters_, true);
  if (jacobian) {
    jacobian->clear();
    if (end) jacobian->assign(points, std::vector<double>(parameters_.size(), 0.0));
  }
  // The surface nodes' depth below the original surface, -v, between the nodes linear.
  std::vector<double> r, depth;
  std::vector<std::size_t> equation;
  for (const auto& c : sim.contact_boundary().candidates()) {
    r.push_back(c.x);
    equation.push_back(static_cast<std::size_t>(c.equation));
    depth.push_back(-sim.displacement()[equation.back()]);
  }
  for (std::size_t i = 0; i < points; ++i) {
    const auto at = bracket(r, data_.abscissa[i]);
    if (!at)
      throw InputError(data_.file, fmt::format("row {}", i + 1),
                       fmt::format("radius {} m is beyond the punch's reach ({} m) on this mesh", data_.abscissa[i],
                                   r.empty() ? 0.0 : r.back()));
    values[i] = (*at)(depth);
    if (end)
      for (std::size_t j = 0; j < parameters_.size(); ++j) {
        std::vector<double> d_depth(equation.size());
        for (std::size_t k = 0; k < equation.size(); ++k) d_depth[k] = -end->displacement[j][equation[k]];
        (*jacobian)[i][j] = (*at)(d_depth);
      }
  }
  return values;
}

std::vector<double> ForwardModel::run(const LoadCase& lc, std::vector<std::vector<double>>* jacobian, int& runs) const {
  // A run that fails inside the fit is retried with steps a quarter, then a sixteenth as long;
  // one that still fails is reported as a failure (the optimiser then shortens its own step),
  // never as a result.
  const bool injected = fault_due("fit_run");  // robustness tests: a run that fails whatever its steps
  for (int attempt = 0;; ++attempt) {
    ++runs;
    try {
      if (injected) throw SolverError("injected failure of a fit's forward run (INDENTSIM_FAULT=fit_run)");
      return run_once(lc, 1 << (2 * attempt), jacobian);
    } catch (const SolverError&) {
      if (attempt == 2) throw;
    }
  }
}

ModelEvaluation ForwardModel::evaluate(const std::vector<double>& theta, bool with_jacobian) const {
  ModelEvaluation e;
  const LoadCase lc = case_at(theta);
  if (sensitivities_) {
    e.values = run(lc, with_jacobian ? &e.jacobian : nullptr, e.forward_runs);
    if (!with_jacobian || !e.jacobian.empty()) return e;
  } else {
    e.values = run(lc, nullptr, e.forward_runs);
    if (!with_jacobian) return e;
  }
  e.jacobian.assign(e.values.size(), std::vector<double>(parameters_.size(), 0.0));
  for (std::size_t j = 0; j < parameters_.size(); ++j) {
    const double scale = theta[j] != 0.0 ? std::abs(theta[j]) : bounds_[j].second - bounds_[j].first;
    double h = finite_difference_step * scale;
    if (theta[j] + h > bounds_[j].second) h = -h;  // stay inside the bounds
    std::vector<double> shifted = theta;
    shifted[j] += h;
    const std::vector<double> values = run(case_at(shifted), nullptr, e.forward_runs);
    for (std::size_t i = 0; i < values.size(); ++i) e.jacobian[i][j] = (values[i] - e.values[i]) / h;
  }
  return e;
}

}  // namespace indentsim
