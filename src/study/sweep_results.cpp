// A sweep's results folder, keyed by hash (sweep_results.hpp).
#include "indentsim/study/sweep_results.hpp"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <new>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "indentsim/input/csv_table.hpp"
#include "indentsim/base/error.hpp"
#include "indentsim/base/file_system.hpp"
#include "indentsim/base/interruption.hpp"
#include "indentsim/driver/run_driver.hpp"
#include "indentsim/output/checkpoint.hpp"

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

/// FNV-1a of a file's bytes, read in blocks; nullopt when it cannot be read.
std::optional<std::uint64_t> file_checksum(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return std::nullopt;
  std::uint64_t hash = 0xcbf29ce484222325ull;
  std::vector<char> block(1 << 16);
  while (in) {
    in.read(block.data(), static_cast<std::streamsize>(block.size()));
    hash = fnv1a(block.data(), static_cast<std::size_t>(in.gcount()), hash);
  }
  if (in.bad()) return std::nullopt;
  return hash;
}

std::string hex16(std::uint64_t h) { return fmt::format("{:016x}", h); }

bool hex_digits(const std::string& text, std::size_t count) {
  return text.size() == count &&
         std::all_of(text.begin(), text.end(), [](char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'); });
}

/// The files kept in a finished run's folder (result.json aside): each one's size and checksum,
/// by its path in the folder.
std::vector<SweepRunResult::KeptFile> kept_files(const fs::path& dir) {
  std::vector<SweepRunResult::KeptFile> files;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    if (!entry.is_regular_file()) continue;
    const std::string name = entry.path().lexically_relative(dir).generic_string();
    if (name == "result.json") continue;
    const auto checksum = file_checksum(entry.path());
    if (!checksum) throw_io_error(entry.path(), "reading a kept file of a sweep run", errno ? errno : EIO);
    files.push_back({name, entry.file_size(), hex16(*checksum)});
  }
  std::sort(files.begin(), files.end(), [](const auto& a, const auto& b) { return a.name < b.name; });
  return files;
}

/// The kept files whose content look_up checks, not only their size: what the table and a
/// study's plots read (a fields/ folder may be large).
bool checksum_checked(const std::string& name) { return name == "curve.csv" || name == "summary.json"; }

/// Whether a kept file's recorded name stays inside the run's folder.
bool inside_folder(const std::string& name) {
  if (name.empty()) return false;
  const fs::path path(name);
  if (path.is_absolute()) return false;
  for (const auto& part : path)
    if (part == "..") return false;
  return true;
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
      const nlohmann::json& a = first["analysis"];
      r.hardness = optional_number(a, "H");
      r.reduced_modulus = optional_number(a, "E_r");
      r.specimen_modulus = optional_number(a, "E");
      r.residual_depth = optional_number(a, "h_f");
      r.pile_up_ratio = optional_number(a, "pile_up_ratio");
    } else if (first.contains("analysis_error") && first["analysis_error"].is_string()) {
      // The row says why its H and E are empty.
      const std::string why =
          fmt::format("no Oliver-Pharr figures (the unloading from step {}): {}",
                      first.contains("step") && first["step"].is_number_integer() ? first["step"].get<int>() : 0,
                      first["analysis_error"].get<std::string>());
      r.message = r.message.empty() ? why : r.message + "; " + why;
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
  j["E"] = number_or_null(specimen_modulus);
  j["h_f"] = number_or_null(residual_depth);
  j["pile_up_ratio"] = number_or_null(pile_up_ratio);
  j["material_E"] = number_or_null(material_E);
  j["newton_iterations"] = newton_iterations;
  j["wall_s"] = wall_seconds;
  nlohmann::ordered_json kept = nlohmann::ordered_json::object();
  for (const KeptFile& f : files) kept[f.name] = {{"bytes", f.bytes}, {"fnv1a", f.fnv1a}};
  j["files"] = std::move(kept);
  // Messages may quote a user's bytes: invalid UTF-8 is replaced, never thrown on.
  return j.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) + "\n";
}

SweepRunResult SweepRunResult::from_json(const std::string& text, const std::string& source) {
  const auto damaged = [&](const std::string& what) { return InputError(source, "result", what); };
  try {
    const nlohmann::json j = nlohmann::json::parse(text);
    if (!j.is_object()) throw damaged("is not a sweep run's result: not a JSON object");
    // A number of the result: finite, or null (or absent) where it may be missing.
    const auto figure = [&](const char* key) -> std::optional<double> {
      if (!j.contains(key) || j.at(key).is_null()) return std::nullopt;
      if (!j.at(key).is_number()) throw damaged(fmt::format("is not a sweep run's result: {} is not a number", key));
      const double v = j.at(key).get<double>();
      if (!std::isfinite(v)) throw damaged(fmt::format("is not a sweep run's result: {} is not finite", key));
      return v;
    };
    const auto count = [&](const char* key) {
      if (!j.at(key).is_number_integer() || j.at(key).get<std::int64_t>() < 0 ||
          j.at(key).get<std::int64_t>() > std::numeric_limits<int>::max())
        throw damaged(fmt::format("is not a sweep run's result: {} is not a count", key));
      return j.at(key).get<int>();
    };
    SweepRunResult r;
    r.hash = j.at("hash").get<std::string>();
    if (!hex_digits(r.hash, 16)) throw damaged("is not a sweep run's result: hash is not 16 hex digits");
    r.index = count("index");
    r.status = j.at("status").get<std::string>();
    if (r.status != "finished" && r.status != "not_converged" && r.status != "failed")
      throw damaged(fmt::format("is not a sweep run's result: unknown status \"{}\"", r.status));
    r.message = j.value("message", "");
    r.force_unit = j.at("units").value("force", "");
    r.increments = count("increments");
    r.peak_depth = figure("peak_depth");
    r.peak_force = figure("peak_force");
    r.final_alpha = figure("final_alpha");
    r.final_force = figure("final_P");
    r.final_contact = figure("final_a");
    r.force_relative_error_estimate = figure("P_relative_error_estimate");
    r.hardness = figure("H");
    r.reduced_modulus = figure("E_r");
    r.specimen_modulus = figure("E");
    r.residual_depth = figure("h_f");
    r.pile_up_ratio = figure("pile_up_ratio");
    r.material_E = figure("material_E");
    r.newton_iterations = count("newton_iterations");
    const auto wall = figure("wall_s");
    if (!wall) throw damaged("is not a sweep run's result: wall_s is missing");
    r.wall_seconds = *wall;
    if (j.contains("files")) {
      if (!j.at("files").is_object()) throw damaged("is not a sweep run's result: files is not an object");
      for (const auto& [name, f] : j.at("files").items()) {
        KeptFile kept;
        kept.name = name;
        if (!inside_folder(name))
          throw damaged(fmt::format("is not a sweep run's result: a kept file \"{}\" outside its folder", name));
        if (!f.is_object() || !f.at("bytes").is_number_unsigned())
          throw damaged(fmt::format("is not a sweep run's result: files.{} has no size", name));
        kept.bytes = f.at("bytes").get<std::uintmax_t>();
        kept.fnv1a = f.at("fnv1a").get<std::string>();
        if (!hex_digits(kept.fnv1a, 16))
          throw damaged(fmt::format("is not a sweep run's result: files.{} has no checksum", name));
        r.files.push_back(std::move(kept));
      }
    }
    return r;
  } catch (const nlohmann::json::exception& e) {
    throw damaged(fmt::format("is not a sweep run's result: {}", e.what()));
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

bool SweepResults::complete(const std::string& hash) const { return look_up(hash).result.has_value(); }

SweepRunLookup SweepResults::look_up(const std::string& hash) const {
  SweepRunLookup found;
  const fs::path dir = out_ / "runs" / hash;
  found.file = dir / "result.json";
  std::error_code ec;
  if (!fs::is_regular_file(found.file, ec)) return found;  // no result (a folder without one is replaced)
  std::ifstream in(found.file, std::ios::binary);
  if (!in) {
    found.problem = fmt::format("cannot be read ({})", std::strerror(errno ? errno : EIO));
    return found;
  }
  std::ostringstream text;
  text << in.rdbuf();
  SweepRunResult r;
  try {
    r = SweepRunResult::from_json(text.str(), found.file.string());
  } catch (const InputError& e) {
    found.problem = e.problem();
    return found;
  }
  if (r.hash != hash) {
    found.problem = fmt::format("is the result of run {} (index {}), not of the run {} whose folder it is in", r.hash,
                                r.index, hash);
    return found;
  }
  // The files kept with it, as they were written (a copy cut short, a file edited or lost).
  for (const auto& f : r.files) {
    const fs::path path = dir / f.name;
    std::error_code size_error;
    if (!fs::is_regular_file(path, ec)) {
      found.problem = fmt::format("{}, kept with it, is missing", f.name);
      return found;
    }
    const std::uintmax_t bytes = fs::file_size(path, size_error);
    if (size_error) {
      found.problem = fmt::format("{}, kept with it, cannot be read ({})", f.name, size_error.message());
      return found;
    }
    if (bytes != f.bytes) {
      found.problem = fmt::format("{} has {} bytes, not the {} result.json recorded (cut short or changed)", f.name,
                                  bytes, f.bytes);
      return found;
    }
    if (checksum_checked(f.name)) {
      const auto checksum = file_checksum(path);
      if (!checksum) {
        found.problem = fmt::format("{}, kept with it, cannot be read", f.name);
        return found;
      }
      if (hex16(*checksum) != f.fnv1a) {
        found.problem = fmt::format("{} is not the file result.json recorded (FNV-1a {}, recorded {}): changed or "
                                    "damaged",
                                    f.name, hex16(*checksum), f.fnv1a);
        return found;
      }
    }
  }
  found.result = std::move(r);
  return found;
}

std::optional<SweepRunResult> SweepResults::result(const std::string& hash) const { return look_up(hash).result; }

SweepRunResult SweepResults::run(const SweepRun& run, const std::vector<std::string>& keep) const {
  // A run without its case is the caller's slip, not a failed run to record and never redo.
  if (run.case_toml.empty())
    throw InputError(fmt::format("sweep run {} ({})", run.index, run.hash), "case",
                     "has no load case to solve (SweepManifest::run_case makes it)");
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
    const LoadCase lc = parse_load_case(run.case_toml, fmt::format("sweep run {} ({})", run.index, run.hash),
                                        {"output.dir=" + toml_string(partial.string()), "output.checkpoint_every=0"});
    result.material_E = lc.material.E;
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
  // Each kept file's size and checksum, so that a copy cut short or a file changed later is seen.
  result.files = kept_files(partial);
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
    // A folder under the hash without a whole result.json is no result (left by hand, damaged,
    // or of another run): it is replaced, once.
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
  table += ",status,peak_depth,peak_force,final_alpha,final_P,final_a,P_relative_error_estimate,H,E_r,E,h_f,"
           "pile_up_ratio,material_E,increments,newton_iterations,wall_s,force_unit,message\n";
  const auto number = [](const std::optional<double>& v) { return v ? fmt::format("{:.17g}", *v) : std::string(); };
  for (const SweepRun& run : manifest.runs) {
    if (const int signal = interruption_requested()) throw Interrupted(signal);
    ++tally.runs;
    std::string row = fmt::format("{},{}", run.index, run.hash);
    for (const auto& value : run.values) {
      // Strings without their TOML quotes: the table holds values, not TOML.
      const bool quoted = value.size() >= 2 && value.front() == '"' && value.back() == '"';
      row += "," + csv_field(quoted ? value.substr(1, value.size() - 2) : value);
    }
    const SweepRunLookup found = look_up(run.hash);
    if (!found.result) {
      ++tally.pending;
      std::string message;
      if (!found.problem.empty()) {
        ++tally.damaged;
        tally.problems.push_back(found.file.string() + ": " + found.problem);
        message = "no result: result.json " + found.problem + "; the sweep does the run again";
      }
      table += row + ",pending" + std::string(17, ',') + csv_field(message) + "\n";  // 17 columns after status
      continue;
    }
    const SweepRunResult& r = *found.result;
    if (r.status == "finished") ++tally.finished;
    else if (r.status == "not_converged") ++tally.not_converged;
    else ++tally.failed;
    table += row + fmt::format(",{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{:.6f},{},{}\n", r.status,
                               number(r.peak_depth), number(r.peak_force), number(r.final_alpha),
                               number(r.final_force), number(r.final_contact),
                               number(r.force_relative_error_estimate), number(r.hardness),
                               number(r.reduced_modulus), number(r.specimen_modulus), number(r.residual_depth),
                               number(r.pile_up_ratio), number(r.material_E), r.increments, r.newton_iterations,
                               r.wall_seconds, csv_field(r.force_unit), csv_field(r.message));
  }
  fs::create_directories(out_);
  write_file_atomically(table_path(), table);
  return tally;
}

}  // namespace indentsim
