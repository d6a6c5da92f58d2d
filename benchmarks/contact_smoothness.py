#!/usr/bin/env python3
"""How smooth is P(h) on loading: the largest deviation of P from a smooth fit of the loading
branch (issue 38's measure).  A sphere: a power law P = C h^m fitted in log-log over the loading
rows with h >= 0.2 h_max (and, as a check that the law itself fits, a log-quadratic).  A cone:
P = C h^2 over the second half of the loading (Kick's law).

    python3 benchmarks/contact_smoothness.py INDENTSIM CASE.toml [--set KEY=VALUE ...]

prints the deviations in % and the wall time.  Runs in a temporary folder."""
import csv, subprocess, sys, tempfile, time, os
import numpy as np


def loading_branch(curve):
    rows = list(csv.DictReader(open(curve)))
    h = [float(r["alpha"]) for r in rows]
    P = [float(r["P"]) for r in rows]
    peak = int(np.argmax(h))
    return np.array(h[: peak + 1]), np.array(P[: peak + 1])


def deviations(h, P, cone):
    if cone:
        keep = h >= 0.5 * h[-1]
        ratio = P[keep] / h[keep] ** 2
        C = np.mean(ratio)
        return {"kick": float(np.max(np.abs(ratio / C - 1.0)) * 100)}
    keep = (h >= 0.2 * h[-1]) & (P > 0)
    x, y = np.log(h[keep]), np.log(P[keep])
    out = {}
    for name, degree in (("power", 1), ("logquad", 2)):
        c = np.polyfit(x, y, degree)
        out[name] = float(np.max(np.abs(np.exp(y - np.polyval(c, x)) - 1.0)) * 100)
    return out


def main():
    exe, case, sets = sys.argv[1], sys.argv[2], sys.argv[3:]
    args = []
    for s in sets:
        if s != "--set":
            args += ["--set", s]
    cone = "cone" in open(case).read()
    for a in args:
        if "punch.shape" in a:
            cone = "cone" in a
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        r = subprocess.run([exe, "run", case, "--out", os.path.join(tmp, "run")] + args,
                           capture_output=True, text=True)
        wall = time.perf_counter() - start
        if r.returncode != 0:
            print(r.stderr)
            sys.exit(1)
        h, P = loading_branch(os.path.join(tmp, "run", "curve.csv"))
        d = deviations(h, P, cone)
        print(" ".join(f"{k}={v:.3f}%" for k, v in d.items()), f"P_peak={P[-1]:.6g}", f"wall={wall:.2f}s")


if __name__ == "__main__":
    main()
