#!/usr/bin/python3
"""indentsim against CalculiX 2.20 (Debian's calculix-ccx) on the same mesh: force and wall time.

    /usr/bin/python3 benchmarks/calculix/compare_calculix.py CASE.toml [--contact-nodes 10 20 40]
        [--increments 24] [--repeats 3] [--indentsim build/indentsim] [--ccx ccx] [--keep DIR]
        [--plot plots/calculix_work_precision.png]

For a plane-strain load case with an elastic material and a cylinder punch (the paper's geometry:
loadcases/paper.toml with --set material.model=elastic, which this script applies itself), and
each contact_nodes N:
  1. indentsim runs the case (the median of --repeats whole runs, process start to exit, with the
     error estimate off and on), then once more writing the fields of step 0, whose grid is
     indentsim's mesh;
  2. the CalculiX deck is built from the load case and that grid -- node for node the same mesh,
     so both codes have the same discretization error and "equal error" means "equal mesh";
  3. ccx solves it (one thread, like indentsim) and its force is read from the .dat file.
Prints P of both (N/m, both halves), their relative difference, the wall times and their ratio,
and the error of P against the Richardson extrapolation of indentsim alone on the two finest meshes
and one twice as fine (--reference-nodes, default twice the largest N), with their observed order.

The deck (ccx 2.20):
  * CPE4 (bilinear, full 2x2 integration -- indentsim's Q1), *SOLID SECTION thickness 1 m;
  * the base fixed, the axis x = 0 held in x (symmetry), the far side free (MODEL.md);
  * contact: one GAPUNI element from each top-surface node with x <= 2 a* to one rigid punch
    node, direction (0, 1, 0), clearance g(x) = R - sqrt(R^2 - x^2): ccx's gap condition is then
    exactly indentsim's vertical-gap Signorini condition u_y <= -alpha + g(x);
  * the punch node is driven to u_y = -alpha in a *STATIC step of fixed increments 1/increments.
CalculiX pitfalls met on the way:
  * numbers on data lines are read in 20-character fields: 13 significant digits fit;
  * GAPUNI elements alone do not make a *STATIC step nonlinear: ccx solves once, linearly, and
    the contact is wrong.  A *PLASTIC material that no element uses switches on its Newton
    iterations (small strains, no NLGEOM);
  * the clearance belongs to the *GAP card, so every gap element gets its own element set;
  * the default gap stiffness 1e12 is far too soft here (1e-7 m of penetration against
    alpha = 5e-5 m); 1e17 leaves P unchanged to the 7 digits the .dat file prints;
  * the .dat file prints 7 significant digits, so ccx's P is known to about 2.5e-7.
"""

import argparse
import base64
import json
import math
import os
import pathlib
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import tomllib
import xml.etree.ElementTree as ET

import numpy as np

ELASTIC = ["--set", "material.model=elastic"]


def fail(message):
    sys.exit(f"compare_calculix: {message}")


def read_case(path, increments):
    with open(path, "rb") as f:
        case = tomllib.load(f)
    geometry, punch, material, load = (case.get(k, {}) for k in ("geometry", "punch", "material", "load"))
    if geometry.get("kind", "plane_strain") != "plane_strain":
        fail(f"{path}: geometry.kind: only plane strain is built here (an axisymmetric deck needs CAX4 "
             "elements and ring gaps; not done)")
    if punch.get("shape", "sphere") != "sphere" or "radius" not in punch:
        fail(f"{path}: punch: only a cylinder (shape = \"sphere\" with a radius) is built here")
    waypoints = load.get("path", [])
    if len(waypoints) != 2 or waypoints[0] != 0.0:
        fail(f"{path}: load.path: only a monotone path [0, alpha] is built here")
    return dict(lx=geometry["lx"], ly=geometry["ly"], radius=punch["radius"], E=material["E"],
                nu=material["nu"], alpha=waypoints[1], increments=increments)


def gap(x, radius):
    """g(x) = R - sqrt(R^2 - x^2), written without cancellation."""
    return x * x / (radius + math.sqrt((radius - x) * (radius + x)))


def run_indentsim(exe, case, nodes, increments, out, extra=()):
    args = [str(exe), "run", str(case), "--out", str(out), "-q", *ELASTIC,
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


def grid_of(run_dir):
    """The x and y node coordinates of indentsim's structured mesh, from fields/step_000000.vtu."""
    piece = ET.parse(run_dir / "fields" / "step_000000.vtu").getroot().find("UnstructuredGrid").find("Piece")
    array = next(d for d in piece.find("Points").findall("DataArray") if d.get("Name") == "coordinates")
    raw = base64.b64decode("".join(array.text.split()))
    size = int.from_bytes(raw[:8], "little")
    points = np.frombuffer(raw[8:8 + size], dtype="<f8").reshape(-1, 3)
    return np.unique(points[:, 0]), np.unique(points[:, 1])


def write_deck(path, scene, xs, ys, contact_half_width, gap_stiffness=1e17):
    nx, ny = len(xs), len(ys)
    node = lambda i, j: j * nx + i + 1  # j = 0 the base, j = ny - 1 the loaded surface
    punch = nx * ny + 1
    lines = ["*HEADING", f"indentsim load case, elastic, {nx} x {ny} nodes", "*NODE, NSET=NALL"]
    w = lines.append
    for j in range(ny):
        for i in range(nx):
            w(f"{node(i, j)}, {xs[i]:.12e}, {ys[j]:.12e}, 0.0")
    w("*NODE, NSET=PUNCH")
    w(f"{punch}, 0.0, {scene['radius']:.12e}, 0.0")
    w("*ELEMENT, TYPE=CPE4, ELSET=EBLOCK")
    e = 0
    for j in range(ny - 1):
        for i in range(nx - 1):
            e += 1
            w(f"{e}, {node(i, j)}, {node(i + 1, j)}, {node(i + 1, j + 1)}, {node(i, j + 1)}")
    reach = min(2.0 * contact_half_width, 0.9 * scene["radius"])
    candidates = [i for i in range(nx) if xs[i] <= reach]
    for i in candidates:
        e += 1
        w(f"*ELEMENT, TYPE=GAPUNI, ELSET=G{i}")
        w(f"{e}, {node(i, ny - 1)}, {punch}")
    w("*NSET, NSET=BASE")
    lines.extend(f"{node(i, 0)}," for i in range(nx))
    w("*NSET, NSET=AXIS")
    lines.extend(f"{node(0, j)}," for j in range(1, ny))
    w("*MATERIAL, NAME=SPECIMEN")
    w("*ELASTIC")
    w(f"{scene['E']:.6e}, {scene['nu']}")
    w("*SOLID SECTION, ELSET=EBLOCK, MATERIAL=SPECIMEN")
    w("1.0")
    # Unused, but it makes ccx iterate (see the pitfalls above).
    w("*MATERIAL, NAME=NONLINEAR_TRIGGER")
    w("*ELASTIC")
    w("1.0, 0.0")
    w("*PLASTIC")
    w("1.0e30, 0.0")
    for i in candidates:  # clearance, direction, (unused), stiffness
        w(f"*GAP, ELSET=G{i}")
        w(f"{gap(xs[i], scene['radius']):.12e}, 0., 1., 0., , {gap_stiffness:.6e}")
    w("*BOUNDARY")
    w("BASE, 1, 2, 0.0")
    w("AXIS, 1, 1, 0.0")
    w(f"{punch}, 1, 1, 0.0")
    w(f"{punch}, 3, 3, 0.0")
    w("*STEP, INC=100000")
    w("*STATIC, DIRECT")
    w(f"{1.0 / scene['increments']:.17g}, 1.0")
    w("*BOUNDARY")
    w(f"{punch}, 2, 2, {-scene['alpha']:.12e}")
    w("*NODE PRINT, NSET=PUNCH, TOTALS=ONLY")
    w("RF")
    w("*END STEP")
    path.write_text("\n".join(lines) + "\n")
    return 2 * (nx * ny - nx) - (ny - 1)  # free DOFs: base fixed, axis held in x


def run_ccx(ccx, workdir, job):
    env = dict(os.environ, OMP_NUM_THREADS="1", CCX_NPROC_STIFFNESS="1", CCX_NPROC_EQUATION_SOLVER="1",
               CCX_NPROC_RESULTS="1")
    start = time.perf_counter()
    proc = subprocess.run([ccx, "-i", job], cwd=workdir, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - start
    if proc.returncode != 0 or "*ERROR" in proc.stdout:
        fail(f"ccx failed (rc {proc.returncode}); deck in {workdir}\n{proc.stdout[-2000:]}")
    text = (workdir / f"{job}.dat").read_text()
    totals = re.findall(r"total force \(fx,fy,fz\) for set PUNCH and time\s+(\S+)\s*\n\s*\n?\s*(\S+)\s+(\S+)", text)
    if not totals or abs(float(totals[-1][0]) - 1.0) > 1e-6:
        fail(f"ccx did not reach the end of its step; see {workdir}")
    return -2.0 * float(totals[-1][2]), wall  # both halves, compression positive


def plot(rows, reference, path):
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
    ax.set_title("Elastic paper geometry, 24 increments:\nthe same meshes, the same P", fontsize=10)
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
    scene = read_case(args.case, args.increments)
    work = args.keep or pathlib.Path(tempfile.mkdtemp(prefix="compare_calculix_"))
    work.mkdir(parents=True, exist_ok=True)

    rows = []
    for n in args.contact_nodes:
        base = work / f"N{n}"
        off = [run_indentsim(args.indentsim, args.case, n, args.increments, base / "indentsim",
                             ["--set", "mesh.error_estimate=off"]) for _ in range(args.repeats)]
        on = [run_indentsim(args.indentsim, args.case, n, args.increments, base / "indentsim_estimate")
              for _ in range(args.repeats)]
        force, half_width = final_force(base / "indentsim")
        run_indentsim(args.indentsim, args.case, n, args.increments, base / "grid",
                      ["--set", "mesh.error_estimate=off", "--set", "output.fields_every=1000"])
        xs, ys = grid_of(base / "grid")
        deck_dir = base / "ccx"
        deck_dir.mkdir(parents=True, exist_ok=True)
        dofs = write_deck(deck_dir / "case.inp", scene, xs, ys, half_width)
        ccx_force, ccx_wall = run_ccx(args.ccx, deck_dir, "case")
        rows.append(dict(nodes=n, dofs=dofs, force=force, ccx_force=ccx_force, off=statistics.median(off),
                         on=statistics.median(on), ccx=ccx_wall))
        print(f"N = {n}: done", file=sys.stderr, flush=True)

    # The reference: Richardson of indentsim on the two finest meshes and a finer one (the same
    # refinement ratio), with the order observed from the three.
    reference = None
    if len(rows) >= 2:
        n1, n2 = rows[-2]["nodes"], rows[-1]["nodes"]
        n3 = args.reference_nodes or 2 * n2
        run_indentsim(args.indentsim, args.case, n3, args.increments, work / f"N{n3}_reference",
                      ["--set", "mesh.error_estimate=off", "--set", "output.fields_every=0"])
        f1, f2, f3 = rows[-2]["force"], rows[-1]["force"], final_force(work / f"N{n3}_reference")[0]
        ratio = n2 / n1
        if (f1 - f2) * (f2 - f3) > 0 and abs(n3 / n2 - ratio) < 1e-9:
            order = math.log(abs(f1 - f2) / abs(f2 - f3)) / math.log(ratio)
            reference = f3 + (f3 - f2) / (ratio ** order - 1.0)
            print(f"reference P = {reference:.8e} N/m (Richardson of indentsim at N = {n1}, {n2}, {n3}; "
                  f"observed order {order:.2f})")
        else:
            print(f"no reference: P at N = {n1}, {n2}, {n3} is not monotone or the meshes are not one ratio apart")
    print(f"{'N':>4} {'DOFs':>7} {'P indentsim [N/m]':>18} {'P ccx [N/m]':>15} {'rel.diff':>9} {'error':>8} "
          f"{'indentsim [s]':>13} {'+estimate [s]':>13} {'ccx [s]':>8} {'ratio':>6} {'ratio+est':>9}")
    for r in rows:
        error = f"{abs(r['force'] - reference) / reference * 100:.3f}%" if reference else "-"
        print(f"{r['nodes']:>4} {r['dofs']:>7} {r['force']:>18.9e} {r['ccx_force']:>15.7e} "
              f"{abs(r['ccx_force'] - r['force']) / r['force']:>9.1e} {error:>8} {r['off']:>13.3f} {r['on']:>13.3f} "
              f"{r['ccx']:>8.2f} {r['ccx'] / r['off']:>6.1f} {r['ccx'] / r['on']:>9.1f}")
    if args.plot and reference:
        plot(rows, reference, args.plot)
    (work / "compare_calculix.json").write_text(json.dumps(dict(case=str(args.case), rows=rows, reference=reference),
                                                           indent=1))
    if not args.keep:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
