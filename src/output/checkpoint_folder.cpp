#include "indentsim/output/checkpoint_folder.hpp"

#include <algorithm>
#include <map>
#include <optional>

#include <fmt/format.h>

#include "indentsim/base/error.hpp"
#include "indentsim/base/file_system.hpp"
#include "indentsim/simulation/load_stepping.hpp"

namespace indentsim {

CheckpointSchedule CheckpointSchedule::of(const LoadCase& load_case) {
  CheckpointSchedule schedule;
  schedule.every = load_case.output.checkpoint_every;
  schedule.keep = load_case.output.keep_checkpoints;
  const std::vector<int> reversals = reversal_steps(plan_increments(load_case.load));
  schedule.waypoint_steps.insert(reversals.begin(), reversals.end());
  return schedule;
}

bool CheckpointSchedule::due(int step) const {
  if (step <= 0) return false;
  return (every > 0 && step % every == 0) || waypoint_steps.count(step) > 0;
}

std::filesystem::path save_checkpoint(const std::filesystem::path& dir, const Checkpoint& checkpoint,
                                      const CheckpointSchedule& schedule) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw_io_error(dir, "creating the folder", ec.value());
  const int step = checkpoint.curve.empty() ? 0 : checkpoint.curve.back().step;
  const std::filesystem::path file = dir / fmt::format("checkpoint_{:06d}.ck", step);
  write_checkpoint(file, checkpoint);
  // Keep the newest `keep` (all when keep = 0) and every waypoint's; remove the others and any
  // temporary file a killed write left.
  std::vector<std::pair<int, std::filesystem::path>> existing;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    const auto& p = entry.path();
    const std::string name = p.filename().string();
    if (p.extension() == ".ck" && name.rfind("checkpoint_", 0) == 0) {
      const std::string digits = p.stem().string().substr(11);
      if (!digits.empty() && digits.size() <= 9 && digits.find_first_not_of("0123456789") == std::string::npos)
        existing.emplace_back(std::stoi(digits), p);
    } else if (p.extension() == ".tmp") {
      std::filesystem::remove(p, ec);
    }
  }
  if (schedule.keep <= 0) return file;
  std::sort(existing.begin(), existing.end());
  for (std::size_t k = 0; k + static_cast<std::size_t>(schedule.keep) < existing.size(); ++k)
    if (!schedule.waypoint_steps.count(existing[k].first)) std::filesystem::remove(existing[k].second, ec);
  return file;
}

bool same_run(const LoadCase& a, const LoadCase& b) {
  return first_physics_difference(a, b).empty() && a.load.control == b.load.control && a.load.path == b.load.path &&
         a.load.increments == b.load.increments && a.load.segment_increments == b.load.segment_increments &&
         a.load.times == b.load.times;
}

namespace {

/// The folder holding the checkpoint files, and the run folder whose case.toml names the run.
std::pair<std::filesystem::path, std::filesystem::path> checkpoint_folders(const std::filesystem::path& folder) {
  std::error_code ec;
  if (std::filesystem::is_directory(folder / "checkpoints", ec)) return {folder / "checkpoints", folder};
  return {folder, folder.has_filename() ? folder.parent_path() : folder.parent_path().parent_path()};
}

}  // namespace

std::vector<CheckpointListing> list_checkpoints(const std::filesystem::path& folder) {
  const auto [checkpoints, run_dir] = checkpoint_folders(folder);
  std::optional<LoadCase> own;
  std::error_code ec;
  if (std::filesystem::is_regular_file(run_dir / "case.toml", ec)) {
    try {
      own = read_load_case(run_dir / "case.toml");
    } catch (const InputError&) {
      // An unreadable case.toml names no run: every checkpoint is judged by itself.
    }
  }
  std::vector<CheckpointListing> listing;
  for (const auto& entry : std::filesystem::directory_iterator(checkpoints, ec)) {
    const auto& p = entry.path();
    const std::string name = p.filename().string();
    if (p.extension() != ".ck" || name.rfind("checkpoint_", 0) != 0) continue;
    CheckpointListing item;
    item.file = p;
    try {
      const Checkpoint c = read_checkpoint(p);
      item.load_case = parse_load_case(c.load_case_toml, p.string());
      const LoadCase& lc = item.load_case;
      item.step = c.curve.back().step;
      item.alpha = c.curve.back().alpha;
      item.force = c.curve.back().force;
      const std::vector<int> reversals = reversal_steps(plan_increments(lc.load));
      item.reversal = std::find(reversals.begin(), reversals.end(), item.step) != reversals.end();
      item.of_the_folders_run = !own || same_run(*own, lc);
    } catch (const InputError& e) {
      item.problem = e.problem();
    }
    listing.push_back(item);
  }
  std::sort(listing.begin(), listing.end(),
            [](const CheckpointListing& a, const CheckpointListing& b) { return a.step < b.step; });
  return listing;
}

std::filesystem::path choose_checkpoint(const std::filesystem::path& argument) {
  std::error_code ec;
  if (!std::filesystem::is_directory(argument, ec)) return argument;
  const std::vector<CheckpointListing> listing = list_checkpoints(argument);
  std::vector<CheckpointListing> usable;
  for (const auto& item : listing)
    if (item.problem.empty() && item.of_the_folders_run) usable.push_back(item);
  if (usable.empty())
    throw InputError(argument.string(), "checkpoint",
                     listing.empty() ? "is a folder without checkpoint_*.ck files"
                                     : fmt::format("holds no resumable checkpoint of its own run ({} checkpoint(s) "
                                                   "damaged or of another run; see indentsim resume {} --list)",
                                                   listing.size(), argument.string()));
  // Without a case.toml, checkpoints of different runs cannot be told apart: refuse to guess.
  for (const auto& item : usable)
    if (!same_run(usable.front().load_case, item.load_case))
      throw InputError(argument.string(), "checkpoint",
                       fmt::format("holds checkpoints of different runs ({} and {}) and no case.toml to tell which "
                                   "is the folder's: name the checkpoint file",
                                   usable.front().file.filename().string(), item.file.filename().string()));
  return usable.back().file;
}

}  // namespace indentsim
