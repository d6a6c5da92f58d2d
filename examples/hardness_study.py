#!/usr/bin/env python3
"""How the hardness of a steel depends on its yield stress and hardening: a notebook-style study.

Set up once (docs/user-guide.md, "Python"):   export PYTHONPATH=$PWD/build/python
Run from the project root:        /usr/bin/python3 examples/hardness_study.py [--out out/hardness_study]

1. Three runs side by side in Python threads (the solve releases the GIL), their curves as NumPy
   arrays and Oliver-Pharr's hardness from each summary; a figure of the curves (OUT/curves.png).
2. The same question as a sweep over yield stress x hardening exponent on a Dask LocalCluster:
   the table results.csv, read back with NumPy, the constraint factor H / sigma_y, and the sweep's
   figure (OUT/sweep/figures/sweep.png: H, E_r and the pile-up ratio against sigma_y, a line per n).
The figures use the project's style and units (plots/indentsim.mplstyle, plots/indentsim_plotting.py).
Each cell below would be a notebook cell.  The mesh is coarse (12 contact nodes) to keep the
example quick; the shipped case's 20 are more accurate.  A run without a hardness (no unloading
branch, a branch that could not be analysed, a run that did not finish) gives NaN and its reason,
never a crash: hardness_of() and why_no_hardness() below.
"""
import argparse
import json
import math
import os
import pathlib
import sys
import tomllib
from concurrent.futures import ThreadPoolExecutor

import matplotlib
matplotlib.use("Agg")
import numpy as np

import indentsim
from indentsim.sweep import read_table, sweep

HERE = os.path.dirname(os.path.abspath(__file__))
CASE = os.path.join(HERE, "..", "loadcases", "axisymmetric", "steel_sphere.toml")
COARSE = {"mesh.contact_nodes": 12}

sys.path.insert(0, os.path.join(HERE, "..", "plots"))
import indentsim_plotting as ip  # noqa: E402  the figures' style, units and curve drawing (plots/)
import plot_results  # noqa: E402  its sweep figure


def hardness_of(summary):
    """Oliver-Pharr's H [Pa] of a run's first unloading branch (its summary.json), and why it is
    NaN when it is: no unloading branch, or one that could not be analysed (its analysis_error)."""
    branches = summary.get("unloading") or []
    if not branches:
        return math.nan, "no unloading branch"
    analysis = branches[0].get("analysis")
    if not isinstance(analysis, dict) or analysis.get("H") is None:
        return math.nan, branches[0].get("analysis_error") or "the unloading branch was not analysed"
    return float(analysis["H"]), ""


def why_no_hardness(table, k, sweep_out):
    """Why row k of a sweep's table (read_table) has no H: the run's status and message, or for a
    finished run the message, else its branch's analysis error (OUT/runs/HASH/summary.json, kept by
    default)."""
    status, message = str(table["status"][k]), str(table["message"][k])
    if status != "finished":
        return f"{status}: {message}" if message else status
    if message:
        return message
    try:
        with open(os.path.join(sweep_out, "runs", str(table["hash"][k]), "summary.json")) as f:
            return hardness_of(json.load(f))[1] or "no H in the table"
    except (OSError, ValueError):
        return "no H in the table (the run's summary.json was not kept)"


def ratio_text(ratio):
    """H / sigma_y as printed: "-" when there is no H."""
    return "-" if math.isnan(ratio) else f"{ratio:.2f}"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out/hardness_study", help="folder for the figure and the sweep")
    out = parser.parse_args().out
    os.makedirs(out, exist_ok=True)

    # --- 1. Three runs in three threads --------------------------------------------------------
    yield_stresses = [300e6, 500e6, 800e6]
    with ThreadPoolExecutor(max_workers=os.cpu_count() or 1) as pool:
        runs = [pool.submit(indentsim.run, CASE, overrides={**COARSE, "material.yield_stress": s})
                for s in yield_stresses]
        try:
            results = [run.result() for run in runs]
        except KeyboardInterrupt:  # Ctrl-C reaches this thread only: stop the runs of the others too
            indentsim.request_stop()
            raise
    # The curves as computed: a marker per increment, lines only where the ball touches (no chord
    # across the increment in which it left the surface; the rows after it are grey crosses), the
    # run's own discretization error as a band, units from the scale of the runs (mN, µm).
    ip.use_style("slide")
    fig, (ax,) = ip.figure("slide")
    units = ip.RunUnits.of_curve(np.concatenate([r.curve["alpha"] for r in results]),
                                 np.concatenate([r.curve["P"] for r in results]),
                                 np.concatenate([r.curve["a"] for r in results]), axisymmetric=True)
    print("sigma_y [MPa]   P_max [N]   H [GPa]   H / sigma_y")
    for k, (sigma_y, r) in enumerate(zip(yield_stresses, results)):
        hardness, why = hardness_of(r.summary)  # Oliver-Pharr on the unloading branch
        print(f"{sigma_y / 1e6:12.0f} {r.summary['peak_force']:11.4g} {hardness / 1e9:9.3f} "
              f"{ratio_text(hardness / sigma_y):>12}" + (f"  ({why})" if why else ""))
        ip.draw_load_depth(ax, r.curve["alpha"], r.curve["P"], r.curve.get("contact_nodes"), units,
                           color=[ip.LOADING, ip.UNLOADING, ip.RELOADING][k % 3],
                           label=f"σ$_y$ = {sigma_y / 1e6:.0f} MPa" + ("" if math.isnan(hardness) else
                                                                       f": $H$ = {hardness / 1e9:.2f} GPa"),
                           separated_label=k == len(results) - 1, error=r.curve.get("P_error_estimate"))
    ax.set(xlabel=f"indentation depth $h$ [{units.depth.name}]", ylabel=units.force_axis(), title="load–depth curves")
    ax.set_xlim(left=0)
    ip.legend(ax, "slide")
    with open(CASE, "rb") as f:
        case = tomllib.load(f)
    ip.run_title(fig, ip.describe_run(case, omit=["material.yield_stress"]) +
                 f"; {COARSE['mesh.contact_nodes']} contact nodes (grey band: each run's error estimate)")
    ip.save(fig, out, "curves")
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
    table = read_table(outcome.table)  # NumPy columns; NaN where a run has no value
    sigma_y, n, H = table["material.yield_stress"], table["material.n"], table["H"]
    for exponent in np.unique(n):
        pick = n == exponent
        print(f"n = {exponent:4.2f}: H / sigma_y = " + ", ".join(ratio_text(c) for c in H[pick] / sigma_y[pick]))
    for k in np.flatnonzero(np.isnan(H)):
        print(f"run {table['hash'][k]} (sigma_y = {sigma_y[k] / 1e6:.0f} MPa, n = {n[k]:.2f}): no H: "
              f"{why_no_hardness(table, k, os.path.dirname(outcome.table))}")
    plot_results.plot_sweep(pathlib.Path(os.path.dirname(outcome.table)), "slide")  # what `indentsim plot` draws


if __name__ == "__main__":  # Dask's worker processes import this file: nothing runs on import
    main()
