#!/usr/bin/python3
"""indentsim against CalculiX 2.20 (Debian's calculix-ccx) on the same mesh: force and wall time.

    /usr/bin/python3 benchmarks/calculix/compare_calculix.py CASE.toml [--contact-nodes 10 20 40]
        [--increments 24] [--repeats 3] [--indentsim build/indentsim] [--ccx ccx] [--keep DIR]
        [--plot plots/calculix_work_precision.png]

For a load case along a monotone path, made elastic by this script (--set material.model=elastic;
the paper's geometry is loadcases/paper.toml; any scene calculix_deck.py builds: plane strain or
axisymmetry, sphere, cone or flat punch, a coated specimen, each layer made elastic too), and each
contact_nodes N:
  1. indentsim runs the case (the median of --repeats whole runs, process start to exit, with the
     error estimate off and on), then once more writing the fields of step 0, whose grid is
     indentsim's mesh;
  2. the CalculiX deck is built from the load case and that grid -- node for node the same mesh,
     so both codes have the same discretization error and "equal error" means "equal mesh";
  3. ccx solves it (one thread, like indentsim) and its force is read from the .dat file.
Prints P of both (N/m of both halves in plane strain, N in axisymmetry), their relative difference,
the wall times and their ratio, and the error of P against the Richardson extrapolation of
indentsim alone on the two finest meshes and one twice as fine (--reference-nodes, default twice
the largest N), with their observed order.

The deck: calculix_deck.py (CPE4, one GAPUNI element per surface node within reach to one rigid
punch node with the vertical gap g(x) as clearance -- contact = "gap", ccx finds the contact
itself -- and the punch driven through indentsim's depths, one ccx increment per indentsim
increment); its docstring lists the CalculiX pitfalls met on the way.  The other script beside it,
same_mesh.py, checks agreement on every scene (axisymmetric, cones, J2, unloading).
"""

import argparse
import json
import math
import pathlib
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import tomllib

from calculix_deck import DeckError, forces_of, length_unit, read_run, run_ccx, write_deck

ELASTIC = ["--set", "material.model=elastic", "--set", "mesh.element=q1"]


def elastic_overrides(case):
    """ELASTIC for a load case: a coated specimen's every layer made elastic as well as its substrate
    (the gap contact is for elastic scenes: calculix_deck.py)."""
    layers = len(case.get("layer", []))
    return ELASTIC + [item for k in range(1, layers + 1) for item in ("--set", f"layer.{k}.material.model=elastic")]


def fail(message):
    sys.exit(f"compare_calculix: {message}")


def check_case(path):
    """The comparison is of the final P along a monotone path (its Richardson reference); returns
    the unit of P in the case's scene and the overrides that make it elastic."""
    with open(path, "rb") as f:
        case = tomllib.load(f)
    waypoints = case.get("load", {}).get("path", [])
    if len(waypoints) != 2 or waypoints[0] != 0.0:
        fail(f"{path}: load.path: only a monotone path [0, alpha] is compared here")
    return "N" if case.get("geometry", {}).get("kind") == "axisymmetric" else "N/m", elastic_overrides(case)


def run_indentsim(exe, case, nodes, increments, out, elastic, extra=()):
    args = [str(exe), "run", str(case), "--out", str(out), "-q", *elastic,
            "--set", f"mesh.contact_nodes={nodes}", "--set", f"load.increments={increments}", *extra]
    start = time.perf_counter()
    proc = subprocess.run(args, capture_output=True, text=True)
    wall = time.perf_counter() - start
    if proc.returncode != 0:
        fail(f"indentsim failed: {' '.join(args)}\n{proc.stderr}")
    return wall


def final_force(run_dir):
    with open(run_dir / "curve.csv") as f:
        header = f.readline().strip().split(",")
        last = f.read().strip().splitlines()[-1].split(",")
    return float(last[header.index("P")]), float(last[header.index("a")])


def ccx_force(ccx, grid_run, deck_dir):
    """ccx's final P on the mesh of an indentsim run folder, and its wall time."""
    scene = read_run(grid_run)
    deck_dir.mkdir(parents=True, exist_ok=True)
    try:
        dofs = write_deck(deck_dir / "case.inp", scene, contact="gap")
        result, wall = run_ccx(ccx, deck_dir, "case", length_unit(scene))
    except DeckError as error:
        fail(str(error))
    forces = forces_of(scene, result, "gap")
    if len(forces) != len(scene["alphas"]) - 1:
        fail(f"ccx did not reach the end of its step; see {deck_dir}")
    return forces[-1], wall, dofs


def plot(rows, reference, path, title):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    error = [abs(r["force"] - reference) / reference * 100 for r in rows]
    fig, ax = plt.subplots(figsize=(6, 4.2))
    for key, label, marker in (("ccx", "CalculiX 2.20 (CPE4 + GAPUNI)", "s"),
                               ("on", "indentsim, error estimate on", "o"),
                               ("off", "indentsim, error estimate off", "^")):
        ax.loglog([r[key] for r in rows], error, marker=marker, label=label)
    for r, e in zip(rows, error):
        ax.annotate(f"N = {r['nodes']}", (r["ccx"], e), textcoords="offset points", xytext=(4, 4), fontsize=8)
    ax.set_xlabel("wall time of the whole run [s] (one thread each)")
    ax.set_ylabel("error of the final P [%]")
    ax.set_title(f"{title}:\nthe same meshes, the same P", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="lower left", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    fig.savefig(path.with_suffix(".svg"))
    print(f"wrote {path}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("case", type=pathlib.Path)
    ap.add_argument("--contact-nodes", type=int, nargs="+", default=[10, 20, 40])
    ap.add_argument("--increments", type=int, default=24)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--reference-nodes", type=int, help="indentsim alone on this mesh for the reference "
                    "(default: twice the largest --contact-nodes)")
    ap.add_argument("--indentsim", type=pathlib.Path, default=pathlib.Path("build/indentsim"))
    ap.add_argument("--ccx", default="ccx")
    ap.add_argument("--keep", type=pathlib.Path, help="keep the runs, decks and results here")
    ap.add_argument("--plot", type=pathlib.Path, help="draw error against wall time (PNG, and SVG beside it)")
    args = ap.parse_args()
    if shutil.which(args.ccx) is None:
        fail(f"{args.ccx} not found: apt-get install calculix-ccx")
    unit, elastic = check_case(args.case)
    work = args.keep or pathlib.Path(tempfile.mkdtemp(prefix="compare_calculix_"))
    work.mkdir(parents=True, exist_ok=True)

    rows = []
    for n in args.contact_nodes:
        base = work / f"N{n}"
        off = [run_indentsim(args.indentsim, args.case, n, args.increments, base / "indentsim", elastic,
                             ["--set", "mesh.error_estimate=off"]) for _ in range(args.repeats)]
        on = [run_indentsim(args.indentsim, args.case, n, args.increments, base / "indentsim_estimate", elastic)
              for _ in range(args.repeats)]
        force, _ = final_force(base / "indentsim")
        run_indentsim(args.indentsim, args.case, n, args.increments, base / "grid", elastic,
                      ["--set", "mesh.error_estimate=off", "--set", "output.fields_every=1000"])
        p_ccx, ccx_wall, dofs = ccx_force(args.ccx, base / "grid", base / "ccx")
        rows.append(dict(nodes=n, dofs=dofs, force=force, ccx_force=p_ccx, off=statistics.median(off),
                         on=statistics.median(on), ccx=ccx_wall))
        print(f"N = {n}: done", file=sys.stderr, flush=True)

    # The reference: Richardson of indentsim on the two finest meshes and a finer one (the same
    # refinement ratio), with the order observed from the three.
    reference = None
    if len(rows) >= 2:
        n1, n2 = rows[-2]["nodes"], rows[-1]["nodes"]
        n3 = args.reference_nodes or 2 * n2
        run_indentsim(args.indentsim, args.case, n3, args.increments, work / f"N{n3}_reference", elastic,
                      ["--set", "mesh.error_estimate=off", "--set", "output.fields_every=0"])
        f1, f2, f3 = rows[-2]["force"], rows[-1]["force"], final_force(work / f"N{n3}_reference")[0]
        ratio = n2 / n1
        if (f1 - f2) * (f2 - f3) > 0 and abs(n3 / n2 - ratio) < 1e-9:
            order = math.log(abs(f1 - f2) / abs(f2 - f3)) / math.log(ratio)
            reference = f3 + (f3 - f2) / (ratio ** order - 1.0)
            print(f"reference P = {reference:.8e} {unit} (Richardson of indentsim at N = {n1}, {n2}, {n3}; "
                  f"observed order {order:.2f})")
        else:
            print(f"no reference: P at N = {n1}, {n2}, {n3} is not monotone or the meshes are not one ratio apart")
    print(f"{'N':>4} {'DOFs':>7} {f'P indentsim [{unit}]':>18} {f'P ccx [{unit}]':>15} {'rel.diff':>9} {'error':>8} "
          f"{'indentsim [s]':>13} {'+estimate [s]':>13} {'ccx [s]':>8} {'ratio':>6} {'ratio+est':>9}")
    for r in rows:
        error = f"{abs(r['force'] - reference) / reference * 100:.3f}%" if reference else "-"
        print(f"{r['nodes']:>4} {r['dofs']:>7} {r['force']:>18.9e} {r['ccx_force']:>15.7e} "
              f"{abs(r['ccx_force'] - r['force']) / r['force']:>9.1e} {error:>8} {r['off']:>13.3f} {r['on']:>13.3f} "
              f"{r['ccx']:>8.2f} {r['ccx'] / r['off']:>6.1f} {r['ccx'] / r['on']:>9.1f}")
    if args.plot and reference:
        plot(rows, reference, args.plot, f"{args.case.stem}, elastic, {args.increments} increments")
    (work / "compare_calculix.json").write_text(json.dumps(dict(case=str(args.case), rows=rows, reference=reference),
                                                           indent=1))
    if not args.keep:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
