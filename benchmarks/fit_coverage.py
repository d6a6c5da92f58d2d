#!/usr/bin/env python3
"""How often the fit's 95% intervals hold the truth (issue 39).

The truth's curve is made by `indentsim run` on a mesh FACTOR times finer than the fit's (so the
forward model's own discretization error is in the data, as nature's would be) and, for a
path-dependent model (J2), with more increments (--data-set load.increments=[...] and --every K:
the data are every K-th row, at the case's own depths), Gaussian noise of
NOISE times the peak force is added with a new seed per realization, and `indentsim fit` fits it
from a start away from the truth.  For every free parameter it counts the realizations whose
interval_95 holds the truth, and how often a parameter called determined is within 5% of it.

    python3 benchmarks/fit_coverage.py build/indentsim loadcases/power_law.toml \\
        --free material.e0=0.005,material.n=0.2 --start material.e0=0.008,material.n=0.3 \\
        --nodes 10 --factor 3 --noise 0.005 --realizations 20
"""
import argparse
import csv
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np


def pairs(text):
    out = {}
    for item in text.split(","):
        key, value = item.split("=")
        out[key] = float(value)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("indentsim")
    ap.add_argument("case")
    ap.add_argument("--free", required=True, help="key=truth,...")
    ap.add_argument("--start", required=True, help="key=start,...")
    ap.add_argument("--nodes", type=int, default=10, help="the fit's mesh.contact_nodes")
    ap.add_argument("--factor", type=int, default=3, help="the data's mesh is this many times finer")
    ap.add_argument("--data-set", action="append", default=[], help="an override of the data's run only")
    ap.add_argument("--every", type=int, default=1, help="the data are every K-th row of the data's run")
    ap.add_argument("--noise", type=float, default=0.005, help="relative to the peak force")
    ap.add_argument("--realizations", type=int, default=20)
    ap.add_argument("--set", action="append", default=[], help="more overrides of the case (data and fit)")
    args = ap.parse_args()
    truth, start = pairs(args.free), pairs(args.start)
    common = sum((["--set", s] for s in args.set), [])
    with tempfile.TemporaryDirectory() as work:
        work = Path(work)
        data_run = work / "truth"
        sets = common + sum((["--set", f"{k}={v}"] for k, v in truth.items()), [])
        subprocess.run([args.indentsim, "run", args.case, "-q", "--out", str(data_run),
                        "--set", f"mesh.contact_nodes={args.factor * args.nodes}",
                        "--set", 'mesh.error_estimate="off"'] + sets + sum((["--set", d] for d in args.data_set), []),
                       check=True)
        with open(data_run / "curve.csv") as f:
            rows = list(csv.DictReader(f))[::args.every]
            rows = [r for r in rows if float(r["alpha"]) > 0.0]
        alpha = np.array([float(r["alpha"]) for r in rows])
        force = np.array([float(r["P"]) for r in rows])
        held = {k: 0 for k in truth}
        determined = {k: 0 for k in truth}
        close = {k: 0 for k in truth}
        fit_sets = common + sum((["--set", f"{k}={v}"] for k, v in start.items()), [])
        for seed in range(args.realizations):
            noisy = force + np.random.default_rng(seed).normal(0.0, args.noise * force.max(), force.size)
            data = work / f"data_{seed}.csv"
            with open(data, "w") as f:
                f.write("alpha,P\n")
                for a, p in zip(alpha, noisy):
                    f.write(f"{a!r},{p!r}\n")
            out = work / f"fit_{seed}"
            done = subprocess.run([args.indentsim, "fit", args.case, "--data", str(data), "--free", ",".join(truth),
                                   "--set", f"mesh.contact_nodes={args.nodes}", "--out", str(out), "--no-plot", "-q"]
                                  + fit_sets, capture_output=True, text=True)
            if done.returncode not in (0, 3):
                print(f"seed {seed}: fit failed ({done.returncode}): {done.stderr.strip()}", file=sys.stderr)
                continue
            fit = json.loads((out / "fit.json").read_text())
            line = [f"seed {seed:2d}"]
            for k, t in truth.items():
                p = fit["parameters"][k]
                lo, hi = p["interval_95"]
                inside = lo is not None and lo <= t <= hi
                held[k] += inside
                if p["determined"]:
                    determined[k] += 1
                    close[k] += abs(p["value"] / t - 1.0) <= 0.05
                line.append(f"{k} {p['value']:.4g} [{lo:.4g}, {hi:.4g}]{'' if inside else ' MISSES'}"
                            f"{' determined' if p['determined'] else ''}")
            print("  ".join(line), flush=True)
        n = args.realizations
        for k in truth:
            print(f"{k}: the 95% interval holds the truth in {held[k]} of {n}; called determined {determined[k]} "
                  f"times, within 5% of the truth {close[k]} of those")


if __name__ == "__main__":
    main()
