// A sweep's results folder, keyed by hash (sweep_results.hpp).
#include "indentsim/study/sweep_results.hpp"

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <new>
#include <sstream>


#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "indentsim/input/csv_table.hpp"
#include "indentsim/base/error.hpp"
#include "indentsim/base/file_system.hpp"
#include "indentsim/base/interruption.hpp"
#include "indentsim/driver/run_driver.hpp"

namespace fs = std::filesystem;

namespace indentsim {

const std::vector<std::string>& sweep_keepable_outputs() {
  static const std::vector<std::string> names{"curve", "summary", "case", "fields", "layers"};
  return names;
}

namespace {

/// The files of a run folder that `keep` names (result.json is always kept).
bool kept(const std::string& file, const std::vector<std::string>& keep) {
  const auto wants = [&](const char* name) { return std::find(keep.begin(), keep.end(), name) != keep.end(); };
  if (file == "result.json") return true;
  if (file == "curve.csv") return wants("curve");
  if (file == "summary.json") return wants("summary");
  if (file == "case.toml") return wants("case");
  if (file == "fields.pvd" || file == "fields") return wants("fields");
  if (file == "layers.csv" || file == "profiles.csv") return wants("layers");
  return false;
}

std::string read_text(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

nlohmann::ordered_json number_or_null(const std::optional<double>& v) {
  return v ? nlohmann::ordered_json(*v) : nlohmann::ordered_json(nullptr);
}
std::optional<double> optional_number(const nlohmann::json& j, const char* key) {
  if (!j.contains(key) || !j.at(key).is_number()) return std::nullopt;
  return j.at(key).get<double>();
}

/// The figures of a finished (or not converged) run: from its curve and its summary.json.
void read_figures(const RunReport& report, SweepRunResult& r) {
  if (!report.curve.empty()) {
    const IncrementRecord& last = report.curve.back();
    r.increments = last.step;
    r.final_alpha = last.alpha;
    r.final_force = last.force;
    r.final_contact = last.half_width;
    for (const IncrementRecord& k : report.curve) r.newton_iterations += static_cast<int>(k.newton_iterations);
  }
  std::error_code ec;
  const fs::path summary_file = report.dir / "summary.json";
  if (!fs::is_regular_file(summary_file, ec)) return;
  const nlohmann::json summary = nlohmann::json::parse(read_text(summary_file), nullptr, false);
  if (summary.is_discarded()) return;
  r.peak_depth = optional_number(summary, "peak_depth");
  r.peak_force = optional_number(summary, "peak_force");
  if (summary.contains("units")) r.force_unit = summary["units"].value("force", "");
  if (summary.contains("error_estimate") && summary["error_estimate"].contains("final"))
    r.force_relative_error_estimate = optional_number(summary["error_estimate"]["final"], "P_relative_error_estimate");
  if (summary.contains("unloading") && summary["unloading"].is_array() && !summary["unloading"].empty()) {
    const nlohmann::json& first = summary["unloading"][0];
    if (first.contains("analysis") && first["analysis"].is_object()) {
      r.hardness = optional_number(first["analysis"], "H");
      r.reduced_modulus = optional_number(first["analysis"], "E_r");
    }
  }
}

/// Removes a folder and everything in it, as far as possible (never throws).
void remove_quietly(const fs::path& dir) {
  std::error_code ec;
  fs::remove_all(dir, ec);
}

}  // namespace

std::string SweepRunResult::to_json() const {
  nlohmann::ordered_json j;
  j["hash"] = hash;
  j["index"] = index;
  j["status"] = status;
  if (!message.empty()) j["message"] = message;
  j["units"] = {{"depth", "m"}, {"force", force_unit}, {"stress", "Pa"}, {"time", "s"}};
  j["increments"] = increments;
  j["peak_depth"] = number_or_null(peak_depth);
  j["peak_force"] = number_or_null(peak_force);
  j["final_alpha"] = number_or_null(final_alpha);
  j["final_P"] = number_or_null(final_force);
  j["final_a"] = number_or_null(final_contact);
  j["P_relative_error_estimate"] = number_or_null(force_relative_error_estimate);
  j["H"] = number_or_null(hardness);
  j["E_r"] = number_or_null(reduced_modulus);
  j["newton_iterations"] = newton_iterations;
  j["wall_s"] = wall_seconds;
  return j.dump(2) + "\n";
}

SweepRunResult SweepRunResult::from_json(const std::string& text, const std::string& source) {
  try {
    const nlohmann::json j = nlohmann::json::parse(text);
    SweepRunResult r;
    r.hash = j.at("hash").get<std::string>();
    r.index = j.at("index").get<int>();
    r.status = j.at("status").get<std::string>();
    r.message = j.value("message", "");
    r.force_unit = j.at("units").value("force", "");
    r.increments = j.at("increments").get<int>();
    r.peak_depth = optional_number(j, "peak_depth");
    r.peak_force = optional_number(j, "peak_force");
    r.final_alpha = optional_number(j, "final_alpha");
    r.final_force = optional_number(j, "final_P");
    r.final_contact = optional_number(j, "final_a");
    r.force_relative_error_estimate = optional_number(j, "P_relative_error_estimate");
    r.hardness = optional_number(j, "H");
    r.reduced_modulus = optional_number(j, "E_r");
    r.newton_iterations = j.at("newton_iterations").get<int>();
    r.wall_seconds = j.at("wall_s").get<double>();
    return r;
  } catch (const nlohmann::json::exception& e) {
    throw InputError(source, "result", fmt::format("is not a sweep run's result: {}", e.what()));
  }
}

SweepResults::SweepResults(fs::path out) : out_(std::move(out)) {}

void SweepResults::write_manifest(const SweepManifest& manifest) const {
  const fs::path file = out_ / "manifest.json";
  const std::string text = manifest.to_json();
  std::error_code ec;
  if (fs::is_regular_file(file, ec) && read_text(file) == text) return;
  fs::create_directories(out_);
  write_file_atomically(file, text);
}

bool SweepResults::complete(const std::string& hash) const {
  std::error_code ec;
  return fs::is_regular_file(out_ / "runs" / hash / "result.json", ec);
}

std::optional<SweepRunResult> SweepResults::result(const std::string& hash) const {
  const fs::path file = out_ / "runs" / hash / "result.json";
  if (!complete(hash)) return std::nullopt;
  return SweepRunResult::from_json(read_text(file), file.string());
}

SweepRunResult SweepResults::run(const SweepRun& run, const std::vector<std::string>& keep) const {
  // A private folder per attempt: two workers given the same run (a retry while the first is
  // still alive) never share one.
  const fs::path runs = out_ / "runs";
  const fs::path partial = runs / ".partial" / fmt::format("{}.{}", run.hash, unique_name_part());
  fs::create_directories(partial.parent_path());
  const auto start = std::chrono::steady_clock::now();
  SweepRunResult result;
  result.hash = run.hash;
  result.index = run.index;
  RunObserver quiet;
  try {
    // Checkpoints are for runs one would resume; a sweep's run is redone whole.
    const LoadCase lc = parse_load_case(run.case_toml, fmt::format("sweep run {} ({})", run.index + 1, run.hash),
                                        {"output.dir=" + toml_string(partial.string()), "output.checkpoint_every=0"});
    const RunReport report = run_load_case(lc, quiet);
    if (report.status == RunStatus::stopped) throw Interrupted(report.stop_signal);
    result.status = to_string(report.status);
    result.message = report.message;
    read_figures(report, result);
  } catch (const InputError& e) {
    // The run's folder could not be prepared (a full disk, a quota): the results folder's
    // problem, not the run's.  It must not become a result that is never run again.
    if (e.key() == "output.dir") {
      remove_quietly(partial);
      throw IoError(partial.string(), "preparing a sweep run's folder", e.problem());
    }
    result.status = "failed";
    result.message = e.what();
  } catch (const std::bad_alloc&) {
    remove_quietly(partial);
    throw;
  } catch (const IoError&) {
    remove_quietly(partial);
    throw;
  } catch (const fs::filesystem_error&) {
    remove_quietly(partial);
    throw;
  } catch (const Interrupted&) {
    remove_quietly(partial);
    throw;
  } catch (const std::exception& e) {
    result.status = "failed";
    result.message = e.what();
  }
  result.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  fs::create_directories(partial);
  for (const auto& entry : fs::directory_iterator(partial))
    if (!kept(entry.path().filename().string(), keep)) fs::remove_all(entry.path());
  write_file_atomically(partial / "result.json", result.to_json());
  // The rename makes the result appear whole or not at all; a result already there (another
  // worker's attempt at the same run) is kept, and this one dropped.
  const fs::path done = runs / run.hash;
  for (int attempt = 0;; ++attempt) {
    if (std::rename(partial.c_str(), done.c_str()) == 0) return result;
    const int error = errno;
    if (error != EEXIST && error != ENOTEMPTY) {
      remove_quietly(partial);
      throw_io_error(done, "moving a finished run into place", error);
    }
    if (const auto earlier = this->result(run.hash)) {
      remove_quietly(partial);
      return *earlier;
    }
    // A folder under the hash without result.json is no result (left by hand, or by a version
    // that wrote it differently): it is replaced, once.
    if (attempt > 0) {
      remove_quietly(partial);
      throw_io_error(done, "replacing a folder that holds no result", error);
    }
    remove_quietly(done);
  }
}

SweepTally SweepResults::collect(const SweepManifest& manifest) const {
  SweepTally tally;
  std::string table = "index,hash";
  for (const auto& key : manifest.keys) table += "," + csv_field(key);
  table += ",status,peak_depth,peak_force,final_alpha,final_P,final_a,P_relative_error_estimate,H,E_r,increments,"
           "newton_iterations,wall_s,force_unit,message\n";
  const auto number = [](const std::optional<double>& v) { return v ? fmt::format("{:.17g}", *v) : std::string(); };
  for (const SweepRun& run : manifest.runs) {
    ++tally.runs;
    std::string row = fmt::format("{},{}", run.index, run.hash);
    for (const auto& value : run.values) {
      // Strings without their TOML quotes: the table holds values, not TOML.
      const bool quoted = value.size() >= 2 && value.front() == '"' && value.back() == '"';
      row += "," + csv_field(quoted ? value.substr(1, value.size() - 2) : value);
    }
    const std::optional<SweepRunResult> r = result(run.hash);
    if (!r) {
      ++tally.pending;
      table += row + ",pending,,,,,,,,,,,,,\n";
      continue;
    }
    if (r->status == "finished") ++tally.finished;
    else if (r->status == "not_converged") ++tally.not_converged;
    else ++tally.failed;
    table += row + fmt::format(",{},{},{},{},{},{},{},{},{},{},{},{:.6f},{},{}\n", r->status, number(r->peak_depth),
                               number(r->peak_force), number(r->final_alpha), number(r->final_force),
                               number(r->final_contact), number(r->force_relative_error_estimate),
                               number(r->hardness), number(r->reduced_modulus), r->increments, r->newton_iterations,
                               r->wall_seconds, csv_field(r->force_unit), csv_field(r->message));
  }
  fs::create_directories(out_);
  write_file_atomically(table_path(), table);
  return tally;
}

}  // namespace indentsim
