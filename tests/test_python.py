"""The Python module and Dask sweeps, as a notebook user and a cluster meet them.

Run by ctest with Debian's python3:  test_python.py INDENTSIM_CLI SOURCE_DIR [unittest args]
(PYTHONPATH holds build/python).  Each test compares with the CLI, which the C++ tests hold to
theory: the module must be the same code, not a second opinion.
"""
import csv
import importlib.util
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
import tomllib
import unittest

import numpy as np

import indentsim
from indentsim.sweep import read_table, sweep

CLI = SOURCE = None
PYTHON = sys.executable
DASK = os.path.join(os.path.dirname(sys.executable), "dask")  # Debian's, beside its python3

SMALL_CASE = """
[geometry]
lx = 15e-3
ly = 10e-3
[punch]
radius = 2e-3
[material]
model = "elastic"
E = 210e9
nu = 0.3
[load]
path = [0.0, 2e-5]
increments = 3
[mesh]
contact_nodes = 8
"""


def cli(*args, env=None):
    return subprocess.run([CLI, *map(str, args)], capture_output=True, text=True, env=env)


def curve_lines(path):
    """curve.csv's lines without the wall-clock column (the last)."""
    with open(path) as f:
        return [line.rsplit(",", 1)[0] for line in f.read().splitlines()]


def table_rows(path):
    """results.csv's rows as dicts without the wall-clock column, keyed by hash."""
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        r.pop("wall_s")
    return {r["hash"]: r for r in rows}


class Temporary(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="indentsim_py_")
        self.base = os.path.join(self.dir, "base.toml")
        with open(self.base, "w") as f:
            f.write(SMALL_CASE)

    def tearDown(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def path(self, *parts):
        return os.path.join(self.dir, *parts)

    def write_sweep(self, name, out, vary, extra=""):
        file = self.path(name)
        with open(file, "w") as f:
            f.write(f'[sweep]\nbase = "base.toml"\nout = "{out}"\n{extra}\n[vary]\n{vary}')
        return file


class Run(Temporary):
    def test_the_curve_is_the_clis_bit_for_bit_from_a_file_and_from_a_dict(self):
        case = os.path.join(SOURCE, "loadcases", "power_law.toml")
        out = self.path("cli")
        p = cli("run", case, "--quiet", "--out", out)
        self.assertEqual(p.returncode, 0, p.stderr)
        with open(os.path.join(out, "curve.csv"), newline="") as f:
            rows = list(csv.reader(f))
        header, body = rows[0], rows[1:]
        from_file = indentsim.run(case)
        with open(os.path.join(out, "case.toml"), "rb") as f:
            as_dict = tomllib.load(f)
        from_dict = indentsim.run(as_dict)
        for r in (from_file, from_dict):
            self.assertEqual(list(r.curve), header)
            for k, name in enumerate(header):
                if name == "wall_s":
                    continue
                expected = np.array([float(row[k]) if row[k] else np.nan for row in body])
                np.testing.assert_array_equal(r.curve[name], expected, err_msg=name)
        # write(): the usual files, the same curve text.
        written = from_file.write(self.path("written"))
        self.assertEqual(curve_lines(os.path.join(written, "curve.csv")), curve_lines(os.path.join(out, "curve.csv")))
        for name in ("summary.json", "case.toml", "fields.pvd", "layers.csv"):
            self.assertTrue(os.path.isfile(os.path.join(written, name)), name)

    def test_the_final_fields_hold_the_contact_condition(self):
        r = indentsim.run(self.base, overrides={"mesh.contact_nodes": 10})
        nx, ny = len(r.mesh["x"]), len(r.mesh["y"])
        self.assertEqual(r.fields["v"].shape, (nx, ny))
        self.assertEqual(r.fields["sigma22"].shape, (nx, ny))
        alpha = r.curve["alpha"][-1]
        # Signorini at the axis: the node under the punch's tip is in contact, v = -alpha exactly
        # up to the Newton tolerance; the far bottom is fixed.
        self.assertAlmostEqual(r.fields["v"][0, -1] / -alpha, 1.0, delta=1e-9)
        self.assertEqual(r.fields["v"][0, 0], 0.0)
        # Compression under the punch: sigma22 < 0 at the axis node of the surface.
        self.assertLess(r.fields["sigma22"][0, -1], 0.0)

    def test_input_errors_carry_the_clis_message(self):
        bad = [("material.nu", 0.7), ("material.Ee", 1e9), ("load.increments", "ten")]
        for key, value in bad:
            with self.subTest(key=key):
                p = cli("run", self.base, "--out", self.path("never"), "--set", f"{key}={value}")
                self.assertEqual(p.returncode, 2)
                with self.assertRaises(indentsim.InputError) as caught:
                    indentsim.run(self.base, overrides={key: value})
                self.assertIsInstance(caught.exception, ValueError)
                self.assertEqual(f"error: {caught.exception}", p.stderr.strip())
                self.assertIn(key, str(caught.exception))
        with self.assertRaises(indentsim.InputError) as caught:
            indentsim.run(self.path("missing.toml"))
        self.assertIn("missing.toml", str(caught.exception))
        with self.assertRaises(indentsim.InputError):
            indentsim.check({"material": 3})
        self.assertFalse(os.path.exists(self.path("never")))

    def test_a_run_that_cannot_converge_raises_with_what_converged(self):
        overrides = {"solver.max_newton": 1, "solver.max_cutbacks": 0}
        p = cli("run", self.base, "--quiet", "--out", self.path("cli"), "--set", "solver.max_newton=1",
                "--set", "solver.max_cutbacks=0")
        self.assertEqual(p.returncode, 3)
        with self.assertRaises(indentsim.NotConvergedError) as caught:
            indentsim.run(self.base, overrides=overrides)
        self.assertEqual(str(caught.exception), p.stderr.strip().splitlines()[-1])  # after the warnings
        self.assertEqual(caught.exception.result.status, "not_converged")
        self.assertEqual(caught.exception.result.curve["step"][0], 0)

    def test_check_plans_without_writing(self):
        c = indentsim.check(self.base, overrides=["output.dir=\"" + self.path("never") + "\""])
        self.assertEqual(c["model"], "elastic")
        self.assertGreater(c["unknowns"], 0)
        self.assertFalse(os.path.exists(self.path("never")))

    def test_the_gil_is_released_while_a_run_solves_and_two_threads_run_alike(self):
        case = os.path.join(SOURCE, "loadcases", "power_law.toml")
        # Without the error estimate: its companion runs on the second core beside the run, and
        # "one run" would no longer be one core's work.
        single = ["mesh.error_estimate=\"off\""]
        start = time.monotonic()
        alone = indentsim.run(case, overrides=single)
        one = time.monotonic() - start
        # While a run solves in another thread, this one runs Python: held for the whole run, the
        # GIL would let it through only before and after.  (A behaviour, not a timing: the count
        # does not depend on how loaded the machine is, only on whether the thread gets the GIL.)
        results = [None, None]

        def solve(k):
            results[k] = indentsim.run(case, overrides=single)
        background = threading.Thread(target=solve, args=(0,))
        turns = 0
        background.start()
        while background.is_alive():
            turns += 1
            time.sleep(0.002)
        background.join()
        self.assertGreaterEqual(turns, 20, f"the main thread ran {turns} times during a {one:.2f} s run")
        # Two runs in two threads give the run's own curve (no shared state), and overlap in time.
        threads = [threading.Thread(target=solve, args=(k,)) for k in range(2)]
        start = time.monotonic()
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        two = time.monotonic() - start
        print(f"\none run {one:.2f} s; two runs in two threads {two:.2f} s (ratio {two / one:.2f}); "
              f"the main thread ran {turns} times during one run")
        for r in results:
            np.testing.assert_array_equal(r.curve["P"], alone.curve["P"])

    def test_analyze_and_fit_are_the_clis(self):
        case = os.path.join(SOURCE, "loadcases", "load_unload.toml")
        out = self.path("lu")
        self.assertEqual(cli("run", case, "--quiet", "--out", out).returncode, 0)
        self.assertEqual(cli("analyze", out, "--set", "analysis.fit_range=[0.2, 1.0]").returncode, 0)
        with open(os.path.join(out, "analysis.json")) as f:
            expected = json.load(f)
        got = indentsim.analyze(out, overrides={"analysis.fit_range": [0.2, 1.0]})
        expected.pop("indentsim", None), got.pop("indentsim", None)
        self.assertEqual(got, expected)
        # A one-parameter fit of E to a curve computed with E = 210 GPa, started at 160 GPa, on the
        # data's own mesh (no refinement for the model's error: the data are that mesh's).
        data_run = self.path("data")
        self.assertEqual(cli("run", self.base, "--quiet", "--out", data_run).returncode, 0)
        data = os.path.join(data_run, "curve.csv")
        started = self.path("started.toml")
        with open(started, "w") as f:
            f.write(SMALL_CASE.replace("E = 210e9", "E = 160e9"))
        p = cli("fit", started, "--data", data, "--free", "material.E", "--bounds", "material.E=50e9:500e9",
                "--mesh-refinements", "0", "--out", self.path("fit_cli"), "--no-plot", "--quiet")
        self.assertEqual(p.returncode, 0, p.stderr)
        fitted = indentsim.fit(started, data=data, free=["material.E"], bounds={"material.E": (50e9, 500e9)},
                               mesh_refinements=0, threads=1, out=self.path("fit_py"))
        with open(self.path("fit_cli", "fit.json")) as f:
            by_cli = json.load(f)
        value = lambda j: j["parameters"]["material.E"]["value"]
        self.assertEqual(value(fitted), value(by_cli))
        self.assertAlmostEqual(value(fitted) / 210e9, 1.0, delta=1e-6)
        self.assertTrue(os.path.isfile(self.path("fit_py", "fitted_case.toml")))


class DaskSweep(Temporary):
    VARY = ('"material.E" = {from = 150e9, to = 250e9, count = 6}\n'
            '"material.nu" = [0.2, 0.25, 0.3, 0.35]\n')

    def test_a_local_cluster_gives_the_table_of_cli_runs_and_of_slurm_shards(self):
        file = self.write_sweep("s.toml", self.path("dask"), self.VARY)
        outcome = sweep(file, workers=2, progress=False)
        self.assertEqual((outcome.runs, outcome.finished, outcome.solved_now), (24, 24, 24))
        dask_rows = table_rows(outcome.table)
        # The same 24 cases run one by one by the CLI.
        with open(self.path("dask", "manifest.json")) as f:
            manifest = json.load(f)
        for run in manifest["runs"]:
            E, nu = run["values"]
            out = self.path("cli", run["hash"])
            p = cli("run", self.base, "--quiet", "--out", out, "--set", f"material.E={E}", "--set", f"material.nu={nu}")
            self.assertEqual(p.returncode, 0, p.stderr)
            with open(os.path.join(out, "curve.csv"), newline="") as f:
                last = list(csv.DictReader(f))[-1]
            row = dask_rows[run["hash"]]
            self.assertEqual(float(row["final_P"]), float(last["P"]))
            self.assertEqual(float(row["final_a"]), float(last["a"]))
            self.assertEqual(curve_lines(self.path("dask", "runs", run["hash"], "curve.csv")),
                             curve_lines(os.path.join(out, "curve.csv")))
        # The Slurm job array's script, its tasks run as Slurm would (SLURM_ARRAY_TASK_ID set).
        slurm_file = self.write_sweep("slurm.toml", self.path("slurm"), self.VARY)
        self.assertEqual(cli("sweep", slurm_file, "--slurm", "--shards", 3).returncode, 0)
        for task in (1, 2, 3):
            env = dict(os.environ, SLURM_ARRAY_TASK_ID=str(task), SLURM_ARRAY_JOB_ID="1")
            p = subprocess.run(["bash", self.path("slurm", "sweep.sbatch")], capture_output=True, text=True, env=env,
                               cwd="/")
            self.assertEqual(p.returncode, 0, p.stderr)
        self.assertEqual(cli("sweep", slurm_file, "--collect").returncode, 0)
        self.assertEqual(table_rows(self.path("slurm", "results.csv")), dask_rows)

    def test_bad_sweep_files_raise_naming_the_key_and_start_nothing(self):
        file = self.write_sweep("bad.toml", self.path("never"), '"material.nu" = {from = 0.3, to = 0.5, count = 3}\n')
        with self.assertRaises(indentsim.InputError) as caught:
            sweep(file, workers=1, progress=False)
        self.assertIn("material.nu", str(caught.exception))
        p = subprocess.run([CLI, "sweep", file, "--dask"], capture_output=True, text=True)
        self.assertEqual(p.returncode, 2)
        self.assertFalse(os.path.exists(self.path("never")))


# A case that runs for minutes unless stopped: 2000 increments of about 0.05 s each.
SLOW = {"load.increments": 2000, "mesh.error_estimate": "off"}

STOP_BY_SIGINT = r"""
import json, signal, sys
import indentsim
signal.signal(signal.SIGINT, signal.default_int_handler)  # as in a terminal, even when started with SIGINT ignored
case, out, increments = sys.argv[1], sys.argv[2], int(sys.argv[3])
print("starting", flush=True)
try:
    indentsim.run(case, overrides={"load.increments": increments, "mesh.error_estimate": "off"}, out=out)
    print(json.dumps({"raised": None}), flush=True)
except BaseException as e:
    r = getattr(e, "result", None)
    print(json.dumps({"raised": type(e).__name__, "keyboard_interrupt": isinstance(e, KeyboardInterrupt),
                      "message": str(e), "status": r.status if r else None,
                      "last_step": int(r.curve["step"][-1]) if r else None}), flush=True)
"""


def python_without_numpy():
    """Another python3 on the PATH (a pyenv or venv one) that cannot import NumPy, or None."""
    mine = os.path.realpath(sys.executable)
    for folder in os.environ.get("PATH", "").split(os.pathsep):
        candidate = os.path.join(folder, "python3")
        if not os.access(candidate, os.X_OK) or os.path.realpath(candidate) == mine:
            continue
        try:
            p = subprocess.run([candidate, "-c", "import numpy"], capture_output=True, timeout=60)
        except (OSError, subprocess.TimeoutExpired):
            continue
        if p.returncode != 0:
            return candidate
    return None


def example_module(name):
    """examples/NAME.py as a module (its main() does not run on import)."""
    spec = importlib.util.spec_from_file_location(name, os.path.join(SOURCE, "examples", f"{name}.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


class ImportWithTheWrongPython(unittest.TestCase):
    def import_error(self, *command):
        p = subprocess.run([*command, "-c", "import indentsim"], capture_output=True, text=True, timeout=120)
        self.assertNotEqual(p.returncode, 0, p.stdout)
        return p.stderr

    def test_a_python_without_numpy_is_told_which_python_and_how_to_use_it(self):
        # Debian's python3 without its site packages (-S) is a Python without NumPy, always at hand.
        message = self.import_error(sys.executable, "-S")
        self.assertIn("ImportError: indentsim cannot be imported by this Python: NumPy cannot be imported", message)
        self.assertIn(sys.executable, message)
        self.assertIn(f"indentsim needs: CPython {sys.version_info.major}.{sys.version_info.minor} on ", message)
        self.assertIn("/usr/bin/python3 -m venv --system-site-packages ENV", message)

    def test_another_python_on_the_path_is_named_next_to_the_one_indentsim_needs(self):
        other = python_without_numpy()
        if other is None:
            self.skipTest("no python3 without NumPy on the PATH besides this one")
        executable = subprocess.run([other, "-c", "import sys; print(sys.executable)"], capture_output=True,
                                    text=True, timeout=60).stdout.strip()
        message = self.import_error(other)
        print(f"\n{other} ({executable}):\n" + "\n".join(message.strip().splitlines()[-4:-1]))
        self.assertIn("indentsim cannot be imported by this Python", message)
        self.assertIn(f"this Python:     {executable}:", message)
        self.assertIn(f"CPython {sys.version_info.major}.{sys.version_info.minor} on ", message)
        self.assertIn("--system-site-packages", message)


class Stop(Temporary):
    def test_ctrl_c_stops_a_run_and_raises_with_its_converged_increments(self):
        case = os.path.join(SOURCE, "loadcases", "power_law.toml")
        out = self.path("stopped")
        child = subprocess.Popen([PYTHON, "-c", STOP_BY_SIGINT, case, out, str(SLOW["load.increments"])],
                                 stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        try:
            self.assertEqual(child.stdout.readline().strip(), "starting")
            time.sleep(1.5)
            child.send_signal(signal.SIGINT)
            signalled = time.monotonic()
            stdout, stderr = child.communicate(timeout=120)
        finally:
            if child.poll() is None:
                child.kill()
                child.wait()
        stopped_within = time.monotonic() - signalled
        self.assertEqual(child.returncode, 0, stderr)
        outcome = json.loads(stdout.strip().splitlines()[-1])
        print(f"\nstopped {stopped_within:.2f} s after SIGINT at increment {outcome['last_step']}: {outcome['message']}")
        self.assertEqual(outcome["raised"], "RunInterrupted")
        self.assertTrue(outcome["keyboard_interrupt"])
        self.assertEqual(outcome["status"], "stopped")
        self.assertLess(outcome["last_step"], SLOW["load.increments"])
        self.assertIn("indentsim resume", outcome["message"])
        self.assertLess(stopped_within, 30.0)
        with open(os.path.join(out, "summary.json")) as f:
            self.assertEqual(json.load(f)["status"], "stopped")
        self.assertTrue(any(name.endswith(".ck") for name in os.listdir(os.path.join(out, "checkpoints"))))

    def test_request_stop_stops_a_run_in_a_worker_thread_and_no_later_run(self):
        case = os.path.join(SOURCE, "loadcases", "power_law.toml")
        caught = {}

        def solve():
            try:
                indentsim.run(case, overrides=SLOW, out=self.path("worker"))
            except BaseException as e:
                caught["error"] = e
        worker = threading.Thread(target=solve)
        worker.start()
        time.sleep(1.0)
        self.assertTrue(indentsim.request_stop())
        worker.join(timeout=120)
        self.assertFalse(worker.is_alive())
        error = caught.get("error")
        self.assertIsInstance(error, indentsim.RunInterrupted)
        self.assertEqual(error.result.status, "stopped")
        self.assertLess(error.result.curve["step"][-1], SLOW["load.increments"])
        self.assertFalse(indentsim.request_stop())  # nothing in progress: nothing to stop, nothing left behind
        self.assertEqual(indentsim.run(self.base).status, "finished")


class WriteIntoAFolder(Temporary):
    def test_write_replaces_an_earlier_runs_files_and_leaves_other_files(self):
        earlier = self.path("earlier")
        p = cli("run", self.base, "--quiet", "--out", earlier, "--set", "output.fields_every=1",
                "--set", "output.checkpoint_every=1")
        self.assertEqual(p.returncode, 0, p.stderr)
        self.assertGreater(len(os.listdir(os.path.join(earlier, "fields"))), 1)
        self.assertTrue(os.listdir(os.path.join(earlier, "checkpoints")))
        with open(os.path.join(earlier, "notes.txt"), "w") as f:
            f.write("mine\n")
        r = indentsim.run(self.base, overrides={"load.increments": 2})  # fields: the final state only
        self.assertEqual(r.write(earlier), earlier)
        self.assertEqual(sorted(os.listdir(os.path.join(earlier, "fields"))),
                         sorted(os.listdir(os.path.join(r.folder, "fields"))))
        for name in ("fields.pvd", "curve.csv", "summary.json", "case.toml"):
            with open(os.path.join(earlier, name)) as a, open(os.path.join(r.folder, name)) as b:
                self.assertEqual(a.read(), b.read(), name)
        checkpoints = os.path.join(earlier, "checkpoints")
        self.assertFalse(os.path.isdir(checkpoints) and os.listdir(checkpoints))
        with open(os.path.join(earlier, "notes.txt")) as f:
            self.assertEqual(f.read(), "mine\n")

    def test_write_refuses_a_folder_a_cli_run_holds(self):
        r = indentsim.run(self.base)
        busy = self.path("busy")
        run = subprocess.Popen([CLI, "run", os.path.join(SOURCE, "loadcases", "power_law.toml"), "--quiet",
                                "--out", busy, "--set", "load.increments=2000", "--set", "mesh.error_estimate=\"off\""],
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            # The folder's listing is settled once the run has written its first summary (curve.csv
            # comes first): from then on only write() could change it, but for the run's own
            # atomic writes' passing *.tmp files.
            def listing():
                return sorted(name for name in os.listdir(busy) if not name.endswith(".tmp"))
            deadline = time.monotonic() + 60
            while not os.path.isfile(os.path.join(busy, "summary.json")) and time.monotonic() < deadline:
                time.sleep(0.02)
            before = listing()
            with self.assertRaises(indentsim.InputError) as caught:
                r.write(busy)
            self.assertEqual(run.poll(), None, "the CLI run ended before write() was tried")
            self.assertIn(f'"{busy}" is in use by another indentsim run (pid {run.pid})', str(caught.exception))
            self.assertEqual(listing(), before)
        finally:
            run.terminate()
            run.wait()


class Study(Temporary):
    # Two unloading increments: Oliver-Pharr's fit needs at least 4 points, so the branch is not analysed.
    UNANALYSABLE = {"load.path": [0.0, 2e-5, 0.0], "load.increments": [3, 2]}

    def test_the_study_gives_nan_and_the_reason_for_a_branch_that_could_not_be_analysed(self):
        r = indentsim.run(self.base, overrides=self.UNANALYSABLE)
        self.assertIsNone(r.summary["unloading"][0]["analysis"])
        study = example_module("hardness_study")
        hardness, why = study.hardness_of(r.summary)
        self.assertTrue(np.isnan(hardness))
        self.assertIn("needs at least 4", why)
        self.assertEqual(study.hardness_of(indentsim.run(self.base).summary)[1], "no unloading branch")

    def test_a_sweeps_table_reads_with_nan_where_a_run_has_no_hardness_and_keeps_each_message(self):
        file = self.write_sweep("study.toml", self.path("study"),
                                '"load.increments" = [5, 40]\n"solver.max_newton" = [1, 50]\n',
                                '[set]\n"load.path" = [0.0, 2e-5, 0.0]\n"solver.max_cutbacks" = 0\n')
        p = cli("sweep", file, "--quiet")
        self.assertEqual(p.returncode, 0, p.stderr)
        table = read_table(self.path("study", "results.csv"))
        self.assertEqual(table["H"].dtype, np.float64)
        self.assertEqual(list(table["index"]), [0, 1, 2, 3])
        study = example_module("hardness_study")
        for k in range(4):
            status, increments = table["status"][k], table["load.increments"][k]
            with self.subTest(status=status, increments=increments):
                if status == "finished" and increments == 40:
                    self.assertGreater(table["H"][k], 0.0)
                    continue
                self.assertTrue(np.isnan(table["H"][k]))
                why = study.why_no_hardness(table, k, self.path("study"))
                if status == "finished":
                    self.assertIn("needs at least 4", why)
                else:
                    self.assertEqual(status, "not_converged")
                    self.assertTrue(table["message"][k])
                    self.assertEqual(why, f"not_converged: {table['message'][k]}")


class CaseValues(Temporary):
    def small_case(self):
        return tomllib.loads(SMALL_CASE)

    def test_a_lone_surrogate_is_refused_naming_its_key_and_nothing_else(self):
        case = self.small_case()
        case["material"]["model"] = "elastic\ud800"
        with self.assertRaises(indentsim.InputError) as caught:
            indentsim.check(case)
        message = str(caught.exception)
        self.assertTrue(message.startswith("case: material.model: "), message)
        self.assertIn("lone surrogate", message)
        self.assertNotIn("[geometry]", message)
        with self.assertRaises(indentsim.InputError) as caught:
            indentsim.run(self.base, overrides={"output.dir": "out\udcff"})
        self.assertTrue(str(caught.exception).startswith("overrides: output.dir: "), str(caught.exception))

    def test_an_integer_beyond_64_bits_is_refused_naming_its_key_and_the_float_to_write(self):
        case = self.small_case()
        case["material"]["E"] = 10**30
        with self.assertRaises(indentsim.InputError) as caught:
            indentsim.run(case)
        self.assertEqual(str(caught.exception), "case: material.E: the integer 1000000000000000000000000000000 does "
                                                "not fit a 64-bit integer (TOML's); write it as a float (1e+30)")
        with self.assertRaises(indentsim.InputError) as caught:
            indentsim.check(self.base, overrides={"load.increments": np.uint64(2**64 - 1)})
        self.assertTrue(str(caught.exception).startswith("overrides: load.increments: the integer 18446744073709551615"))
        # The largest 64-bit integer is TOML: the library judges it (out of range, by name).
        with self.assertRaises(indentsim.InputError) as caught:
            indentsim.check(self.base, overrides={"load.increments": 2**63 - 1})
        self.assertNotIn("line", str(caught.exception))
        self.assertIn("load.increments", str(caught.exception))

    def test_fit_takes_one_key_or_one_bounds_text_as_a_list_of_one(self):
        data_run = self.path("data")
        self.assertEqual(cli("run", self.base, "--quiet", "--out", data_run).returncode, 0)
        data = os.path.join(data_run, "curve.csv")
        # material.E is free, material.nu is not: the library names the bounds' key, after reading free whole.
        for bounds in ({"material.nu": (0.1, 0.4)}, "material.nu=0.1:0.4", ["material.nu=0.1:0.4"]):
            with self.subTest(bounds=bounds), self.assertRaises(indentsim.InputError) as caught:
                indentsim.fit(self.base, data=data, free="material.E", bounds=bounds, out=self.path("fit"))
            self.assertEqual(str(caught.exception), "--bounds: material.nu: has bounds but is not free")
        with self.assertRaises(indentsim.InputError) as caught:
            indentsim.fit(self.base, data=data, free="material.E", starts="3")
        self.assertEqual(str(caught.exception), "starts: must be an integer (got '3')")
        with self.assertRaises(indentsim.InputError) as caught:
            indentsim.fit(self.base, data=data, free="material.E", threads=2.0)
        self.assertEqual(str(caught.exception), "threads: must be an integer (got 2.0)")
        with self.assertRaises(indentsim.InputError) as caught:
            indentsim.fit(self.base, data=data, free="material.E", bounds={"material.E": 5e9})
        self.assertIn("bounds: material.E: expects (lower, upper)", str(caught.exception))


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class DistributedSweep(Temporary):
    """A real scheduler and two workers on 127.0.0.1, started as a site would start them."""

    def start(self, *args):
        log = open(self.path(f"log_{len(self.processes)}.txt"), "w")
        p = subprocess.Popen(args, stdout=log, stderr=subprocess.STDOUT, start_new_session=True, env=self.env)
        self.processes.append(p)
        return p

    def kill(self, p):
        os.killpg(p.pid, signal.SIGKILL)
        p.wait()

    def setUp(self):
        super().setUp()
        self.processes = []
        self.env = dict(os.environ)
        port = free_port()
        self.address = f"tcp://127.0.0.1:{port}"
        self.start(DASK, "scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard")
        self.workers = [self.start(DASK, "worker", self.address, "--nworkers", "1", "--nthreads", "1",
                                   "--no-dashboard", "--host", "127.0.0.1") for _ in range(2)]
        from dask.distributed import Client
        with Client(self.address, timeout=60) as c:
            c.wait_for_workers(2, timeout=60)

    def tearDown(self):
        for p in self.processes:
            if p.poll() is None:
                self.kill(p)
        super().tearDown()

    def results(self, out):
        runs = os.path.join(out, "runs")
        return sorted(d for d in os.listdir(runs) if not d.startswith(".")) if os.path.isdir(runs) else []

    def client(self, file):
        return self.start(PYTHON, "-m", "indentsim.sweep", file, "--scheduler", self.address, "--batch", "1", "--quiet")

    def wait_for(self, out, count, process):
        deadline = time.monotonic() + 120
        while len(self.results(out)) < count and process.poll() is None and time.monotonic() < deadline:
            time.sleep(0.02)

    def test_a_killed_worker_and_a_killed_client_lose_nothing_and_repeat_nothing(self):
        # 16 runs of about 0.3 s each, one per task.
        vary = '"material.E" = {from = 150e9, to = 250e9, count = 8}\n"material.nu" = [0.25, 0.3]\n'
        extra = '[set]\n"mesh.contact_nodes" = 24\n"load.increments" = 8\n'
        first = self.write_sweep("first.toml", self.path("first"), vary, extra)
        client = self.client(first)
        self.wait_for(self.path("first"), 4, client)
        self.kill(self.workers[0])  # mid-run: its batch goes to the other worker
        self.assertEqual(client.wait(timeout=300), 0, open(self.path("log_3.txt")).read())
        with open(self.path("first", "results.csv"), newline="") as f:
            rows = list(csv.DictReader(f))
        self.assertEqual(len(rows), 16)
        self.assertEqual(len({r["hash"] for r in rows}), 16)
        self.assertTrue(all(r["status"] == "finished" for r in rows))
        self.assertEqual(len(self.results(self.path("first"))), 16)

        # The client killed halfway through a second sweep, then started again.
        second = self.write_sweep("second.toml", self.path("second"), vary.replace("0.3]", "0.35]"), extra)
        client = self.client(second)
        self.wait_for(self.path("second"), 6, client)
        self.kill(client)
        time.sleep(2.0)  # the worker finishes the run it had; the scheduler drops the rest
        done = len(self.results(self.path("second")))
        self.assertLess(done, 16)
        p = subprocess.run([PYTHON, "-m", "indentsim.sweep", second, "--scheduler", self.address, "--quiet"],
                           capture_output=True, text=True, env=self.env, timeout=300)
        self.assertEqual(p.returncode, 0, p.stderr)
        print(f"\nsecond sweep: {done} results when the client was killed; restarted: {p.stdout.splitlines()[0]}")
        self.assertIn(f"({16 - done} solved now, {done} had results", p.stdout)
        self.assertEqual(len(self.results(self.path("second"))), 16)


if __name__ == "__main__":
    CLI, SOURCE = sys.argv[1], sys.argv[2]
    unittest.main(argv=[sys.argv[0], *sys.argv[3:]], verbosity=2)
