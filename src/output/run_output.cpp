#include "indentsim/output/run_output.hpp"

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "indentsim/geometry/punch.hpp"
#include "indentsim/simulation/simulation.hpp"
#include "indentsim/base/version.hpp"

namespace indentsim {

namespace {

/// A JSON string literal of `text` (quotes, backslashes and control characters escaped).
std::string json_string(const std::string& text) {
  std::string out = "\"";
  for (unsigned char c : text) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += static_cast<char>(c);
    } else if (c < 0x20) {
      out += fmt::format("\\u{:04x}", c);
    } else {
      out += static_cast<char>(c);
    }
  }
  return out + "\"";
}

/// What summary.json says of the run besides its results: who wrote it, the units, the material.
std::string run_fields(const LoadCase& lc) {
  const auto& m = lc.material;
  const bool axisymmetric = lc.geometry.kind == SceneKind::axisymmetric;
  return fmt::format(
      "  \"indentsim\": {},\n"
      "  \"scene\": {{\"kind\": \"{}\", \"punch\": \"{}\"}},\n"
      "  \"units\": {{\"depth\": \"m\", \"force\": \"{}\", \"stiffness\": \"{}\", \"stress\": \"Pa\"}},\n"
      "  \"model\": \"{}\",\n"
      "  \"material\": {{\"E\": {}, \"nu\": {}, \"e0\": {}, \"yield_stress\": {}, \"hardening\": \"{}\", "
      "\"kappa\": {}, \"n\": {}}},\n",
      json_string(version_line()), to_string(lc.geometry.kind), to_string(lc.punch.shape),
      axisymmetric ? "N (the whole specimen)" : "N/m (per unit thickness, both halves)",
      axisymmetric ? "N/m" : "N/m per m", to_string(m.model), m.E, m.nu, m.e0,
      m.yield_stress.value_or(yield_stress_of_e0(m.e0, m.E, m.nu)),
      to_string(m.hardening), m.kappa, m.n);
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
                         bool estimate_pending)
    : file_(file), error_estimate_(error_estimate), estimate_columns_(error_estimate != nullptr || estimate_pending) {
  file_.append(header(estimate_columns_) + "\n");
}

void CurveWriter::set_error_estimate(const DiscretizationErrorEstimate* error_estimate,
                                     const std::vector<IncrementRecord>& rows_written) {
  error_estimate_ = error_estimate;
  if (!error_estimate_ || rows_written.empty()) return;
  std::string text = header(estimate_columns_) + "\n";
  for (const IncrementRecord& r : rows_written) text += format(r, error_estimate_, estimate_columns_) + "\n";
  file_.replace(text);
}

std::string CurveWriter::header(bool with_error_estimate) {
  // The wall-clock time stays the last column: everything before it is the same in every run.
  return std::string("step,alpha,P,a,contact_nodes,newton_iters,factorizations,cutbacks,plastic_points,"
                     "max_strain_intensity") +
         (with_error_estimate ? ",P_error_estimate,a_error_estimate,P_extrapolated" : "") + ",wall_s";
}

std::string CurveWriter::format(const IncrementRecord& r, const DiscretizationErrorEstimate* error_estimate,
                                bool with_estimate_columns) {
  // Full round-trip precision: the curve is data, not a report.
  std::string line = fmt::format("{},{:.17g},{:.17g},{:.17g},{},{},{},{},{},{:.17g}", r.step, r.alpha, r.force,
                                 r.half_width, r.contact_nodes, r.newton_iterations, r.factorizations, r.cutbacks,
                                 r.plastic_points, r.max_strain_intensity);
  if (error_estimate || with_estimate_columns) {
    if (const auto e = error_estimate ? error_estimate->at(r) : std::nullopt)
      line += fmt::format(",{:.6e},{:.6e},{:.17g}", e->force_error, e->width_error, e->force_extrapolated);
    else
      line += ",,,";  // the companion stopped before this increment (or never ran)
  }
  return line + fmt::format(",{:.6f}", r.wall_seconds);
}

void CurveWriter::write(const IncrementRecord& record) {
  file_.append(format(record, error_estimate_, estimate_columns_) + "\n");
}

LoadHistorySummary::LoadHistorySummary(const LoadCase* load_case) {
  if (!load_case) return;
  punch_ = make_punch(load_case->punch);
  context_.scene = load_case->geometry.kind;
  context_.punch = punch_.get();
  context_.shape = load_case->punch.shape;
  context_.settings = load_case->analysis;
  context_.specimen_nu = load_case->material.nu;
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
  steps_.push_back(r.step);
  if (r.force > peak_force_) peak_force_ = r.force;
  peak_depth_ = std::max(peak_depth_, r.alpha);
  if (previous_) {
    const IncrementRecord& previous = *previous_;
    const bool down = r.alpha < previous.alpha;
    if (down && !unloading_ && previous.force > 0.0) {
      // A reversal at `previous`: the first unloading increment's secant is S; the last loading
      // increment's secant is the loading slope just before it.
      Unloading u;
      u.step = previous.step;
      u.depth = previous.alpha;
      u.force = previous.force;
      u.stiffness = (previous.force - r.force) / (previous.alpha - r.alpha);
      if (before_previous_) {
        const IncrementRecord& before = *before_previous_;
        if (before.alpha != previous.alpha)
          u.loading_stiffness = (previous.force - before.force) / (previous.alpha - before.alpha);
      }
      unloadings_.push_back(u);
    }
    if (down) unloading_ = true;
    if (r.alpha > previous.alpha) unloading_ = false;
    if (unloading_ && !unloadings_.empty() && !unloadings_.back().separated && r.force == 0.0 &&
        r.contact_nodes == 0) {
      unloadings_.back().separated = true;
      unloadings_.back().residual_depth = free_surface_depth;
      unloadings_.back().separation_step = r.step;
    }
  }
  before_previous_ = previous_;
  previous_ = r;
}

std::string LoadHistorySummary::json(const std::string& run_fields, RunStatus status, const std::string& message,
                                     const PhaseTimes& times, const std::string& result_fields) const {
  std::string out = fmt::format("{{\n  \"status\": \"{}\",\n", to_string(status));
  if (!message.empty()) out += fmt::format("  \"message\": {},\n", json_string(message));
  out += run_fields;
  if (!times.phases().empty()) {
    out += "  \"time_s\": {";
    for (std::size_t k = 0; k < times.phases().size(); ++k)
      out += fmt::format("{}\"{}\": {:.6f}", k ? ", " : "", times.phases()[k].first, times.phases()[k].second);
    out += "},\n";
  }
  out += fmt::format("  \"increments\": {},\n  \"peak_depth\": {:.17g},\n"
                     "  \"peak_force\": {:.17g},\n  \"unloading\": [",
                     previous_ ? previous_->step : 0, peak_depth_, peak_force_);
  for (std::size_t i = 0; i < unloadings_.size(); ++i) {
    const Unloading& u = unloadings_[i];
    out += fmt::format("{}\n    {{\"step\": {}, \"depth\": {:.17g}, \"force\": {:.17g}, \"stiffness\": {:.17g}, "
                       "\"loading_stiffness\": {:.17g}, \"separated\": {}, \"residual_depth\": {}, "
                       "\"separation_step\": {}}}",
                       i ? "," : "", u.step, u.depth, u.force, u.stiffness, u.loading_stiffness,
                       u.separated ? "true" : "false",
                       u.separated ? fmt::format("{:.17g}", u.residual_depth) : std::string("null"),
                       u.separated ? std::to_string(u.separation_step) : std::string("null"));
    if (punch_) {
      // The Oliver-Pharr analysis of this branch, next to the true contact at its peak.
      out.pop_back();  // the object's closing brace: the analysis goes inside it
      std::optional<TrueContact> truth;
      for (const auto& [s, t] : truths_)
        if (s == u.step) truth = t;
      try {
        for (const CurveBranch& b : unloading_branches(depths_))
          if (steps_[b.peak] == u.step)
            out += ", \"analysis\": " + to_json(analyze_branch(depths_, forces_, b, context_, truth), context_, "    ");
      } catch (const AnalysisError& e) {
        out += ", \"analysis\": null, \"analysis_error\": " + json_string(e.what());
      }
      out += "}";
    }
  }
  out += unloadings_.empty() ? "]" : "\n  ]";
  if (!result_fields.empty()) out += ",\n" + result_fields.substr(0, result_fields.size() - 2);  // its last ",\n"
  return out + "\n}\n";
}

RunOutput::RunOutput(const std::filesystem::path& dir, const LoadCase& load_case,
                     const DiscretizationErrorEstimate* error_estimate,
                     const std::vector<IncrementRecord>& replay_curve, const std::vector<double>& replay_depths)
    : RunOutput(dir, load_case, error_estimate, replay_curve, replay_depths, false) {}

RunOutput::RunOutput(const std::filesystem::path& dir, const LoadCase& load_case, bool error_estimate_pending)
    : RunOutput(dir, load_case, nullptr, {}, {}, error_estimate_pending) {}

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
      curve_(dir / "curve.csv", error_estimate, error_estimate_pending),
      fields_(dir),
      deepest_depth_(load_case.max_depth()) {
  const std::vector<double> targets = plan_increments(load_case.load);
  for (int k : reversal_steps(targets))
    if (targets[static_cast<std::size_t>(k)] > targets[static_cast<std::size_t>(k) - 1]) peak_steps_.push_back(k);
  write_file_atomically(dir_ / "case.toml", to_toml(load_case));
  write_file_atomically(dir_ / "summary.json", summary_.json(run_fields_, RunStatus::running, ""));
  for (std::size_t k = 0; k < replay_curve.size(); ++k) {
    const IncrementRecord& r = replay_curve[k];
    curve_.write(r);
    summary_.add(r, replay_depths[k]);
    records_.push_back(r);
    depths_.push_back(replay_depths[k]);
    last_step_ = r.step;
    // Fields written before the interruption stay in the series.
    const std::string vtu = fmt::format("fields/step_{:06d}.vtu", r.step);
    if (std::filesystem::exists(dir_ / vtu)) {
      fields_.add_existing(r.step, vtu);
      last_fields_step_ = r.step;
    }
    // The deepest state passed before the checkpoint: its fields are on disk, its tables are not
    // (they are computed from a live state).
    if (r.alpha == deepest_depth_ && peak_step_ < 0 && r.step > 0) peak_step_ = r.step;
  }
}

void RunOutput::increment(const Simulation& sim, const IncrementRecord& record) {
  curve_.write(record);
  const double depth = sim.free_surface_depth();
  summary_.add(record, depth);
  records_.push_back(record);
  depths_.push_back(depth);
  last_step_ = record.step;
  if (fields_every_ > 0 && record.step % fields_every_ == 0) write_fields(sim, record.step);
  record_true_contact(sim, record.step);
  // The deepest state is what figures show by default (a history may end unloaded, with nothing
  // to see): its fields are always written and its layer view kept for the tables.
  if (record.alpha == deepest_depth_ && peak_step_ < 0 && record.step > 0) {
    peak_step_ = record.step;
    if (last_fields_step_ != record.step) write_fields(sim, record.step);
    peak_tables_ = layer_tables(sim, record.step, true);
  }
}

void RunOutput::record_true_contact(const Simulation& sim, int step) {
  if (std::find(peak_steps_.begin(), peak_steps_.end(), step) == peak_steps_.end()) return;
  const ContactResult contact = sim.contact();
  if (contact.contact_nodes == 0) return;
  summary_.set_true_contact(step, TrueContact{sim.unloading_stiffness(), sim.contact_half_width()});
}

std::pair<std::string, std::string> RunOutput::layer_tables(const Simulation& sim, int step, bool header) const {
  const auto& mesh = sim.mesh();
  const auto layer = nodal_layer_forces(mesh, sim.bulk());
  const FieldFrame frame{step, sim.alpha()};
  return {layers_csv(layer_forces(mesh, layer), sim.contact().force, frame, header),
          profiles_csv(mesh, profile_lines(mesh, profile_depths_), layer, average_to_nodes(mesh, sim.bulk()), frame,
                       header)};
}

void RunOutput::write_fields(const Simulation& sim, int step) {
  const NodalStresses nodal = average_to_nodes(sim.mesh(), sim.bulk());
  fields_.add(step, vtu_document(FieldFrame{step, sim.alpha()}, sim.mesh(), sim.displacement().data(), sim.bulk(), nodal, sim.contact_boundary(),
                           sim.contact()));
  last_fields_step_ = step;
}

void RunOutput::finish(const Simulation& sim, RunStatus status, const std::string& message, const PhaseTimes& times) {
  if (last_step_ >= 0) {
    if (last_fields_step_ != last_step_) write_fields(sim, last_step_);
    const bool peak_apart = !peak_tables_.first.empty() && peak_step_ != last_step_;
    const auto [layers, profiles] = layer_tables(sim, last_step_, !peak_apart);
    write_file_atomically(dir_ / "layers.csv", peak_apart ? peak_tables_.first + layers : layers);
    write_file_atomically(dir_ / "profiles.csv", peak_apart ? peak_tables_.second + profiles : profiles);
  }
  write_file_atomically(dir_ / "summary.json", summary_.json(run_fields_, status, message, times, error_fields(times)));
}

std::string RunOutput::error_fields(const PhaseTimes& times) const {
  std::string out;
  std::optional<DiscretizationErrorEstimate::AtIncrement> final_estimate;
  if (error_estimate_ && !records_.empty()) {
    const DiscretizationErrorEstimate& e = *error_estimate_;
    std::string companions;
    for (const CompanionRun& c : e.companions())
      companions += fmt::format("{}{}", companions.empty() ? "" : ", ", c.contact_nodes);
    const auto at_row = [&](const IncrementRecord& r) {
      const auto estimate = e.at(r);
      if (!estimate) return std::string("null");
      return fmt::format("{{\"step\": {}, \"alpha\": {:.17g}, \"P\": {:.17g}, \"P_error_estimate\": {:.6e}, "
                         "\"P_relative_error_estimate\": {:.6e}, \"P_extrapolated\": {:.17g}, \"P_order\": {:.4g}, "
                         "\"P_order_observed\": {}, \"a\": {:.17g}, \"a_error_estimate\": {:.6e}}}",
                         r.step, r.alpha, r.force, estimate->force_error,
                         r.force != 0.0 ? estimate->force_error / std::abs(r.force) : 0.0, estimate->force_extrapolated,
                         estimate->force_order, estimate->order_observed ? "true" : "false", r.half_width,
                         estimate->width_error);
    };
    const IncrementRecord* peak = &records_.front();
    for (const IncrementRecord& r : records_)
      if (std::abs(r.force) > std::abs(peak->force)) peak = &r;
    final_estimate = e.at(records_.back());
    // The companions' work against the rest of the run (planning, model, stepping, output), and
    // the wall time they added: the run's wait for them ("error estimate" phase), less than their
    // work where they ran on a second core beside the model's build (run_driver.cpp).
    double wait_seconds = 0.0, run_seconds = 0.0;
    for (const auto& [phase, seconds] : times.phases()) (phase == "error estimate" ? wait_seconds : run_seconds) += seconds;
    const double estimate_seconds = e.wall_seconds();
    out += fmt::format("  \"error_estimate\": {{\"method\": \"{}\", \"contact_nodes\": {}, "
                       "\"companion_contact_nodes\": [{}], \"P_nominal_order\": {}, \"a_order\": {},\n"
                       "    \"final\": {},\n    \"peak\": {},\n"
                       "    \"time_s\": {:.6f}, \"cost_fraction\": {}, \"wall_added_s\": {:.6f}, \"wall_fraction\": {}}},\n",
                       e.method() == ErrorEstimateChoice::observed ? "observed" : "richardson", e.contact_nodes(),
                       companions, e.force_order(),
                       DiscretizationErrorEstimate::nominal_width_order, at_row(records_.back()), at_row(*peak),
                       estimate_seconds, run_seconds > 0.0 ? fmt::format("{:.4f}", estimate_seconds / run_seconds) : "null",
                       wait_seconds, run_seconds > 0.0 ? fmt::format("{:.4f}", wait_seconds / run_seconds) : "null");
  }
  if (target_choice_) {
    std::string attempts;
    for (const auto& a : target_choice_->attempts)
      attempts += fmt::format("{}{{\"role\": \"{}\", \"contact_nodes\": {}, \"P_relative_error_estimate\": {:.6e}}}",
                              attempts.empty() ? "" : ", ", a.role, a.contact_nodes, a.relative_error);
    std::string reached = "null", met = "null";
    if (final_estimate && !records_.empty() && records_.back().force != 0.0) {
      const double relative = final_estimate->force_error / std::abs(records_.back().force);
      reached = fmt::format("{:.6e}", relative);
      met = relative <= target_choice_->target ? "true" : "false";
    }
    out += fmt::format("  \"target_error\": {{\"target\": {}, \"before\": [{}], \"contact_nodes\": {}, "
                       "\"P_relative_error_estimate\": {}, \"met\": {}}},\n",
                       target_choice_->target, attempts, error_estimate_ ? error_estimate_->contact_nodes() : 0,
                       reached, met);
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
