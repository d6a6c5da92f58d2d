#include "indentsim/output/run_output.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <cstdlib>
#include <stdexcept>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "indentsim/geometry/punch.hpp"
#include "indentsim/materials/hardening.hpp"
#include "indentsim/base/version.hpp"

namespace indentsim {

namespace {

/// `x` to `digits` significant digits: summary.json states error estimates and orders no finer
/// than they are known (the value a reader parses is the rounded one).
double significant(double x, int digits) {
  if (!std::isfinite(x) || x == 0.0) return x;
  return std::strtod(fmt::format("{:.{}e}", x, digits - 1).c_str(), nullptr);  // never throws
}

/// A measured time in seconds to the microsecond, a ratio of times to 1e-4: what a clock can say.
double seconds(double t) { return std::round(t * 1e6) / 1e6; }
double ratio(double r) { return std::round(r * 1e4) / 1e4; }

// A rate-dependent flow rule's parameters (docs/MODEL.md §13.3), beside the hardening curve's
// (which Norton's creep does not use).
void add_flow_rule(const MaterialInput& m, nlohmann::ordered_json& law) {
  if (m.rate == RateLaw::none) return;
  law["rate"] = to_string(m.rate);
  if (m.rate == RateLaw::perzyna) law["reference_strain_rate"] = m.reference_strain_rate.value_or(0.0);
  if (m.rate == RateLaw::norton) {
    law["creep_coefficient"] = m.creep_coefficient.value_or(0.0);
    law["reference_stress"] = m.reference_stress.value_or(0.0);
  }
  law["rate_exponent"] = m.rate_exponent.value_or(0.0);
}

/// One material as summary.json gives it: its elastic constants, its yield surface and hardening
/// curve (Norton's creep has neither) and its flow rule.
nlohmann::ordered_json material_fields(const MaterialInput& m) {
  nlohmann::ordered_json material;
  if (m.rate == RateLaw::norton) {  // no yield surface, no hardening curve
    material = {{"E", m.E}, {"nu", m.nu}};
    add_flow_rule(m, material);
    return material;
  }
  if (!m.flow_stress_law()) {
    material = {{"E", m.E},
                {"nu", m.nu},
                {"e0", m.e0},
                {"yield_stress", m.yield_stress.value_or(yield_stress_of_e0(m.e0, m.E, m.nu))},
                {"hardening", to_string(m.hardening)},
                {"kappa", m.kappa},
                {"n", m.n}};
    add_flow_rule(m, material);
    return material;
  }
  // A tensile test's flow curve: its initial yield stress and the law's own parameters.
  const double yield = make_hardening_curve(m)->initial_yield();
  material = {{"E", m.E},
              {"nu", m.nu},
              {"e0", e0_of_yield_stress(yield, m.E, m.nu)},
              {"yield_stress", yield},
              {"hardening", to_string(m.hardening)}};
  switch (m.hardening) {
    case HardeningLaw::power_law: material["n"] = m.n; break;
    case HardeningLaw::ludwik: material["K"] = m.K.value_or(0.0), material["n"] = m.n; break;
    case HardeningLaw::swift:
      material["K"] = m.K.value_or(0.0), material["prestrain"] = m.prestrain.value_or(0.0), material["n"] = m.n;
      break;
    case HardeningLaw::voce: material["Q"] = m.Q.value_or(0.0), material["b"] = m.b.value_or(0.0); break;
    case HardeningLaw::table:
      material["points"] = m.hardening_points;
      material["table_extension"] = to_string(m.table_extension);
      break;
    case HardeningLaw::linear:
    case HardeningLaw::power: break;
  }
  add_flow_rule(m, material);
  return material;
}

/// What summary.json says of the run besides its results: who wrote it, the units, the material
/// (the substrate's, with the layers above it from the surface down: docs/MODEL.md §14.1).
nlohmann::ordered_json run_fields(const LoadCase& lc) {
  const bool axisymmetric = lc.geometry.kind == SceneKind::axisymmetric;
  nlohmann::ordered_json j;
  j["indentsim"] = version_line();
  j["scene"] = {{"kind", to_string(lc.geometry.kind)}, {"strain", to_string(lc.geometry.strain)}, {"punch", to_string(lc.punch.shape)}};
  j["units"] = {{"depth", "m"},
                {"force", axisymmetric ? "N (the whole specimen)" : "N/m (per unit thickness, both halves)"},
                {"stiffness", axisymmetric ? "N/m" : "N/m per m"},
                {"stress", "Pa"}};
  j["model"] = to_string(lc.material.model);
  j["material"] = material_fields(lc.material);
  if (!lc.layers.empty()) {
    auto& layers = j["layers"] = nlohmann::ordered_json::array();
    double top = 0.0;
    for (const LayerInput& layer : lc.layers) {
      layers.push_back({{"thickness", layer.thickness},
                        {"top_depth", top},
                        {"bottom_depth", top + layer.thickness},
                        {"model", to_string(layer.material.model)},
                        {"material", material_fields(layer.material)}});
      top += layer.thickness;
    }
  }
  return j;
}

}  // namespace

std::string to_string(RunStatus status) {
  switch (status) {
    case RunStatus::running: return "running";
    case RunStatus::finished: return "finished";
    case RunStatus::not_converged: return "not_converged";
    case RunStatus::stopped: return "stopped";
    case RunStatus::failed: return "failed";
  }
  return "?";
}

CurveWriter::CurveWriter(const std::filesystem::path& file, const DiscretizationErrorEstimate* error_estimate,
                         bool estimate_pending, std::vector<double> times)
    : file_(file),
      error_estimate_(error_estimate),
      estimate_columns_(error_estimate != nullptr || estimate_pending),
      times_(std::move(times)) {
  file_.append(header(estimate_columns_, !times_.empty()) + "\n");
}

void CurveWriter::set_error_estimate(const DiscretizationErrorEstimate* error_estimate,
                                     const std::vector<IncrementRecord>& rows_written) {
  error_estimate_ = error_estimate;
  if (!error_estimate_ || rows_written.empty()) return;
  std::string text = header(estimate_columns_, !times_.empty()) + "\n";
  for (const IncrementRecord& r : rows_written) text += format(r) + "\n";
  file_.replace(text);
}

std::string CurveWriter::header(bool with_error_estimate, bool with_time) {
  // The wall-clock time stays the last column: everything before it is the same in every run.
  return std::string(with_time ? "step,time," : "step,") +
         "alpha,P,a,contact_nodes,newton_iters,factorizations,cutbacks,plastic_points,max_strain_intensity" +
         (with_error_estimate ? ",P_error_estimate,a_error_estimate,P_extrapolated" : "") + ",wall_s";
}

std::string CurveWriter::format(const IncrementRecord& r) const {
  // Full round-trip precision: the curve is data, not a report.
  std::string line = fmt::format("{},", r.step);
  if (!times_.empty()) line += fmt::format("{:.17g},", times_.at(static_cast<std::size_t>(r.step)));
  line += fmt::format("{:.17g},{:.17g},{:.17g},{},{},{},{},{},{:.17g}", r.alpha, r.force, r.half_width,
                      r.contact_nodes, r.newton_iterations, r.factorizations, r.cutbacks, r.plastic_points,
                      r.max_strain_intensity);
  if (estimate_columns_) {
    if (const auto e = error_estimate_ ? error_estimate_->at(r) : std::nullopt)
      line += fmt::format(",{:.6e},{:.6e},{:.17g}", e->force_error, e->width_error, e->force_extrapolated);
    else
      line += ",,,";  // the companion stopped before this increment (or never ran)
  }
  return line + fmt::format(",{:.6f}", r.wall_seconds);
}

void CurveWriter::write(const IncrementRecord& record) {
  file_.append(format(record) + "\n");
}

LoadHistorySummary::LoadHistorySummary(const LoadCase* load_case) {
  if (!load_case) return;
  punch_ = make_punch(load_case->punch);
  context_.scene = load_case->geometry.kind;
  context_.punch = punch_.get();
  context_.shape = load_case->punch.shape;
  context_.settings = load_case->analysis;
  context_.specimen_nu = load_case->surface_material().nu;  // the top layer's, under a coated surface (MODEL.md §14.1)
  context_.coating = coating_of(*load_case);
  if (load_case->load.control == LoadControlKind::force) targets_ = plan_increments(load_case->load);
}

void LoadHistorySummary::set_true_contact(int step, const TrueContact& truth) {
  for (auto& [s, t] : truths_)
    if (s == step) {
      t = truth;
      return;
    }
  truths_.emplace_back(step, truth);
}

void LoadHistorySummary::add(const IncrementRecord& r, double free_surface_depth) {
  depths_.push_back(r.alpha);
  forces_.push_back(r.force);
  controlled_.push_back(run_branch_coordinate(targets_, r));
  steps_.push_back(r.step);
  contact_nodes_.push_back(r.contact_nodes);
  free_surface_depths_.push_back(free_surface_depth);
  if (r.force > peak_force_) peak_force_ = r.force;
  peak_depth_ = std::max(peak_depth_, r.alpha);
}

std::vector<LoadHistorySummary::Unloading> LoadHistorySummary::unloadings() const {
  std::vector<Unloading> unloadings;
  for (const CurveBranch& b : unloading_branches(controlled_)) {
    const std::size_t k = b.peak;
    if (!(forces_[k] > 0.0)) continue;  // the punch had left before the reversal: nothing unloads
    // The first unloading increment's secant is S; the last loading increment's secant is the
    // loading slope just before it.
    Unloading u;
    u.step = steps_[k];
    u.depth = depths_[k];
    u.force = forces_[k];
    // A creeping specimen's depth may still rise as the force falls (the "nose"): then the first
    // increment's secant is no unloading stiffness, and summary.json says null.
    u.stiffness = depths_[k] > depths_[k + 1] ? (forces_[k] - forces_[k + 1]) / (depths_[k] - depths_[k + 1])
                                              : std::numeric_limits<double>::quiet_NaN();
    if (k > 0 && depths_[k - 1] != depths_[k])
      u.loading_stiffness = (forces_[k] - forces_[k - 1]) / (depths_[k] - depths_[k - 1]);
    for (std::size_t i = k + 1; i <= b.end; ++i)
      if (forces_[i] == 0.0 && contact_nodes_[i] == 0) {
        u.separated = true;
        u.residual_depth = free_surface_depths_[i];
        u.separation_step = steps_[i];
        break;
      }
    unloadings.push_back(u);
  }
  return unloadings;
}

std::string LoadHistorySummary::json(const nlohmann::ordered_json& run_fields, RunStatus status,
                                     const std::string& message, const PhaseTimes& times,
                                     const nlohmann::ordered_json& result_fields) const {
  nlohmann::ordered_json j;
  j["status"] = to_string(status);
  if (!message.empty()) j["message"] = message;
  j.update(run_fields);
  if (!times.phases().empty()) {
    nlohmann::ordered_json phases = nlohmann::ordered_json::object();
    for (const auto& [phase, t] : times.phases()) phases[phase] = seconds(t);
    j["time_s"] = phases;
  }
  j["increments"] = steps_.empty() ? 0 : steps_.back();
  j["peak_depth"] = peak_depth_;
  j["peak_force"] = peak_force_;
  nlohmann::ordered_json unloading = nlohmann::ordered_json::array();
  const std::vector<CurveBranch> branches = unloading_branches(controlled_);
  for (const Unloading& u : unloadings()) {
    nlohmann::ordered_json b = {{"step", u.step},
                                {"depth", u.depth},
                                {"force", u.force},
                                {"stiffness", u.stiffness},
                                {"loading_stiffness", u.loading_stiffness},
                                {"separated", u.separated},
                                {"residual_depth", u.separated ? nlohmann::ordered_json(u.residual_depth) : nullptr},
                                {"separation_step", u.separated ? nlohmann::ordered_json(u.separation_step) : nullptr}};
    if (punch_) {
      // The Oliver-Pharr analysis of this branch, next to the true contact at its peak.
      std::optional<TrueContact> truth;
      for (const auto& [s, t] : truths_)
        if (s == u.step) truth = t;
      try {
        for (const CurveBranch& branch : branches)
          if (steps_[branch.peak] == u.step)
            b["analysis"] = branch_json(analyze_branch(depths_, forces_, branch, context_, truth), context_);
      } catch (const AnalysisError& e) {
        b["analysis"] = nullptr;
        b["analysis_error"] = e.what();
      }
    }
    unloading.push_back(std::move(b));
  }
  j["unloading"] = std::move(unloading);
  j.update(result_fields);
  // Messages may quote a user's bytes (a file name): invalid UTF-8 is replaced, never thrown on.
  return j.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) + "\n";
}

RunOutput::RunOutput(const std::filesystem::path& dir, const LoadCase& load_case,
                     const DiscretizationErrorEstimate* error_estimate,
                     const std::vector<IncrementRecord>& replay_curve, const std::vector<double>& replay_depths)
    : RunOutput(dir, load_case, error_estimate, replay_curve, replay_depths, false) {}

RunOutput::RunOutput(const std::filesystem::path& dir, const LoadCase& load_case, bool error_estimate_pending)
    : RunOutput(dir, load_case, nullptr, {}, {}, error_estimate_pending) {}

void RunOutput::set_configuration(const RunConfiguration& configuration) {
  nlohmann::ordered_json j = nlohmann::ordered_json::object();
  for (const auto& [name, value] : describe(configuration)) j[name] = value;
  run_fields_["configuration"] = std::move(j);
  run_fields_["scene"]["strain"] = to_string(configuration.strain);  // "auto" made concrete
  // The folder says it from its first write on: a run killed before it finishes keeps it.
  write_file_atomically(dir_ / "summary.json", summary_.json(run_fields_, RunStatus::running, ""));
}

void RunOutput::set_error_estimate(const DiscretizationErrorEstimate* error_estimate) {
  error_estimate_ = error_estimate;
  curve_.set_error_estimate(error_estimate, records_);
}

RunOutput::RunOutput(const std::filesystem::path& dir, const LoadCase& load_case,
                     const DiscretizationErrorEstimate* error_estimate,
                     const std::vector<IncrementRecord>& replay_curve, const std::vector<double>& replay_depths,
                     bool error_estimate_pending)
    : dir_(dir),
      run_fields_(run_fields(load_case)),
      error_estimate_(error_estimate),
      summary_(&load_case),
      fields_every_(load_case.output.fields_every),
      profile_depths_(load_case.output.profile_depths),
      curve_(dir / "curve.csv", error_estimate, error_estimate_pending, plan_times(load_case.load)),
      fields_(dir),
      increments_(static_cast<int>(plan_increments(load_case.load).size()) - 1) {
  // The rows are the planned targets, one each: the deepest state is the last row of the first
  // stay at the largest target (a depth, or under force control a force): the end of a hold there,
  // after its creep (without a rate-dependent material the hold repeats the state).
  const std::vector<double> targets = plan_increments(load_case.load);
  auto largest = std::max_element(targets.begin(), targets.end());
  while (largest + 1 != targets.end() && *(largest + 1) == *largest) ++largest;
  deepest_step_ = static_cast<int>(largest - targets.begin());
  run_fields_["deepest_step"] = deepest_step_;  // the state the figures show by default
  for (const CurveBranch& b : unloading_branches(targets)) peak_steps_.push_back(static_cast<int>(b.peak));
  write_file_atomically(dir_ / "case.toml", to_toml(load_case));
  write_file_atomically(dir_ / "summary.json", summary_.json(run_fields_, RunStatus::running, ""));
  for (std::size_t k = 0; k < replay_curve.size(); ++k) {
    const IncrementRecord& r = replay_curve[k];
    curve_.write(r);
    summary_.add(r, replay_depths[k]);
    records_.push_back(r);
    depths_.push_back(replay_depths[k]);
    last_step_ = r.step;
    // Fields written before the interruption stay in the series -- those the schedule writes (every
    // fields_every increments, the deepest state); the frame a stop wrote of its last state is
    // not one an uninterrupted run has, and goes.
    const bool deepest = r.step == deepest_step_ && peak_step_ < 0 && r.step > 0;
    const bool scheduled = (fields_every_ > 0 && r.step % fields_every_ == 0) || deepest;
    const std::string vtu = fmt::format("fields/step_{:06d}.vtu", r.step);
    if (std::filesystem::exists(dir_ / vtu)) {
      if (scheduled) {
        fields_.add_existing(r.step, vtu);
        last_fields_step_ = r.step;
      } else {
        std::error_code ec;
        std::filesystem::remove(dir_ / vtu, ec);
      }
    }
    // The deepest state passed before the checkpoint: its fields are on disk, its tables are not
    // (they are computed from a live state).
    if (deepest) peak_step_ = r.step;
  }
}

void RunOutput::increment(const IncrementSnapshot& state) {
  const IncrementRecord& record = state.record;
  curve_.write(record);
  summary_.add(record, state.free_surface_depth);
  records_.push_back(record);
  depths_.push_back(state.free_surface_depth);
  last_step_ = record.step;
  if (fields_every_ > 0 && record.step % fields_every_ == 0) write_fields(state, record.step);
  record_true_contact(state, record.step);
  // The deepest state is what figures show by default (a history may end unloaded, with nothing
  // to see): its fields are always written and its layer view kept for the tables.
  if (record.step == deepest_step_ && peak_step_ < 0 && record.step > 0) {
    peak_step_ = record.step;
    if (last_fields_step_ != record.step) write_fields(state, record.step);
    peak_tables_ = layer_tables(state, record.step, true);
  }
}

void RunOutput::record_true_contact(const IncrementSnapshot& state, int step) {
  if (std::find(peak_steps_.begin(), peak_steps_.end(), step) == peak_steps_.end()) return;
  if (state.contact().contact_nodes == 0) return;
  summary_.set_true_contact(step, TrueContact{state.unloading_stiffness(), state.contact_half_width()});
}

std::pair<std::string, std::string> RunOutput::layer_tables(const IncrementSnapshot& state, int step,
                                                            bool header) const {
  const Mesh& mesh = state.mesh;
  const auto layer = nodal_line_forces(mesh, state.bulk);
  const FieldFrame frame{step, state.alpha};
  return {layers_csv(line_forces(mesh, layer), state.contact().force, frame, header),
          profiles_csv(mesh, profile_lines(mesh, profile_depths_), layer, average_to_nodes(mesh, state.bulk), frame,
                       header)};
}

void RunOutput::write_fields(const IncrementSnapshot& state, int step) {
  const NodalStresses nodal = average_to_nodes(state.mesh, state.bulk);
  fields_.add(step, vtu_document(FieldFrame{step, state.alpha}, state.mesh, state.displacement.data(), state.bulk,
                                 nodal, state.contact_boundary, state.contact()));
  last_fields_step_ = step;
}

void RunOutput::finish(const IncrementSnapshot& final_state, RunStatus status, const std::string& message,
                       const PhaseTimes& times) {
  if (last_step_ >= 0) {
    if (last_fields_step_ != last_step_) write_fields(final_state, last_step_);
    const bool peak_apart = !peak_tables_.first.empty() && peak_step_ != last_step_;
    const auto [layers, profiles] = layer_tables(final_state, last_step_, !peak_apart);
    write_file_atomically(dir_ / "layers.csv", peak_apart ? peak_tables_.first + layers : layers);
    write_file_atomically(dir_ / "profiles.csv", peak_apart ? peak_tables_.second + profiles : profiles);
  }
  nlohmann::ordered_json results = error_fields(times);
  // Finite strain with a condensed far field: how far that field's small-strain linearization
  // was from its own validity (docs/MODEL.md §12.4).
  if (const auto far = final_state.bulk.far_field_check())
    results["far_field"] = {{"kinematics", "small strain, linear elastic (condensed)"},
                            {"largest_displacement_gradient", significant(far->largest_gradient, 7)},
                            {"limit", far->limit}};
  write_file_atomically(dir_ / "summary.json", summary_.json(run_fields_, status, message, times, results));
}

namespace {

// summary.json's error_estimate.increments: what halving the increments does to P at the deepest
// point (null for a run that does not depend on its increments, error_estimate.hpp).
nlohmann::ordered_json increment_fields(const DiscretizationErrorEstimate& e) {
  const auto& s = e.increment_sensitivity();
  if (!s) return nullptr;
  return {{"contact_nodes", s->contact_nodes},
          {"alpha", s->alpha},
          {"P", s->force},
          {"P_half_the_increments", s->force_halved},
          {"P_relative_change", significant(s->relative_change(), 7)}};
}

}  // namespace

nlohmann::ordered_json RunOutput::error_fields(const PhaseTimes& times) const {
  nlohmann::ordered_json out = nlohmann::ordered_json::object();
  if (error_estimate_ && !records_.empty()) {
    const DiscretizationErrorEstimate& e = *error_estimate_;
    nlohmann::ordered_json companions = nlohmann::ordered_json::array();
    for (const CompanionRun& c : e.companions()) companions.push_back(c.contact_nodes);
    const auto at_row = [&](const IncrementRecord& r) -> nlohmann::ordered_json {
      const auto estimate = e.at(r);
      if (!estimate) return nullptr;
      return {{"step", r.step},
              {"alpha", r.alpha},
              {"P", r.force},
              {"P_error_estimate", significant(estimate->force_error, 7)},
              {"P_relative_error_estimate",
               significant(r.force != 0.0 ? estimate->force_error / std::abs(r.force) : 0.0, 7)},
              {"P_extrapolated", estimate->force_extrapolated},
              {"P_order", significant(estimate->force_order, 4)},
              {"P_order_observed", estimate->order_observed},
              {"a", r.half_width},
              {"a_error_estimate", significant(estimate->width_error, 7)}};
    };
    const IncrementRecord* peak = &records_.front();
    for (const IncrementRecord& r : records_)
      if (std::abs(r.force) > std::abs(peak->force)) peak = &r;
    // The companions' work against the rest of the run (planning, model, stepping, output), and
    // the wall time they added: the run's wait for them ("error estimate" phase), less than their
    // work where they ran on a second core beside the model's build (run_driver.cpp).
    double wait_seconds = 0.0, run_seconds = 0.0;
    for (const auto& [phase, t] : times.phases()) (phase == "error estimate" ? wait_seconds : run_seconds) += t;
    const double estimate_seconds = e.wall_seconds();
    const auto fraction = [&](double t) -> nlohmann::ordered_json {
      if (run_seconds > 0.0) return ratio(t / run_seconds);
      return nullptr;
    };
    out["error_estimate"] = {{"method", e.method() == ErrorEstimateChoice::observed ? "observed" : "richardson"},
                             {"contact_nodes", e.contact_nodes()},
                             {"companion_contact_nodes", companions},
                             {"P_nominal_order", e.force_order()},
                             {"a_order", DiscretizationErrorEstimate::nominal_width_order},
                             {"final", at_row(records_.back())},
                             {"peak", at_row(*peak)},
                             {"increments", increment_fields(e)},
                             {"time_s", seconds(estimate_seconds)},
                             {"cost_fraction", fraction(estimate_seconds)},
                             {"wall_added_s", seconds(wait_seconds)},
                             {"wall_fraction", fraction(wait_seconds)}};
  }
  if (target_choice_) {
    // The same measures the driver judged the target by (run_driver.cpp): the mesh's estimate of
    // the final P (the peak's on a path that ends unloaded) and, for a path-dependent run, the
    // change of P that halving the increments made.
    const auto change_of = [](const std::optional<double>& c) -> nlohmann::ordered_json {
      if (c) return significant(*c, 7);
      return nullptr;
    };
    nlohmann::ordered_json attempts = nlohmann::ordered_json::array();
    for (const auto& a : target_choice_->attempts)
      attempts.push_back({{"role", a.role},
                          {"contact_nodes", a.contact_nodes},
                          {"increments", a.increments},
                          {"P_relative_error_estimate", significant(a.relative_error, 7)},
                          {"P_relative_change_half_the_increments", change_of(a.increment_change)}});
    nlohmann::ordered_json reached = nullptr, met = nullptr;
    std::optional<double> change;
    if (error_estimate_) {
      if (const auto& s = error_estimate_->increment_sensitivity()) change = s->relative_change();
      if (const auto relative = relative_force_error(*error_estimate_, records_)) {
        reached = significant(*relative, 7);
        met = *relative <= target_choice_->target && (!change || *change <= target_choice_->target);
      }
    }
    out["target_error"] = {{"target", target_choice_->target},
                           {"before", attempts},
                           {"contact_nodes", error_estimate_ ? error_estimate_->contact_nodes() : 0},
                           {"increments", increments_},
                           {"P_relative_error_estimate", reached},
                           {"P_relative_change_half_the_increments", change_of(change)},
                           {"met", met}};
  }
  return out;
}

void RunOutput::fail(const std::string& message) noexcept {
  try {
    // On a full disk the temporary files are what is left to free first.
    std::error_code ec;
    for (const auto& folder : {dir_, dir_ / "fields", dir_ / "checkpoints"})
      for (const auto& entry : std::filesystem::directory_iterator(folder, ec))
        if (entry.path().extension() == ".tmp") std::filesystem::remove(entry.path(), ec);
    write_file_atomically(dir_ / "summary.json", summary_.json(run_fields_, RunStatus::failed, message));
  } catch (...) {
    // summary.json still says "running", and no process holds the folder: readers see a run that
    // did not finish.
  }
}

}  // namespace indentsim
