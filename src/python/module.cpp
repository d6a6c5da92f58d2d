// indentsim._indentsim: the library for Python (pybind11), thin glue under python/indentsim.
// Every call is the library's own, as the CLI makes it; the GIL is released while C++ works
// (nothing in the released sections touches a Python object), so runs in Python threads solve
// in parallel.  The library's errors become Python exceptions carrying the CLI's message:
// InputError (a ValueError), IoError (an OSError), SolverError (a RuntimeError).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include <fmt/format.h>

#include "indentsim/analysis/curve_analysis.hpp"
#include "indentsim/base/error.hpp"
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
  FitJob job = read_fit_job(command_line);
  const FitResult result = fit(job.problem);
  write_fit_results(job.out_dir, job.problem, result);
  return fit_json(job.problem, result).dump(2) + "\n";
}

/// A sweep expanded (and validated): manifest.json's text, written into its folder.
std::string sweep_manifest(const std::string& file) {
  py::gil_scoped_release unlocked;
  const SweepManifest manifest = expand_sweep(read_sweep_definition(file));
  SweepResults(manifest.definition.out).write_manifest(manifest);
  return manifest.to_json();
}

/// A batch of a sweep's runs (index, hash, case TOML), each solved unless it has a result; the
/// statuses in order.  Run on a Dask worker: the runs' own failures are results, not exceptions.
std::vector<std::string> run_sweep_batch(const std::string& out, const std::vector<std::string>& keep,
                                         const std::vector<std::tuple<int, std::string, std::string>>& runs) {
  py::gil_scoped_release unlocked;
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
      .def_readwrite("force_unit", &MeasuredCurveOptions::force_unit);

  py::class_<FitCommandLine>(m, "FitCommandLine")
      .def(py::init<>())
      .def_readwrite("input", &FitCommandLine::input)
      .def_readwrite("data_files", &FitCommandLine::data_files)
      .def_readwrite("free", &FitCommandLine::free)
      .def_readwrite("bounds", &FitCommandLine::bounds)
      .def_readwrite("overrides", &FitCommandLine::overrides)
      .def_readwrite("starts", &FitCommandLine::starts)
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
          [](FitCommandLine& c, const std::string& v) { c.columns.force_unit = v; });

  m.def("version", &version_line);
  m.def("run_case", &run_case, py::arg("file"), py::arg("toml_text"), py::arg("source"), py::arg("overrides"),
        py::arg("out"));
  m.def("check_case", &check_case, py::arg("file"), py::arg("toml_text"), py::arg("source"), py::arg("overrides"));
  m.def("analyze", &analyze, py::arg("curve"), py::arg("overrides"), py::arg("measured"), py::arg("out"));
  m.def("fit", &fit_curves, py::arg("command_line"));
  m.def("sweep_manifest", &sweep_manifest, py::arg("file"));
  m.def("run_sweep_batch", &run_sweep_batch, py::arg("out"), py::arg("keep"), py::arg("runs"));
  m.def("collect_sweep", &collect_sweep, py::arg("manifest_file"));
}
