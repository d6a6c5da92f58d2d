#!/usr/bin/python3
"""The speed goals of plastic scenes, measured in one run (prints; a benchmark, not a test).

    /usr/bin/python3 benchmarks/speed_goals.py [--build build] [--baseline BIN] [--repeats 3]
        [--skip-factorizations] [--skip-scaling] [--skip-calculix]

1. Factorizations per increment of every shipped plastic case at its own mesh (whole runs with
   the default settings, from curve.csv), with Newton iterations per increment and the error
   estimate's cost (summary.json).  Goal: at most 2.5.
2. Time per increment against DOFs on deep_plastic.toml, contact_nodes 12, 24, 48
   (`indentsim_bench --nodes 12,24,48`, its least-squares exponent), with KLU (the default) and
   with CHOLMOD factoring the preconditioner.  Goal: DOFs^1.25 or slower growth.
3. deep_plastic.toml at 0.1% error of P (contact_nodes 30: 0.102% against the Richardson
   extrapolation of contact_nodes 30 and 60, observed order 1.65): whole runs, process start to
   exit, of this build and of --baseline (an indentsim binary built at another commit, e.g. the
   start of the work: `git worktree add /tmp/base 68f4144 && cmake -S /tmp/base -B /tmp/base/build
   -DCMAKE_BUILD_TYPE=Release && cmake --build /tmp/base/build --target indentsim_cli`), taken in
   turns so that both see the same machine; medians and their ratio.  Goal: 5x.
4. CalculiX 2.20 on the elastic paper geometry at equal error: benchmarks/calculix/compare_calculix.py
   when `ccx` is installed (Debian's calculix-ccx).  Goal: 50x.
"""

import argparse
import csv
import json
import pathlib
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
PLASTIC_CASES = ["paper.toml", "power_law.toml", "deep_plastic.toml", "load_unload.toml",
                 "axisymmetric/steel_sphere.toml", "axisymmetric/berkovich_cone.toml",
                 "axisymmetric/blunted_cone.toml"]


def run(exe, case, out, *overrides):
    args = [str(exe), "run", str(case), "--out", str(out), "-q"]
    for o in overrides:
        args += ["--set", o]
    start = time.perf_counter()
    proc = subprocess.run(args, capture_output=True, text=True)
    wall = time.perf_counter() - start
    if proc.returncode != 0:
        sys.exit(f"speed_goals: {' '.join(args)} failed:\n{proc.stderr}")
    return wall


def curve(out):
    with open(out / "curve.csv") as f:
        return list(csv.DictReader(f))


def factorizations(exe, work):
    print("1. Factorizations per increment at each shipped plastic case's own mesh (goal <= 2.5)")
    print(f"{'case':<34} {'increments':>10} {'newton/inc':>10} {'factor/inc':>10} {'estimate cost':>13} "
          f"{'wall added':>10} {'wall_s':>7}")
    for name in PLASTIC_CASES:
        out = work / name.replace("/", "_")
        wall = run(exe, ROOT / "loadcases" / name, out, "output.fields_every=0")
        rows = curve(out)[1:]
        n = len(rows)
        newton = sum(int(r["newton_iters"]) for r in rows) / n
        factor = sum(int(r["factorizations"]) for r in rows) / n
        summary = json.loads((out / "summary.json").read_text())
        estimate = summary.get("error_estimate", {})
        # The companion's own time against the run's, and the wall time it added (it runs on a
        # second core beside the model's build where there is one).
        cost, added = estimate.get("cost_fraction"), estimate.get("wall_fraction")
        cost_text = f"{100 * cost:.1f}%" if cost is not None else "-"
        added_text = f"{100 * added:.1f}%" if added is not None else "-"
        print(f"{name:<34} {n:>10} {newton:>10.2f} {factor:>10.2f} {cost_text:>13} {added_text:>10} {wall:>7.2f}")
    print()


def scaling(build, work):
    print("2. Time per increment against DOFs, deep_plastic.toml, contact_nodes 12, 24, 48 (goal: DOFs^1.25)")
    cholmod = work / "deep_plastic_cholmod.toml"
    text = (ROOT / "loadcases" / "deep_plastic.toml").read_text()
    cholmod.write_text(text.replace("[mesh]", '[solver]\nlinear = "cholmod"\n\n[mesh]'))
    for label, case in (("KLU (default)", ROOT / "loadcases" / "deep_plastic.toml"), ("CHOLMOD", cholmod)):
        proc = subprocess.run([str(build / "indentsim_bench"), "1", "--nodes", "12,24,48", str(case)],
                              capture_output=True, text=True)
        if proc.returncode != 0:
            sys.exit(f"speed_goals: indentsim_bench failed:\n{proc.stderr}")
        lines = [l for l in proc.stdout.splitlines() if re.match(r"\s+\d", l) or "DOFs^" in l]
        print(f"  {label}:")
        for l in lines:
            print("   " + l.strip())
    print()


def deep_plastic_at_tenth_percent(exe, baseline, repeats, work):
    print("3. deep_plastic.toml at 0.1% error of P (contact_nodes 30), whole runs (goal: 5x the start)")
    case = ROOT / "loadcases" / "deep_plastic.toml"
    configs = [("this build, KLU (default)", exe, []), ("this build, CHOLMOD", exe, ["solver.linear=cholmod"])]
    if baseline:
        configs += [("baseline, KLU (default)", baseline, []), ("baseline, CHOLMOD", baseline, ["solver.linear=cholmod"])]
    times = {label: [] for label, _, _ in configs}
    forces = {}
    for _ in range(repeats):
        for label, binary, extra in configs:
            out = work / ("deep30_" + re.sub(r"\W+", "_", label))
            times[label].append(run(binary, case, out, "mesh.contact_nodes=30", "output.fields_every=0", *extra))
            forces[label] = float(curve(out)[-1]["P"])
    for label, _, _ in configs:
        print(f"  {label:<26} median {statistics.median(times[label]):6.2f} s of {repeats} "
              f"({', '.join(f'{t:.2f}' for t in times[label])}); final P {forces[label]:.6e} N/m")
    if baseline:
        reference = statistics.median(times["baseline, KLU (default)"])
        for label in ("this build, KLU (default)", "this build, CHOLMOD"):
            print(f"  baseline (default) / {label}: {reference / statistics.median(times[label]):.2f}x")
    else:
        print("  (no --baseline binary: no ratio)")
    print()


def calculix(exe):
    print("4. CalculiX 2.20, elastic paper geometry, equal error (goal: 50x)")
    if shutil.which("ccx") is None:
        print("  ccx not installed (apt-get install calculix-ccx): skipped")
        return
    subprocess.run([sys.executable, str(ROOT / "benchmarks" / "calculix" / "compare_calculix.py"),
                    str(ROOT / "loadcases" / "paper.toml"), "--indentsim", str(exe)], check=False)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--build", default=str(ROOT / "build"))
    parser.add_argument("--baseline", help="an indentsim binary of another commit, for the ratio of item 3")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--skip-factorizations", action="store_true")
    parser.add_argument("--skip-scaling", action="store_true")
    parser.add_argument("--skip-calculix", action="store_true")
    args = parser.parse_args()
    build = pathlib.Path(args.build)
    exe = build / "indentsim"
    with tempfile.TemporaryDirectory() as tmp:
        work = pathlib.Path(tmp)
        if not args.skip_factorizations:
            factorizations(exe, work)
        if not args.skip_scaling:
            scaling(build, work)
        deep_plastic_at_tenth_percent(exe, args.baseline, args.repeats, work)
        if not args.skip_calculix:
            calculix(exe)


if __name__ == "__main__":
    main()
