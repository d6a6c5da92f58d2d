#!/usr/bin/python3
"""The Berkovich-equivalent cone against a published finite-element table of sharp indentation
(prints; not a test).

    /usr/bin/python3 benchmarks/sharp_table.py [--strain small,finite] [--cases 1,2,85]
        [--jobs 2] [--binary BIN] [--csv FILE] [--set KEY=VALUE ...]

The table (benchmarks/data/sharp_cone_fem.csv, its source in its header) gives, for a rigid 70.3 deg
cone on power-law hardening solids (nu = 0.3, E/sigma_y 25 to 700, n 0 to 0.5), Kick's coefficient
C = P / h^2, the unloading slope dP/dh at h_m = 0.2 um and the plastic work ratio Wp/Wt.  Every case
is run as the shipped cone (loadcases/axisymmetric/berkovich_cone.toml) with
material.hardening = "power_law", the table's E, sigma_y and n, loaded to 1 um in 20 increments and
unloaded to 0.95 um in 25 (points for the Oliver-Pharr fit where h_f / h_max reaches 0.97) and to 0
in 30, at the default mesh, without the error estimate; then:

- C: least squares of P = C h^2 over the loading points with h >= h_max / 2 (Kick's law; the fit
  averages the node-entry ripple of a single point);
- S: the run's exact unloading stiffness at the peak, times 0.2 um / h_max (a cone has no length:
  S is proportional to h_max); beside it the slope of Oliver and Pharr's power-law fit of the
  unloading points between 20% and 98% of P_max (S_fit), which a table built from unloading curves
  may hold instead;
- Wp/Wt: 1 - W_e / W_t of the run's analysis (trapezoids over the loading and unloading points).

The goal of issue 40: C and S within 3%, Wp/Wt within 0.02.  The table's own scatter is measured
against the smooth functions Dao et al. fitted to their simulations (Pi1 for C / sigma_0.033 and Pi2
for S / (E* h_m), both of x = ln(E* / sigma_0.033) and n, E* = E / (1 - nu^2) for the rigid cone,
sigma_0.033 the flow stress at the representative plastic strain 0.033): the summary prints both
the table's and indentsim's distance from them.
"""

import argparse
import concurrent.futures
import csv
import json
import math
import pathlib
import statistics
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent
CASE = ROOT / "loadcases" / "axisymmetric" / "berkovich_cone.toml"
TABLE = ROOT / "benchmarks" / "data" / "sharp_cone_fem.csv"
H_MAX = 1e-6
H_TABLE = 0.2e-6  # the depth of the table's unloading slope
NU = 0.3


def dao_functions(n, E, sigma_y):
    """C and S at h_m = 0.2 um from Dao et al.'s Pi1 and Pi2 (Acta Mater. 49, 2001)."""
    contact_modulus = E / (1.0 - NU * NU)
    representative = sigma_y * (1.0 + E / sigma_y * 0.033) ** n
    x = math.log(contact_modulus / representative)
    pi1 = -1.131 * x**3 + 13.635 * x**2 - 30.594 * x + 29.267
    a3 = -1.40557 * n**3 + 0.77526 * n**2 + 0.15830 * n - 0.06831
    a2 = 17.93006 * n**3 - 9.22091 * n**2 - 2.37733 * n + 0.86295
    a1 = -79.99715 * n**3 + 40.55620 * n**2 + 9.00157 * n - 2.54543
    a0 = 122.65069 * n**3 - 63.88418 * n**2 - 9.58936 * n + 6.20045
    pi2 = a3 * x**3 + a2 * x**2 + a1 * x + a0
    return pi1 * representative, pi2 * contact_modulus * H_TABLE


def read_table():
    with open(TABLE) as f:
        rows = [line for line in f if not line.startswith("#")]
    table = []
    for r in csv.DictReader(rows):
        table.append({
            "case": int(r["Case"]),
            "n": float(r["n"]),
            "E": float(r["E (GPa)"]) * 1e9,
            "sigma_y": float(r["sy (GPa)"]) * 1e9,
            "C": float(r["C (GPa)"]) * 1e9,
            "S": float(r["dP/dh (N/m)"]),
            "Wp_Wt": float(r["Wp/Wt"]),
        })
    return table


def run_case(binary, row, strain, folder, extra):
    out = pathlib.Path(folder) / f"{strain}_{row['case']}"
    overrides = {
        "material.model": '"j2"',
        "material.hardening": '"power_law"',
        "material.E": repr(row["E"]),
        "material.nu": repr(NU),
        "material.yield_stress": repr(row["sigma_y"]),
        "material.n": repr(row["n"]),
        "load.path": f"[0.0, {H_MAX!r}, {0.95 * H_MAX!r}, 0.0]",
        "load.increments": "[20, 25, 30]",
        "mesh.error_estimate": '"off"',
        "geometry.strain": f'"{strain}"',
    }
    command = [binary, "run", str(CASE), "--quiet", "--out", str(out)]
    for key, value in overrides.items():
        command += ["--set", f"{key}={value}"]
    for item in extra:
        command += ["--set", item]
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        return None, (result.stderr.strip().splitlines() or ["(no message)"])[-1]
    with open(out / "curve.csv") as f:
        curve = [(float(r["alpha"]), float(r["P"])) for r in csv.DictReader(f)]
    with open(out / "summary.json") as f:
        summary = json.load(f)
    peak = max(range(len(curve)), key=lambda k: curve[k][0])
    loading = [(h, P) for h, P in curve[: peak + 1] if h >= 0.5 * curve[peak][0]]
    C = sum(P * h * h for h, P in loading) / sum(h**4 for h, _ in loading)
    branch = summary["unloading"][0]
    analysis = branch.get("analysis")
    if not analysis:
        return None, "no Oliver-Pharr analysis of the unloading"
    return {
        "C": C,
        "S": analysis["S_exact"] * H_TABLE / branch["depth"],
        "S_fit": analysis["S_fit"] * H_TABLE / branch["depth"],
        "Wp_Wt": 1.0 - analysis["W_e_over_W_t"],
        "pile_up": analysis.get("pile_up_ratio", math.nan),
        "seconds": sum(summary["time_s"].values()),
    }, None


def run_all(args, table, strains):
    records = []
    with tempfile.TemporaryDirectory() as folder, concurrent.futures.ThreadPoolExecutor(args.jobs) as pool:
        futures = {(row["case"], strain): pool.submit(run_case, args.binary, row, strain, folder, args.set)
                   for row in table for strain in strains}
        print(f"{'case':>5} {'n':>5} {'E/sy':>6} {'strain':>7}  {'C err':>7} {'S err':>7} {'S_fit':>7} {'dWp/Wt':>7}"
              f" {'pile-up':>7} {'s':>5}")
        for row in table:
            for strain in strains:
                result, error = futures[(row["case"], strain)].result()
                if error:
                    print(f"{row['case']:>5} {strain}: failed: {error}", file=sys.stderr)
                    continue
                rec = {
                    "case": row["case"], "n": row["n"], "E_over_sigma_y": row["E"] / row["sigma_y"],
                    "strain": strain, "C": result["C"], "S": result["S"], "S_fit": result["S_fit"],
                    "Wp_Wt": result["Wp_Wt"], "pile_up": result["pile_up"], "seconds": result["seconds"],
                }
                records.append(with_references(rec, row))
                print(f"{rec['case']:>5} {rec['n']:>5.3g} {rec['E_over_sigma_y']:>6.0f} {strain:>7}"
                      f"  {100 * rec['C_error']:>+6.2f}% {100 * rec['S_error']:>+6.2f}% {100 * rec['S_fit_error']:>+6.2f}%"
                      f" {rec['Wp_Wt_error']:>+7.3f} {rec['pile_up']:>7.3f} {rec['seconds']:>5.1f}", flush=True)
    return records


def with_references(rec, row):
    """The table's figures and Dao et al.'s functions beside a run's, and the differences."""
    C_dao, S_dao = dao_functions(row["n"], row["E"], row["sigma_y"])
    rec.update({
        "C_table": row["C"], "S_table": row["S"], "Wp_Wt_table": row["Wp_Wt"], "C_dao": C_dao, "S_dao": S_dao,
        "C_error": rec["C"] / row["C"] - 1.0, "S_error": rec["S"] / row["S"] - 1.0,
        "S_fit_error": rec["S_fit"] / row["S"] - 1.0, "Wp_Wt_error": rec["Wp_Wt"] - row["Wp_Wt"],
    })
    return rec


def read_records(path, table):
    rows = {row["case"]: row for row in table}
    records = []
    with open(path) as f:
        for r in csv.DictReader(f):
            rec = {"case": int(r["case"]), "strain": r["strain"]}
            for key in ("n", "E_over_sigma_y", "C", "S", "S_fit", "Wp_Wt", "pile_up", "seconds"):
                rec[key] = float(r[key])
            if rec["case"] in rows:
                records.append(with_references(rec, rows[rec["case"]]))
    return records


def summarize(records, strains):
    print("\nstrain   cases  C: median |err|  max |err|  within 3%   S: median |err|  max |err|  within 3%"
          "   Wp/Wt: median |err|  max |err|  within 0.02   median s")
    for strain in strains:
        rs = [r for r in records if r["strain"] == strain]
        if not rs:
            continue
        c = [abs(r["C_error"]) for r in rs]
        s = [abs(r["S_error"]) for r in rs]
        w = [abs(r["Wp_Wt_error"]) for r in rs]
        print(f"{strain:<8} {len(rs):>5}  {100 * statistics.median(c):>14.2f}% {100 * max(c):>9.2f}%"
              f" {sum(x <= 0.03 for x in c):>6}/{len(rs)}"
              f"  {100 * statistics.median(s):>14.2f}% {100 * max(s):>9.2f}% {sum(x <= 0.03 for x in s):>6}/{len(rs)}"
              f"  {statistics.median(w):>18.4f} {max(w):>10.4f} {sum(x <= 0.02 for x in w):>8}/{len(rs)}"
              f"   {statistics.median(r['seconds'] for r in rs):>8.1f}")
    print("\nagainst Dao et al.'s Pi1 and Pi2 (median |difference|, largest, mean)")

    def spread(values):
        return (f"{100 * statistics.median(abs(v) for v in values):5.2f}% {100 * max(abs(v) for v in values):6.2f}%"
                f" {100 * statistics.mean(values):+6.2f}%")

    for strain in strains:
        rs = [r for r in records if r["strain"] == strain]
        if not rs:
            continue
        if strain == strains[0]:
            print(f"  the table      C {spread([r['C_table'] / r['C_dao'] - 1 for r in rs])}"
                  f"   S {spread([r['S_table'] / r['S_dao'] - 1 for r in rs])}")
        print(f"  {strain:<14} C {spread([r['C'] / r['C_dao'] - 1 for r in rs])}"
              f"   S {spread([r['S'] / r['S_dao'] - 1 for r in rs])}")


def plot(records, strains, path):
    """C, S and Wp/Wt against the table by E/sigma_y, one colour per kinematics, the goal shaded."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(13, 4.2), constrained_layout=True)
    colours = {"small": "tab:blue", "finite": "tab:red"}
    markers = {0.0: "o", 0.1: "s", 0.3: "^", 0.5: "D"}
    panels = [("C_error", 100.0, "C / C$_{table}$ - 1 [%]", 3.0), ("S_error", 100.0, "S / S$_{table}$ - 1 [%]", 3.0),
              ("Wp_Wt_error", 1.0, "W$_p$/W$_t$ - table", 0.02)]
    for ax, (key, scale, label, goal) in zip(axes, panels):
        ax.axhspan(-goal, goal, color="0.9", zorder=0)
        ax.axhline(0.0, color="0.5", lw=0.8)
        for strain in strains:
            for r in (r for r in records if r["strain"] == strain):
                marker = markers.get(round(r["n"], 1), "x") if r["case"] < 1000 else "x"
                colour = colours.get(strain, "k")
                style = {"color": colour} if marker == "x" else {"facecolors": "none", "edgecolors": colour}
                ax.scatter(r["E_over_sigma_y"], scale * r[key], s=18, marker=marker, linewidths=0.9, **style)
        ax.set_xscale("log")
        ax.set_xticks([20, 50, 100, 200, 500, 1000], ["20", "50", "100", "200", "500", "1000"])
        ax.set_xlabel("E / $\\sigma_y$")
        ax.set_ylabel(label)
        limit = 4.0 * goal
        ax.set_ylim(-limit, limit)
    from matplotlib.lines import Line2D
    handles = [Line2D([], [], ls="", marker="o", mfc="none", mec=colours[s], label=f"{s} strain") for s in strains]
    handles += [Line2D([], [], ls="", marker=m, mfc="none", mec="k", label=f"n = {n:g}") for n, m in markers.items()]
    handles += [Line2D([], [], ls="", marker="x", mec="k", label="random n")]
    axes[2].legend(handles=handles, fontsize=8, loc="upper right", ncol=2)
    fig.suptitle("Rigid 70.3$^\\circ$ cone, power-law solids ($\\nu$ = 0.3), default mesh, against the published "
                 "finite-element table (shaded: the goal; points beyond the axes are clipped)", fontsize=10)
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--strain", default="small,finite")
    parser.add_argument("--cases", default="", help="comma-separated case numbers (default: all)")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--binary", default=str(ROOT / "build" / "indentsim"))
    parser.add_argument("--csv", help="also write every case's figures to this CSV")
    parser.add_argument("--from-csv", help="summarize (and plot) a CSV written by --csv instead of running")
    parser.add_argument("--plot", help="draw C, S and Wp/Wt against the table into this PNG")
    parser.add_argument("--set", action="append", default=[], help="one more key for every run")
    args = parser.parse_args()
    table = read_table()
    if args.cases:
        wanted = {int(c) for c in args.cases.split(",")}
        table = [r for r in table if r["case"] in wanted]
    strains = args.strain.split(",")
    records = read_records(args.from_csv, table) if args.from_csv else run_all(args, table, strains)
    if args.csv and records and not args.from_csv:
        with open(args.csv, "w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=list(records[0].keys()))
            writer.writeheader()
            writer.writerows(records)
    summarize(records, strains)
    if args.plot and records:
        plot(records, strains, args.plot)


if __name__ == "__main__":
    main()
