#!/usr/bin/python3
"""indentsim against CalculiX 2.20 on the same mesh, increment by increment: an independent check.

    /usr/bin/python3 benchmarks/calculix/same_mesh.py CASE.toml [CASE.toml ...] [--set key=value ...]
        [--contact-nodes N] [--indentsim build/indentsim] [--ccx ccx] [--keep DIR] [--verbose]

For each load case: indentsim runs it with the full-integration element (mesh.element = "q1"; ccx
has no B-bar for CPE4/CAX4), the error estimate off and the fields of every increment written; the
CalculiX deck is built from that run folder (calculix_deck.py: the same nodes, the same punch
profile written out again from MODEL.md, the same material, the same increments) and ccx runs it,
one thread, with the contact imposed in one of three ways (--contact):
  * replay (default, every scene): indentsim's displacements prescribed at every node, increment by
    increment.  ccx updates its own J2 stresses along that strain path and prints its element
    forces: at indentsim's unknowns they must vanish (the residual), at the contact nodes they are
    the reactions, whose sum is ccx's P and whose signs, with indentsim's surface, must satisfy the
    Signorini conditions;
  * given: indentsim's contact set prescribed to the punch, ccx solves the rest itself (on the
    elastic scenes; on plastic ones ccx's Newton iterations stall or cycle);
  * gap: ccx finds the contact itself with gap elements (elastic scenes).
Both codes solve one discrete problem, so their P must agree at every increment to the solvers'
tolerances and ccx's 7 printed digits, plus what the deck itself changes (ccx's axisymmetric wedge,
a tabulated power law: calculix_deck.expected_difference).  Prints, per case, the largest
difference of P over the path relative to the peak P, the difference at the peak and at the end,
the residual, the Signorini conditions in ccx's forces and both wall times (a replay has no
equilibrium iterations in ccx, so its time is no speed comparison; compare_calculix.py makes one);
with --verbose every increment.  Exit status 1 if a case was not compared, differs by more than allowed or breaks
the Signorini conditions.
"""

import argparse
import pathlib
import shutil
import subprocess
import sys
import tempfile
import time

from calculix_deck import (DeckError, check_signorini, expected_difference, forces_of, length_unit, read_run,
                           region_materials, replay_residual, run_ccx, write_deck)


def run_indentsim(exe, case, out, overrides):
    args = [str(exe), "run", str(case), "--out", str(out), "-q", "--set", "mesh.element=q1",
            "--set", "mesh.error_estimate=off", "--set", "output.fields_every=1"]
    for item in overrides:
        args += ["--set", item]
    start = time.perf_counter()
    proc = subprocess.run(args, capture_output=True, text=True)
    wall = time.perf_counter() - start
    if proc.returncode != 0:
        raise DeckError(f"indentsim failed: {' '.join(args)}\n{proc.stderr}")
    return wall


def compare(case, args, work):
    overrides = list(args.set)
    if args.contact_nodes:
        overrides.append(f"mesh.contact_nodes={args.contact_nodes}")
    run_dir = work / "indentsim"
    wall = run_indentsim(args.indentsim, case, run_dir, overrides)
    scene = read_run(run_dir)
    deck_dir = work / "ccx"
    deck_dir.mkdir(parents=True, exist_ok=True)
    dofs = write_deck(deck_dir / "case.inp", scene, args.contact)
    result, ccx_wall = run_ccx(args.ccx, deck_dir, "case", length_unit(scene))
    forces = scene["forces"]
    ccx_forces = [None] + forces_of(scene, result, args.contact)
    if len(ccx_forces) != len(forces):
        raise DeckError(f"ccx printed {len(ccx_forces) - 1} increments of {len(forces) - 1}; see {deck_dir}")
    peak = max(forces)
    k_peak = forces.index(peak)
    differences = [(ccx_forces[k] - forces[k]) / peak for k in range(1, len(forces))]
    pull = penetration = residual = float("nan")
    steps = range(1, len(forces))
    top = (len(scene["ys"]) - 1) * len(scene["xs"])
    if args.contact == "replay":
        surface = [(scene["displacements"][k][top:], result["RF_all"][k - 1][top:]) for k in steps]
        balance = [replay_residual(scene, k, result["RF_all"][k - 1]) for k in steps]
        residual = max(b[0] for b in balance) / max(b[1] for b in balance)
    elif args.contact == "given":
        surface = [(result["U"][k - 1], result["RF"][k - 1]) for k in steps]
    if args.contact != "gap":
        checks = [check_signorini(scene, k, *surface[k - 1]) for k in steps]
        pull = max(c[0] for c in checks) / max(c[1] for c in checks)
        penetration = max(c[2] for c in checks) / max(scene["alphas"])
    if args.verbose:
        print(f"  {'k':>4} {'alpha [m]':>12} {'contact':>7} {'P indentsim':>16} {'P ccx':>14} {'diff / P_peak':>13}")
        for k in range(1, len(forces)):
            nodes = len(scene["contact_sets"][k]) if scene["contact_sets"] else "-"
            print(f"  {k:>4} {scene['alphas'][k]:>12.5e} {nodes:>7} {forces[k]:>16.9e} {ccx_forces[k]:>14.7e} "
                  f"{differences[k - 1]:>13.2e}")
    # The models from the surface down: "j2 on elastic" a J2 film on an elastic substrate.
    materials = region_materials(scene["case"])
    models = " on ".join(material["model"] for _, material in materials[1:] + materials[:1])
    return dict(case=str(case), kind=scene["kind"], shape=scene["case"]["punch"]["shape"],
                model=models, dofs=dofs, increments=len(forces) - 1,
                peak=peak, largest=max(abs(d) for d in differences),
                at_peak=(ccx_forces[k_peak] - peak) / peak, at_end=differences[-1], pull=pull,
                penetration=penetration, residual=residual, allowed=expected_difference(scene), wall=wall,
                ccx_wall=ccx_wall)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("cases", type=pathlib.Path, nargs="+")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="override a load-case key in every case (as indentsim run --set)")
    ap.add_argument("--contact-nodes", type=int)
    ap.add_argument("--contact", choices=("replay", "given", "gap"), default="replay",
                    help="replay: indentsim's displacements prescribed at every node, ccx's element forces "
                         "checked (every scene); given: indentsim's contact set prescribed, ccx solves; gap: ccx "
                         "finds the contact with gap elements (elastic scenes)")
    ap.add_argument("--indentsim", type=pathlib.Path, default=pathlib.Path("build/indentsim"))
    ap.add_argument("--ccx", default="ccx")
    ap.add_argument("--keep", type=pathlib.Path, help="keep the runs, decks and ccx's output here")
    ap.add_argument("--verbose", action="store_true", help="print every increment")
    args = ap.parse_args()
    if shutil.which(args.ccx) is None:
        sys.exit(f"same_mesh: {args.ccx} not found: apt-get install calculix-ccx")
    root = args.keep or pathlib.Path(tempfile.mkdtemp(prefix="same_mesh_"))
    rows, failed = [], False
    for i, case in enumerate(args.cases):
        print(f"{case}:", flush=True)
        try:
            rows.append(compare(case, args, root / f"{i:02d}_{case.stem}"))
        except DeckError as error:
            print(f"  not compared: {error}")
            failed = True
    print(f"\n{'case':<44} {'scene':<40} {'DOFs':>6} {'incr':>4} {'peak P':>10} {'largest':>8} {'at peak':>8} "
          f"{'at end':>8} {'residual':>8} {'allowed':>17} {'pull':>7} {'penetr.':>7} {'indentsim':>9} {'ccx':>7}")
    for r in rows:
        scene = f"{r['kind']}, {r['shape']}, {r['model']}"
        print(f"{r['case']:<44} {scene:<40} {r['dofs']:>6} {r['increments']:>4} {r['peak']:>10.4e} "
              f"{r['largest']:>8.1e} {r['at_peak']:>8.1e} {r['at_end']:>8.1e} {r['residual']:>8.1e} "
              f"{r['allowed'][0]:>8.1e} {r['allowed'][1]:>8.1e} {r['pull']:>7.0e} "
              f"{r['penetration']:>7.0e} "
              f"{r['wall']:>8.2f}s {r['ccx_wall']:>6.1f}s")
        failed |= not (r["largest"] <= r["allowed"][0]) or r["residual"] > r["allowed"][1]
        failed |= r["pull"] > 1e-6 or r["penetration"] > 1e-6
    print("P: N/m of both halves in plane strain, N in axisymmetry.  largest, at peak, at end: ccx's P minus\n"
          "indentsim's, relative to the peak P.  residual (replay): ccx's element forces at indentsim's unknowns\n"
          "relative to the largest contact reaction.  allowed: the difference in P and the residual the deck\n"
          "itself brings (calculix_deck.expected_difference).  pull: the largest tensile reaction of a contact\n"
          "node relative to the largest push; penetr.: the deepest free node through the punch relative to the\n"
          "peak depth (0 where the Signorini conditions hold).")
    if not args.keep:
        shutil.rmtree(root, ignore_errors=True)
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
