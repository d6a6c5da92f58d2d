#!/usr/bin/env python3
"""Figures of an indentsim run.

    python3 plots/plot_results.py OUTDIR [--zoom Z]

Reads OUTDIR/case.toml, curve.csv, profiles.csv and the last VTU of fields.pvd, and writes PNG and
SVG files into OUTDIR/figures/:
  curve          the P-alpha curve (elastic runs: also the P-a relation against Hertz line contact)
  pressure       the contact pressure from the layer forces against Hertz for the same force
  profiles       sigma_N and sigma_T along the surface and the chosen depths (the paper's Fig. 5):
                 lines from the local stiffness rows, markers from Gauss-point stresses
  plastic_zone   strain intensity e_u / e0 and the yielded region under the punch (the paper's Fig. 6)
Needs Debian's python3-matplotlib (installed by scripts/install-deps.sh).
"""
import argparse
import csv
import math
import pathlib
import sys
import tomllib
import xml.etree.ElementTree as ET

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.collections import PolyCollection  # noqa: E402


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def save(fig, outdir, name):
    fig.tight_layout()
    for suffix in ("png", "svg"):
        fig.savefig(outdir / f"{name}.{suffix}", dpi=150)
    plt.close(fig)
    print(f"wrote {outdir / name}.png")


def hertz_force(a, radius, e_star):
    return math.pi * e_star * a * a / (4 * radius)


def plot_curve(case, curve, outdir):
    elastic = case["material"]["model"] == "elastic"
    fig, axes = plt.subplots(1, 2 if elastic else 1, figsize=(11 if elastic else 5.5, 4.2), squeeze=False)
    ax = axes[0][0]
    ax.plot([float(r["alpha"]) * 1e6 for r in curve], [float(r["P"]) / 1e3 for r in curve], "o-", ms=3)
    ax.set_xlabel("indentation depth α [µm]")
    ax.set_ylabel("punch force P [kN/m]")
    ax.set_title(f"P–α curve ({case['material']['model']})")
    ax.grid(alpha=0.3)
    if elastic:
        e_star = case["material"]["E"] / (1 - case["material"]["nu"] ** 2)
        radius = case["punch"]["radius"]
        ax = axes[0][1]
        a_max = max(float(r["a"]) for r in curve)
        a_line = [a_max * k / 100 for k in range(101)]
        ax.plot([a * 1e6 for a in a_line], [hertz_force(a, radius, e_star) / 1e3 for a in a_line], "-",
                label="Hertz line contact")
        ax.plot([float(r["a"]) * 1e6 for r in curve], [float(r["P"]) / 1e3 for r in curve], "o", ms=4,
                label="indentsim")
        ax.set_xlabel("contact half-width a [µm]")
        ax.set_ylabel("punch force P [kN/m]")
        ax.set_title("P–a against Hertz")
        ax.legend()
        ax.grid(alpha=0.3)
    save(fig, outdir, "curve")


def plot_pressure(case, curve, profiles, outdir):
    top = max(int(r["line"]) for r in profiles)
    surface = [r for r in profiles if int(r["line"]) == top]
    force = float(curve[-1]["P"])
    a = float(curve[-1]["a"])
    e_star = case["material"]["E"] / (1 - case["material"]["nu"] ** 2)
    radius = case["punch"]["radius"]
    fig, ax = plt.subplots(figsize=(5.5, 4.2))
    xs = [float(r["x"]) for r in surface if float(r["x"]) <= 1.6 * max(a, 1e-300)]
    ps = [-float(r["sigmaN_layer"]) for r in surface if float(r["x"]) <= 1.6 * max(a, 1e-300)]
    ax.plot([x * 1e6 for x in xs], [p / 1e6 for p in ps], "o", ms=4, label="indentsim (layer forces)")
    if force > 0:
        a_h = math.sqrt(4 * force * radius / (math.pi * e_star))
        p0 = 2 * force / (math.pi * a_h)
        grid = [a_h * k / 200 for k in range(201)]
        ax.plot([x * 1e6 for x in grid], [p0 * math.sqrt(max(0.0, 1 - (x / a_h) ** 2)) / 1e6 for x in grid], "-",
                label="Hertz, same P")
    ax.set_xlabel("x [µm]")
    ax.set_ylabel("contact pressure p [MPa]")
    ax.set_title(f"Contact pressure at α = {float(curve[-1]['alpha']) * 1e6:.3g} µm")
    ax.legend()
    ax.grid(alpha=0.3)
    save(fig, outdir, "pressure")


def plot_profiles(curve, profiles, outdir):
    a = float(curve[-1]["a"])
    lines = sorted({int(r["line"]) for r in profiles}, reverse=True)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for line in lines:
        rows = [r for r in profiles if int(r["line"]) == line and float(r["x"]) <= 3 * max(a, 1e-300)]
        depth = -float(rows[0]["y"])
        label = "surface" if depth == 0 else f"depth {depth * 1e3:.3g} mm"
        x = [float(r["x"]) * 1e3 for r in rows]
        for ax, layer, nodal in ((axes[0], "sigmaN_layer", "sigma22_nodal"), (axes[1], "sigmaT_layer", "sigma12_nodal")):
            (drawn,) = ax.plot(x, [float(r[layer]) / 1e6 for r in rows], "-", label=f"{label}: layer forces")
            ax.plot(x, [float(r[nodal]) / 1e6 for r in rows], "o", ms=3, color=drawn.get_color(),
                    label=f"{label}: Gauss points")
    axes[0].set_ylabel("σ_N ≈ σ22 [MPa]")
    axes[1].set_ylabel("σ_T ≈ σ12 [MPa]")
    for ax, title in zip(axes, ("normal stress σ_N", "tangential stress σ_T")):
        ax.set_xlabel("x [mm]")
        ax.set_title(title)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    save(fig, outdir, "profiles")


def last_vtu(outdir):
    collection = ET.parse(outdir / "fields.pvd").getroot().find("Collection")
    files = [d.get("file") for d in collection.findall("DataSet")]
    if not files:
        sys.exit(f"{outdir}/fields.pvd lists no data sets")
    return outdir / files[-1]


def read_vtu(path):
    piece = ET.parse(path).getroot().find("UnstructuredGrid").find("Piece")

    def array(parent, name):
        for d in piece.find(parent).findall("DataArray"):
            if d.get("Name") == name:
                return [float(v) for v in d.text.split()]
        raise KeyError(name)

    points = array("Points", "coordinates")
    xy = [(points[3 * k], points[3 * k + 1]) for k in range(len(points) // 3)]
    connectivity = [int(v) for v in array("Cells", "connectivity")]
    quads = [connectivity[4 * e:4 * e + 4] for e in range(len(connectivity) // 4)]
    return xy, quads, array("CellData", "strain_intensity"), array("CellData", "plastic")


def plot_plastic_zone(case, curve, rundir, outdir):
    xy, quads, e_u, plastic = read_vtu(last_vtu(rundir))
    e0 = case["material"]["e0"]
    a = max(float(curve[-1]["a"]), 1e-300)
    window = 3 * a
    polys, values, yielded = [], [], []
    for quad, value, flag in zip(quads, e_u, plastic):
        corners = [xy[n] for n in quad]
        if min(c[0] for c in corners) > window or max(c[1] for c in corners) < -window:
            continue
        polys.append([(c[0] * 1e3, c[1] * 1e3) for c in corners])
        values.append(value / e0)
        yielded.append(flag)
    fig, ax = plt.subplots(figsize=(6.5, 5))
    cells = PolyCollection(polys, array=values, cmap="viridis", edgecolors="face", linewidths=0.2)
    ax.add_collection(cells)
    fig.colorbar(cells, ax=ax, label="strain intensity e_u / e0")
    outline = [p for p, f in zip(polys, yielded) if f > 0]
    if outline:
        ax.add_collection(PolyCollection(outline, facecolors="none", edgecolors="white", linewidths=0.3))
    radius = case["punch"]["radius"]
    alpha = float(curve[-1]["alpha"])
    xs = [window * k / 100 for k in range(101) if window * k / 100 < radius]
    ax.plot([x * 1e3 for x in xs], [(-alpha + radius - math.sqrt(radius**2 - x**2)) * 1e3 for x in xs], "r-",
            lw=1.2, label="punch")
    ax.set_xlim(0, window * 1e3)
    ax.set_ylim(-window * 1e3, 0.15 * window * 1e3)
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    count = int(sum(1 for f in plastic if f > 0))
    ax.set_title(f"Plastic zone (white outline: {count} yielded elements)")
    ax.legend(loc="lower right")
    save(fig, outdir, "plastic_zone")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("outdir", type=pathlib.Path)
    args = parser.parse_args()
    outdir = args.outdir
    with open(outdir / "case.toml", "rb") as f:
        case = tomllib.load(f)
    curve = read_csv(outdir / "curve.csv")
    profiles = read_csv(outdir / "profiles.csv")
    figures = outdir / "figures"
    figures.mkdir(exist_ok=True)
    plot_curve(case, curve, figures)
    plot_pressure(case, curve, profiles, figures)
    plot_profiles(curve, profiles, figures)
    plot_plastic_zone(case, curve, outdir, figures)


if __name__ == "__main__":
    main()
