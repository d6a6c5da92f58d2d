#pragma once
// A sweep on a Slurm cluster: one sbatch script whose job array runs the sweep's shards, array
// task i running `indentsim sweep SWEEP --shard i/N` (sweep.hpp: the runs whose 0-based index is i - 1 mod N).  Every
// task writes its finished runs under their hashes (sweep_results.hpp), so a task that dies or
// runs out of time is simply submitted again, and `--collect` builds the table at the end.
#include <filesystem>
#include <string>

namespace indentsim {

struct SlurmArrayJob {
  std::filesystem::path executable;   ///< the indentsim to run (this one)
  std::filesystem::path working_dir;  ///< where the sweep's relative paths start (--chdir)
  std::string sweep_file;             ///< as given on the command line
  std::filesystem::path out;          ///< the sweep's results folder (logs go to OUT/slurm)
  int shards = 1;                     ///< array tasks 1..shards
};

/// The sbatch script.  The site's own #SBATCH lines (partition, time, account) are added to its
/// header by hand; it asks for one CPU per task, which is what one run uses.
std::string slurm_array_script(const SlurmArrayJob& job);

/// `text` quoted for a POSIX shell: in single quotes, each ' written as '\''.
std::string shell_quote(const std::string& text);

}  // namespace indentsim
