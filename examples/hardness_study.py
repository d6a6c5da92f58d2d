#!/usr/bin/env python3
"""How the hardness of a steel depends on its yield stress and hardening: a notebook-style study.

Set up once (docs/user-guide.md, "Python"):   export PYTHONPATH=$PWD/build/python
Run from the project root:        /usr/bin/python3 examples/hardness_study.py [--out out/hardness_study]

1. Three runs side by side in Python threads (the solve releases the GIL), their curves as NumPy
   arrays and Oliver-Pharr's hardness from each summary; a figure of the curves.
2. The same question as a sweep over yield stress x hardening exponent on a Dask LocalCluster:
   the table results.csv, read back with NumPy, and the constraint factor H / sigma_y.
Each cell below would be a notebook cell.  The mesh is coarse (12 contact nodes) to keep the
example quick; the shipped case's 20 are more accurate.
"""
import argparse
import csv
import os
from concurrent.futures import ThreadPoolExecutor

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import indentsim
from indentsim.sweep import sweep

HERE = os.path.dirname(os.path.abspath(__file__))
CASE = os.path.join(HERE, "..", "loadcases", "axisymmetric", "steel_sphere.toml")
COARSE = {"mesh.contact_nodes": 12}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out/hardness_study", help="folder for the figure and the sweep")
    out = parser.parse_args().out
    os.makedirs(out, exist_ok=True)

    # --- 1. Three runs in three threads --------------------------------------------------------
    yield_stresses = [300e6, 500e6, 800e6]
    with ThreadPoolExecutor(max_workers=os.cpu_count() or 1) as pool:
        results = list(pool.map(lambda s: indentsim.run(CASE, overrides={**COARSE, "material.yield_stress": s}),
                                yield_stresses))
    fig, ax = plt.subplots(figsize=(6, 4))
    print("sigma_y [MPa]   P_max [N]   H [GPa]   H / sigma_y")
    for sigma_y, r in zip(yield_stresses, results):
        hardness = r.summary["unloading"][0]["analysis"]["H"]  # Oliver-Pharr on the unloading branch
        print(f"{sigma_y / 1e6:12.0f} {r.summary['peak_force']:11.4g} {hardness / 1e9:9.3f} {hardness / sigma_y:12.2f}")
        ax.plot(r.curve["alpha"] * 1e6, r.curve["P"], label=f"sigma_y = {sigma_y / 1e6:.0f} MPa")
    ax.set(xlabel="depth alpha [um]", ylabel=f"P [{r.summary['units']['force']}]",
           title="0.5 mm sphere into J2 steel (n = 0.15)")
    ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(out, "curves.png"), dpi=120)
    results[1].write(os.path.join(out, "sigma_y_500MPa"))  # the usual files of one run

    # --- 2. A sweep on Dask: yield stress x hardening exponent --------------------------------
    sweep_file = os.path.join(out, "sweep.toml")
    with open(sweep_file, "w") as f:
        f.write(f'[sweep]\nbase = "{os.path.abspath(CASE)}"\nout = "{os.path.join(out, "sweep")}"\n'
                '[set]\n"mesh.contact_nodes" = 12\n"mesh.error_estimate" = "off"\n'
                '[vary]\n"material.yield_stress" = {from = 300e6, to = 900e6, count = 3, scale = "log"}\n'
                '"material.n" = [0.05, 0.25]\n')
    outcome = sweep(sweep_file, workers=os.cpu_count() or 1)  # a LocalCluster; --scheduler for a real one
    print(f"sweep: {outcome.finished} of {outcome.runs} runs finished ({outcome.solved_now} solved now) "
          f"in {outcome.wall_seconds:.1f} s; table {outcome.table}")
    with open(outcome.table, newline="") as f:
        rows = list(csv.DictReader(f))
    sigma_y = np.array([float(r["material.yield_stress"]) for r in rows])
    n = np.array([float(r["material.n"]) for r in rows])
    H = np.array([float(r["H"]) for r in rows])
    for exponent in np.unique(n):
        pick = n == exponent
        print(f"n = {exponent:4.2f}: H / sigma_y = " + ", ".join(f"{c:.2f}" for c in H[pick] / sigma_y[pick]))


if __name__ == "__main__":  # Dask's worker processes import this file: nothing runs on import
    main()
