#!/usr/bin/env python3
"""Figures of an indentsim run.

    indentsim plot OUTDIR [--step N]          (or: python3 plots/plot_results.py OUTDIR [--step N])

Reads OUTDIR/case.toml, curve.csv, summary.json, profiles.csv and the VTU of one increment from
fields.pvd -- by default the deepest state of the load path, which indentsim always writes (a
history that ends unloaded has nothing to show at its end) -- and writes PNG and SVG files into
OUTDIR/figures/:
  curve          the P-alpha curve (P in kN/m in plane strain, in N in axisymmetry), loading and
                 unloading branches in their own colours, the peak, the unloading stiffness S as a
                 tangent and the residual depth h_f marked (elastic runs: also the P-a relation
                 against Hertz line contact, Hertz for a sphere, Sneddon for a cone)
  pressure       the contact pressure from the layer forces against that theory for the same force
  profiles       sigma_N and sigma_T along the surface and the chosen depths (the paper's Fig. 5):
                 lines from the local stiffness rows, markers from Gauss-point stresses
  plastic_zone   strain intensity e_u / e0 on the deformed mesh, the outline of the yielded region
                 and the punch where it stands (the paper's Fig. 6); the window follows the zone
and, when `indentsim analyze OUTDIR` has written OUTDIR/analysis.json, analysis.png beside it.

    indentsim analyze CURVE --plot            (or: python3 plots/plot_results.py --analysis FILE.json)

draws an analysis.json: each unloading branch with its power-law fit, S as the tangent at h_max,
h_f, h_c and h_max marked, and a table of the Oliver-Pharr numbers (with the true contact's for a
run): FILE.png and FILE.svg beside it.
Needs Debian's python3-matplotlib (installed by scripts/install-deps.sh).
"""
import argparse
import base64
import csv
import json
import math
import pathlib
import sys
import tomllib
import xml.etree.ElementTree as ET

import matplotlib
import numpy as np

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


class Scene:
    """What the figures need of the scene: the unit of P and the theory of the punch's shape.

    Plane strain: P per unit thickness [kN/m], Hertz line contact for the cylinder.  Axisymmetry:
    P in newtons, Hertz for the sphere, Sneddon for the cone and the flat punch.  Other shapes
    have no closed form: their figures show indentsim alone."""

    def __init__(self, case):
        self.axisymmetric = case["geometry"].get("kind", "plane_strain") == "axisymmetric"
        self.punch = case["punch"]
        self.shape = self.punch.get("shape", "sphere")
        self.e_star = case["material"]["E"] / (1 - case["material"]["nu"] ** 2)
        self.force_scale, self.force_unit = (1.0, "N") if self.axisymmetric else (1e3, "kN/m")
        self.stiffness_unit = "N/m" if self.axisymmetric else "N/m per m"
        self.width_name = "contact radius a" if self.axisymmetric else "contact half-width a"
        cot = 1 / math.tan(math.radians(self.punch.get("half_angle", 45.0)))
        sharp_cone = self.shape == "cone" and self.punch.get("tip_radius", 0.0) == 0.0
        r = self.punch.get("radius", 0.0)
        # (name, P(a), a(P), p(x; a, P)) of the theory for this scene, or None.
        if self.shape == "sphere" and not self.axisymmetric:
            self.theory = ("Hertz line contact", lambda a: math.pi * self.e_star * a * a / (4 * r),
                           lambda p: math.sqrt(4 * p * r / (math.pi * self.e_star)),
                           lambda x, a, p: 2 * p / (math.pi * a) * math.sqrt(max(0.0, 1 - (x / a) ** 2)))
        elif self.shape == "sphere":
            self.theory = ("Hertz", lambda a: 4 * self.e_star * a**3 / (3 * r),
                           lambda p: (3 * p * r / (4 * self.e_star)) ** (1 / 3),
                           lambda x, a, p: 3 * p / (2 * math.pi * a * a) * math.sqrt(max(0.0, 1 - (x / a) ** 2)))
        elif sharp_cone and self.axisymmetric:
            self.theory = ("Sneddon", lambda a: math.pi * a * a * self.e_star * cot / 2,
                           lambda p: math.sqrt(2 * p / (math.pi * self.e_star * cot)),
                           lambda x, a, p: self.e_star * cot / 2 * math.acosh(a / x) if 0 < x < a else 0.0)
        else:
            self.theory = None

    def force(self, value):
        return float(value) / self.force_scale

    def punch_height(self, x):
        """g(x) of the punch, or None beyond its rim."""
        if self.shape == "sphere":
            r = self.punch["radius"]
            return r - math.sqrt(r * r - x * x) if x < r else None
        if self.shape == "flat":
            return 0.0 if x <= self.punch["radius"] else None
        if self.shape == "cone":
            theta, tip = math.radians(self.punch["half_angle"]), self.punch.get("tip_radius", 0.0)
            cap = tip * math.cos(theta)
            if x < cap:
                return tip - math.sqrt(tip * tip - x * x)
            return tip - math.sqrt(tip * tip - cap * cap) + (x - cap) / math.tan(theta)
        points = self.punch["profile_points"]
        for (r0, g0), (r1, g1) in zip(points, points[1:]):
            if r0 <= x <= r1:
                return g0 + (g1 - g0) * (x - r0) / (r1 - r0)
        return None


def case_name(case_text):
    """The load case's file name, from case.toml's first comment line "(from PATH)"."""
    first = case_text.splitlines()[0] if case_text else ""
    if "(from " in first:
        return pathlib.Path(first.split("(from ", 1)[1].split(")", 1)[0]).stem
    return "run"


def branches(curve):
    """Consecutive runs of rows going the same way: [(loading?, rows)], each run sharing its first row."""
    out = []
    for k in range(1, len(curve)):
        loading = float(curve[k]["alpha"]) >= float(curve[k - 1]["alpha"])
        if not out or out[-1][0] != loading:
            out.append((loading, [curve[k - 1]]))
        out[-1][1].append(curve[k])
    return out


def plot_curve(case, name, curve, summary, outdir):
    scene = Scene(case)
    elastic = case["material"]["model"] == "elastic" and scene.theory is not None
    fig, axes = plt.subplots(1, 2 if elastic else 1, figsize=(11 if elastic else 6, 4.4), squeeze=False)
    ax = axes[0][0]
    drawn = set()
    style = {"loading": ("tab:blue", "-", 2), "unloading": ("tab:orange", "-", 3), "reloading": ("tab:green", "--", 4)}
    for k, (loading, rows) in enumerate(branches(curve)):
        label = "unloading" if not loading else ("loading" if k == 0 else "reloading")
        color, line, order = style[label]
        ax.plot([float(r["alpha"]) * 1e6 for r in rows], [scene.force(r["P"]) for r in rows], "o", ls=line, ms=3,
                color=color, zorder=order, label=None if label in drawn else label)
        drawn.add(label)
    peak = max(curve, key=lambda r: float(r["P"]))
    ax.plot(float(peak["alpha"]) * 1e6, scene.force(peak["P"]), "k*", ms=10, label="peak")
    # The run's own discretization error (mesh.error_estimate): a band of P +- the estimate, and
    # the figure at the peak in the legend (a band of 0.1% is thinner than the line).
    with_error = [r for r in curve if r.get("P_error_estimate")]
    if with_error:
        alphas = [float(r["alpha"]) * 1e6 for r in with_error]
        ax.fill_between(alphas, [scene.force(float(r["P"]) - float(r["P_error_estimate"])) for r in with_error],
                        [scene.force(float(r["P"]) + float(r["P_error_estimate"])) for r in with_error],
                        color="tab:gray", alpha=0.35, lw=0, zorder=1)
        if peak.get("P_error_estimate") and float(peak["P"]) > 0:
            relative = float(peak["P_error_estimate"]) / float(peak["P"])
            ax.fill_between([], [], [], color="tab:gray", alpha=0.35, lw=0,
                            label=f"discretization error ± {100 * relative:.2g}% at the peak")
    for u in summary.get("unloading", []):
        h, p, stiffness = u["depth"], u["force"], u["stiffness"]
        if stiffness > 0:
            h0 = h - p / stiffness  # where the tangent at the reversal meets P = 0
            ax.plot([h0 * 1e6, h * 1e6], [0, scene.force(p)], "k--", lw=0.8,
                    label=f"S = {stiffness:.3g} {scene.stiffness_unit}")
        if u.get("separated") and u.get("residual_depth") is not None:
            ax.plot(u["residual_depth"] * 1e6, 0, "rv", ms=8, label=f"h_f = {u['residual_depth'] * 1e6:.3g} µm")
    ax.set_xlabel("indentation depth α [µm]")
    ax.set_ylabel(f"punch force P [{scene.force_unit}]")
    ax.set_title(f"{name}: P–α ({case['material']['model']}, {scene.shape})")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    if elastic:
        theory_name, force_of_a = scene.theory[0], scene.theory[1]
        ax = axes[0][1]
        a_max = max(float(r["a"]) for r in curve)
        a_line = [a_max * k / 100 for k in range(101)]
        ax.plot([a * 1e6 for a in a_line], [force_of_a(a) / scene.force_scale for a in a_line], "-", label=theory_name)
        ax.plot([float(r["a"]) * 1e6 for r in curve], [scene.force(r["P"]) for r in curve], "o", ms=4,
                label="indentsim")
        ax.set_xlabel(f"{scene.width_name} [µm]")
        ax.set_ylabel(f"punch force P [{scene.force_unit}]")
        ax.set_title(f"{name}: P–a against {theory_name}")
        ax.legend()
        ax.grid(alpha=0.3)
    save(fig, outdir, "curve")


def plot_pressure(case, name, row, profiles, surface_from_vtu, outdir):
    force = float(row["P"])
    a = float(row["a"])
    if profiles:
        top = max(int(r["line"]) for r in profiles)
        surface = [(float(r["x"]), -float(r["sigmaN_layer"])) for r in profiles if int(r["line"]) == top]
        source = "layer forces"
    else:
        surface, source = surface_from_vtu, "nodal contact pressure"
    scene = Scene(case)
    fig, ax = plt.subplots(figsize=(5.5, 4.2))
    shown = [(x, p) for x, p in surface if x <= 1.6 * max(a, 1e-300)]
    ax.plot([x * 1e6 for x, _ in shown], [p / 1e6 for _, p in shown], "o", ms=4, label=f"indentsim ({source})")
    if force > 0 and scene.theory is not None and case["material"]["model"] == "elastic":
        theory_name, _, a_of_force, pressure = scene.theory
        a_t = a_of_force(force)
        grid = [a_t * k / 200 for k in range(1, 201)]
        ax.plot([x * 1e6 for x in grid], [pressure(x, a_t, force) / 1e6 for x in grid], "-", label=f"{theory_name}, same P")
    ax.set_xlabel("r [µm]" if scene.axisymmetric else "x [µm]")
    ax.set_ylabel("contact pressure p [MPa]")
    ax.set_title(f"{name}: contact pressure at α = {float(row['alpha']) * 1e6:.3g} µm (step {row['step']})")
    ax.legend()
    ax.grid(alpha=0.3)
    save(fig, outdir, "pressure")


def plot_profiles(name, row, profiles, outdir):
    a = float(row["a"])
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
        ax.set_title(f"{name}: {title} at α = {float(row['alpha']) * 1e6:.3g} µm")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    save(fig, outdir, "profiles")


def vtu_of_step(outdir, step):
    collection = ET.parse(outdir / "fields.pvd").getroot().find("Collection")
    written = {int(d.get("timestep")): d.get("file") for d in collection.findall("DataSet")}
    if step not in written:
        sys.exit(f"{outdir}: no fields were written for step {step} (written: {sorted(written)}; "
                 "output.fields_every chooses more)")
    return outdir / written[step]


VTK_TYPES = {"Float64": "<f8", "Float32": "<f4", "Int64": "<i8", "Int32": "<i4", "UInt8": "u1"}


def decode_data_array(d):
    """Values of a VTK XML DataArray: format="binary" (base64 of a UInt64 byte count and the raw
    little-endian values, as indentsim writes them) or "ascii" (older runs)."""
    if d.get("format") == "binary":
        raw = base64.b64decode("".join(d.text.split()))
        size = int.from_bytes(raw[:8], "little")
        return np.frombuffer(raw[8:8 + size], dtype=VTK_TYPES[d.get("type")]).astype(float).tolist()
    return [float(v) for v in d.text.split()]


def read_vtu(path):
    piece = ET.parse(path).getroot().find("UnstructuredGrid").find("Piece")

    def array(parent, name):
        for d in piece.find(parent).findall("DataArray"):
            if d.get("Name") == name:
                return decode_data_array(d)
        raise KeyError(name)

    points = array("Points", "coordinates")
    u = array("PointData", "displacement")
    xy = [(points[3 * k], points[3 * k + 1]) for k in range(len(points) // 3)]
    deformed = [(x + u[3 * k], y + u[3 * k + 1]) for k, (x, y) in enumerate(xy)]
    connectivity = [int(v) for v in array("Cells", "connectivity")]
    quads = [connectivity[4 * e:4 * e + 4] for e in range(len(connectivity) // 4)]
    pressure = array("PointData", "contact_pressure")
    top = max(y for _, y in xy)
    surface = sorted((x, p) for (x, y), p in zip(xy, pressure) if y == top)
    return {"xy": xy, "deformed": deformed, "quads": quads, "e_u": array("CellData", "strain_intensity"),
            "plastic": array("CellData", "plastic"), "surface_pressure": surface}


def yielded_outline(quads, plastic):
    """The edges between yielded and elastic elements (or the mesh boundary): the zone's outline."""
    edges = {}
    for quad, flag in zip(quads, plastic):
        for k in range(4):
            edge = tuple(sorted((quad[k], quad[(k + 1) % 4])))
            edges.setdefault(edge, []).append(flag > 0)
    return [edge for edge, flags in edges.items() if any(flags) and not all(flags) or flags == [True]]


def plot_plastic_zone(case, name, row, fields, outdir):
    xy, deformed, quads = fields["xy"], fields["deformed"], fields["quads"]
    e0 = case["material"]["e0"]
    a = max(float(row["a"]), 1e-300)
    outline = yielded_outline(quads, fields["plastic"])
    # The window follows the zone: the contact and the yielded region, with a margin.
    reach = max([a] + [max(abs(xy[n][0]), abs(xy[n][1])) for edge in outline for n in edge])
    window = 1.3 * reach if outline else 3 * a
    polys, values = [], []
    for quad, value in zip(quads, fields["e_u"]):
        if min(xy[n][0] for n in quad) > window or max(xy[n][1] for n in quad) < -window:
            continue
        polys.append([(deformed[n][0] * 1e3, deformed[n][1] * 1e3) for n in quad])
        values.append(value / e0)
    fig, ax = plt.subplots(figsize=(6.5, 5))
    cells = PolyCollection(polys, array=values, cmap="viridis", edgecolors="face", linewidths=0.2)
    ax.add_collection(cells)
    fig.colorbar(cells, ax=ax, label="strain intensity e_u / e0")
    for k, (n1, n2) in enumerate(outline):
        ax.plot([deformed[n1][0] * 1e3, deformed[n2][0] * 1e3], [deformed[n1][1] * 1e3, deformed[n2][1] * 1e3], "w-",
                lw=1.2, label="yielded region" if k == 0 else None)
    scene = Scene(case)
    alpha = float(row["alpha"])
    outline_xs = [window * k / 200 for k in range(201)]
    punch = [(x, scene.punch_height(x)) for x in outline_xs if scene.punch_height(x) is not None]
    ax.plot([x * 1e3 for x, _ in punch], [(g - alpha) * 1e3 for _, g in punch], "r-", lw=1.5, label="punch")
    ax.set_xlim(0, window * 1e3)
    ax.set_ylim(-window * 1e3, 0.15 * window * 1e3)
    ax.set_aspect("equal")
    ax.set_xlabel(("r" if scene.axisymmetric else "x") + " [mm] (deformed)")
    ax.set_ylabel(("z" if scene.axisymmetric else "y") + " [mm] (deformed)")
    count = int(sum(1 for f in fields["plastic"] if f > 0))
    ax.set_title(f"{name}: α = {alpha * 1e6:.3g} µm, {count} yielded elements")
    ax.legend(loc="lower right", fontsize=7)
    save(fig, outdir, "plastic_zone")


def plot_analysis(path):
    """The Oliver-Pharr analysis of analysis.json: each unloading branch with its power-law fit,
    the stiffness S as the tangent at h_max, h_f, h_c and h_max marked, and the numbers beside."""
    report = json.loads(path.read_text())
    depth, force = report["curve_si"]["depth"], report["curve_si"]["force"]
    axi = report["scene"] == "axisymmetric"
    deepest = max(depth) if depth else 1.0
    h_unit, h_scale = ("nm", 1e9) if deepest < 20e-6 else ("µm", 1e6)
    peak = max(force) if force else 1.0
    if axi:
        p_unit, p_scale = ("mN", 1e3) if peak < 1.0 else ("N", 1.0)
    else:
        p_unit, p_scale = ("kN/m", 1e-3) if peak > 1e3 else ("N/m", 1.0)
    branches = report["branches"]
    fig, axes = plt.subplots(len(branches), 3, figsize=(15, 4.2 * len(branches)), squeeze=False,
                             gridspec_kw={"width_ratios": [1, 1, 0.9]})
    h = [d * h_scale for d in depth]
    P = [f * p_scale for f in force]
    for (whole, ax, table_ax), b in zip(axes, branches):
        i0, ip, ie = b["index"]["loading_start"], b["index"]["peak"], b["index"]["end"]
        fit = b["fit"]
        h_f, h_max, P_max = fit["h_f"], b["h_max"], b["P_max"]
        S = b["S_fit"]
        lo, hi = fit["range"]
        # Left: the whole curve, the branch's loading and unloading in their colours.
        whole.plot(h, P, "-", lw=0.8, color="lightgray")
        whole.plot(h[i0:ip + 1], P[i0:ip + 1], "-", lw=1.2, color="tab:blue", label="loading")
        whole.plot(h[ip:ie + 1], P[ip:ie + 1], "-", lw=1.2, color="tab:orange", label="unloading")
        whole.set_xlabel(f"depth h [{h_unit}]")
        whole.set_ylabel(f"force P [{p_unit}]")
        whole.set_title(f"{pathlib.Path(report['curve']).name}: unloading {b['where']}", fontsize=10)
        whole.legend(fontsize=7, loc="upper left")
        # Middle: the unloading branch, the fit over its range, S as the tangent at h_max (it
        # meets the depth axis at h_max - P_max / S), and h_f, h_c, h_max.
        ax.plot(h[ip:ie + 1], P[ip:ie + 1], "o", ms=3, color="tab:orange", label="unloading")
        xs = [h_f + (h_max - h_f) * k / 100 for k in range(101)]
        ax.plot([x * h_scale for x in xs], [fit["B"] * (x - h_f) ** fit["m"] * p_scale for x in xs], "-",
                color="black", lw=1.2, label=f"P = B (h - h_f)^m, m = {fit['m']:.3g} (fit over {lo:g}-{hi:g} P_max)")
        h0 = h_max - P_max / S
        ax.plot([h0 * h_scale, h_max * h_scale], [0, P_max * p_scale], "--", color="tab:red", lw=1,
                label=f"S = {S:.4g} {'N/m' if axi else 'N/m per m'}")
        for k, (x, label) in enumerate(((h_f, "h_f"), (b["h_c"], "h_c"), (h_max, "h_max"))):
            ax.axvline(x * h_scale, color="gray", ls=":", lw=0.8)
            ax.annotate(label, (x * h_scale, P_max * p_scale * (1.03 + 0.05 * (k % 2))), ha="center", fontsize=8)
        left = min(h_f, h0) - 0.1 * (h_max - min(h_f, h0))
        ax.set_xlim(left * h_scale, (h_max + 0.05 * (h_max - left)) * h_scale)
        ax.set_ylim(0, P_max * p_scale * 1.15)
        ax.set_xlabel(f"depth h [{h_unit}]")
        ax.set_ylabel(f"force P [{p_unit}]")
        ax.legend(fontsize=7, loc="center left")
        rows = [("P_max", f"{P_max * p_scale:.5g} {p_unit}"), ("h_max", f"{h_max * h_scale:.5g} {h_unit}"),
                ("S (fit)", f"{S:.5g} N/m"), ("S (exact)", "-" if b["S_exact"] is None else f"{b['S_exact']:.5g} N/m"),
                ("epsilon, beta", f"{b['epsilon']:g}, {b['beta']:g}"), ("h_c", f"{b['h_c'] * h_scale:.5g} {h_unit}"),
                ("h_f", f"{h_f * h_scale:.5g} {h_unit}"),
                ("A_c" if axi else "2 r(h_c)", f"{b['A_c']:.4g} {'m²' if axi else 'm'}"),
                ("H", f"{b['H'] / 1e9:.4g} GPa"),
                ("E_r", "not defined (plane strain)" if b["E_r"] is None and not axi
                 else ("-" if b["E_r"] is None else f"{b['E_r'] / 1e9:.4g} GPa")),
                ("E (specimen)", "-" if b["E"] is None else f"{b['E'] / 1e9:.4g} GPa"),
                ("W_e / W_t", f"{b['W_e_over_W_t']:.3f}")]
        if b["pile_up_ratio"] is not None:
            rows += [("true contact radius", f"{b['true_contact_radius'] * h_scale:.5g} {h_unit}"),
                     ("H (true area)", f"{b['true_H'] / 1e9:.4g} GPa"),
                     ("E_r (true area)", "-" if b["true_E_r"] is None else f"{b['true_E_r'] / 1e9:.4g} GPa"),
                     ("A_true / A_c", f"{b['pile_up_ratio']:.3f} ({'pile-up' if b['pile_up_ratio'] > 1 else 'sink-in'})")]
        table_ax.axis("off")
        table = table_ax.table(cellText=[[k, v] for k, v in rows], colLabels=["Oliver-Pharr", ""], loc="center",
                               cellLoc="left", colWidths=[0.45, 0.55])
        table.auto_set_font_size(False)
        table.set_fontsize(8)
        table.scale(1, 1.25)
    fig.tight_layout()
    stem = path.with_suffix("")
    for suffix in ("png", "svg"):
        fig.savefig(f"{stem}.{suffix}", dpi=150)
    plt.close(fig)
    print(f"wrote {stem}.png")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("outdir", type=pathlib.Path, nargs="?")
    parser.add_argument("--step", type=int, help="the increment to show (default: the deepest of the load path)")
    parser.add_argument("--analysis", type=pathlib.Path, help="draw this analysis.json (indentsim analyze) instead")
    args = parser.parse_args()
    if args.analysis:
        plot_analysis(args.analysis)
        return
    if args.outdir is None:
        parser.error("give a run's folder or --analysis FILE")
    outdir = args.outdir
    case_text = (outdir / "case.toml").read_text()
    case = tomllib.loads(case_text)
    name = case_name(case_text)
    curve = read_csv(outdir / "curve.csv")
    summary = json.loads((outdir / "summary.json").read_text()) if (outdir / "summary.json").is_file() else {}
    step = args.step if args.step is not None else int(max(curve, key=lambda r: float(r["alpha"]))["step"])
    rows = [r for r in curve if int(r["step"]) == step]
    if not rows:
        sys.exit(f"{outdir}: the run has no step {step} (steps 0 to {curve[-1]['step']})")
    row = rows[0]
    profiles = [r for r in read_csv(outdir / "profiles.csv") if int(r["step"]) == step]
    fields = read_vtu(vtu_of_step(outdir, step))
    figures = outdir / "figures"
    figures.mkdir(exist_ok=True)
    plot_curve(case, name, curve, summary, figures)
    plot_pressure(case, name, row, profiles, fields["surface_pressure"], figures)
    if profiles:
        plot_profiles(name, row, profiles, figures)
    else:
        print(f"no layer view tabulated for step {step} (profiles.csv holds the deepest and the final state): "
              "no profiles figure")
    plot_plastic_zone(case, name, row, fields, figures)
    if (outdir / "analysis.json").is_file():
        plot_analysis(outdir / "analysis.json")


if __name__ == "__main__":
    main()
