#!/usr/bin/env python3
"""What finite strain changes in P, scene by scene: the measurements behind geometry.strain = "auto"
(prints; not a test).

    /usr/bin/python3 benchmarks/strain_share.py [--elastic-stress cauchy,kirchhoff] [--binary BIN]

Runs each scene of docs/MODEL.md section 12.5 (shipped cases, the error estimate off) in small and
in finite strain, the latter with each elastic stress given (material.elastic_stress: the Cauchy or
the Kirchhoff stress = D : e), and prints P finite / P small - 1 at the deepest point and that share
per unit alpha / a, the mean strain under the punch (a/R = sqrt(alpha/R) for an elastic sphere,
(pi/2) cot(70.3 deg) = 0.56 for the elastic cone, 0.01 for the flat punch at alpha = 0.5 um, and the
runs' own contact radius for the plastic scenes).  "auto" estimates the share as 0.25 alpha/a
elastic and 0.06 alpha/a plastic: each must stay above what this prints.
"""
import argparse
import csv
import pathlib
import subprocess
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent
CASES = ROOT / "loadcases" / "axisymmetric"

# name, case, overrides, alpha / a (None: the run's own contact radius at the deepest point)
SCENES = [
    ("elastic sphere, alpha/R = 1e-4", "elastic_sphere.toml",
     ["mesh.contact_nodes=12", "load.path=[0.0, 1e-7]", "load.increments=4"], 0.01),
    ("elastic sphere, alpha/R = 1e-3", "elastic_sphere.toml",
     ["mesh.contact_nodes=12", "load.path=[0.0, 1e-6]", "load.increments=4"], 1e-3 ** 0.5),
    ("elastic sphere, alpha/R = 1e-2", "elastic_sphere.toml",
     ["mesh.contact_nodes=12", "load.path=[0.0, 1e-5]", "load.increments=4"], 0.1),
    ("elastic Berkovich cone, 1 um", "berkovich_cone.toml",
     ['material.model="elastic"', "load.path=[0.0, 1e-6]", "load.increments=8"], 0.56),
    ("elastic flat punch, alpha/a = 0.01", "flat_punch.toml", [], 0.01),
    ("J2 steel sphere, 10 um", "steel_sphere.toml", ["load.path=[0.0, 1e-5]", "load.increments=20"], None),
    ("J2 Berkovich cone, 1 um", "berkovich_cone.toml", ["load.path=[0.0, 1e-6]", "load.increments=20"], None),
]


def deepest(binary, case, overrides, out):
    """P and the contact radius at the deepest point of a run, or None with the error."""
    command = [binary, "run", str(CASES / case), "--quiet", "--out", str(out)]
    for o in overrides + ['mesh.error_estimate="off"']:
        command += ["--set", o]
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        return None, result.stderr.strip().splitlines()[-1:]
    with open(out / "curve.csv") as f:
        rows = list(csv.DictReader(f))
    row = max(rows, key=lambda r: float(r["alpha"]))
    return (float(row["P"]), float(row["alpha"]), float(row["a"])), None


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--elastic-stress", default="cauchy,kirchhoff")
    parser.add_argument("--binary", default=str(ROOT / "build" / "indentsim"))
    args = parser.parse_args()
    measures = args.elastic_stress.split(",")
    print(f"{'scene':38s} {'alpha/a':>8s}" + "".join(f"  {m + ': share':>18s} {'per alpha/a':>11s}" for m in measures))
    with tempfile.TemporaryDirectory() as folder:
        for k, (name, case, overrides, alpha_over_a) in enumerate(SCENES):
            small, error = deepest(args.binary, case, overrides + ['geometry.strain="small"'],
                                   pathlib.Path(folder) / f"{k}_small")
            if small is None:
                print(f"{name:38s} small strain failed: {error}")
                continue
            ratio = alpha_over_a if alpha_over_a is not None else small[1] / small[2]
            line = f"{name:38s} {ratio:8.3f}"
            for m in measures:
                finite, error = deepest(args.binary, case,
                                        overrides + ['geometry.strain="finite"', f'material.elastic_stress="{m}"'],
                                        pathlib.Path(folder) / f"{k}_{m}")
                if finite is None:
                    line += f"  {'failed':>18s} {'':>11s}"
                    continue
                share = finite[0] / small[0] - 1.0
                line += f"  {share:18.3e} {abs(share) / ratio:11.3f}"
            print(line, flush=True)


if __name__ == "__main__":
    main()
