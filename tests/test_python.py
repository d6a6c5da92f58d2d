"""The Python module and Dask sweeps, as a notebook user and a cluster meet them.

Run by ctest with Debian's python3:  test_python.py INDENTSIM_CLI SOURCE_DIR [unittest args]
(PYTHONPATH holds build/python).  Each test compares with the CLI, which the C++ tests hold to
theory: the module must be the same code, not a second opinion.
"""
import csv
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
from indentsim.sweep import sweep

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

    @unittest.skipIf((os.cpu_count() or 1) < 2, "needs 2 cores")
    def test_the_gil_is_released_two_runs_in_two_threads_take_the_time_of_one(self):
        case = os.path.join(SOURCE, "loadcases", "power_law.toml")
        # Without the error estimate: its companion runs on the second core beside the run, and
        # "one run" would no longer be one core's work.
        single = ["mesh.error_estimate=\"off\""]
        start = time.monotonic()
        alone = indentsim.run(case, overrides=single)
        one = time.monotonic() - start
        results = [None, None]

        def solve(k):
            results[k] = indentsim.run(case, overrides=single)
        threads = [threading.Thread(target=solve, args=(k,)) for k in range(2)]
        start = time.monotonic()
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        two = time.monotonic() - start
        print(f"\none run {one:.2f} s; two runs in two threads {two:.2f} s (ratio {two / one:.2f})")
        self.assertLess(two / one, 1.5)  # 2.0 if the GIL were held
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
        # A one-parameter fit of E to a curve computed with E = 210 GPa, started at 160 GPa.
        data_run = self.path("data")
        self.assertEqual(cli("run", self.base, "--quiet", "--out", data_run).returncode, 0)
        data = os.path.join(data_run, "curve.csv")
        started = self.path("started.toml")
        with open(started, "w") as f:
            f.write(SMALL_CASE.replace("E = 210e9", "E = 160e9"))
        p = cli("fit", started, "--data", data, "--free", "material.E", "--bounds", "material.E=50e9:500e9",
                "--out", self.path("fit_cli"), "--no-plot", "--quiet")
        self.assertEqual(p.returncode, 0, p.stderr)
        fitted = indentsim.fit(started, data=data, free=["material.E"], bounds={"material.E": (50e9, 500e9)},
                               out=self.path("fit_py"))
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
