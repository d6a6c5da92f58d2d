"""Parameter sweeps on Dask distributed: a LocalCluster on this machine, or a running scheduler.

    python3 -m indentsim.sweep SWEEP.toml                       # a LocalCluster, one worker per core
    python3 -m indentsim.sweep SWEEP.toml --scheduler tcp://head:8786
    indentsim sweep SWEEP.toml --dask [--scheduler ...]         # the same, from the CLI

    from indentsim.sweep import sweep, read_table
    outcome = sweep("study.toml", workers=2)                   # from a notebook or a script
    table = read_table(outcome.table)                          # OUT/results.csv as NumPy columns

The library expands the sweep file into its manifest (every run a complete load case keyed by
its hash; bad input raises InputError before anything starts).  The runs without a result are
cut into batches, and each batch is one Dask task: a worker solves its runs in-process, with
the GIL released, and writes each result atomically under its hash in OUT/runs.  So:

  - a sweep stopped in any way (Ctrl-C, a killed client) is finished by running it again: only
    the runs without a result are computed;
  - a worker that dies has its batch rescheduled on another by the scheduler (up to
    distributed.scheduler.allowed-failures times); a batch that raises (the results folder
    cannot be written) is retried (`retries`);
  - a run that fails for its own reasons (its input, no convergence) is a result with its error,
    never retried;
  - results are the same files `indentsim sweep --shard i/N` and Slurm job arrays write, so a
    sweep can be started on one engine and finished on another.

Workers on other machines need the same indentsim, Python and Dask versions as the client, the
indentsim package on their PYTHONPATH, and OUT on a shared file system.
"""
import argparse
import csv
import json
import logging
import math
import os
import sys
import time
from dataclasses import dataclass

from . import _indentsim

__all__ = ["sweep", "SweepOutcome", "SchedulerError", "run_batch", "read_table"]


@dataclass
class SweepOutcome:
    """What a sweep did: the table's path and counts, and how many runs this call solved."""
    table: str
    runs: int
    finished: int
    not_converged: int
    failed: int
    pending: int
    solved_now: int
    had_results: int
    wall_seconds: float


def run_batch(out, keep, runs):
    """One Dask task: solves each (index, hash, case) of `runs` that has no result yet, in this
    worker's process; returns their statuses ("had:..." for those a result already had)."""
    return _indentsim.run_sweep_batch(out, keep, runs)


def read_table(table):
    """A sweep's table (OUT/results.csv, or any CSV with a header) as {column: NumPy array}, in
    the table's order.  A column whose cells are all numbers or empty is an array of floats, an
    empty cell NaN: a run with no value there (no unloading branch, a branch that could not be
    analysed, a run that failed or is pending: see its `status` and `message`).  `index` is an
    array of integers; hash, status, force_unit, message and a varied key of strings are arrays
    of strings."""
    import numpy as np
    with open(os.fspath(table), newline="") as f:
        rows = list(csv.reader(f))
    if not rows:
        raise _indentsim.InputError(f"{os.fspath(table)}: table: is empty (no header)")
    header, body = rows[0], rows[1:]
    columns = {}
    for k, name in enumerate(header):
        cells = [r[k] if k < len(r) else "" for r in body]
        if name in _TEXT_COLUMNS:
            columns[name] = np.array(cells, dtype=str)
            continue
        try:
            numbers = np.array([float(c) if c.strip() else math.nan for c in cells], dtype=float)
        except ValueError:
            columns[name] = np.array(cells, dtype=str)
            continue
        columns[name] = numbers.astype(int) if name == "index" and np.all(np.isfinite(numbers)) else numbers
    return columns


_TEXT_COLUMNS = {"hash", "status", "force_unit", "message"}  # a hash may be all digits: still text


SCHEDULER_TIMEOUT_S = 5  # how long a --scheduler that does not answer is tried


class SchedulerError(ValueError):
    """The scheduler given cannot be used: a malformed address, or none answering there."""

    def __init__(self, scheduler, problem):
        super().__init__(f"scheduler {scheduler}: {problem}")
        self.scheduler, self.problem = scheduler, problem


def _has_result(out, run):
    return os.path.isfile(os.path.join(out, "runs", run["hash"], "result.json"))


def _client(scheduler, workers):
    """A client of the scheduler given, or of a LocalCluster on this machine (one single-threaded
    worker process per core: a run uses one core)."""
    from dask.distributed import Client, LocalCluster
    if scheduler:
        # A malformed address raises ValueError at once; an unreachable one OSError after the
        # timeout (Dask's default would wait 30 s, then print pages of traceback).
        try:
            return Client(scheduler, timeout=SCHEDULER_TIMEOUT_S), None
        except (OSError, ValueError, TypeError) as e:
            problem = str(e) or type(e).__name__
            if isinstance(e, OSError):
                problem = f"cannot connect ({problem}); is a scheduler running there?"
            else:
                problem = f"not a scheduler address such as tcp://head:8786 ({problem})"
            raise SchedulerError(scheduler, problem) from None
    cluster = LocalCluster(n_workers=workers or os.cpu_count() or 1, threads_per_worker=1, processes=True,
                           dashboard_address=None, silence_logs=logging.ERROR)
    return Client(cluster), cluster


def sweep(sweep_file, scheduler=None, workers=None, batch=None, progress=True, retries=2):
    """Runs every run of `sweep_file` that has no result, on the Dask scheduler at `scheduler`
    (e.g. "tcp://head:8786") or on a LocalCluster of `workers` processes; then writes the table.
    `batch`: runs per task (default: about four tasks per worker thread, at most 16 runs each)."""
    start = time.monotonic()
    manifest = json.loads(_indentsim.sweep_manifest(os.fspath(sweep_file)))
    out = os.path.abspath(manifest["out"])  # workers may start elsewhere
    keep = manifest["keep"]
    pending = [r for r in manifest["runs"] if not _has_result(out, r)]
    solved = had = 0
    if pending:
        from dask.distributed import as_completed
        from tqdm import tqdm
        client, cluster = _client(scheduler, workers)
        try:
            threads = max(1, sum(client.nthreads().values()))
            size = batch or max(1, min(16, math.ceil(len(pending) / (4 * threads))))
            batches = [pending[k:k + size] for k in range(0, len(pending), size)]
            futures = [client.submit(run_batch, out, keep, [(r["index"], r["hash"], r["case"]) for r in b],
                                     pure=False, retries=retries) for b in batches]
            with tqdm(total=len(pending), unit="run", disable=not progress, desc="sweep",
                      file=sys.stderr) as bar:
                for future in as_completed(futures):
                    statuses = future.result()
                    had += sum(s.startswith("had:") for s in statuses)
                    solved += sum(not s.startswith("had:") for s in statuses)
                    bar.update(len(statuses))
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
    tally = _indentsim.collect_sweep(os.path.join(manifest["out"], "manifest.json"))
    return SweepOutcome(table=os.path.join(manifest["out"], "results.csv"), solved_now=solved,
                        had_results=len(manifest["runs"]) - len(pending) + had,
                        wall_seconds=time.monotonic() - start, **tally)


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python3 -m indentsim.sweep",
                                     description="an indentsim sweep on Dask distributed")
    parser.add_argument("sweep", help="sweep file (TOML)")
    parser.add_argument("--scheduler", help="a running scheduler, e.g. tcp://head:8786 (default: a LocalCluster)")
    parser.add_argument("--workers", type=int, help="LocalCluster: worker processes (default: one per core)")
    parser.add_argument("--batch", type=int, help="runs per Dask task")
    parser.add_argument("--quiet", "-q", action="store_true", help="no progress bar")
    a = parser.parse_args(argv)
    if a.workers is not None and a.workers < 1:
        parser.error("--workers must be at least 1")
    if a.batch is not None and a.batch < 1:
        parser.error("--batch must be at least 1")
    try:
        o = sweep(a.sweep, scheduler=a.scheduler, workers=a.workers, batch=a.batch, progress=not a.quiet)
    except SchedulerError as e:
        print(f"error: --scheduler {e.scheduler}: {e.problem}", file=sys.stderr)
        return 2
    except _indentsim.InputError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except _indentsim.IoError as e:
        print(f"error: {e}", file=sys.stderr)
        return 4
    except KeyboardInterrupt:
        print("sweep stopped: the runs with results are kept; the same command finishes the rest", file=sys.stderr)
        return 130
    print(f"{o.runs} runs: {o.finished} finished, {o.not_converged} not converged, {o.failed} failed "
          f"({o.solved_now} solved now, {o.had_results} had results; {o.wall_seconds:.1f} s)\ntable: {o.table}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
