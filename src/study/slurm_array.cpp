// The sbatch script of a sweep's job array (slurm_array.hpp).
#include "indentsim/study/slurm_array.hpp"

#include <fmt/format.h>

namespace indentsim {

std::string shell_quote(const std::string& text) {
  std::string quoted = "'";
  for (char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

std::string slurm_array_script(const SlurmArrayJob& job) {
  // #SBATCH lines are read by sbatch, not by the shell: no quoting there.  sbatch does not create
  // the log folder; `indentsim sweep --slurm` does, beside the script.
  return fmt::format(
      "#!/bin/bash\n"
      "# Written by `indentsim sweep {file} --slurm`: array task i runs shard i of {n} of the sweep\n"
      "# (the runs whose index, from 0, is i - 1 mod {n}).  Submit with `sbatch {script}`, adding\n"
      "# your site's #SBATCH lines (partition, time, account) below.  A task that fails or runs out\n"
      "# of time can be submitted again (sbatch --array=K {script}): runs already done are\n"
      "# skipped.  At the end, `indentsim sweep {file} --collect` writes {table}.\n"
      "#SBATCH --job-name=indentsim-sweep\n"
      "#SBATCH --array=1-{n}\n"
      "#SBATCH --ntasks=1\n"
      "#SBATCH --cpus-per-task=1\n"
      "#SBATCH --chdir={here}\n"
      "#SBATCH --output={logs}/shard_%a.log\n"
      "set -euo pipefail\n"
      "cd {here_q}\n"
      "exec {self} sweep {file_q} --shard \"${{SLURM_ARRAY_TASK_ID}}/{n}\" --quiet\n",
      fmt::arg("file", job.sweep_file), fmt::arg("n", job.shards), fmt::arg("script", (job.out / "sweep.sbatch").string()),
      fmt::arg("table", (job.out / "results.csv").string()), fmt::arg("here", job.working_dir.string()),
      fmt::arg("logs", (job.out / "slurm").string()), fmt::arg("here_q", shell_quote(job.working_dir.string())),
      fmt::arg("self", shell_quote(job.executable.string())), fmt::arg("file_q", shell_quote(job.sweep_file)));
}

}  // namespace indentsim
