#!/usr/bin/env python3
"""P-alpha curve of a run, and for elastic runs the P-a relation against Hertz line contact.

    python3 plots/plot_curve.py OUTDIR [--radius R --E E --nu NU]

Reads OUTDIR/curve.csv and writes OUTDIR/curve.png and OUTDIR/curve.svg.  With the punch
radius and elastic constants given, a second panel compares P(a) with Hertz,
P = pi E* a^2 / (4 R), E* = E / (1 - nu^2).
"""
import argparse
import csv
import math
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read_curve(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        sys.exit(f"{path}: no rows")
    return {k: [float(r[k]) for r in rows] for k in ("alpha", "P", "a")}


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("outdir", type=pathlib.Path)
    parser.add_argument("--radius", type=float, help="punch radius R [m] (enables the Hertz panel)")
    parser.add_argument("--E", type=float, default=210e9, help="Young's modulus [Pa]")
    parser.add_argument("--nu", type=float, default=0.3, help="Poisson's ratio")
    args = parser.parse_args()

    curve = read_curve(args.outdir / "curve.csv")
    panels = 2 if args.radius else 1
    fig, axes = plt.subplots(1, panels, figsize=(5.5 * panels, 4.2), squeeze=False)
    ax = axes[0][0]
    ax.plot([a * 1e6 for a in curve["alpha"]], [p / 1e3 for p in curve["P"]], "o-", ms=3)
    ax.set_xlabel("indentation depth α [µm]")
    ax.set_ylabel("punch force P [kN/m]")
    ax.set_title("P–α curve")
    ax.grid(alpha=0.3)

    if args.radius:
        e_star = args.E / (1 - args.nu**2)
        ax = axes[0][1]
        a_max = max(curve["a"])
        a_line = [a_max * k / 100 for k in range(101)]
        ax.plot([a * 1e6 for a in a_line], [math.pi * e_star * a * a / (4 * args.radius) / 1e3 for a in a_line],
                "-", label="Hertz line contact")
        ax.plot([a * 1e6 for a in curve["a"]], [p / 1e3 for p in curve["P"]], "o", ms=4, label="indentsim")
        ax.set_xlabel("contact half-width a [µm]")
        ax.set_ylabel("punch force P [kN/m]")
        ax.set_title("P–a against Hertz")
        ax.legend()
        ax.grid(alpha=0.3)

    fig.tight_layout()
    for suffix in ("png", "svg"):
        fig.savefig(args.outdir / f"curve.{suffix}", dpi=150)
    print(f"wrote {args.outdir / 'curve.png'} and {args.outdir / 'curve.svg'}")


if __name__ == "__main__":
    main()
