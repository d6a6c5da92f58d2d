#!/usr/bin/env python3
"""How P at the deepest point of a loading moves with the number of increments on one mesh: the
path-integration error of a history-dependent run (J2, friction), which no mesh companion sees
(issue 38's error bars).  Each doubling's change, its ratio to the previous one (0.5 for a first-
order integration in its asymptotic range), the loading branch's smoothness (contact_smoothness.py's
measure) and the wall time.

    python3 benchmarks/increment_convergence.py INDENTSIM CASE.toml [--counts 10,20,40,80] [--set KEY=VALUE ...]

The case's load path is cut to its deepest waypoint (loading only).  Runs in a temporary folder."""
import argparse, os, subprocess, sys, tempfile, time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from contact_smoothness import loading_branch, deviations  # noqa: E402


def deepest_depth(case):
    import tomllib
    with open(case, "rb") as f:
        path = tomllib.load(f)["load"]["path"]
    return max(path)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("exe")
    parser.add_argument("case")
    parser.add_argument("--counts", default="10,20,40,80")
    parser.add_argument("--set", action="append", default=[])
    a = parser.parse_args()
    depth = deepest_depth(a.case)
    cone = "cone" in open(a.case).read()
    sets = []
    for s in a.set + [f"load.path=[0,{depth!r}]", 'mesh.error_estimate="off"']:
        sets += ["--set", s]
    print(f"{a.case}: loading to {depth:g} m, P at the deepest point against the increments")
    print(f"{'increments':>10} {'P':>14} {'change':>9} {'ratio':>6} {'smoothness':>11} {'wall':>7}")
    previous, change = None, None
    for n in (int(c) for c in a.counts.split(",")):
        with tempfile.TemporaryDirectory() as tmp:
            start = time.perf_counter()
            r = subprocess.run([a.exe, "run", a.case, "--out", os.path.join(tmp, "run"), "-q",
                                "--set", f"load.increments={n}"] + sets, capture_output=True, text=True)
            wall = time.perf_counter() - start
            if r.returncode != 0:
                print(r.stderr)
                sys.exit(1)
            h, P = loading_branch(os.path.join(tmp, "run", "curve.csv"))
        smooth = max(deviations(h, P, cone).values())
        new_change = None if previous is None else (P[-1] - previous) / previous
        ratio = "" if change in (None, 0.0) or new_change is None else f"{new_change / change:6.2f}"
        shown = "" if new_change is None else f"{new_change * 100:+8.3f}%"
        print(f"{n:>10} {P[-1]:>14.8g} {shown:>9} {ratio:>6} {smooth:>10.3f}% {wall:>6.1f}s")
        previous, change = P[-1], new_change


if __name__ == "__main__":
    main()
