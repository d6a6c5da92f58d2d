#!/usr/bin/python3
"""The elastic cone's S / (2 E* a) in small and finite strain, against Hay, Bolshakov and Pharr's
gamma (prints; not a test).

    /usr/bin/python3 benchmarks/cone_gamma.py [--nu 0.25,0.3,0.4] [--nodes 15,30,60]
        [--binary BIN] [--strain small,finite]

Runs the shipped Berkovich-equivalent cone (70.3 deg) on an elastic specimen to 1 um, 8
increments, without the error estimate, for every Poisson's ratio, contact-node count and
kinematics given, and prints S / (2 E* a) with E* = E / (1 - nu^2) and a the contact radius the run
reports (the current configuration's in finite strain).  S is taken as 2 P / h: an elastic cone is
self-similar (no length in the cone or the law), so P ~ h^2 and dP/dh = 2 P / h exactly, without
the noise of a one-step unloading slope whose contact set changes at the peak.  Beside it,
gamma(nu, psi) of Hay, Bolshakov and Pharr (J. Mater. Res. 14, 2296, 1999, their eq. for a rigid
cone): the small-strain bulk with Sneddon's boundary conditions gives 1 (Sneddon); their gamma
corrects for the radial displacement of the surface.
"""

import argparse
import csv
import math
import pathlib
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent
CASE = ROOT / "loadcases" / "axisymmetric" / "berkovich_cone.toml"
E = 70e9  # the shipped case's modulus
HALF_ANGLE = 70.3


def hay_bolshakov_pharr_gamma(nu, half_angle=HALF_ANGLE):
    cot = 1.0 / math.tan(math.radians(half_angle))
    k = (1.0 - 2.0 * nu) / (4.0 * (1.0 - nu))
    return math.pi * (math.pi / 4 + 0.1548 * cot * k) / (math.pi / 2 - 0.8312 * cot * k) ** 2


def stiffness_ratio(binary, nu, nodes, strain, folder):
    out = pathlib.Path(folder) / f"{strain}_{nu}_{nodes}"
    overrides = {
        "material.model": '"elastic"',
        "material.nu": str(nu),
        "mesh.contact_nodes": str(nodes),
        "mesh.error_estimate": '"off"',
        "load.path": "[0.0, 1e-6]",
        "load.increments": "[8]",
        "geometry.strain": f'"{strain}"',
    }
    command = [binary, "run", str(CASE), "--quiet", "--out", str(out)]
    for key, value in overrides.items():
        command += ["--set", f"{key}={value}"]
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        return None, result.stderr.strip().splitlines()[-1:]
    with open(out / "curve.csv") as f:
        last = list(csv.DictReader(f))[-1]
    P, h, a = float(last["P"]), float(last["alpha"]), float(last["a"])
    return P / (h * E / (1.0 - nu * nu) * a), None


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--nu", default="0.25,0.3,0.4")
    parser.add_argument("--nodes", default="15,30,60")
    parser.add_argument("--strain", default="small,finite")
    parser.add_argument("--binary", default=str(ROOT / "build" / "indentsim"))
    args = parser.parse_args()
    nus = [float(v) for v in args.nu.split(",")]
    nodes = [int(v) for v in args.nodes.split(",")]
    strains = args.strain.split(",")
    print("nu     strain   " + "  ".join(f"{n:>7d}" for n in nodes) + "   HBP gamma")
    with tempfile.TemporaryDirectory() as folder:
        for nu in nus:
            for strain in strains:
                cells = []
                for n in nodes:
                    ratio, error = stiffness_ratio(args.binary, nu, n, strain, folder)
                    cells.append(f"{ratio:7.4f}" if ratio is not None else "  fail ")
                    if error:
                        print(f"  nu = {nu}, {n} nodes, {strain}: {error}", file=sys.stderr)
                print(f"{nu:<6} {strain:<8} " + "  ".join(cells) + f"   {hay_bolshakov_pharr_gamma(nu):.4f}")


if __name__ == "__main__":
    main()
