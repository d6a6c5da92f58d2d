// indentsim._indentsim: the library for Python (pybind11), thin glue under python/indentsim.
// Every call is the library's own, as the CLI makes it; the GIL is released while C++ works
// (nothing in the released sections touches a Python object), so runs in Python threads solve
// in parallel.  The library's errors become Python exceptions carrying the CLI's message:
// InputError (a ValueError), IoError (an OSError), SolverError (a RuntimeError); a stop request
// that ends a call before it has anything to return, KeyboardInterrupt.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include <fmt/format.h>

#include "indentsim/analysis/curve_analysis.hpp"
#include "indentsim/base/error.hpp"
#include "indentsim/base/interruption.hpp"
#include "indentsim/output/run_folder.hpp"
#include "indentsim/output/fields.hpp"
#include "indentsim/fitting/fit.hpp"
#include "indentsim/fitting/fit_files.hpp"
#include "indentsim/input/load_case.hpp"
#include "indentsim/driver/run_driver.hpp"
#include "indentsim/simulation/simulation.hpp"
#include "indentsim/study/sweep.hpp"
#include "indentsim/study/sweep_results.hpp"
#include "indentsim/base/version.hpp"

namespace py = pybind11;
namespace fs = std::filesystem;
using namespace indentsim;

namespace {

/// The library's work in progress in this process (runs, fits, sweep batches), for request_stop().
/// A stop request is the library's interruption flag (interruption.hpp), the one SIGINT raises in
/// the CLI and every run polls.  It is raised only while work is in progress and lowered when the
/// last of it ends, so that a request never stops a later call.
std::mutex work_mutex;
int work_in_progress = 0;

class WorkInProgress {
public:
  WorkInProgress() {
    const std::lock_guard<std::mutex> lock(work_mutex);
    ++work_in_progress;
  }
  ~WorkInProgress() {
    const std::lock_guard<std::mutex> lock(work_mutex);
    if (--work_in_progress == 0) clear_interruption();
  }
  WorkInProgress(const WorkInProgress&) = delete;
  WorkInProgress& operator=(const WorkInProgress&) = delete;
};

/// request_stop(): the work in progress stops as the CLI stops on SIGINT (a run after its last
/// converged increment, checkpointed, with status "stopped").  False when nothing was in progress:
/// nothing is stopped and no request is left behind.  Called with the GIL held, from any thread.
bool request_stop() {
  const std::lock_guard<std::mutex> lock(work_mutex);
  if (work_in_progress == 0) return false;
  request_interruption(SIGINT);
  return true;
}

/// A run's end as Python sees it, with the final state's fields on the nodes.
struct PythonRun {
  std::string status, message, source;
  int exit_status = 0;
  fs::path dir;
  std::vector<std::string> warnings;
  std::vector<double> x, y;                   ///< the mesh's grid lines [m]
  std::vector<double> displacement;           ///< nodes_x * nodes_y * 2 [m], node (i, j) at i * nodes_y + j
  std::vector<double> stress;                 ///< nodes_x * nodes_y * 5: sigma11, sigma22, sigma12, sigma33 [Pa], e_u
};

/// Keeps the run's warnings and its final fields; says nothing.
class CollectingObserver : public RunObserver {
public:
  explicit CollectingObserver(PythonRun& run) : run_(run) {}
  void warning(const std::string& text) override { run_.warnings.push_back(text); }
  void final_state(const Simulation& sim) override {
    const Mesh& mesh = sim.mesh();
    run_.x = mesh.x();
    run_.y = mesh.y();
    const NodalStresses nodal = average_to_nodes(mesh, sim.bulk());
    run_.displacement.clear();
    run_.stress.clear();
    for (int n = 0; n < mesh.nodes(); ++n) {
      const auto d = nodal_displacement(mesh, sim.displacement().data(), n);
      run_.displacement.insert(run_.displacement.end(), d.begin(), d.end());
      const auto& s = nodal.values[static_cast<std::size_t>(n)];
      run_.stress.insert(run_.stress.end(), s.begin(), s.end());
    }
  }

private:
  PythonRun& run_;
};

PythonRun finish(const RunReport& report, PythonRun run) {
  run.status = to_string(report.status);
  run.message = report.message;
  run.source = report.load_case.source;
  run.exit_status = report.exit_status();
  run.dir = report.dir;
  return run;
}

/// run(): a load case file, or TOML text (the Python side writes a dict as TOML), into `out`.
PythonRun run_case(const std::string& file, const std::string& toml_text, const std::string& source,
                   std::vector<std::string> overrides, const std::string& out) {
  py::gil_scoped_release unlocked;
  const WorkInProgress working;  // a stop request ends the run with status "stopped"
  overrides.push_back("output.dir=" + toml_string(out));
  const LoadCase lc = file.empty() ? parse_load_case(toml_text, source, overrides) : read_load_case(file, overrides);
  PythonRun run;
  CollectingObserver observer(run);
  const RunReport report = run_load_case(lc, observer);
  return finish(report, std::move(run));
}

/// check(): the load case validated and its mesh planned (pilot included), nothing written.
py::dict check_case(const std::string& file, const std::string& toml_text, const std::string& source,
                    const std::vector<std::string>& overrides) {
  LoadCase lc;
  MeshPlan plan;
  std::vector<std::string> warnings;
  int unknowns = 0;
  {
    py::gil_scoped_release unlocked;
    lc = file.empty() ? parse_load_case(toml_text, source, overrides) : read_load_case(file, overrides);
    lc = with_depth_estimate(std::move(lc));  // force control's depth pilot
    plan = plan_run(lc).mesh;
    warnings = plausibility_warnings(lc, plan);
    unknowns = Mesh::from_plan(lc, plan).equations();
  }
  py::dict d;
  d["model"] = to_string(lc.material.model);
  d["max_depth"] = lc.max_depth();
  d["increments"] = lc.load.increments;
  d["nodes_x"] = plan.nodes_x;
  d["nodes_y"] = plan.nodes_y;
  d["unknowns"] = unknowns;
  d["warnings"] = warnings;
  d["case_toml"] = to_toml(lc);
  return d;
}

/// analyze(): analysis.json's content (as JSON text); written to `out` when one is given.
std::string analyze(const std::string& curve, const std::vector<std::string>& overrides,
                    const MeasuredCurveOptions& measured, const std::string& out) {
  py::gil_scoped_release unlocked;
  const std::string json = analysis_json(analyze_curve(curve, overrides, measured)).dump(2) + "\n";
  if (!out.empty()) write_file_atomically(out, json);
  return json;
}

/// fit(): fit.json's content (as JSON text); fit.json, fit_curves.csv and fitted_case.toml are
/// written into the job's folder, as `indentsim fit` writes them.
std::string fit_curves(FitCommandLine command_line) {
  py::gil_scoped_release unlocked;
  const WorkInProgress working;
  FitJob job = read_fit_job(command_line);
  const FitResult result = run_fit_job(job, command_line.resume);
  return fit_json(job.problem, result).dump(2) + "\n";
}

/// A sweep expanded (and validated), its compact manifest.json written into its folder; returned:
/// the manifest with every run's complete case ("case"), which the batches hand the workers.  A
/// run folder whose result.json is no result of its run (damaged, another run's, its files not as
/// recorded) is removed, with a warning on stderr naming the file and what is wrong, so that the
/// sweep does the run again (as `indentsim sweep` does).
std::string sweep_manifest(const std::string& file) {
  std::string text;
  std::vector<std::string> problems;
  {
    py::gil_scoped_release unlocked;
    const SweepManifest manifest = expand_sweep(read_sweep_definition(file));
    const SweepResults results(manifest.definition.out);
    results.write_manifest(manifest);
    for (const SweepRun& run : manifest.runs) {
      const SweepRunLookup found = results.look_up(run.hash);
      if (found.problem.empty()) continue;
      problems.push_back(fmt::format("{}: {}; run {} is done again", found.file.string(), found.problem, run.index));
      std::error_code ec;
      fs::remove_all(found.file.parent_path(), ec);
    }
    text = manifest.to_json_with_cases();
  }
  const py::object stderr_file = py::module_::import("sys").attr("stderr");
  for (const std::string& problem : problems) py::print("warning: " + problem, py::arg("file") = stderr_file);
  return text;
}

/// A batch of a sweep's runs (index, hash, case TOML), each solved unless it has a result; the
/// statuses in order.  Run on a Dask worker: the runs' own failures are results, not exceptions.
std::vector<std::string> run_sweep_batch(const std::string& out, const std::vector<std::string>& keep,
                                         const std::vector<std::tuple<int, std::string, std::string>>& runs) {
  py::gil_scoped_release unlocked;
  const WorkInProgress working;
  const SweepResults results(out);
  std::vector<std::string> statuses;
  for (const auto& [index, hash, case_toml] : runs) {
    if (const auto done = results.result(hash)) {
      statuses.push_back("had:" + done->status);
      continue;
    }
    SweepRun run;
    run.index = index;
    run.hash = hash;
    run.case_toml = case_toml;
    statuses.push_back(results.run(run, keep).status);
  }
  return statuses;
}

/// Result.write(): `dir` made a run's folder as a run makes it (run_folder.hpp): locked (InputError
/// when another run holds DIR/.indentsim.lock), checked, and an earlier run's files removed; then
/// `write` (Python's copy of the run's files) is called while the lock is held.  The GIL is held
/// throughout: the folder work is short, and `write` is Python.
void write_run_folder(const std::string& dir, const std::string& source, const py::function& write) {
  RunFolder folder(dir, source);
  folder.clear_earlier_run();
  write();
}

/// The table of a sweep's results: {runs, finished, not_converged, failed, pending}.
py::dict collect_sweep(const std::string& manifest_file) {
  SweepTally t;
  {
    py::gil_scoped_release unlocked;
    std::ifstream in(manifest_file, std::ios::binary);
    if (!in) throw InputError(manifest_file, "manifest", "cannot be read");
    std::ostringstream text;
    text << in.rdbuf();
    const SweepManifest manifest = SweepManifest::from_json(text.str(), manifest_file);
    t = SweepResults(manifest.definition.out).collect(manifest);
  }
  // A result.json that is no result (damaged, another run's, its files not as recorded): its row
  // is pending, and the file and what is wrong are said on stderr, as the CLI says them.
  if (!t.problems.empty()) {
    const py::object stderr_file = py::module_::import("sys").attr("stderr");
    for (const std::string& problem : t.problems)
      py::print(fmt::format("warning: {}; its row is pending (a sweep does the run again)", problem),
                py::arg("file") = stderr_file);
  }
  py::dict d;
  d["runs"] = t.runs;
  d["finished"] = t.finished;
  d["not_converged"] = t.not_converged;
  d["failed"] = t.failed;
  d["pending"] = t.pending;
  return d;
}

}  // namespace

PYBIND11_MODULE(_indentsim, m) {
  m.doc() = "indentsim's library (use the indentsim package, which wraps it)";
  // The CLI's messages: "file: key: problem" for input, "file: action: reason" for I/O.
  static py::exception<InputError> input_error(m, "InputError", PyExc_ValueError);
  static py::exception<IoError> io_error(m, "IoError", PyExc_OSError);
  static py::exception<SolverError> solver_error(m, "SolverError", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      input_error(e.what());
    } catch (const IoError& e) {
      io_error(e.what());
    } catch (const SolverError& e) {
      solver_error(e.what());
    } catch (const Interrupted& e) {
      // Stopped before there was anything to return (a run in its pilot, a fit, a sweep batch).
      const std::string message =
          fmt::format("stopped by signal {} (Ctrl-C, or indentsim.request_stop())", e.signal());
      PyErr_SetString(PyExc_KeyboardInterrupt, message.c_str());
    }
  });

  py::class_<PythonRun>(m, "RunEnd")
      .def_readonly("status", &PythonRun::status)
      .def_readonly("message", &PythonRun::message)
      .def_readonly("source", &PythonRun::source)
      .def_readonly("exit_status", &PythonRun::exit_status)
      .def_readonly("warnings", &PythonRun::warnings)
      .def_property_readonly("dir", [](const PythonRun& r) { return r.dir.string(); })
      .def_property_readonly("x", [](const PythonRun& r) { return py::array_t<double>(r.x.size(), r.x.data()); })
      .def_property_readonly("y", [](const PythonRun& r) { return py::array_t<double>(r.y.size(), r.y.data()); })
      .def_property_readonly("displacement",
                             [](const PythonRun& r) {
                               return py::array_t<double>({r.x.size(), r.y.size(), std::size_t{2}}, r.displacement.data());
                             })
      .def_property_readonly("stress", [](const PythonRun& r) {
        return py::array_t<double>({r.x.size(), r.y.size(), std::size_t{5}}, r.stress.data());
      });

  py::class_<MeasuredCurveOptions>(m, "MeasuredCurveOptions")
      .def(py::init<>())
      .def_readwrite("indenter_file", &MeasuredCurveOptions::indenter_file)
      .def_readwrite("depth_column", &MeasuredCurveOptions::depth_column)
      .def_readwrite("force_column", &MeasuredCurveOptions::force_column)
      .def_readwrite("depth_unit", &MeasuredCurveOptions::depth_unit)
      .def_readwrite("force_unit", &MeasuredCurveOptions::force_unit)
      .def_readwrite("time_column", &MeasuredCurveOptions::time_column)
      .def_readwrite("time_unit", &MeasuredCurveOptions::time_unit);

  py::class_<FitCommandLine>(m, "FitCommandLine")
      .def(py::init<>())
      .def_readwrite("input", &FitCommandLine::input)
      .def_readwrite("data_files", &FitCommandLine::data_files)
      .def_readwrite("free", &FitCommandLine::free)
      .def_readwrite("bounds", &FitCommandLine::bounds)
      .def_readwrite("overrides", &FitCommandLine::overrides)
      .def_readwrite("starts", &FitCommandLine::starts)
      .def_readwrite("mesh_refinements", &FitCommandLine::mesh_refinements)
      .def_readwrite("threads", &FitCommandLine::threads)
      .def_readwrite("resume", &FitCommandLine::resume)
      .def_readwrite("no_design", &FitCommandLine::no_design)
      .def_readwrite("no_profile", &FitCommandLine::no_profile)
      .def_readwrite("out", &FitCommandLine::out)
      .def_readwrite("finite_differences", &FitCommandLine::finite_differences)
      .def_readwrite("single_level", &FitCommandLine::single_level)
      .def_property(
          "depth_column", [](const FitCommandLine& c) { return c.columns.depth_column; },
          [](FitCommandLine& c, const std::string& v) { c.columns.depth_column = v; })
      .def_property(
          "force_column", [](const FitCommandLine& c) { return c.columns.force_column; },
          [](FitCommandLine& c, const std::string& v) { c.columns.force_column = v; })
      .def_property(
          "depth_unit", [](const FitCommandLine& c) { return c.columns.depth_unit; },
          [](FitCommandLine& c, const std::string& v) { c.columns.depth_unit = v; })
      .def_property(
          "force_unit", [](const FitCommandLine& c) { return c.columns.force_unit; },
          [](FitCommandLine& c, const std::string& v) { c.columns.force_unit = v; })
      .def_property(
          "time_column", [](const FitCommandLine& c) { return c.columns.time_column; },
          [](FitCommandLine& c, const std::string& v) { c.columns.time_column = v; })
      .def_property(
          "time_unit", [](const FitCommandLine& c) { return c.columns.time_unit; },
          [](FitCommandLine& c, const std::string& v) { c.columns.time_unit = v; });

  m.def("version", &version_line);
  m.def("run_case", &run_case, py::arg("file"), py::arg("toml_text"), py::arg("source"), py::arg("overrides"),
        py::arg("out"));
  m.def("check_case", &check_case, py::arg("file"), py::arg("toml_text"), py::arg("source"), py::arg("overrides"));
  m.def("analyze", &analyze, py::arg("curve"), py::arg("overrides"), py::arg("measured"), py::arg("out"));
  m.def("fit", &fit_curves, py::arg("command_line"));
  m.def("sweep_manifest", &sweep_manifest, py::arg("file"));
  m.def("run_sweep_batch", &run_sweep_batch, py::arg("out"), py::arg("keep"), py::arg("runs"));
  m.def("collect_sweep", &collect_sweep, py::arg("manifest_file"));
  m.def("request_stop", &request_stop);
  m.def("write_run_folder", &write_run_folder, py::arg("dir"), py::arg("source"), py::arg("write"));
}
