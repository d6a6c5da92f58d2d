#!/usr/bin/env python3
"""Sweep throughput: runs per second of small elastic cases, by engine, with medians of repeats.

    PYTHONPATH=build/python /usr/bin/python3 benchmarks/sweep_throughput.py [--runs 48] [--repeats 3]

Engines, each on the same N cases (loadcases/elastic.toml at its default mesh, material.E varied
so that every run is a new case):
  shell loop      one `indentsim run` process per case, one after the other
  sweep (CLI)     `indentsim sweep` in one process (shard 1/1)
  Dask 1 worker   indentsim.sweep on a LocalCluster of 1 worker process
  Dask 2 workers  ... of 2 worker processes (the scaling from 1 to 2)
For the sweeps, the runs' own wall times (results.csv's wall_s) are summed: an engine's overhead
is its wall time minus that sum over its workers (scheduling, start and stop of the cluster,
reading and writing results), reported per run and as a fraction of a run.  The start of the
LocalCluster is counted: it is what a user waits for.
"""
import argparse
import csv
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--runs", type=int, default=48)
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--cli", default=os.path.join(ROOT, "build", "indentsim"))
    a = p.parse_args()
    from indentsim.sweep import sweep
    work = tempfile.mkdtemp(prefix="indentsim_sweep_bench_")
    base = os.path.join(ROOT, "loadcases", "elastic.toml")
    values = [f"{150e9 + k * 1e9:.6g}" for k in range(a.runs)]
    times = {name: [] for name in ("shell loop", "sweep (CLI)", "Dask 1 worker", "Dask 2 workers")}
    inside = {name: [] for name in times}  # the runs' own wall time, summed
    cluster = []  # a LocalCluster of 2 workers started and stopped, nothing run

    def start_and_stop():
        import logging
        from dask.distributed import Client, LocalCluster
        start = time.monotonic()
        with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                          silence_logs=logging.ERROR) as c, Client(c) as client:
            client.wait_for_workers(2)
        return time.monotonic() - start

    def runs_time(out):
        with open(os.path.join(out, "results.csv"), newline="") as f:
            return sum(float(r["wall_s"]) for r in csv.DictReader(f))
    try:
        for repeat in range(a.repeats):
            def sweep_file(name):
                file = os.path.join(work, f"{name}_{repeat}.toml")
                with open(file, "w") as f:
                    f.write(f'[sweep]\nbase = "{base}"\nout = "{os.path.join(work, name + "_" + str(repeat))}"\n'
                            f'[vary]\n"material.E" = [{", ".join(values)}]\n')
                return file

            start = time.monotonic()
            for k, E in enumerate(values):
                subprocess.run([a.cli, "run", base, "--quiet", "--out", os.path.join(work, f"loop_{repeat}_{k}"),
                                "--set", f"material.E={E}"], check=True)
            times["shell loop"].append(time.monotonic() - start)

            start = time.monotonic()
            subprocess.run([a.cli, "sweep", sweep_file("cli"), "--quiet"], check=True, stdout=subprocess.DEVNULL)
            times["sweep (CLI)"].append(time.monotonic() - start)
            inside["sweep (CLI)"].append(runs_time(os.path.join(work, f"cli_{repeat}")))

            cluster.append(start_and_stop())
            for workers in (1, 2):
                start = time.monotonic()
                o = sweep(sweep_file(f"dask{workers}"), workers=workers, progress=False)
                assert o.finished == a.runs, o
                name = f"Dask {workers} worker" + ("s" if workers > 1 else "")
                times[name].append(time.monotonic() - start)
                inside[name].append(runs_time(os.path.join(work, f"dask{workers}_{repeat}")) / workers)
    finally:
        shutil.rmtree(work, ignore_errors=True)

    median = {k: statistics.median(v) for k, v in times.items()}
    print(f"{a.runs} runs of loadcases/elastic.toml (default mesh), median of {a.repeats} on {os.cpu_count()} cores")
    print(f"{'engine':<16} {'wall [s]':>9} {'runs/s':>8} {'vs shell loop':>14} {'run [ms]':>9} {'overhead/run':>13}")
    for name, t in median.items():
        line = f"{name:<16} {t:9.2f} {a.runs / t:8.2f} {median['shell loop'] / t:13.2f}x"
        if inside[name]:
            workers = 2 if name.endswith("2 workers") else 1
            run = statistics.median(inside[name]) * workers / a.runs
            overhead = statistics.median(t - i for t, i in zip(times[name], inside[name])) * workers / a.runs
            line += f" {run * 1e3:9.0f} {overhead * 1e3:7.0f} ms {100 * overhead / run:3.0f}%"
        print(line)
    fixed = statistics.median(cluster)
    for name, workers in (("Dask 1 worker", 1), ("Dask 2 workers", 2)):
        run = statistics.median(inside[name]) * workers / a.runs
        beyond = (median[name] - fixed - statistics.median(inside[name])) * workers / a.runs
        print(f"{name}, beyond the cluster's start and stop ({fixed:.2f} s): {beyond * 1e3:.0f} ms per run "
              f"({100 * beyond / run:.0f}% of a run)" + ("; this includes the last batches' tail, one worker idle "
                                                         "while the other finishes" if workers > 1 else ""))
    print(f"scaling 1 -> 2 Dask workers: {median['Dask 1 worker'] / median['Dask 2 workers']:.2f}x")

if __name__ == "__main__":
    sys.exit(main())
