#!/usr/bin/python3
"""Random load cases: robustness and Newton effort of one or more builds (prints; not a test).

    /usr/bin/python3 benchmarks/random_cases.py [--seeds 1,2,3] [--cases 40] [--binary BIN ...]
        [--keep DIR] [--write-only DIR]

Draws load cases across everything the code models -- plane strain and axisymmetry; sphere
(cylinder), cone (wedge), blunted cone and flat punch; elastic, Ilyushin and J2 with linear and
power hardening; monotone loading, unloading to separation, and unload-reload -- with specimen
sizes from 0.1 to 10 mm, moduli from 3 to 400 GPa, Poisson's ratios up to 0.49 and 8 to 30
contact nodes, and runs each with every binary given (default: this build's CLI), without the
error estimate.  Prints, per binary, the runs that failed and the totals of Newton iterations,
factorizations and wall time, then every case whose Newton iterations differ by more than 5%
between the first binary and another.  The draws depend only on the seeds: the same seeds give
the same cases.  (The comparison behind the line-search-first ladder used seeds 1, 2, 3 with
30, 40, 40 cases; this script draws the same number per seed.)
"""

import argparse
import csv
import json
import pathlib
import random
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent


def draw_case(rng):
    """One load case as TOML text."""
    kind = rng.choice(["plane_strain", "axisymmetric"])
    shape = rng.choice(["sphere", "cone", "flat", "blunted"])
    E = rng.choice([70e9, 120e9, 210e9, 3e9, 400e9])
    nu = rng.choice([0.2, 0.3, 0.33, 0.45, 0.49])
    model = rng.choice(["elastic", "ilyushin", "j2", "j2"])
    size = rng.choice([1e-4, 1e-3, 1e-2])
    lx, ly = size * rng.uniform(0.8, 2.5), size * rng.uniform(0.5, 2)
    depth = size * rng.choice([0.002, 0.01, 0.03])
    if shape == "sphere":
        radius = size * rng.uniform(0.1, 0.6)
        depth = min(depth, 0.2 * radius)
        punch = [f'shape = "{"sphere" if kind == "axisymmetric" else "cylinder"}"', f"radius = {radius:.6g}"]
    elif shape == "cone":
        punch = ['shape = "cone"', f"half_angle = {rng.choice([60, 65.3, 70.3, 80])}"]
    elif shape == "blunted":
        punch = ['shape = "cone"', f"half_angle = {rng.choice([60, 70.3])}",
                 f"tip_radius = {depth * rng.uniform(0.5, 5):.6g}"]
    else:
        punch = ['shape = "flat"', f"radius = {size * rng.uniform(0.05, 0.2):.6g}"]
        depth = min(depth, 0.002 * size)
    material = [f'model = "{model}"', f"E = {E:.6g}", f"nu = {nu}"]
    yield_strain = rng.choice([0.001, 0.003, 0.01])
    if model != "elastic":
        law = rng.choice(["linear", "power"])
        material.append(f"e0 = {yield_strain:.6g}" if model == "ilyushin" else f"yield_stress = {yield_strain * E:.6g}")
        material.append(f'hardening = "{law}"')
        material.append(f"kappa = {rng.choice([0.5, 0.9, 0.99])}" if law == "linear" else f"n = {rng.choice([0.05, 0.1, 0.3])}")
    history = rng.choice(["monotone", "unload", "cycle"])
    if history == "monotone":
        path, increments = [0, depth], rng.choice([5, 10, 25])
    elif history == "unload":
        path, increments = [0, depth, 0], [rng.choice([10, 20]), rng.choice([5, 10])]
    else:
        path, increments = [0, depth, 0.3 * depth, 1.2 * depth], [10, 5, 10]
    contact_nodes = rng.choice([8, 15, 20, 30])
    rng.choice(["richardson", "off", "observed"])  # kept so that the draws stay those of the study
    path_text = json.dumps([float(f"{x:.6g}") for x in path])
    nl = "\n"
    return (f'[geometry]\nkind = "{kind}"\nlx = {lx:.6g}\nly = {ly:.6g}\n\n[punch]\n{nl.join(punch)}\n\n'
            f"[material]\n{nl.join(material)}\n\n[load]\npath = {path_text}\nincrements = {json.dumps(increments)}\n\n"
            f'[mesh]\ncontact_nodes = {contact_nodes}\nerror_estimate = "off"\n\n[output]\ndir = "out"\n')


def draw_cases(seeds, per_seed):
    """(name, TOML text) of every case the seeds ("1,2,3") draw, per_seed each (0: 30 for seed 1,
    else 40)."""
    for seed in (int(s) for s in seeds.split(",")):
        rng = random.Random(seed)
        for k in range(per_seed or (30 if seed == 1 else 40)):
            yield f"case_{seed}_{k:02d}", draw_case(rng)


def run(binary, case, out):
    """(Newton iterations, factorizations, wall seconds) of one run, or the error's last line."""
    start = time.monotonic()
    try:
        proc = subprocess.run([binary, "run", str(case), "--out", str(out), "-q"], capture_output=True, text=True,
                              timeout=600)
    except subprocess.TimeoutExpired:
        return "no result after 600 s"
    seconds = time.monotonic() - start
    if proc.returncode != 0:
        return (proc.stderr.strip().splitlines() or ["exit status %d" % proc.returncode])[-1]
    with open(out / "curve.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    return (sum(int(r["newton_iters"]) for r in rows), sum(int(r["factorizations"]) for r in rows), seconds)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", default="1,2,3")
    parser.add_argument("--cases", type=int, default=0, help="cases per seed (default: 30 for seed 1, else 40)")
    parser.add_argument("--binary", action="append", help="an indentsim CLI (repeat to compare builds)")
    parser.add_argument("--keep", help="write the cases and runs here instead of a temporary folder")
    parser.add_argument("--write-only", metavar="DIR",
                        help="only write the cases to DIR, Ilyushin's as J2 (for benchmarks/calculix/same_mesh.py, "
                             "which has no Ilyushin law in CalculiX), and run nothing")
    args = parser.parse_args()
    if args.write_only:
        folder = pathlib.Path(args.write_only)
        folder.mkdir(parents=True, exist_ok=True)
        for name, text in draw_cases(args.seeds, args.cases):
            (folder / f"{name}.toml").write_text(text.replace('model = "ilyushin"', 'model = "j2"'))
        return 0
    binaries = args.binary or [str(ROOT / "build" / "indentsim")]
    with tempfile.TemporaryDirectory() as tmp:
        folder = pathlib.Path(args.keep or tmp)
        folder.mkdir(parents=True, exist_ok=True)
        cases = []
        for name, text in draw_cases(args.seeds, args.cases):
            case = folder / f"{name}.toml"
            case.write_text(text)
            cases.append(case)
        results = {b: {} for b in binaries}
        for case in cases:  # builds in turns, so that both see the same machine
            for j, b in enumerate(binaries):
                results[b][case.stem] = run(b, case, folder / f"{case.stem}_run{j}")
        for b in binaries:
            ok = [r for r in results[b].values() if isinstance(r, tuple)]
            print(f"{b}: {len(ok)} of {len(cases)} runs converged; Newton iterations {sum(r[0] for r in ok)}, "
                  f"factorizations {sum(r[1] for r in ok)}, wall {sum(r[2] for r in ok):.1f} s")
            for name, r in results[b].items():
                if not isinstance(r, tuple):
                    print(f"  FAILED {name}: {r}")
        first = results[binaries[0]]
        for b in binaries[1:]:
            for name, r in results[b].items():
                f = first[name]
                if isinstance(r, tuple) and isinstance(f, tuple) and f[0] > 0 and abs(r[0] / f[0] - 1) > 0.05:
                    print(f"  {name}: Newton {f[0]} -> {r[0]}, factorizations {f[1]} -> {r[1]}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
