// indentsim: the command line.  Thin glue over the library: read a load case (or a checkpoint),
// run it, write the outputs.  Exit status: 0 success, 2 bad input (nothing written), 3 the solver
// could not converge (converged increments are kept), 4 a file could not be written or read (the
// operating system's reason is printed; the folder is marked failed), 128 + signal when stopped
// by SIGINT or SIGTERM (after checkpointing), 1 anything else.
#include <algorithm>
#include <cerrno>
#include <cstring>
#include <optional>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <unistd.h>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "indentsim/output/checkpoint.hpp"
#include "indentsim/output/checkpoint_folder.hpp"
#include "indentsim/analysis/curve_analysis.hpp"
#include "indentsim/base/error.hpp"
#include "indentsim/simulation/error_estimate.hpp"
#include "indentsim/fitting/fit_files.hpp"
#include "indentsim/base/file_system.hpp"
#include "indentsim/base/interruption.hpp"
#include "indentsim/output/run_output.hpp"
#include "indentsim/input/load_case.hpp"
#include "indentsim/driver/run_driver.hpp"
#include "indentsim/output/run_folder.hpp"
#include "indentsim/simulation/simulation.hpp"
#include "indentsim/study/slurm_array.hpp"
#include "indentsim/study/sweep.hpp"
#include "indentsim/study/sweep_results.hpp"
#include "indentsim/base/version.hpp"
#include "indentsim/base/worker_threads.hpp"

namespace fs = std::filesystem;
using namespace indentsim;

namespace {

constexpr int exit_bad_input = 2;
constexpr int exit_io_failure = 4;

/// What a run says, on the terminal: notes on stdout (unless quiet), warnings on stderr, and the
/// progress line on stderr for runs longer than a moment (increment k of N, alpha, P, Newton
/// iterations, elapsed and remaining time), rewritten in place on a terminal, otherwise a line
/// every few seconds.
class ConsoleObserver : public RunObserver {
public:
  explicit ConsoleObserver(bool quiet) : quiet_(quiet), terminal_(isatty(fileno(stderr)) != 0), start_(clock::now()) {}

  void note(const std::string& line) override {
    if (!quiet_) fmt::print("{}\n", line);
  }
  void increments_started() override { start_ = last_ = clock::now(); }  // elapsed: the increments'
  void warning(const std::string& text) override {
    clear_line();
    fmt::print(stderr, "warning: {}\n", text);
  }
  void increment(const IncrementRecord& r, int planned, const std::string& force_unit) override {
    if (quiet_) return;
    const double elapsed = seconds_since(start_);
    if (elapsed < 1.0) return;
    if (!terminal_ && seconds_since(last_) < 5.0 && r.step < planned) return;
    last_ = clock::now();
    const double remaining = elapsed / r.step * std::max(0, planned - r.step);
    const std::string line = fmt::format("increment {}/{}  alpha = {:.4g} m  P = {:.5g} {}  Newton {}  elapsed {:.1f} s  "
                                         "remaining ~{:.1f} s",
                                         r.step, planned, r.alpha, r.force, force_unit, r.newton_iterations, elapsed,
                                         remaining);
    if (terminal_) {
      fmt::print(stderr, "\r{}\033[K", line);
      shown_ = true;
    } else {
      fmt::print(stderr, "{}\n", line);
    }
    std::fflush(stderr);
  }
  void increments_ended() override {
    if (shown_) fmt::print(stderr, "\n");
    shown_ = false;
  }

private:
  using clock = std::chrono::steady_clock;
  static double seconds_since(clock::time_point t) { return std::chrono::duration<double>(clock::now() - t).count(); }
  void clear_line() {
    if (shown_) fmt::print(stderr, "\r\033[K");
    shown_ = false;
  }
  bool quiet_, terminal_, shown_ = false;
  clock::time_point start_, last_{};
};

/// The end of a run on the terminal and its exit status: the reason it did not converge, or how
/// to resume it, on stderr (named by the case or checkpoint run); the curve's path otherwise.
int report_end(const RunReport& report, bool quiet) {
  const std::string& label = report.load_case.source;
  if (report.status == RunStatus::not_converged) fmt::print(stderr, "{}: {}\n", label, report.message);
  if (report.status == RunStatus::stopped)
    fmt::print(stderr, "{}: stopped by signal {} after increment {}; resume with: indentsim resume {}\n", label,
               report.stop_signal, report.last_step, report.resume_checkpoint.string());
  if (!quiet) fmt::print("P-alpha curve: {}\n", report.curve_file.string());
  return report.exit_status();
}

int command_check(const std::string& file, const std::vector<std::string>& overrides) {
  const LoadCase lc = with_depth_estimate(read_load_case(file, overrides));  // force control's depth pilot
  inspect_output_dir(lc.output.dir, lc.source);
  const RunConfiguration configuration = resolve_choices(lc, plan_run(lc));  // what run uses, pilot included
  const MeshPlan& p = configuration.plan.mesh;
  for (const auto& warning : plausibility_warnings(lc, p)) fmt::print(stderr, "warning: {}\n", warning);
  fmt::print("{}: valid; model {}, depth up to {:.4g} m in {} increments; mesh {} x {} nodes, {} unknowns\n", file,
             to_string(lc.material.model), lc.max_depth(), lc.load.increments, p.nodes_x, p.nodes_y,
             configuration.unknowns);
  fmt::print("the run's configuration (every \"auto\" resolved):\n");
  for (const auto& [name, value] : describe(configuration)) fmt::print("  {}: {}\n", name, value);
  return 0;
}

extern "C" void on_stop_signal(int signal) { request_interruption(signal); }

int command_run(const std::string& file, const std::vector<std::string>& overrides, const std::string& out,
                bool quiet) {
  std::vector<std::string> all = overrides;
  if (!out.empty()) all.push_back("output.dir=" + toml_string(out));
  ConsoleObserver console(quiet);
  return report_end(run_load_case(read_load_case(file, all), console), quiet);
}

int command_list_checkpoints(const std::string& argument) {
  const auto listing = list_checkpoints(argument);
  if (listing.empty()) throw InputError(argument, "checkpoint", "is a folder without checkpoint_*.ck files");
  fmt::print("{:<28} {:>8} {:>14} {:>14}  note\n", "checkpoint", "step", "alpha [m]", "P");
  for (const auto& c : listing) {
    std::string note = c.problem.empty() ? (c.reversal ? "reversal of the load path" : "") : "cannot resume: " + c.problem;
    if (c.problem.empty() && !c.of_the_folders_run) note = "of another run than the folder's case.toml";
    if (c.problem.empty())
      fmt::print("{:<28} {:>8} {:>14.6g} {:>14.6g}  {}\n", c.file.filename().string(), c.step, c.alpha, c.force, note);
    else
      fmt::print("{:<28} {:>8} {:>14} {:>14}  {}\n", c.file.filename().string(), "-", "-", "-", note);
  }
  return 0;
}

int command_resume(const std::string& argument, const std::vector<std::string>& overrides, const std::string& out,
                   bool quiet) {
  ConsoleObserver console(quiet);
  return report_end(resume_run(argument, overrides, out, console), quiet);
}

/// The figure script beside this executable (installed with it by CMake).
fs::path figure_script(const std::string& for_what) {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  const fs::path script = self.parent_path() / "plot_results.py";
  if (ec || !fs::is_regular_file(script))
    throw InputError(for_what, "plot", fmt::format("the figure script is not beside the executable (looked for {})",
                                                   script.string()));
  return script;
}

/// Replaces this process with Debian's python3 (the one the setup script gives matplotlib)
/// running `args`, whatever python3 comes first on the PATH.
[[noreturn]] void exec_python(std::vector<std::string> args, const std::string& for_what) {
  const std::string python = fs::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
  args.insert(args.begin(), python);
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::fflush(stdout);
  ::execvp(argv[0], argv.data());
  throw InputError(for_what, "python3", fmt::format("cannot run {}: {}", python, std::strerror(errno)));
}

/// `indentsim plot DIR [--step N] [--data CSV] [--size slide|column]`: the figure script beside this executable, run by Debian's
/// python3 (the one the setup script gives matplotlib), whatever python3 comes first on the PATH.
int command_plot(const std::string& dir, const std::optional<int>& step, const std::string& data,
                 const MeasuredCurveOptions& columns, const std::string& size) {
  const fs::path script = figure_script(dir);
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw InputError(dir, "plot", "is not a run's or a sweep's output folder");
  const bool sweep = fs::is_regular_file(fs::path(dir) / "results.csv", ec);
  const bool run = fs::is_regular_file(fs::path(dir) / "case.toml", ec) && fs::is_regular_file(fs::path(dir) / "curve.csv", ec);
  if (!sweep && !run)
    throw InputError(dir, "plot", "holds no run (case.toml and curve.csv) and no sweep (results.csv): nothing to draw");
  std::vector<std::string> args{script.string(), dir};
  if (step) {
    if (!run) throw InputError(dir, "--step", "is for a run's folder, not a sweep's");
    // The curve's rows are its increments 0..N: a step beyond them has no state to show.
    std::ifstream curve(fs::path(dir) / "curve.csv");
    long rows = -1;  // the header
    for (std::string line; std::getline(curve, line);)
      if (!line.empty()) ++rows;
    if (*step < 0 || *step >= rows)
      throw InputError(dir, "--step", fmt::format("{} is not an increment of the run (it has 0 to {})", *step, rows - 1));
    args.push_back("--step");
    args.push_back(std::to_string(*step));
  }
  if (!data.empty()) {
    if (!run) throw InputError(dir, "--data", "overlays a measured curve on a run's, not on a sweep's");
    if (!fs::is_regular_file(data, ec)) throw InputError(data, "--data", "is not a readable file");
    args.push_back("--data");
    args.push_back(data);
    for (const auto& [flag, value] : {std::pair<const char*, const std::string&>{"--depth-column", columns.depth_column},
                                      {"--force-column", columns.force_column},
                                      {"--depth-unit", columns.depth_unit},
                                      {"--force-unit", columns.force_unit}})
      if (!value.empty()) {
        args.push_back(flag);
        args.push_back(value);
      }
  } else if (columns.given()) {
    throw InputError(dir, "--data", "the column and unit options describe a measured curve: give it with --data");
  }
  if (!size.empty()) {
    args.push_back("--size");
    args.push_back(size);
  }
  exec_python(args, dir);
}

/// `indentsim analyze CURVE`: Oliver-Pharr on every unloading branch of a run's curve (its folder
/// or curve.csv) or of a measured CSV; prints the results and writes analysis.json (and with
/// --plot its figure).  Anything that cannot be analysed exits 2 with nothing written.
int command_analyze(const std::string& curve, const std::vector<std::string>& overrides,
                    const MeasuredCurveOptions& measured, const std::string& out_file, bool plot) {
  const CurveAnalysis analysis = analyze_curve(curve, overrides, measured);
  const fs::path out = out_file.empty() ? default_analysis_path(curve, analysis.simulated) : fs::path(out_file);
  const fs::path script = plot ? figure_script(curve) : fs::path();
  write_file_atomically(out, analysis_json(analysis).dump(2) + "\n");
  fmt::print("{}analysis: {}\n", analysis_table(analysis), out.string());
  for (const std::string& w : implausible_results(analysis)) fmt::print(stderr, "warning: {}\n", w);
  for (const std::string& w : substrate_effect_warnings(analysis)) fmt::print(stderr, "warning: {}\n", w);
  if (plot) exec_python({script.string(), "--analysis", out.string()}, curve);
  return 0;
}

/// `indentsim fit`: material parameters from measured curves (fit.hpp); writes DIR/fit.json,
/// DIR/fit_curves.csv, DIR/fitted_case.toml (one per data set beyond the first: fitted_case_K.toml)
/// and the figure DIR/fit.png.  Exit status: 0 a good fit; 3 a poor fit (rms misfit beyond
/// poor_fit_rms_limit of the peak, or a parameter at a bound: the files are written, fit.json's
/// "quality" says why, each problem is a warning); 2 bad input, before any run, with nothing
/// written; 128 + signal after SIGINT/SIGTERM (the checkpoint DIR/fit_checkpoint.json kept for
/// --resume, the best parameters so far on stderr).  -q: no progress line and no notes, only the result, warnings and errors.
int command_fit(FitCommandLine cl, bool quiet, bool plot) {
  constexpr int exit_poor_fit = 3;  // like a run that did not converge: what was computed is kept
  FitJob job = read_fit_job(cl);
  const bool terminal = isatty(fileno(stderr)) != 0;
  bool progress_shown = false;
  if (!quiet) {
    for (const std::string& note : job.notes) fmt::print("note: {}\n", note);
    std::fflush(stdout);
    job.problem.settings.on_iteration = [&](const FitProgress& p) {
      std::string values;
      for (std::size_t j = 0; j < p.theta.size(); ++j)
        values += fmt::format("  {}={:.5g}", key_of(job.problem.free[j].parameter), p.theta[j]);
      const std::string where = p.phase == "coarse" || p.phase == "fine"
                                    ? fmt::format("fit {} start {}/{}", p.phase, p.start, p.starts)
                                    : fmt::format("fit {}", p.phase);  // polish, refined, profile
      const auto duration = [](double seconds) {
        return seconds < 90.0 ? fmt::format("{:.0f} s", seconds)
               : seconds < 5400.0 ? fmt::format("{:.1f} min", seconds / 60.0)
                                  : fmt::format("{:.1f} h", seconds / 3600.0);
      };
      const std::string remaining =
          std::isfinite(p.remaining_seconds) ? fmt::format(", remaining ~{}", duration(p.remaining_seconds)) : "";
      fmt::print(stderr, "{}{} iteration {:>2}  cost {:.4e}{}  ({} runs, {} coarse; elapsed {}{}){}",
                 terminal ? "\r\033[K" : "", where, p.iteration, p.cost, values, p.forward_runs, p.coarse_runs,
                 duration(p.elapsed_seconds), remaining, terminal ? "" : "\n");
      progress_shown = terminal;
    };
  }
  job.problem.settings.on_warning = [&](const std::string& warning) {
    if (progress_shown) fmt::print(stderr, "\r\033[K");
    fmt::print(stderr, "warning: {}\n", warning);
  };
  FitResult result;
  try {
    result = run_fit_job(job, cl.resume);
  } catch (const FitInterrupted& e) {
    if (progress_shown) fmt::print(stderr, "\n");
    const fs::path checkpoint = fs::path(job.out_dir) / fit_checkpoint_name;
    std::error_code ec;
    if (fs::exists(checkpoint, ec))
      fmt::print(stderr,
                 "fit stopped by signal {} after {} forward run(s) ({} more on the coarse meshes); its checkpoint is "
                 "{}: the same command with --resume continues it\n",
                 e.signal(), e.forward_runs(), e.coarse_runs(), checkpoint.string());
    else
      fmt::print(stderr, "fit stopped by signal {} after {} forward run(s) ({} more on the coarse meshes) before its "
                         "first accepted step; nothing written to {}\n",
                 e.signal(), e.forward_runs(), e.coarse_runs(), job.out_dir);
    if (e.best().empty()) {
      fmt::print(stderr, "no start had reached a successful forward run: no parameters to keep\n");
    } else {
      // The --set options in the keys the case gives (a case with e0 refuses a yield stress).
      const LoadCase& given = job.problem.data.front().load_case;
      LoadCase best = given;
      for (std::size_t j = 0; j < e.best().size(); ++j) set_value(best, job.problem.free[j].parameter, e.best()[j]);
      std::string values, sets;
      for (std::size_t j = 0; j < e.best().size(); ++j) {
        const RegionParameter parameter = job.problem.free[j].parameter;
        values += fmt::format("  {}={:.6g}", key_of(parameter), e.best()[j]);
        if (parameter.which == MaterialParameter::yield_stress && !given.region_material(parameter.region).yield_stress)
          sets += fmt::format(" --set {}={:.6g}", key_of(RegionParameter{MaterialParameter::e0, parameter.region}),
                              best.region_material(parameter.region).e0);
        else
          sets += fmt::format(" --set {}={:.6g}", key_of(parameter), e.best()[j]);
      }
      fmt::print(stderr, "the best parameters so far ({}, cost {:.4e}; not a converged fit):{}\nto fit again from there:{}\n",
                 e.phase() == "coarse"    ? "on the coarse meshes"
                 : e.phase() == "refined" ? "on the forward meshes refined for the model's error"
                                          : "on the cases' own meshes",
                 e.cost(), values, sets);
    }
    return 128 + e.signal();
  }
  if (progress_shown) fmt::print(stderr, "\n");
  const fs::path dir = job.out_dir;
  fmt::print("fit of {} data set(s), {} forward runs (and {} on the coarse meshes), {:.1f} s ({}):\n",
             job.problem.data.size(), result.forward_runs, result.coarse_runs, result.wall_seconds,
             result.data.front().gradients);
  // Each parameter with its 95% interval (noise and the model's own error) and the verdict.
  for (std::size_t j = 0; j < result.values.size(); ++j) {
    const ParameterDetermination& pd = result.determination[j];
    fmt::print("  {:<22} {:.6g}  95% [{:.4g}, {:.4g}]: {}\n", key_of(job.problem.free[j].parameter), result.values[j],
               pd.lower, pd.upper, pd.verdict);
  }
  fmt::print("  (standard errors: noise {}{})\n", [&] {
    std::string s;
    for (std::size_t j = 0; j < result.values.size(); ++j)
      s += fmt::format("{}{:.3g}", j ? ", " : "", result.std_errors[j]);
    return s;
  }(), [&] {
    if (!result.model_error_estimated) return std::string("; the model's own error not estimated");
    std::string s = "; the model's discretization shift ";
    bool increments = false;
    for (std::size_t j = 0; j < result.values.size(); ++j) {
      s += fmt::format("{}{:.3g}", j ? ", " : "", result.determination[j].model_shift);
      increments = increments || result.determination[j].model_shift_increments != 0.0;
    }
    if (increments) {
      s += " (the increments' share ";
      for (std::size_t j = 0; j < result.values.size(); ++j)
        s += fmt::format("{}{:.3g}", j ? ", " : "", result.determination[j].model_shift_increments);
      s += ")";
    }
    return s;
  }());
  if (result.good())
    fmt::print("  rms residual {:.3g}% (relative); condition number {:.3g}: {}\n", 100.0 * result.rms_relative,
               result.condition_number,
               result.identifiable ? "every parameter determined" : "NOT every parameter determined");
  else
    fmt::print("  rms residual {:.3g}% (relative); condition number {:.3g}; {}\n", 100.0 * result.rms_relative,
               result.condition_number, result.quality);
  if (!result.poorly_determined.empty()) fmt::print("  {}\n", result.poorly_determined);
  // The next measurement: each candidate addition's predicted noise-only 95% half-widths.
  if (!result.experiment_design.empty() && !result.identifiable) {
    fmt::print("  what another measurement would do (noise-only 95% half-widths; today");
    for (std::size_t j = 0; j < result.noise_relative_half_width.size(); ++j)
      fmt::print(" {} +-{:.3g}%", key_of(job.problem.free[j].parameter), 100.0 * result.noise_relative_half_width[j]);
    fmt::print("):\n");
    for (const CandidateExperiment& c : result.experiment_design) {
      if (!c.failure.empty()) {
        fmt::print("    {:<17} not evaluated: {}\n", c.name, c.failure);
        continue;
      }
      std::string widths;
      for (std::size_t j = 0; j < c.relative_half_width.size(); ++j)
        widths += fmt::format("  {} +-{:.3g}% ({:.2g}x narrower)", key_of(job.problem.free[j].parameter),
                              100.0 * c.relative_half_width[j], c.shrink[j]);
      fmt::print("    {:<17}{}: {}\n", c.name, widths, c.description);
    }
  }
  if (!quiet && (result.failed_runs > 0 || result.refused_evaluations > 0))
    fmt::print("  {} forward run(s) failed even with steps a sixteenth as long, and {} parameter point(s) were refused "
               "by the model; the optimiser stepped back from each\n",
               result.failed_runs, result.refused_evaluations);
  for (const std::string& problem : result.quality_problems)
    fmt::print(stderr, "warning: poor fit: {} ({})\n", problem,
               problem.find(" bound ") != std::string::npos
                   ? "the optimum lies at or beyond it, so the value is no estimate: widen --bounds, or check the data"
                   : fmt::format("a fit that describes its data stays below {:g}%: check the force column's sign and "
                                 "unit, the scene (axisymmetric or plane strain) and the load case",
                                 100.0 * poor_fit_rms_limit));
  fmt::print("results: {}{}\n", (dir / "fit.json").string(), result.good() ? "" : " (quality: poor fit)");
  const int status = result.good() ? 0 : exit_poor_fit;
  if (plot) {
    std::error_code ec;
    const fs::path script = fs::read_symlink("/proc/self/exe", ec).parent_path() / "plot_fit.py";
    if (ec || !fs::is_regular_file(script)) {
      fmt::print(stderr, "warning: the figure script plot_fit.py is not beside the executable; no figure\n");
    } else if (status == 0) {
      exec_python({script.string(), dir.string()}, dir.string());
    } else {
      // A poor fit's figure is drawn by a child process, so that the exit status stays the fit's.
      const auto quoted = [](const std::string& text) {
        std::string q = "'";
        for (char c : text) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
        return q + "'";
      };
      const std::string python = fs::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
      std::fflush(stdout);
      if (std::system((quoted(python) + " " + quoted(script.string()) + " " + quoted(dir.string())).c_str()) != 0)
        fmt::print(stderr, "warning: the figure of {} could not be drawn\n", dir.string());
    }
  }
  return status;
}

struct SweepOptions {
  std::string shard, scheduler;
  bool slurm = false, collect = false, list = false, dask = false;
  int shards = 0, workers = 0;
};

/// `indentsim sweep --dask`: the Python package's Dask driver (python/indentsim/sweep.py), found
/// beside this executable (build/python), run by Debian's python3 in place of this process.
[[noreturn]] void exec_dask_sweep(const std::string& file, const SweepOptions& o, bool quiet) {
  std::error_code ec;
  const fs::path package = fs::read_symlink("/proc/self/exe", ec).parent_path() / "python";
  if (ec || !fs::is_regular_file(package / "indentsim" / "sweep.py"))
    throw InputError(file, "--dask", fmt::format("the Python package is not beside the executable (looked in {}); build "
                                                 "with INDENTSIM_BUILD_PYTHON=ON",
                                                 package.string()));
  const char* old = std::getenv("PYTHONPATH");
  const std::string path = package.string() + (old && *old ? ":" + std::string(old) : "");
  ::setenv("PYTHONPATH", path.c_str(), 1);
  std::vector<std::string> args{"-m", "indentsim.sweep", file};
  if (!o.scheduler.empty()) args.insert(args.end(), {"--scheduler", o.scheduler});
  if (o.workers > 0) args.insert(args.end(), {"--workers", std::to_string(o.workers)});
  if (quiet) args.push_back("--quiet");
  exec_python(args, file);
}

/// A result.json that is no result, on stderr: the file, what is wrong, and what happens.
void warn_damaged(const SweepRunLookup& found, const std::string& then) {
  fmt::print(stderr, "warning: {}: {}; {}\n", found.file.string(), found.problem, then);
}

/// `indentsim sweep SWEEP.toml`: the sweep expanded and validated (exit 2 naming the key, nothing
/// started), its manifest written; then one of: every run in this process and the table (the
/// default), one shard (--shard i/N), the Slurm array's script (--slurm), the table of what is
/// done (--collect), or the runs listed (--list).  Runs with a result are never run again; a
/// result.json that is no whole result of its run is named in a warning and its run done again.
/// Runs are numbered from 0, as in results.csv.  SIGINT/SIGTERM stop it within a run's expansion
/// or at the next Newton iteration of a run.
int command_sweep(const std::string& file, const SweepOptions& o, bool quiet) {
  if (o.dask) {
    try {
      expand_sweep(read_sweep_definition(file));  // bad input exits 2 here, before Python starts
    } catch (const Interrupted& e) {
      fmt::print(stderr, "sweep stopped by signal {} while {} was expanded: nothing was started\n", e.signal(), file);
      return 128 + e.signal();
    }
    exec_dask_sweep(file, o, quiet);
  }
  const bool sharded = !o.shard.empty();
  const auto [i, n] = sharded ? parse_shard(o.shard) : std::pair{1, 1};
  SweepManifest manifest;
  try {
    manifest = expand_sweep(read_sweep_definition(file));
  } catch (const Interrupted& e) {
    fmt::print(stderr, "sweep stopped by signal {} while {} was expanded: nothing was started\n", e.signal(), file);
    return 128 + e.signal();
  }
  const SweepResults results(manifest.definition.out);
  if (manifest.merged_duplicates > 0)
    fmt::print(stderr, "note: {} combination(s) of {} gave the case of an earlier run; each case is run once ({} runs)\n",
               manifest.merged_duplicates, file, manifest.runs.size());
  if (o.list) {
    for (const SweepRun& r : manifest.runs) {
      if (const int signal = interruption_requested()) return 128 + signal;
      std::string values;
      for (std::size_t j = 0; j < manifest.keys.size(); ++j) values += fmt::format("  {} = {}", manifest.keys[j], r.values[j]);
      const SweepRunLookup found = results.look_up(r.hash);
      if (!found.problem.empty()) warn_damaged(found, "listed as pending (the sweep does the run again)");
      fmt::print("{:>6} {} {}{}\n", r.index, r.hash, found.result ? "done   " : "pending", values);
    }
    fmt::print("{}: {} runs (numbered from 0, as in results.csv)\n", file, manifest.runs.size());
    return 0;
  }
  try {
    results.write_manifest(manifest);
  } catch (const Interrupted& e) {
    fmt::print(stderr, "sweep stopped by signal {} while its manifest was written: nothing was started\n", e.signal());
    return 128 + e.signal();
  }
  const auto collect = [&](bool with_pending) {
    const SweepTally t = results.collect(manifest);
    for (const std::string& problem : t.problems)
      fmt::print(stderr, "warning: {}; its row is pending (the sweep does the run again)\n", problem);
    fmt::print("{} runs: {} finished, {} not converged, {} failed", t.runs, t.finished, t.not_converged, t.failed);
    if (with_pending || t.pending > 0) fmt::print(", {} pending", t.pending);
    if (t.damaged > 0) fmt::print(" ({} of them with a damaged result, named above)", t.damaged);
    fmt::print("\ntable: {}\n", results.table_path().string());
  };
  if (o.collect) {
    try {
      collect(true);
    } catch (const Interrupted& e) {
      fmt::print(stderr, "sweep --collect stopped by signal {}: the table was not written\n", e.signal());
      return 128 + e.signal();
    }
    return 0;
  }
  if (o.slurm) {
    const int shards = o.shards > 0 ? std::min<int>(o.shards, static_cast<int>(manifest.runs.size()))
                                    : std::min<int>(100, static_cast<int>(manifest.runs.size()));
    std::error_code ec;
    const fs::path self = fs::read_symlink("/proc/self/exe", ec);
    const fs::path script = manifest.definition.out / "sweep.sbatch";
    fs::create_directories(manifest.definition.out / "slurm");
    write_file_atomically(script, slurm_array_script({ec ? fs::path("indentsim") : self, fs::current_path(), file,
                                                      manifest.definition.out, shards}));
    fs::permissions(script, fs::perms::owner_exec | fs::perms::group_exec, fs::perm_options::add);
    fmt::print("{} runs in {} array tasks: sbatch {}\nthen: indentsim sweep {} --collect\n", manifest.runs.size(), shards,
               script.string(), file);
    return 0;
  }
  const std::vector<const SweepRun*> runs = shard_runs(manifest, i, n);
  const bool terminal = isatty(fileno(stderr)) != 0;
  const auto start = std::chrono::steady_clock::now();
  auto last_line = start;
  int done = 0, skipped = 0, failed = 0, solved = 0;
  try {
    for (const SweepRun* run : runs) {
      if (const int signal = interruption_requested()) throw Interrupted(signal);
      const SweepRunLookup found = results.look_up(run->hash);
      if (found.result) {
        ++skipped;
      } else {
        if (!found.problem.empty()) {
          if (terminal && !quiet) fmt::print(stderr, "\r\033[K");
          warn_damaged(found, fmt::format("run {} is done again", run->index));
        }
        SweepRun job = *run;
        job.case_toml = manifest.run_case(*run);
        const SweepRunResult r = results.run(job, manifest.definition.keep);
        ++solved;
        if (r.status != "finished") {
          ++failed;
          if (terminal && !quiet) fmt::print(stderr, "\r\033[K");
          fmt::print(stderr, "run {} ({}): {}: {}\n", run->index, run->hash, r.status, r.message);
        }
      }
      ++done;
      const auto now = std::chrono::steady_clock::now();
      if (!quiet && (terminal || now - last_line > std::chrono::seconds(5) || done == static_cast<int>(runs.size()))) {
        last_line = now;
        const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        const double remaining = solved > 0 ? elapsed / solved * static_cast<double>(runs.size() - done) : 0.0;
        fmt::print(stderr, "{}sweep{}: {}/{} runs ({} already done, {} not finished)  elapsed {:.1f} s  remaining ~{:.0f} s{}",
                   terminal ? "\r\033[K" : "", sharded ? fmt::format(" shard {}/{}", i, n) : "", done, runs.size(), skipped,
                   failed, elapsed, remaining, terminal ? "" : "\n");
        std::fflush(stderr);
      }
    }
    if (!quiet && terminal) fmt::print(stderr, "\n");
    if (sharded) {
      fmt::print("shard {}/{}: {} runs ({} solved now, {} had results)\n", i, n, runs.size(), solved, skipped);
      return 0;
    }
    collect(false);
  } catch (const Interrupted& e) {
    if (!quiet && terminal) fmt::print(stderr, "\n");
    fmt::print(stderr, "sweep stopped by signal {}: {} of {} runs have results; the same command finishes the rest\n",
               e.signal(), done, runs.size());
    return 128 + e.signal();
  }
  return 0;
}

int command_keys(bool markdown) {
  if (markdown) {
    fmt::print("{}", keys_markdown());
    return 0;
  }
  for (const auto& k : describe_keys()) {
    fmt::print("{}  ({}{}{})\n", k.key, k.type, k.unit.empty() ? "" : ", " + k.unit,
               k.required ? ", required" : ", default " + k.default_value);
    if (!k.range.empty()) fmt::print("    accepted: {}\n", k.range);
    fmt::print("    {}\n", k.help);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  stop_idle_blas_workers();  // one thread of our own: OpenBLAS's idle workers only spin (worker_threads.hpp)
  CLI::App app{"indentsim: indentation of an elasto-plastic specimen by a rigid punch (plane strain or axisymmetric; "
               "sphere, cone, flat, measured profile or calibrated area function)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", version_line());
  std::string file, out;
  std::vector<std::string> overrides;
  bool quiet = false;

  CLI::App* run = app.add_subcommand(
      "run", "solve a load case; write DIR/curve.csv, fields.pvd, layers.csv, profiles.csv, case.toml");
  run->add_option("case", file, "load case (TOML)")->required();
  run->add_option("--out", out, "output folder (overrides output.dir)");
  run->add_option("--set", overrides, "override one key: section.key=value (repeat for more)")
      ->allow_extra_args(false)
      ->take_all();
  run->add_flag("--quiet,-q", quiet, "print nothing but warnings and errors (no progress line)");

  bool list = false;
  CLI::App* resume = app.add_subcommand(
      "resume", "continue a run from a checkpoint (a file, or a run folder: its own newest checkpoint)");
  resume->add_option("checkpoint", file, "checkpoint file, run folder or checkpoints folder")->required();
  resume->add_flag("--list", list, "list the folder's checkpoints (step, alpha, P) and exit");
  resume->add_option("--out", out, "output folder (default: the run's own)");
  resume->add_option("--set", overrides, "override one key, e.g. load.path=... to branch (repeat for more)")
      ->allow_extra_args(false)
      ->take_all();
  resume->add_flag("--quiet,-q", quiet, "print nothing but warnings and errors (no progress line)");

  std::optional<int> plot_step;
  CLI::App* plot = app.add_subcommand("plot", "write the figures of a run into DIR/figures (PNG and SVG)");
  std::string plot_data, plot_size;
  plot->add_option("dir", file, "the run's output folder, or a sweep's (H, E_r, pile-up against the swept keys)")
      ->required();
  plot->add_option("--step", plot_step, "the increment to show (default: the deepest of the load path)");
  plot->add_option("--data", plot_data, "a measured load-depth CSV to overlay on the run's curve (as analyze reads it)");
  plot->add_option("--size", plot_size, "slide (16:9, the default) or column (a journal column)")
      ->check(CLI::IsMember({"slide", "column"}));
  MeasuredCurveOptions plot_columns;
  plot->add_option("--depth-column", plot_columns.depth_column, "--data: the depth column's header name");
  plot->add_option("--force-column", plot_columns.force_column, "--data: the force column's header name");
  plot->add_option("--depth-unit", plot_columns.depth_unit, "--data: nm, um, mm or m (else from the header)");
  plot->add_option("--force-unit", plot_columns.force_unit, "--data: mN, uN, nN or N, per length in plane strain (else from the header)");

  MeasuredCurveOptions analyze_options;
  std::string analysis_out;
  bool analysis_plot = false;
  CLI::App* analyze = app.add_subcommand(
      "analyze", "Oliver-Pharr hardness and modulus of every unloading branch of a run (its folder) or of a measured "
                 "load-depth CSV; writes analysis.json");
  analyze->add_option("curve", file, "a run's output folder (or its curve.csv), or a measured CSV")->required();
  analyze->add_option("--indenter", analyze_options.indenter_file,
                      "measured curve: TOML with [punch], [analysis], [curve] and optionally geometry.kind, material.nu");
  analyze->add_option("--set", overrides, "set one key: punch.shape=cone, analysis.beta=1.034, curve.depth_unit=nm, ...")
      ->allow_extra_args(false)
      ->take_all();
  analyze->add_option("--depth-column", analyze_options.depth_column, "measured curve: the depth column's header name");
  analyze->add_option("--force-column", analyze_options.force_column, "measured curve: the force column's header name");
  analyze->add_option("--depth-unit", analyze_options.depth_unit, "measured curve: nm, um, mm or m (else from the header)");
  analyze->add_option("--force-unit", analyze_options.force_unit, "measured curve: mN, uN, nN or N (else from the header)");
  analyze->add_option("--time-column", analyze_options.time_column,
                      "measured curve: the time column's header name (holds: creep and Feng-Ngan's correction)");
  analyze->add_option("--time-unit", analyze_options.time_unit, "measured curve: s, ms or min (else from the header)");
  analyze->add_option("--out", analysis_out, "analysis.json's path (default: the run's folder, or NAME.analysis.json "
                                                    "beside a measured file)");
  analyze->add_flag("--plot", analysis_plot, "also draw the figure (PNG and SVG beside analysis.json)");

  FitCommandLine fit_options;
  bool no_plot = false;
  CLI::App* fit = app.add_subcommand(
      "fit", "material parameters from measured force-depth curves (and imprints): a load case with --data, or a fit "
             "file with [[data]] tables; writes DIR/fit.json, fit_curves.csv, fitted_case.toml, fit.png");
  fit->add_option("input", fit_options.input, "load case (with --data) or fit file (TOML)")->required();
  fit->add_option("--data", fit_options.data_files, "the measured curve (CSV: alpha [m], P [N] unless told)");
  fit->add_option("--free", fit_options.free, "parameters to fit: material.E, .nu, .e0 or .yield_stress, .kappa, .n, .K, .prestrain, .Q, .b, "
                  ".reference_strain_rate, .creep_coefficient, .reference_stress, .rate_exponent")
      ->delimiter(',');
  fit->add_option("--bounds", fit_options.bounds, "bounds of one parameter: material.n=0.01:0.6 (repeat)");
  fit->add_option("--starts", fit_options.starts,
                  "starts (default 4): the case's values, then points spread over the bounds");
  fit->add_option("--mesh-refinements", fit_options.mesh_refinements,
                  "times the forward meshes may be refined (twice the contact nodes each) where the model's own "
                  "error moves a parameter more than the noise does (default 1)");
  fit->add_option("--threads", fit_options.threads,
                  "starts run side by side on this many threads (default: the cores this process may use); the "
                  "answer does not depend on it");
  fit->add_option("--set", fit_options.overrides, "override one key of every data set's case")->allow_extra_args(false)->take_all();
  fit->add_option("--out", fit_options.out, "output folder (default out/fit, or [fit] out)");
  fit->add_option("--depth-column", fit_options.columns.depth_column, "the curve's depth column (default alpha)");
  fit->add_option("--force-column", fit_options.columns.force_column, "the curve's force column (default P)");
  fit->add_option("--depth-unit", fit_options.columns.depth_unit, "nm, um, mm or m (else the header's, else m)");
  fit->add_option("--force-unit", fit_options.columns.force_unit, "mN, uN, nN or N (else the header's, else N)");
  fit->add_option("--time-column", fit_options.columns.time_column,
                  "the curve's time column: the curve is then a time history along the case's load.times (default "
                  "time, when the case has load.times and the header names it)");
  fit->add_option("--time-unit", fit_options.columns.time_unit, "s, ms or min (else the header's, else s)");
  fit->add_flag("--finite-differences", fit_options.finite_differences, "gradients by finite differences of whole runs");
  fit->add_flag("--single-level", fit_options.single_level,
                "fit on the cases' own meshes throughout (no coarse phase on half the contact nodes)");
  fit->add_flag("--resume", fit_options.resume,
                "continue the fit stopped in the output folder from its fit_checkpoint.json (the same command otherwise)");
  fit->add_flag("--no-design", fit_options.no_design,
                "no table of the measurements that would narrow the intervals (it costs a run per candidate)");
  fit->add_flag("--no-profile", fit_options.no_profile,
                "linearized intervals only, no profile likelihood (it costs a few optimisations per parameter)");
  fit->add_flag("--no-plot", no_plot, "write no figure");
  fit->add_flag("--quiet,-q", quiet, "no progress line and no notes: the result, warnings and errors only");

  SweepOptions sweep_options;
  CLI::App* sweep = app.add_subcommand(
      "sweep", "a parameter sweep: every run of SWEEP.toml (or one shard of them, or a Slurm job array), each result "
               "kept under its case's hash; the table OUT/results.csv");
  sweep->add_option("sweep", file, "sweep file (TOML: [sweep] base, out, design; [set]; [vary])")->required();
  CLI::Option* shard_option = sweep->add_option("--shard", sweep_options.shard, "run only shard i of N (i/N): the runs whose index (from 0) is i-1 mod N");
  CLI::Option* slurm_option = sweep->add_flag("--slurm", sweep_options.slurm, "write OUT/sweep.sbatch, a job array of shards");
  sweep->add_option("--shards", sweep_options.shards,
                    "--slurm: the number of array tasks (default: runs, at most 100; Slurm's MaxArraySize is 1001 by default)")
      ->check(CLI::Range(1, 1000))
      ->needs(slurm_option);
  CLI::Option* collect_option = sweep->add_flag("--collect", sweep_options.collect, "write the table of the runs done so far");
  CLI::Option* list_option = sweep->add_flag("--list", sweep_options.list, "list the runs (hash, values, done) and exit");
  CLI::Option* dask_option = sweep->add_flag("--dask", sweep_options.dask,
                                             "run on Dask distributed (python3 -m indentsim.sweep): a LocalCluster, or --scheduler");
  sweep->add_option("--scheduler", sweep_options.scheduler, "--dask: a running scheduler, e.g. tcp://head:8786")->needs(dask_option);
  sweep->add_option("--workers", sweep_options.workers, "--dask: LocalCluster worker processes (default: one per core)")
      ->check(CLI::Range(1, 4096))
      ->needs(dask_option);
  dask_option->excludes(shard_option)->excludes(slurm_option)->excludes(collect_option)->excludes(list_option);
  shard_option->excludes(slurm_option)->excludes(collect_option)->excludes(list_option);
  slurm_option->excludes(collect_option)->excludes(list_option);
  collect_option->excludes(list_option);
  sweep->add_flag("--quiet,-q", quiet, "no progress line");

  bool markdown = false;
  CLI::App* keys = app.add_subcommand("keys", "list every load-case key: type, default, accepted values, unit, meaning");
  keys->add_flag("--markdown", markdown, "as the README's Markdown table");

  CLI::App* check = app.add_subcommand("check", "validate a load case without solving");
  check->add_option("case", file, "load case (TOML)")->required();
  check->add_option("--set", overrides, "override one key: section.key=value (repeat for more)")
      ->allow_extra_args(false)
      ->take_all();

  // An unknown command is named, with the real ones (CLI11 would only say one is required).
  const auto subcommands = app.get_subcommands([](CLI::App*) { return true; });
  const bool known = argc > 1 && std::any_of(subcommands.begin(), subcommands.end(),
                                             [&](const CLI::App* sub) { return sub->get_name() == argv[1]; });
  if (argc > 1 && argv[1][0] != '-' && !known) {
    std::string commands;
    for (const CLI::App* sub : subcommands) commands += (commands.empty() ? "" : ", ") + sub->get_name();
    fmt::print(stderr, "error: \"{}\" is not an indentsim command (commands: {}; see indentsim --help)\n",
               printable(argv[1], 60), commands);
    return exit_bad_input;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return exit_bad_input;
  }

  // SIGINT/SIGTERM stop a run at the next Newton iteration, after its last converged increment
  // is checkpointed (drive); before the first increment there is nothing to keep.
  std::signal(SIGINT, on_stop_signal);
  std::signal(SIGTERM, on_stop_signal);
  try {
    for (CLI::App* command : {run, resume})
      if (command->parsed() && command->get_option("--out")->count() > 0 && out.empty())
        throw InputError("--out", "--out", "must name a folder (it is empty)");
    if (keys->parsed()) return command_keys(markdown);
    if (plot->parsed()) return command_plot(file, plot_step, plot_data, plot_columns, plot_size);
    if (analyze->parsed()) return command_analyze(file, overrides, analyze_options, analysis_out, analysis_plot);
    if (fit->parsed()) return command_fit(fit_options, quiet, !no_plot);
    if (run->parsed()) return command_run(file, overrides, out, quiet);
    if (sweep->parsed()) return command_sweep(file, sweep_options, quiet);
    if (resume->parsed()) return list ? command_list_checkpoints(file) : command_resume(file, overrides, out, quiet);
    return command_check(file, overrides);
  } catch (const InputError& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return exit_bad_input;
  } catch (const IoError& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return exit_io_failure;
  } catch (const std::filesystem::filesystem_error& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return exit_io_failure;
  } catch (const Interrupted& i) {
    fmt::print(stderr, "stopped by signal {} before the first increment; nothing to resume\n", i.signal());
    return 128 + i.signal();
  } catch (const std::exception& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return 1;
  }
}
