#!/usr/bin/env python3
"""Figures of an indentsim run, of its Oliver-Pharr analysis, and of a sweep.

    indentsim plot DIR [--step N] [--data CURVE.csv] [--size slide|column]
    python3 plots/plot_results.py DIR [--step N] [--data CURVE.csv [--depth-unit nm --force-unit mN ...]]
                                      [--size slide|column]

A run's folder (case.toml, curve.csv, summary.json, profiles.csv and the VTU of one increment from
fields.pvd -- by default the deepest state of the load path, which indentsim always writes): PNG
and SVG files in DIR/figures/:
  curve          the load-depth curve P-h as computed: loading, unloading and reloading in their
                 colours with a marker at every computed increment, lines only between increments
                 that both touch, the rows after separation as grey crosses, the peak, the
                 unloading stiffness S and the residual depth h_f (elastic runs: also P against the
                 contact radius a, with Hertz or Sneddon); with --data, a measured curve over it
  pressure       the contact pressure p(r) (or p(x)) against that theory for the same force, the
                 contact radius a marked
  profiles       the paper's layer view (Yazici 2023, Fig. 5): sigma_N (paper) = sigma_zz and
                 sigma_T (paper) = sigma_rz along the surface and the chosen depths
  plastic_zone   the strain intensity e_u/e0 on the deformed mesh (both halves), its colour scale
                 logarithmic where the tip dominates, the yield outline e_u = e0 as a contour (J2:
                 also where the material has yielded) and the indenter where it stands
and, when `indentsim analyze DIR` has written DIR/analysis.json, analysis.png beside it.  Units are
chosen once per run from its scale (indentsim_plotting.RunUnits) and shared by every figure.

A coated specimen (summary.json's `layers`, the fields' `region`; docs/MODEL.md §14): the titles
name the coating on the substrate; plastic_zone divides each element's e_u by its own region's e0,
outlines each region's own yield on its own nodes, hatches an elastic layer (it never yields) and
draws every interface, displaced; the Hertz or Sneddon references of curve and pressure are the
film's half-space (solid) and the substrate's (grey, dotted) -- a coated specimen has no closed
form; profiles names the region of each line; analysis says which ν its E is through (the top
layer's); sweep draws the film's and the substrate's E/(1-ν²).

A sweep's folder (results.csv, and manifest.json, `indentsim sweep`): DIR/figures/sweep.png and
.svg: hardness H, reduced modulus E_r and the pile-up ratio A_true/A_c against the swept
parameter (one line per value of a second swept parameter).

    indentsim analyze CURVE --plot        (or: python3 plots/plot_results.py --analysis FILE.json)

draws an analysis.json: the whole curve, each unloading branch with its power-law fit, S as the
tangent at h_max, h_f, h_c and h_max marked, and a table of the Oliver-Pharr numbers (with the true
contact's for a run): FILE.png and FILE.svg beside it.  A coated run with two or more branches (a
multi-cycle load path) gains a last row, the substrate effect (MODEL.md §14.4): E_r (Oliver-Pharr
and true contact) against h_max/t, t the top film's thickness, between the film's and the region
below's own E/(1 - ν²), with Gao, Chiu and Lee's (1992) model at each branch's a/t; and H
(Oliver-Pharr and true) against h_max/t.

--size slide (default: 16:9, 1920 x 1080 px) or column (a journal column, 3.5 in wide, 300 dpi);
the style is plots/indentsim.mplstyle.  Needs Debian's python3-matplotlib (scripts/install-deps.sh).
"""
import argparse
import base64
import csv
import json
import math
import pathlib
import sys
import textwrap
import tomllib
import xml.etree.ElementTree as ET

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import indentsim_plotting as ip  # noqa: E402

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib import patheffects, transforms  # noqa: E402
from matplotlib.collections import PolyCollection  # noqa: E402
from matplotlib.colors import LogNorm, Normalize  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Patch, Polygon  # noqa: E402

read_csv = ip.read_csv


class Scene:
    """What the figures need of the scene: the punch's shape and the theory for it.

    Plane strain: Hertz line contact for the cylinder.  Axisymmetry: Hertz for the sphere, Sneddon
    for the cone.  Other shapes have no closed form: their figures show indentsim alone.

    A coated specimen (docs/MODEL.md §14) has no closed form either: `theory` is then the
    homogeneous theory with the surface layer's E* (the film alone, which the contact feels first),
    and `references` holds it and the substrate's (the substrate alone), each named by its region,
    so that a figure draws the two half-spaces between which the coated one lies."""

    def __init__(self, case, summary=None):
        self.axisymmetric = ip.is_axisymmetric(case)
        self.punch = case["punch"]
        self.shape = self.punch.get("shape", "sphere")
        self.materials = ip.region_materials(case, summary)  # [0] the substrate, [k] layer k from the surface
        self.coated = len(self.materials) > 1
        self.region_names = ip.region_names(len(self.materials))
        self.elastic = all(m.get("model", "elastic") == "elastic" for m in self.materials)
        self.e_star = case["material"]["E"] / (1 - case["material"]["nu"] ** 2)
        if self.coated:  # the surface layer's, as the contact estimates of the run (MODEL.md §14.1)
            self.e_star = ip.e_star(self.materials[1])
        self.r = "r" if self.axisymmetric else "x"
        self.width_name = "contact radius $a$" if self.axisymmetric else "contact half-width $a$"
        self.theory = self.theory_for(self.e_star)
        # (words for the legend, theory, main) of each half-space a figure draws.
        self.references = [("", self.theory, True)] if self.theory is not None else []
        if self.coated and self.theory is not None and self.shape != "flat":  # flat: p(r) holds no E*
            substrate = ip.e_star(self.materials[0])
            self.references = [
                (f", the {self.region_names[1]} alone ($E^*$ = {ip.stress_unit(self.e_star).text(self.e_star, 3)})",
                 self.theory, True),
                (f", the substrate alone ($E^*$ = {ip.stress_unit(substrate).text(substrate, 3)})",
                 self.theory_for(substrate), False)]

    def theory_for(self, e_star):
        """(name, P(a), a(P), p(x; a, P)) of the theory for this scene and a half-space of
        plane-strain modulus e_star, or None."""
        cot = 1 / math.tan(math.radians(self.punch.get("half_angle", 45.0)))
        sharp_cone = self.shape == "cone" and self.punch.get("tip_radius", 0.0) == 0.0
        r = self.punch.get("radius", 0.0)
        if self.shape == "sphere" and not self.axisymmetric:
            return ("Hertz line contact", lambda a: math.pi * e_star * a * a / (4 * r),
                    lambda p: math.sqrt(4 * p * r / (math.pi * e_star)),
                    lambda x, a, p: 2 * p / (math.pi * a) * math.sqrt(max(0.0, 1 - (x / a) ** 2)))
        if self.shape == "sphere":
            return ("Hertz", lambda a: 4 * e_star * a**3 / (3 * r),
                    lambda p: (3 * p * r / (4 * e_star)) ** (1 / 3),
                    lambda x, a, p: 3 * p / (2 * math.pi * a * a) * math.sqrt(max(0.0, 1 - (x / a) ** 2)))
        if sharp_cone and self.axisymmetric:
            return ("Sneddon", lambda a: math.pi * a * a * e_star * cot / 2,
                    lambda p: math.sqrt(2 * p / (math.pi * e_star * cot)),
                    lambda x, a, p: e_star * cot / 2 * math.acosh(a / x) if 0 < x < a else 0.0)
        if self.shape == "flat" and self.axisymmetric:
            # Sneddon's flat punch: the contact is the face, a = R; p = P / (2 pi a sqrt(a^2 - r^2)).
            return ("Sneddon", None, lambda p: r,
                    lambda x, a, p: p / (2 * math.pi * a * math.sqrt(a * a - x * x)) if x < a else 0.0)
        return None

    def contact_area(self, a):
        """The projected contact area (axisymmetric) or width 2a (plane strain, per unit thickness)."""
        return math.pi * a * a if self.axisymmetric else 2 * a

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
        if self.shape == "area_function":
            return area_function_height(self.punch["area_coefficients"], x)
        points = self.punch["profile_points"]
        for (r0, g0), (r1, g1) in zip(points, points[1:]):
            if r0 <= x <= r1:
                return g0 + (g1 - g0) * (x - r0) / (r1 - r0)
        return None


def area_function_height(coefficients, x):
    """The depth h of the equal-area profile at radius x: A(h) = pi x^2 (docs/MODEL.md §13.5),
    with A(h) = C0 h^2 + C1 h + C2 h^(1/2) + ... + C8 h^(1/128); None where A stops growing."""
    def area(h):
        return sum(c * h ** (2.0 if k == 0 else 2.0 ** (1 - k)) for k, c in enumerate(coefficients))
    target = math.pi * x * x
    if target == 0.0:
        return 0.0
    lo, hi = 0.0, 1e-15
    for _ in range(400):  # as AreaFunctionPunch::surface_height
        if area(hi) >= target:
            break
        if area(hi) > 0.0 and area(hi * (1 + 1e-9)) <= area(hi):
            return None
        lo, hi = hi, 2 * hi
    else:
        return None
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if area(mid) >= target:
            hi = mid
        else:
            lo = mid
    return hi


def column_of(rows, name, default=0.0):
    return np.array([float(r[name]) if r.get(name) not in (None, "") else default for r in rows])


# --- curve.png ------------------------------------------------------------------------------------

def plot_curve(case, summary, curve, units, size, outdir, measured=None):
    scene = Scene(case, summary)
    elastic = scene.elastic and scene.theory is not None and scene.theory[1] is not None
    depth, force = column_of(curve, "alpha"), column_of(curve, "P")
    nodes = column_of(curve, "contact_nodes", 1.0) if "contact_nodes" in curve[0] else None
    # The legend's entries: the kinds of branch, separated rows, the peak, the error band, S, h_f.
    unloading = summary.get("unloading") or []
    entries = len(set(ip.branch_kinds(depth))) + bool(ip.separated_rows(force, nodes).any()) + 1 + \
        bool(curve[0].get("P_error_estimate")) + bool(unloading) + any(u.get("separated") for u in unloading) + \
        (measured is not None)
    strip = None
    if size == "column" and not elastic:
        fig, axes, strip = ip.figure(size, legend_row=ip.legend_height(entries, size))
    elif elastic:  # two panels: the curve's legend in a strip below them (three columns on a slide)
        fig, axes, strip = ip.figure(size, columns=2, legend_row=ip.legend_height(
            entries, size, 3 if size == "slide" else 1))
    else:
        fig, axes = ip.figure(size)
    ax = axes[0]
    if measured is not None:
        h_m, p_m, name = measured
        ax.plot(units.depth(h_m), units.force(p_m), "-", color=ip.MEASURED, lw=plt.rcParams["lines.linewidth"] * 0.7,
                alpha=0.8, zorder=2, label=f"measured: {name}")
    # The run's own discretization error (mesh.error_estimate): a band of P +- the estimate along
    # the curve, and the figure at the peak in the legend (a band of 0.1% is thinner than the line).
    error = column_of(curve, "P_error_estimate") if curve[0].get("P_error_estimate") not in (None, "") else None
    ip.draw_load_depth(ax, depth, force, nodes, units, error=error)
    k = int(np.argmax(force))
    ax.plot(units.depth(depth[k]), units.force(force[k]), "*", color=ip.BLACK,
            ms=plt.rcParams["lines.markersize"] * 2.4, zorder=5,
            label=f"$P_\\mathrm{{max}}$ = {units.force.text(force[k])} at $h_\\mathrm{{max}}$ = "
                  f"{units.depth.text(depth[k])}")
    if error is not None and error[k] > 0 and force[k] > 0:
        ax.fill_between([], [], [], color="#999999", alpha=0.3, lw=0,
                        label=f"discretization error ± {100 * error[k] / force[k]:.2g}% at the peak")
    for n, u in enumerate(summary.get("unloading", [])):
        h, p, stiffness = u["depth"], u["force"], u["stiffness"]
        if stiffness is not None and stiffness > 0:
            h0 = h - p / stiffness  # where the secant from the reversal meets P = 0
            ax.plot(units.depth(np.array([h0, h])), units.force(np.array([0, p])), ":", color=ip.BLACK,
                    lw=plt.rcParams["lines.linewidth"] * 0.7, zorder=4,
                    label=f"$S$ = {units.stiffness.text(stiffness)} (first unloading step)" if n == 0 else None)
        if u.get("separated") and u.get("residual_depth") is not None:
            ax.plot(units.depth(u["residual_depth"]), 0, "v", color=ip.THEORY,
                    ms=plt.rcParams["lines.markersize"] * 1.8, zorder=6, clip_on=False,
                    label=f"$h_\\mathrm{{f}}$ = {units.depth.text(u['residual_depth'])}, residual depth"
                    if n == 0 else None)
    ax.set_xlabel(f"indentation depth $h$ [{units.depth.name}]")
    ax.set_ylabel(units.force_axis())
    ax.set_xlim(left=0)
    ax.set_ylim(bottom=-0.02 * units.force(max(force.max(), 1e-300)))
    ax.set_title("load–depth curve" + (", simulated and measured" if measured is not None else ""))
    if elastic:
        handles = ax.get_legend_handles_labels()[0]
        ip.strip_legend(strip, handles, size, columns=min(len(handles), 3) if size == "slide" else 1)
    else:
        ip.legend(ax, size, strip=strip, loc="upper left")
    if elastic:
        ax = axes[1]
        a = column_of(curve, "a")
        a_line = np.linspace(0, a.max(), 101)
        # A coated specimen: the film's half-space and the substrate's (MODEL.md §14; no closed form).
        for words, (theory_name, force_of_a, _, _), main in scene.references:
            ax.plot(units.position(a_line), units.force(np.array([force_of_a(x) for x in a_line])),
                    "-" if main else ":", color=ip.THEORY if main else "#666666", label=theory_name + words)
        ax.plot(units.position(a), units.force(force), "o", color=ip.LOADING, label="indentsim")
        ax.set_xlabel(f"{scene.width_name} [{units.position.name}]")
        ax.set_ylabel(units.force_axis())
        ax.set_title("load against contact size")
        ax.legend(loc="upper left")
    ip.run_title(fig, ip.describe_run(case, summary))
    ip.save(fig, outdir, "curve")


# --- pressure.png ---------------------------------------------------------------------------------

def plot_pressure(case, summary, row, profiles, surface_from_vtu, units, size, outdir):
    force = float(row["P"])
    a = float(row["a"])
    scene = Scene(case, summary)
    if profiles:
        top = max(int(r["line"]) for r in profiles)
        surface = [(float(r["x"]), -float(r["sigmaN_layer"])) for r in profiles if int(r["line"]) == top]
        source = "indentsim: surface traction"
    else:
        surface, source = surface_from_vtu, "indentsim: nodal contact pressure"
    fig, axes = ip.figure(size)
    ax = axes[0]
    reach = 1.6 * max(a, 1e-300)
    shown = [(x, p) for x, p in surface if x <= reach]
    ax.plot(units.position(np.array([x for x, _ in shown])), units.stress(np.array([p for _, p in shown])), "o-",
            color=ip.LOADING, lw=plt.rcParams["lines.linewidth"] * 0.6, label=source, zorder=3)
    # The elastic theory for the same force; for a plastic run a reference (dashed).  A coated
    # specimen has none: the film's half-space and the substrate's (Scene.references), the
    # substrate's grey and dotted, both left out with the film's.
    for words, (theory_name, _, a_of_force, pressure), main in (scene.references if force > 0 else []):
        elastic = scene.elastic
        a_t = a_of_force(force)
        grid = np.linspace(a_t / 400, a_t * (0.98 if scene.shape == "flat" else 1.0), 400)  # flat: singular at a
        theory = np.array([pressure(x, a_t, force) for x in grid])
        computed = max((p for _, p in shown), default=0.0)
        if elastic or theory.max() <= 2 * computed:  # a reference far off the plastic pressure: left out
            ax.plot(units.position(grid), units.stress(theory), ("-" if elastic else "--") if main else ":",
                    color=ip.THEORY if main else "#666666",
                    label=f"{theory_name}{words}, same $P$" + ("" if elastic else " (elastic, for reference)"))
        elif scene.coated:  # the film's left out: the substrate's too, and the legend says why (room above)
            ax.plot([], [], " ", label=f"{theory_name} left out: the {scene.region_names[1]} alone would peak at "
                                       f"{units.stress.text(theory.max())}")
            ax.set_ylim(0, 1.45 * units.stress(computed))
            break
    if a > 0:
        ax.axvline(units.position(a), color="#666666", ls=":", lw=1.2,
                   label=f"{scene.width_name} = {units.position.text(a)}")
    ax.set_xlim(0, units.position(reach))
    ax.set_ylim(bottom=0)
    ax.set_xlabel(f"{'radial coordinate $r$' if scene.axisymmetric else 'distance from the axis $x$'} "
                  f"[{units.position.name}]")
    ax.set_ylabel(f"contact pressure $p$ [{units.stress.name}]")
    ax.set_title(f"contact pressure at $h$ = {units.depth.text(float(row['alpha']))} (step {row['step']}), "
                 f"$P$ = {units.force.text(force)}")
    ax.legend(loc="upper right" if size == "slide" else "best")
    ip.run_title(fig, ip.describe_run(case, summary))
    ip.save(fig, outdir, "pressure")


# --- profiles.png ---------------------------------------------------------------------------------

def region_at_depth(case, summary, depth):
    """The region's name ("film", "substrate", "layer 2", ...) at a depth [m] below the undeformed
    surface of a coated specimen, or the interface's ("film / substrate interface": its nodal
    values are the layer above's, MODEL.md §14.1; σ_zz and the shear, which the profiles show, are
    continuous across it); None for a homogeneous specimen."""
    layers = ip.layers_of(case, summary)
    if not layers:
        return None
    names = ip.region_names(len(layers) + 1)
    for k, layer in enumerate(layers, start=1):
        bottom = layer["bottom_depth"]
        if abs(depth - bottom) <= 1e-6 * bottom:
            below = names[k + 1] if k + 1 < len(names) else names[0]
            return f"{names[k]} / {below} interface"
        if depth < bottom:
            return names[k]
    return names[0]


def plot_profiles(case, summary, row, profiles, units, size, outdir):
    scene = Scene(case, summary)
    a = float(row["a"])
    reach = 3 * max(a, 1e-300)
    lines = sorted({int(r["line"]) for r in profiles}, reverse=True)
    entries = len(lines) + 3
    fig, axes, strip = ip.figure(size, columns=2, legend_row=ip.legend_height(entries, size, min(entries, 3)
                                                                               if size == "slide" else 1))
    shear = "σ$_{rz}$" if scene.axisymmetric else "σ$_{xz}$"
    colours = [ip.LOADING, ip.UNLOADING, ip.RELOADING, ip.PURPLE, ip.SKY, ip.THEORY]
    handles = []
    for n, line in enumerate(lines):
        rows = [r for r in profiles if int(r["line"]) == line and float(r["x"]) <= reach]
        depth = -float(rows[0]["y"])
        c = colours[n % len(colours)]
        region = region_at_depth(case, summary, depth)
        handles.append(Line2D([], [], color=c,
                              label=("surface" if depth == 0 else f"$z$ = −{units.position.text(depth)}") +
                              (f" ({region})" if region else "")))
        x = units.position(column_of(rows, "x"))
        for ax, layer, nodal in ((axes[0], "sigmaN_layer", "sigma22_nodal"),
                                 (axes[1], "sigmaT_layer", "sigma12_nodal")):
            ax.plot(x, units.stress(column_of(rows, layer)), "-", color=c)
            ax.plot(x, units.stress(column_of(rows, nodal)), "o", color=c, ms=plt.rcParams["lines.markersize"] * 0.8,
                    mfc="none")
    handles += [Line2D([], [], color="#555555", ls="-", label="layer view (paper: layer forces / w)"),
                Line2D([], [], color="#555555", ls="none", marker="o", mfc="none", label="Gauss points → nodes")]
    axes[0].set_ylabel(f"σ$_{{zz}}$ [{units.stress.name}]")
    axes[1].set_ylabel(f"{shear} [{units.stress.name}]")
    h = units.depth.text(float(row["alpha"]))
    titles = ("normal stress: σ$_N$ (paper) = σ$_{zz}$", f"shear stress: σ$_T$ (paper) = {shear}")
    for ax, title in zip(axes, titles):
        ax.set_xlabel(f"{'radial coordinate $r$' if scene.axisymmetric else '$x$'} [{units.position.name}]")
        ax.set_title(title)
        ax.axvline(units.position(a), color="#666666", ls=":", lw=1.2)
    handles.append(Line2D([], [], color="#666666", ls=":", lw=1.2, label=f"$a$ = {units.position.text(a)}"))
    ip.strip_legend(strip, handles, size, columns=min(len(handles), 3) if size == "slide" else 1)
    ip.run_title(fig, f"the paper's layer view (Yazıcı 2023, Fig. 5) at $h$ = {h} (step {row['step']})",
                 ip.describe_run(case, summary))
    ip.save(fig, outdir, "profiles")


# --- plastic_zone.png -----------------------------------------------------------------------------

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
        return np.frombuffer(raw[8:8 + size], dtype=VTK_TYPES[d.get("type")]).astype(float)
    return np.array([float(v) for v in d.text.split()])


def read_vtu(path):
    piece = ET.parse(path).getroot().find("UnstructuredGrid").find("Piece")

    def array(parent, name):
        for d in piece.find(parent).findall("DataArray"):
            if d.get("Name") == name:
                return decode_data_array(d)
        raise KeyError(name)

    points = array("Points", "coordinates").reshape(-1, 3)[:, :2]
    u = array("PointData", "displacement").reshape(-1, 3)[:, :2]
    quads = array("Cells", "connectivity").astype(int).reshape(-1, 4)
    pressure = array("PointData", "contact_pressure")
    top = points[:, 1].max()
    on_top = points[:, 1] == top
    surface = sorted(zip(points[on_top, 0].tolist(), pressure[on_top].tolist()))
    plastic = array("CellData", "plastic")
    try:
        plastic_points = array("CellData", "plastic_points")
    except KeyError:  # an older run's fields: the flag alone
        plastic_points = 4.0 * plastic
    try:  # the material region of each cell: 0 the substrate, k layer k from the surface
        region = array("CellData", "region").astype(int)
    except KeyError:  # a run from before coated specimens: one region
        region = np.zeros(len(quads), int)
    return {"xy": points, "deformed": points + u, "quads": quads, "e_u": array("CellData", "strain_intensity"),
            "e_u_nodal": array("PointData", "strain_intensity"), "plastic": plastic,
            "plastic_points": plastic_points, "region": region, "surface_pressure": surface}


def structured(xy):
    """(nx, ny) of indentsim's structured mesh: node n = i * ny + j (x index i, y index j)."""
    ny = int(np.count_nonzero(xy[:, 0] == xy[0, 0]))
    return len(xy) // ny, ny


def nodal_average(quads, cell_values, nodes):
    total, count = np.zeros(nodes), np.zeros(nodes)
    for k in range(4):
        np.add.at(total, quads[:, k], cell_values)
        np.add.at(count, quads[:, k], 1)
    return total / np.maximum(count, 1)


def region_bands(quads, region, ny, regions):
    """The node rows (lo, hi) of each region's band (its elements lie between node rows lo and hi;
    node n = i * ny + j), from the cells' regions; None for a region without elements."""
    rows = quads.min(axis=1) % ny
    bands = []
    for r in range(regions):
        mine = rows[region == r]
        bands.append((int(mine.min()), int(mine.max()) + 1) if len(mine) else None)
    return bands


def region_nodal(fields, r, band, ny):
    """(e_u, yielded fraction) at the nodes of region r's band, (nx, rows): the fields' nodal e_u
    (Gauss points extrapolated and averaged within the region), except on the band's top row when
    a region lies above it -- the interface's nodal values are that region's side (MODEL.md §14.1)
    -- where it is the mean of this region's own elements beside the node (no extrapolation, so
    half an element smoother there).  The yielded fraction: plastic Gauss points / 4 of the
    region's own elements, averaged to the nodes."""
    xy, quads = fields["xy"], fields["quads"]
    nx = len(xy) // ny
    lo, hi = band
    mine = fields["region"] == r
    e_u = fields["e_u_nodal"].reshape(nx, ny)[:, lo:hi + 1].copy()
    if hi < ny - 1:
        e_u[:, -1] = nodal_average(quads[mine], fields["e_u"][mine], len(xy)).reshape(nx, ny)[:, hi]
    yielded = nodal_average(quads[mine], fields["plastic_points"][mine] / 4.0, len(xy)).reshape(nx, ny)[:, lo:hi + 1]
    return e_u, yielded


def plot_plastic_zone(case, summary, row, fields, units, size, outdir, deepest=None):
    """`deepest`: the deepest depth reached up to the state shown; below it the state is unloaded
    (J2: the region that has yielded is then drawn too; at the deepest state it is the region
    e_u >= e0).

    A coated specimen (docs/MODEL.md §14): each element's e_u is divided by its own region's e0
    (summary.json: the substrate's `material.e0`, layer k's `layers[k-1].material.e0`), and the
    outline e_u = e0 is contoured region by region on that region's own nodal values, so that it
    is each region's own yield (it ends at an interface; the interface is drawn).  An elastic
    region never yields: it is coloured by e_u over the e0 of its material block (0.027 unless the
    case set one: a scale, not a yield), hatched, with no outline (that e0 is no yield of the run);
    a coated specimen whose every region is elastic is drawn as an elastic run is: each region's
    e_u = e0 dashed, "where a plastic law would yield".  A region without an e0 (Norton creep)
    leaves the colour unnormalised (e_u) for the whole figure.  The interfaces are drawn as the
    rows of nodes they are, displaced."""
    unloaded = deepest is not None and float(row["alpha"]) < deepest
    xy, deformed, quads = fields["xy"], fields["deformed"], fields["quads"]
    scene = Scene(case, summary)
    materials, names, coated = scene.materials, scene.region_names, scene.coated
    regions = max(len(materials), int(fields["region"].max()) + 1)
    names = ip.region_names(regions) if regions > len(materials) else names
    models = [(materials[r] if r < len(materials) else {}).get("model", "elastic") for r in range(regions)]
    # e0: the case's, or sigma_y / (3 mu) of a flow-curve law (swift, table) that states no e0.
    e0 = summary.get("material", {}).get("e0") if summary else None
    e0s = [e0 or case["material"].get("e0")] + [(materials[r] if r < len(materials) else {}).get("e0")
                                                for r in range(1, regions)]
    normalised = all(e0s)
    scales = np.array([e if normalised else 1.0 for e in e0s])
    a = max(float(row["a"]), 1e-300)
    nx, ny = structured(xy)
    grid = lambda v: v.reshape(nx, ny)  # noqa: E731
    bands = region_bands(quads, fields["region"], ny, regions)
    # Each region's nodal e_u/e0 and yielded fraction on its own band of node rows.
    nodal = [None if band is None else region_nodal(fields, r, band, ny) for r, band in enumerate(bands)]
    ratios = [None if n is None else n[0] / (e0s[r] if e0s[r] else 1.0) for r, n in enumerate(nodal)]
    # The window follows the zone: the contact and where e_u >= e0 or the material has yielded.
    zone = np.zeros((nx, ny), bool)
    for reg, (band, ratio, n) in enumerate(zip(bands, ratios, nodal)):
        if band is not None and not (models[reg] == "elastic" and not all(m == "elastic" for m in models)):
            zone[:, band[0]:band[1] + 1] |= (ratio >= 1.0) | (n[1] >= 0.5)
    zone = zone.ravel()
    reach = max([a] + np.abs(xy[zone]).max(axis=1).tolist()) if zone.any() else a
    window = 1.3 * reach if zone.any() else 3 * a
    keep = [q for q in range(len(quads))
            if xy[quads[q], 0].min() <= window and xy[quads[q], 1].max() >= -window]
    values = (fields["e_u"] / scales[fields["region"]])[keep]
    positive = values[values > 0]
    vmax = float(values.max()) if len(values) else 1.0
    # A field the tip dominates (its maximum ten times the median, as under a cone or deep in the
    # plastic range) on a logarithmic scale over three decades; else linear from 0.
    log = len(positive) > 0 and (vmax > 10 * float(np.median(positive)) or vmax > 10)
    norm = LogNorm(vmin=max(float(positive.min()), vmax * 1e-3), vmax=vmax) if log else Normalize(vmin=0, vmax=vmax)
    strip = None
    if coated and size == "column":  # a coated specimen's longer legend in a strip below the panel
        entries = 5 + 2 * (regions - 1) + unloaded
        fig, axes, strip = ip.figure(size, legend_row=ip.legend_height(entries, size))
    else:
        fig, axes = ip.figure(size)
    ax = axes[0]
    polys = np.array([units.position(deformed[quads[q]]) for q in keep])
    mirrored = polys.copy()
    mirrored[:, :, 0] *= -1
    cells = PolyCollection(np.concatenate([polys, mirrored]), array=np.concatenate([values, values]),
                           cmap="viridis", norm=norm, edgecolors="face", linewidths=0.3, antialiased=False)
    ax.add_collection(cells)
    what = "e$_u$/e$_0$" if normalised else "e$_u$"
    # Where the maximum is: the centre of its element (deformed), named in the colour bar's label.
    top = keep[int(np.argmax(values))]
    cx, cz = units.position(deformed[quads[top]].mean(axis=0))
    r = "r" if scene.axisymmetric else "x"
    where = f"{r} = {ip.number(abs(cx), 2)}, z = {ip.number(cz, 2)} {units.position.name}"
    if size == "slide" and coated:  # each element over its own region's e0 (the legend names them)
        label = f"strain intensity {'e$_u$ / its region’s e$_0$' if normalised else what}\n" + \
            ("log scale; " if log else "") + f"max {ip.number(vmax, 3)} in the {names[fields['region'][top]]}" + \
            f"\nat {where}"
    elif size == "slide":
        label = f"strain intensity {what}" + (", log scale" if log else "") + \
            f"\n(max {ip.number(vmax, 3)} at {where})"
    else:
        label = f"{what}" + (" (log)" if log else "") + f"; max {ip.number(vmax, 3)}"
    bar = fig.colorbar(cells, ax=ax, label=label, extend="min" if log and float(positive.min()) < vmax * 1e-3
                       else "neither", shrink=0.95, pad=0.02)
    bar.ax.tick_params(labelsize=plt.rcParams["ytick.labelsize"])
    if log:
        bar.ax.yaxis.set_major_formatter(plt.FuncFormatter(lambda v, _: ip.number(v, 3)))
    # The yield outline: e_u = e0 on the nodal field (Gauss-point values extrapolated and averaged),
    # contoured on the deformed mesh, both halves; region by region, each on its own band.
    X, Y = grid(units.position(deformed[:, 0])), grid(units.position(deformed[:, 1]))
    handles = []
    lw = plt.rcParams["lines.linewidth"]
    outline = [patheffects.withStroke(linewidth=lw * 1.6, foreground="black")]
    all_elastic = all(m == "elastic" for m in models)
    top_down = list(range(1, regions)) + [0]  # the regions from the surface down: layer 1, 2, ..., the substrate
    drawn = set()  # "yield", "elastic": the kinds of outline drawn
    plastic_names = [names[reg] for reg in top_down if models[reg] != "elastic"]
    for reg in top_down:  # from the surface down
        band, ratio = bands[reg], ratios[reg]
        if band is None or not e0s[reg] or ratio.max() < 1.0:
            continue
        elastic_region = models[reg] == "elastic"
        if coated and elastic_region and not all_elastic:
            continue  # its e0 is its block's (0.027 unless set), no yield: the colour's scale only
        style = "--" if elastic_region else "-"
        rows = slice(band[0], band[1] + 1)
        for sign in (1, -1):
            contour = ax.contour(sign * X[:, rows], Y[:, rows], ratio, levels=[1.0], colors="white",
                                 linewidths=lw * 0.9, linestyles=style)
            plt.setp(contour.collections, path_effects=outline)
        if not coated:
            handles.append(Line2D([], [], color="white", lw=lw * 0.9, ls=style, path_effects=outline,
                                  label="e$_u$ = e$_0$" + (": where a plastic law would yield" if elastic_region
                                                           else "" if unloaded else " (yield)")))
        elif ("elastic" if elastic_region else "yield") not in drawn:
            drawn.add("elastic" if elastic_region else "yield")
            whose = "each region's" if len(plastic_names) != 1 else f"the {plastic_names[0]}'s"
            handles.append(Line2D([], [], color="white", lw=lw * 0.9, ls=style, path_effects=outline,
                                  label="e$_u$ = e$_0$" + (" of each region: where a plastic law would yield"
                                                           if elastic_region else f" ({whose} e$_0$)" if unloaded
                                                           else f" ({whose} yield)")))
    # An elastic region of a coated specimen with a plastic one: hatched (it never yields).
    D = deformed.reshape(nx, ny, 2)
    shown = [i for i in range(nx) if i == 0 or xy[(i - 1) * ny, 0] <= window]  # the window and one column more
    for reg in top_down:
        if not coated or all_elastic or models[reg] != "elastic" or bands[reg] is None:
            continue
        lo, hi = bands[reg]
        upper, lower = units.position(D[shown, hi]), units.position(D[shown, lo])
        flip = np.array([-1.0, 1.0])
        polygon = np.concatenate([upper[::-1] * flip, upper, lower[::-1], lower * flip])
        ax.add_patch(Polygon(polygon, closed=True, fill=False, hatch="//", edgecolor=(1, 1, 1, 0.55), lw=0,
                             zorder=2.5))
        handles.append(Patch(fill=False, hatch="//", edgecolor="#777777", lw=0,
                             label=f"elastic {names[reg]} (never yields)"))
    yielded_drawn = False
    for reg in top_down:
        if models[reg] != "j2" or not unloaded or bands[reg] is None or nodal[reg][1].max() < 0.5:
            continue
        rows = slice(bands[reg][0], bands[reg][1] + 1)
        for sign in (1, -1):
            contour = ax.contour(sign * X[:, rows], Y[:, rows], nodal[reg][1], levels=[0.5], colors=ip.PURPLE,
                                 linewidths=lw * 0.8, linestyles="--")
            plt.setp(contour.collections, path_effects=outline)
        if not yielded_drawn:
            handles.append(Line2D([], [], color=ip.PURPLE, lw=lw * 0.8, ls="--", path_effects=outline,
                                  label="has yielded (plastic strain > 0)"))
            yielded_drawn = True
    # The interfaces: each a row of nodes, followed where it has moved (MODEL.md §14.3).
    halo = [patheffects.withStroke(linewidth=lw * 1.5, foreground="white")]
    for k, layer in enumerate(ip.layers_of(case, summary) if coated else [], start=1):
        depth = layer["bottom_depth"]
        if k < len(bands) and bands[k] is not None:
            j = bands[k][0]
        else:  # the fields hold no such region: the node row nearest the interface's depth
            j = int(np.argmin(np.abs(grid(xy[:, 1])[0] + depth)))
        line = units.position(D[shown, j])
        below = names[k + 1] if k + 1 < regions else names[0]
        style = ["-.", (0, (6, 2, 1, 2, 1, 2)), ":"][(k - 1) % 3]
        ax.plot(np.concatenate([-line[::-1, 0], line[:, 0]]), np.concatenate([line[::-1, 1], line[:, 1]]),
                ls=style, color=ip.BLACK, lw=lw, path_effects=halo, zorder=4)
        handles.append(Line2D([], [], ls=style, color=ip.BLACK, lw=lw, path_effects=halo,
                              label=f"interface ({names[k]} / {below}), {units.position.text(depth)} deep" +
                              (" (below the view)" if depth > window * 1.001 else "")))
    h = float(row["alpha"])
    xs = np.linspace(0, window, 400)
    punch = [(x, scene.punch_height(x)) for x in xs if scene.punch_height(x) is not None]
    px = units.position(np.array([x for x, _ in punch]))
    pz = units.position(np.array([g - h for _, g in punch]))
    ax.plot(np.concatenate([-px[::-1], px]), np.concatenate([pz[::-1], pz]), "-", color=ip.THEORY, lw=lw * 1.1,
            zorder=5)
    handles.append(Line2D([], [], color=ip.THEORY, lw=lw * 1.1, label="indenter"))
    w = units.position(window)
    ax.set_xlim(-w, w)
    ax.set_ylim(-w, 0.15 * w)
    ax.set_aspect("equal")
    ax.grid(False)
    ax.set_facecolor("#f4f4f4")
    ax.set_xlabel(f"{'radial coordinate $r$' if scene.axisymmetric else '$x$'} [{units.position.name}]" +
                  (" (deformed mesh, mirrored about the axis)" if size == "slide" else ""))
    ax.set_ylabel(f"$z$ [{units.position.name}] (deformed)")
    count = int(np.count_nonzero(fields["plastic"] > 0))
    yielded = f"{count} of {len(quads)} elements yielded" if not all_elastic else "an elastic run, no yield"
    if coated and not all_elastic:
        yielded += " (" + ", ".join(
            f"{names[reg]} {int(np.count_nonzero((fields['plastic'] > 0) & (fields['region'] == reg)))}"
            for reg in top_down if models[reg] != "elastic") + ")"
    title = f"{'plastic zone' if not all_elastic else 'strain intensity'} at $h$ = {units.depth.text(h)} " \
        f"(step {row['step']}" + \
        (f", unloaded from {units.depth.text(deepest)}" if unloaded else "") + f"): {yielded}"
    # A coated specimen's legend is titled with each region's e0, the colour's divisor.  (It hides
    # the left half's lower corner, interfaces included: the right half shows them, mirrored.)
    divisors = None
    if coated:
        divisors = "e$_0$: " + ", ".join(
            f"{names[reg]} {ip.number(e0s[reg], 3) if e0s[reg] else '–'}" +
            (" (elastic: a scale)" if e0s[reg] and models[reg] == "elastic" and not all_elastic else "")
            for reg in top_down)
        divisors = textwrap.fill(divisors, 44 if size == "slide" else 60, break_long_words=False)
    if strip is not None:
        strip.legend(handles=handles, loc="center", frameon=False, title=divisors)
    else:
        ax.legend(handles=handles, loc="lower left", facecolor="#ffffff", framealpha=0.95, title=divisors)
    ip.run_title(fig, title, ip.describe_run(case, summary))
    ip.save(fig, outdir, "plastic_zone")


# --- analysis.png ---------------------------------------------------------------------------------

def analysis_case(report):
    """A load case's worth of words from analysis.json: the run's own case.toml where it is there."""
    curve = pathlib.Path(report.get("curve", ""))
    if report.get("origin") == "run" and (curve.parent / "case.toml").is_file():
        case = tomllib.loads((curve.parent / "case.toml").read_text())
        summary_file = curve.parent / "summary.json"
        summary = json.loads(summary_file.read_text()) if summary_file.is_file() else {}
        return case, summary, curve.parent
    ind = report.get("indenter", {})
    punch = {"shape": ind.get("shape", "sphere")}
    if "half_angle_degrees" in ind:
        punch["half_angle"] = ind["half_angle_degrees"]
    for k in ("tip_radius", "radius", "profile", "area_coefficients"):
        if k in ind:
            punch[k] = ind[k]
    return {"geometry": {"kind": report.get("scene", "axisymmetric")}, "punch": punch}, {}, None


def plot_analysis(path, size):
    """The Oliver-Pharr analysis of analysis.json: the whole curve, each unloading branch with its
    power-law fit, the stiffness S as the tangent at h_max, h_f, h_c and h_max marked, and the
    numbers beside; a coated run with two or more branches, also the substrate effect
    (plot_substrate_effect) in a last row."""
    report = json.loads(path.read_text())
    depth = np.array(report["curve_si"]["depth"], float)
    force = np.array(report["curve_si"]["force"], float)
    time = np.array(report["curve_si"]["time"], float) if "time" in report["curve_si"] else None
    axi = report["scene"] == "axisymmetric"
    case, summary, run = analysis_case(report)
    branches = report["branches"]
    if run is not None:
        units = ip.RunUnits.of_run(run)
        rows = read_csv(run / "curve.csv")
        same = len(rows) == len(depth) and "contact_nodes" in rows[0]  # curve_si is the run's curve.csv
        nodes = column_of(rows, "contact_nodes", 1.0) if same else None
        title = ip.describe_run(case, summary)
    else:
        contact = np.zeros_like(depth)
        if branches:
            contact[branches[0]["index"]["peak"]] = max(b["contact_radius"] or 0.0 for b in branches)
        units = ip.RunUnits.of_curve(depth, force, contact, axi)
        nodes = None
        title = f"{pathlib.Path(report['curve']).name}, measured; {ip.indenter_words(case)}; " \
                f"{'axisymmetric' if axi else 'plane strain'}"
    # A coated run's E is the whole stack's apparent modulus, through the surface layer's ν
    # (analysis.json: specimen_nu; MODEL.md §14.1): the table says so.
    layers = ip.layers_of(case, summary) if run is not None else []
    e_label = "$E$ (specimen)"
    if layers:
        nu = report.get("specimen_nu", layers[0]["material"].get("nu"))
        e_label = "$E$ (ν$_\\mathrm{film}$" if len(layers) == 1 else "$E$ (ν$_1$"  # layer 1's, at the surface
        e_label += f" = {ip.number(nu, 3)})" if nu is not None else ")"
    n = max(len(branches), 1)
    slide = size == "slide"
    # A coated run with several branches (a multi-cycle load path): a last row, the substrate effect
    # (E_r and H against h_max/t; MODEL.md §14.4).  Any other run: the figure as it always was.
    substrate_effect = bool(layers) and len(branches) >= 2
    if substrate_effect:
        fig, axes, effect_axes = substrate_effect_layout(n, slide)
    elif slide:
        fig, axes = plt.subplots(n, 3, figsize=(ip.SLIDE_WIDTH, ip.SLIDE_WIDTH * 9 / 16 * (1 + 0.8 * (n - 1))),
                                 squeeze=False, width_ratios=[0.85, 1.1, 1.05])
    else:
        fig, axes = plt.subplots(3 * n, 1, figsize=(ip.COLUMN_WIDTH, 7.4 * n), squeeze=False,
                                 height_ratios=[1, 1, 1.15] * n)
        axes = [[axes[3 * k][0], axes[3 * k + 1][0], axes[3 * k + 2][0]] for k in range(n)]
    h, P = units.depth(depth), units.force(force)
    lw = plt.rcParams["lines.linewidth"]
    for (whole, ax, table_ax), b in zip(axes, branches):
        i0, ip_, ie = b["index"]["loading_start"], b["index"]["peak"], b["index"]["end"]
        fit = b["fit"]
        h_f, h_max, P_max = fit["h_f"], b["h_max"], b["P_max"]
        S = b["S_fit"]
        lo, hi = fit["range"]
        # Left: the whole curve, as computed (a run) or as measured.
        if nodes is not None:
            ip.draw_load_depth(whole, depth, force, nodes, units, markers=len(depth) < 200, separated_label=False)
        else:
            whole.plot(h, P, "-", lw=lw * 0.5, color="#bbbbbb")
            whole.plot(h[i0:ip_ + 1], P[i0:ip_ + 1], "-", lw=lw * 0.8, color=ip.LOADING, label="loading")
            whole.plot(h[ip_:ie + 1], P[ip_:ie + 1], "-", lw=lw * 0.8, color=ip.UNLOADING, label="unloading")
        if len(branches) > 1:  # which of the branches this row of panels analyses
            touching_rows = [k for k in range(ip_, ie + 1) if P[k] > 0]
            whole.plot(h[touching_rows], P[touching_rows], "-", color=ip.UNLOADING, lw=lw * 4, alpha=0.3, zorder=1,
                       solid_capstyle="round", label="this branch")
        whole.set_xlabel(f"depth $h$ [{units.depth.name}]")
        whole.set_ylabel(units.force_axis())
        whole.set_title("whole curve")
        whole.set_xlim(left=0)
        whole.legend(loc="upper left", fontsize=plt.rcParams["legend.fontsize"] * 0.9)
        hold = b.get("hold")
        if hold and time is not None:
            # The hold before this unloading: its creep, depth against time (inset, lower right).
            k0, k1 = hold["start_index"], ip_
            inset = whole.inset_axes([0.5, 0.12, 0.36, 0.34])
            t0, h0 = time[k0], depth[k0]
            inset.plot(time[k0:k1 + 1] - t0, units.depth(depth[k0:k1 + 1] - h0), "-o", color=ip.LOADING,
                       ms=plt.rcParams["lines.markersize"] * 0.5, lw=lw * 0.7)
            small = plt.rcParams["legend.fontsize"] * 0.8
            inset.set_xlabel("hold time [s]", fontsize=small, labelpad=1)
            inset.set_ylabel(f"creep [{units.depth.name}]", fontsize=small, labelpad=1)
            inset.tick_params(labelsize=small * 0.9, pad=1)
            inset.set_title("hold", fontsize=small, pad=2)
        # Middle: the unloading branch, the fit over its range, S as the tangent at h_max (it
        # meets the depth axis at h_max - P_max / S), and h_f, h_c, h_max.
        touching = slice(ip_, ie + 1)
        hs, Ps = h[touching], P[touching]
        on = Ps > 0 if nodes is not None else np.ones_like(Ps, bool)
        dense = on.sum() > 60  # a measured branch: small markers under the fit
        ax.plot(hs[on], Ps[on], "o", color=ip.UNLOADING, label="unloading", zorder=2 if dense else 4,
                ms=plt.rcParams["lines.markersize"] * (0.45 if dense else 1.0))
        left = min(h_f, h_max - P_max / S) - 0.12 * (h_max - min(h_f, h_max - P_max / S))
        off = ~on & (hs >= units.depth(left))
        if off.any():
            ax.plot(hs[off], Ps[off], "x", color=ip.SEPARATED, label="separated (P = 0)", zorder=4, clip_on=False)
        xs = np.linspace(h_f, h_max, 200)
        ax.plot(units.depth(xs), units.force(fit["B"] * (xs - h_f) ** fit["m"]), "-", color=ip.BLACK, lw=lw * 0.8,
                label=f"fit $B(h - h_\\mathrm{{f}})^m$, $m$ = {fit['m']:.3g}",
                zorder=3)
        h0 = h_max - P_max / S
        ax.plot(units.depth(np.array([h0, h_max])), units.force(np.array([0, P_max])), "--", color=ip.THEORY,
                lw=lw * 0.8, label=f"$S$ = {units.stiffness.text(S)}, tangent", zorder=3)
        # h_f, h_c and h_max: dotted lines, named on a second depth axis along the top.
        marks = [h_f, b["h_c"], h_max]
        for x in marks:
            ax.axvline(units.depth(x), color="#777777", ls=":", lw=1)
        top = ax.secondary_xaxis("top")
        top.set_xticks([units.depth(x) for x in marks], ["$h_\\mathrm{f}$", "$h_\\mathrm{c}$", "$h_\\mathrm{max}$"])
        top.tick_params(length=0, pad=2)
        left = min(h_f, h0) - 0.12 * (h_max - min(h_f, h0))
        ax.set_xlim(units.depth(left), units.depth(h_max + 0.05 * (h_max - left)))
        ax.set_ylim(0, units.force(P_max) * 1.08)
        ax.set_xlabel(f"depth $h$ [{units.depth.name}]")
        ax.set_ylabel(units.force_axis())
        ax.set_title(f"unloading, {b['where'].replace('-', '–')}")
        ax.legend(loc="upper left", fontsize=plt.rcParams["legend.fontsize"] * 0.9)
        # Right: the numbers, in the figures' units.
        hardness = ip.stress_unit(b["H"])
        modulus = units.modulus
        area_unit = units.position
        rows = [("$P_\\mathrm{max}$", units.force.text(P_max, 4)), ("$h_\\mathrm{max}$", units.depth.text(h_max, 4)),
                ("$S$ (fit)", units.stiffness.text(S, 4)),
                ("$S$ (exact)", "–" if b["S_exact"] is None else units.stiffness.text(b["S_exact"], 4)),
                ("fit exponent $m$", f"{fit['m']:.4g}"),
                ("fit range", f"{100 * lo:g}–{100 * hi:g}% of $P_\\mathrm{{max}}$"),
                ("ε, β", f"{b['epsilon']:g}, {b['beta']:g}"), ("$h_\\mathrm{c}$", units.depth.text(b["h_c"], 4)),
                ("$h_\\mathrm{f}$", units.depth.text(h_f, 4)),
                ("$A_\\mathrm{c}$" if axi else "$2a(h_\\mathrm{c})$",
                 f"{ip.number(b['A_c'] / area_unit.scale**2, 4)} {area_unit.name}²" if axi
                 else area_unit.text(b["A_c"], 4)),
                ("$H$", hardness.text(b["H"], 4)),
                ("$E_\\mathrm{r}$", "– (plane strain)" if b["E_r"] is None and not axi
                 else ("–" if b["E_r"] is None else modulus.text(b["E_r"], 4))),
                (e_label, "–" if b["E"] is None else modulus.text(b["E"], 4)),
                ("$W_\\mathrm{e}/W_\\mathrm{t}$", f"{b['W_e_over_W_t']:.3f}")]
        if b.get("pile_up_ratio") is not None:
            rows += [("$a$ (true contact)", area_unit.text(b["true_contact_radius"], 4)),
                     ("$H$ (true area)", hardness.text(b["true_H"], 4)),
                     ("$E_\\mathrm{r}$ (true area)",
                      "–" if b["true_E_r"] is None else modulus.text(b["true_E_r"], 4)),
                     ("$A_\\mathrm{true}/A_\\mathrm{c}$",
                      f"{b['pile_up_ratio']:.3f} ({'pile-up' if b['pile_up_ratio'] > 1 else 'sink-in'})")]
        if hold:
            rows += [("creep in the hold", f"{units.depth.text(hold['creep_depth'], 4)} in {hold['duration_s']:.3g} s")]
            if hold.get("S_corrected") is not None:
                rows += [("$S$ (Feng–Ngan)", units.stiffness.text(hold["S_corrected"], 4))]
            if hold.get("E_corrected") is not None:
                rows += [("$E$ (Feng–Ngan)", modulus.text(hold["E_corrected"], 4))]
            if hold.get("stress_exponent") is not None:
                rows += [("creep exponent $n$", f"{hold['stress_exponent']:.3g}")]
        table_ax.axis("off")
        table = table_ax.table(cellText=[[k, v] for k, v in rows], colLabels=["Oliver-Pharr", "(this branch)"],
                               cellLoc="left", colWidths=[0.47, 0.53], edges="horizontal", bbox=[0, 0, 1, 1])
        table.auto_set_font_size(False)
        table.set_fontsize(plt.rcParams["legend.fontsize"] * (0.95 if slide else 1.0))
        for (r, _), cell in table.get_celld().items():
            cell.set_edgecolor("#cccccc")
            if r == 0:
                cell.get_text().set_fontweight("bold")
    if not branches:
        axes[0][0].text(0.5, 0.5, "no unloading branch", ha="center", transform=axes[0][0].transAxes)
    if substrate_effect:
        plot_substrate_effect(*effect_axes, branches, layers, ip.region_materials(case, summary)[0],
                              report.get("indenter", {}), axi, slide)
    ip.run_title(fig, title)
    stem = path.with_suffix("")
    ip.save(fig, stem.parent, stem.name)


# Gao, Chiu and Lee (Int. J. Solids Struct. 29, 1992): a film of thickness t on a substrate under a
# flat punch of radius a, to first order in their mismatch; as src/analysis/coating_analysis.cpp
# (docs/MODEL.md §14.4).

def gao_weights(x, nu):
    """Gao's weights (I0, I1) at x = t/a, ν the substrate's (the zeroth order)."""
    # x ln((1 + x^2)/x^2) -> 0 as x -> 0: written with log1p.
    x_log = x * math.log1p(1.0 / (x * x)) if x > 0 else 0.0
    i0 = 2 / math.pi * math.atan(x) + ((1 - 2 * nu) * x_log - x / (1 + x * x)) / (2 * math.pi * (1 - nu))
    i1 = 2 / math.pi * math.atan(x) + x_log / math.pi
    return i0, i1


def gao_contact_modulus(film, below, x):
    """The coated specimen's contact modulus E* = 2μ/(1 - ν) [Pa] by Gao's model at x = t/a, with
    μ = μ_s + (μ_f - μ_s) I0 and ν = ν_s + (ν_f - ν_s) I1; film and below are material blocks."""
    nu_f, nu_s = film.get("nu", 0.3), below.get("nu", 0.3)
    i0, i1 = gao_weights(x, nu_s)
    mu_f, mu_s = film["E"] / (2 * (1 + nu_f)), below["E"] / (2 * (1 + nu_s))
    mu, nu = mu_s + (mu_f - mu_s) * i0, nu_s + (nu_f - nu_s) * i1
    return 2 * mu / (1 - nu)


def substrate_effect_layout(n, slide):
    """The analysis figure of a coated run with n >= 2 branches: the n rows of a branch's three panels
    and a last row of two, the apparent E_r and H against h_max/t: (fig, axes, (ax_E, ax_H))."""
    if slide:
        fig = plt.figure(figsize=(ip.SLIDE_WIDTH, ip.SLIDE_WIDTH * 9 / 16 * (1 + 0.8 * (n - 1) + 1.0)))
        grid = fig.add_gridspec(n + 1, 3, width_ratios=[0.85, 1.1, 1.05], height_ratios=[1] * n + [1.25])
        axes = [[fig.add_subplot(grid[k, j]) for j in range(3)] for k in range(n)]
        last = grid[n, :].subgridspec(1, 2, width_ratios=[1.15, 0.85])
        return fig, axes, (fig.add_subplot(last[0, 0]), fig.add_subplot(last[0, 1]))
    fig, column = plt.subplots(3 * n + 2, 1, figsize=(ip.COLUMN_WIDTH, 7.4 * n + 5.4), squeeze=False,
                               height_ratios=[1, 1, 1.15] * n + [1.25, 1])
    axes = [[column[3 * k][0], column[3 * k + 1][0], column[3 * k + 2][0]] for k in range(n)]
    return fig, axes, (column[3 * n][0], column[3 * n + 1][0])


def plot_substrate_effect(ax_e, ax_h, branches, layers, substrate, indenter, axi, slide):
    """The substrate effect over a coated run's unloading branches (MODEL.md §14.4): the apparent
    reduced modulus E_r (Oliver-Pharr, and at the true contact) against h_max/t, t the top film's
    thickness, between the film's own and the region below's E/(1 - ν²) (dotted), with Gao, Chiu
    and Lee's model at each branch's a/t (the Oliver-Pharr a, and the true one); and the hardness H
    (Oliver-Pharr and true) against h_max/t.  An elastic indenter's (analysis.json: indenter.E)
    compliance is added to the references and the model: they are then E_r's, as the data are."""
    t = layers[0]["thickness"]
    film = layers[0]["material"]
    below = layers[1]["material"] if len(layers) > 1 else substrate
    names = ip.region_names(len(layers) + 1)
    film_name, below_name = names[1], (names[2] if len(layers) > 1 else names[0])
    lw = plt.rcParams["lines.linewidth"]
    small = plt.rcParams["legend.fontsize"]
    ms = plt.rcParams["lines.markersize"] * 1.3

    def coating(b, key, si):
        """The branch's coating.KEY (analysis.json), or its SI / t."""
        c = b.get("coating") or {}
        if c.get(key) is not None:
            return c[key]
        return b[si] / t if b.get(si) is not None else None

    rows = sorted(branches, key=lambda b: coating(b, "h_max_over_t", "h_max"))
    x = np.array([coating(b, "h_max_over_t", "h_max") for b in rows], float)
    a_over_t = [coating(b, "contact_radius_over_t", "contact_radius") for b in rows]
    log_x = x.min() > 0 and x.max() / x.min() >= 8  # as the sweep's figure
    # The indenter's compliance (1 - ν_i²)/E_i, which E_r holds beside the specimen's.
    indenter_E = indenter.get("E")
    compliance = (1 - indenter.get("nu", 0.07) ** 2) / indenter_E if isinstance(indenter_E, (int, float)) else 0.0

    def reduced(e_star):
        return 1.0 / (1.0 / e_star + compliance)

    # Their own E/(1 - ν²); under an elastic indenter their own E_r against it, as the data are.
    modulus = "own $E_\\mathrm{r}$" if compliance else "own $E/(1-ν^2)$"
    gpa = ip.Unit("GPa", 1e9)

    def series(ax, key, true_key, unit):
        """The Oliver-Pharr values and the true contact's against h_max/t (where there are any)."""
        drawn = False
        for k, label, marker, colour in ((key, "Oliver–Pharr", "o", ip.LOADING),
                                         (true_key, "true contact", "s", ip.RELOADING)):
            pairs = [(xi, b[k]) for xi, b in zip(x, rows) if b.get(k) is not None]
            if pairs:
                ax.plot([p[0] for p in pairs], [unit(p[1]) for p in pairs], "-" + marker, color=colour, ms=ms,
                        lw=lw * 0.6, label=label, zorder=4)
                drawn = True
        return drawn

    # Left: E_r, the film's and the region below's references, Gao's model.
    panels = [ax_h]
    if series(ax_e, "E_r", "true_E_r", gpa):
        panels.insert(0, ax_e)
        if axi:
            gao = [reduced(gao_contact_modulus(film, below, 1.0 / r)) if r else None for r in a_over_t]
            pairs = [(xi, g) for xi, g in zip(x, gao) if g is not None]
            ax_e.plot([p[0] for p in pairs], [gpa(p[1]) for p in pairs], "-", color=ip.THEORY, lw=lw,
                      label="Gao, Chiu & Lee 1992 at $a/t$", zorder=3)
            true_a = [b.get("true_contact_radius") for b in rows]
            if any(true_a) and any(b.get("true_E_r") is not None for b in rows):
                pairs = [(xi, reduced(gao_contact_modulus(film, below, t / a))) for xi, a in zip(x, true_a) if a]
                ax_e.plot([p[0] for p in pairs], [gpa(p[1]) for p in pairs], "--", color=ip.THEORY, lw=lw * 0.8,
                          label="Gao, Chiu & Lee 1992 at the true $a/t$", zorder=3)
        # The references, dotted, named on a second E axis at the right (clear of the data).
        references = [(words, gpa(reduced(ip.e_star(m)))) for words, m in ((film_name, film), (below_name, below))
                      if m.get("E")]
        for k, (_, y) in enumerate(references):
            ax_e.axhline(y, color="#777777", ls=":", lw=1.2, zorder=2,
                         label=None if k else f"{', '.join(w for w, _ in references)}: {modulus}")
        if references:
            lo, hi = ax_e.get_ylim()
            lo, hi = min([lo] + [y for _, y in references]), max([hi] + [y for _, y in references])
            ax_e.set_ylim(lo - 0.05 * (hi - lo), hi + 0.05 * (hi - lo))
            right = ax_e.secondary_yaxis("right")
            right.set_yticks([y for _, y in references],
                             [f"{words}\n{ip.number(y, 3)} {gpa.name}" for words, y in references])
            right.get_yaxis().set_minor_locator(plt.NullLocator())
            right.tick_params(labelsize=small * 0.95, colors="#555555", pad=2)
        # The legend under the panel (below its depth axis's label), where it hides neither the data
        # nor the references: two columns on a slide, one in a journal column.
        under = transforms.offset_copy(ax_e.transAxes, ax_e.figure, y=-3.0 * plt.rcParams["axes.labelsize"],
                                       units="points")
        ax_e.legend(loc="upper center", bbox_to_anchor=(0.5, 0.0), bbox_transform=under,
                    ncol=2 if slide else 1, fontsize=small * 0.95)
        ax_e.set_ylabel(f"$E_\\mathrm{{r}}$ [{gpa.name}]")
    else:  # plane strain: no E_r; the panel says so, as the sweep's empty panels do
        ax_e.text(0.5, 0.5, "no reduced modulus $E_\\mathrm{r}$" + (" in plane strain" if not axi else ""),
                  ha="center", va="center", transform=ax_e.transAxes, color="#555555", fontsize=small)
        ax_e.set_xticks([])
        ax_e.set_yticks([])
        for spine in ax_e.spines.values():
            spine.set_color("#dddddd")
    ax_e.set_title("substrate effect: reduced modulus")
    # Right: the hardness, Oliver-Pharr and true.
    hardness = [v for b in rows for v in (b.get("H"), b.get("true_H")) if v is not None]
    h_unit = ip.stress_unit(max(hardness)) if hardness else gpa
    if series(ax_h, "H", "true_H", h_unit):
        ax_h.legend(loc="best", fontsize=small * 0.95)
    ax_h.set_title("substrate effect: hardness")
    ax_h.set_ylabel(f"hardness $H$ [{h_unit.name}]")
    for ax in panels:
        ax.set_xlabel(f"$h_\\mathrm{{max}}/t$ ($t$ = {ip.length_unit(t).text(t)}, {film_name})")
        if log_x:
            ax.set_xscale("log")
            ax.set_xticks(x)
            ax.get_xaxis().set_minor_formatter(plt.NullFormatter())
            ax.get_xaxis().set_major_formatter(plt.FuncFormatter(lambda v, _: ip.number(v, 2)))
        # Each branch's a/t (the Oliver-Pharr contact radius), where Gao's model is evaluated.
        top = ax.secondary_xaxis("top")
        top.set_xticks([xi for xi, r in zip(x, a_over_t) if r], [ip.number(r, 2) for r in a_over_t if r])
        top.get_xaxis().set_minor_locator(plt.NullLocator())
        top.tick_params(labelsize=small * 0.9, pad=1)
        top.set_xlabel("$a/t$ (Oliver–Pharr $a$)" if axi else "$a/t$ ($a$ the half-width)", fontsize=small,
                       labelpad=2)


# --- sweep.png ------------------------------------------------------------------------------------

def as_number(text):
    try:
        return float(text)
    except (TypeError, ValueError):
        return None


def sweep_case(folder, manifest):
    """The load case of the sweep's first run, for the figure's words: the manifest's own copy
    (indentsim_sweep 1), the run's kept case.toml, or the base case with [set] and the run's
    values applied (the base found as the sweep named it, from the folder it was started in);
    {} when none is found."""
    runs = manifest.get("runs") or []
    if not runs:
        return {}
    first = runs[0]
    if first.get("case"):
        return tomllib.loads(first["case"])
    kept = folder / "runs" / first["hash"] / "case.toml"
    if kept.is_file():
        return tomllib.loads(kept.read_text())
    base = pathlib.Path(manifest.get("base", ""))
    candidates = [base]
    out = pathlib.Path(manifest.get("out", ""))
    if not base.is_absolute() and not out.is_absolute() and out.parts:
        # The folder the sweep was started in: the results folder less its `out` path.
        started = folder.resolve()
        for _ in out.parts:
            started = started.parent
        candidates.append(started / base)
    for candidate in candidates:
        if candidate.is_file():
            try:
                case = tomllib.loads(candidate.read_text())
                for assignment in list(manifest.get("set", [])) + [f"{k}={v}" for k, v in
                                                                    zip(manifest.get("keys", []), first["values"])]:
                    key, value = assignment.split("=", 1)
                    *sections, name = key.strip().strip('"').split(".")
                    table = case
                    for section in sections:
                        table = table.setdefault(section, {})
                    table[name] = tomllib.loads(f"v = {value}")["v"]
                return case
            except (tomllib.TOMLDecodeError, ValueError, AttributeError):
                return {}
    return {}


def plot_sweep(folder, size):
    """FOLDER/figures/sweep.png and .svg: H, E_r (plane strain: the peak load) and the pile-up
    ratio against the swept keys, from results.csv (and manifest.json for the case's words)."""
    manifest_file = folder / "manifest.json"
    manifest = json.loads(manifest_file.read_text()) if manifest_file.is_file() else {}
    with open(folder / "results.csv", newline="") as f:
        header = next(csv.reader(f), [])
    # The swept keys: the manifest's, or results.csv's columns between hash and status.
    keys = manifest.get("keys") or header[header.index("hash") + 1:header.index("status")]
    rows = read_csv(folder / "results.csv")
    done = [r for r in rows if r["status"] == "finished"]
    # The pile-up ratio: results.csv's column, or (older sweeps) each run's kept summary.json.
    pile_up = {}
    for r in done:
        if r.get("pile_up_ratio"):
            pile_up[r["hash"]] = float(r["pile_up_ratio"])
            continue
        s = folder / "runs" / r["hash"] / "summary.json"
        if s.is_file():
            unloading = json.loads(s.read_text()).get("unloading") or []
            analysis = unloading[0].get("analysis") if unloading else None
            if analysis and analysis.get("pile_up_ratio") is not None:
                pile_up[r["hash"]] = analysis["pile_up_ratio"]
    base_case = sweep_case(folder, manifest)
    numeric = {k: all(as_number(r[k]) is not None for r in rows) for k in keys}
    distinct = {k: sorted({r[k] for r in rows}, key=lambda v: (as_number(v) is None, as_number(v) or 0, v))
                for k in keys}
    # x: the first numeric key with the most values; lines: the values of the next key.
    order = sorted(keys, key=lambda k: (-numeric[k], -len(distinct[k]), keys.index(k)))
    x_key = order[0]
    others = [k for k in keys if k != x_key]
    x_values = [as_number(v) for v in distinct[x_key]] if numeric[x_key] else list(range(len(distinct[x_key])))
    x_label, x_unit = ip.key_axis(x_key, [v for v in x_values if v is not None])

    def x_of(r):
        return x_unit(as_number(r[x_key])) if numeric[x_key] else distinct[x_key].index(r[x_key])

    def group_of(r):
        return tuple(r[k] for k in others)

    groups = sorted({group_of(r) for r in rows}, key=lambda g: tuple(as_number(v) or 0 for v in g))
    latin = len(groups) > 8 or all(sum(1 for r in rows if group_of(r) == g) == 1 for g in groups) and len(others) > 0
    H = [float(r["H"]) for r in done if r["H"]]
    Er = [float(r["E_r"]) for r in done if r["E_r"]]
    h_unit = ip.stress_unit(max(H)) if H else ip.Unit("GPa", 1e9)
    e_unit = ip.stress_unit(max(Er)) if Er else ip.Unit("GPa", 1e9)
    plane_strain = not ip.is_axisymmetric(base_case) if base_case else \
        any("N/m" in r.get("force_unit", "") for r in done)
    panels = [("hardness $H$", f"[{h_unit.name}]", lambda r: float(r["H"]) / h_unit.scale if r["H"] else None,
               "no hardness: no unloading branch was analysed\n(results.csv: message)")]
    if plane_strain:  # E_r is not defined in plane strain: the peak load instead
        peaks = [float(r["peak_force"]) for r in done if r["peak_force"]]
        p_unit = ip.force_unit(max(peaks), False) if peaks else ip.Unit("N/m", 1.0)
        panels.append(("peak load $P_\\mathrm{max}$ ($E_\\mathrm{r}$: none in plane strain)",
                       f"[{p_unit.name}]", lambda r: float(r["peak_force"]) / p_unit.scale if r["peak_force"] else None,
                       "no peak load"))
    else:
        panels.append(("reduced modulus $E_\\mathrm{r}$", f"[{e_unit.name}]",
                       lambda r: float(r["E_r"]) / e_unit.scale if r["E_r"] else None,
                       "no reduced modulus: no unloading branch was analysed\n(results.csv: message)"))
    panels.append(("pile-up ratio $A_\\mathrm{true}/A_\\mathrm{c}$", "", lambda r: pile_up.get(r["hash"]),
                   "no pile-up ratio: results.csv has none and the runs'\nsummary.json were not kept "
                   "(sweep.keep: \"summary\")"))
    fig, axes = ip.figure(size, columns=3)
    colours = [ip.LOADING, ip.UNLOADING, ip.RELOADING, ip.THEORY, ip.PURPLE, ip.SKY, ip.BLACK, "#F0E442"]
    numbers = [v for v in x_values if v is not None]
    log_x = numeric[x_key] and min(numbers) > 0 and max(numbers) / min(numbers) >= 8
    for ax, (name, unit, value, empty) in zip(axes, panels):
        plotted = False
        if latin:
            xs = [x_of(r) for r in done if value(r) is not None]
            ys = [value(r) for r in done if value(r) is not None]
            if others and all(as_number(r[others[0]]) is not None for r in done):
                cs = [as_number(r[others[0]]) for r in done if value(r) is not None]
                c_label, c_unit = ip.key_axis(others[0], [as_number(r[others[0]]) for r in done])
                points = ax.scatter(xs, ys, c=[c_unit(c) for c in cs], cmap="viridis", zorder=3,
                                    vmin=c_unit(min(as_number(r[others[0]]) for r in done)),
                                    vmax=c_unit(max(as_number(r[others[0]]) for r in done)))
                if ax is axes[-1] and xs:
                    fig.colorbar(points, ax=axes, label=c_label, shrink=0.9)
            else:
                ax.scatter(xs, ys, color=ip.LOADING, zorder=3)
            plotted = bool(xs)
        else:
            for n, g in enumerate(groups):
                mine = sorted([r for r in done if group_of(r) == g and value(r) is not None], key=x_of)
                if not mine:
                    continue
                label = ", ".join(f"{ip.key_symbol(k)} = {ip.key_value_text(k, v)}" for k, v in zip(others, g)) or None
                ax.plot([x_of(r) for r in mine], [value(r) for r in mine], "o-", color=colours[n % len(colours)],
                        label=label)
                plotted = True
        if name.startswith("pile-up") and plotted:
            ax.axhline(1.0, color="#777777", ls=":", lw=1.2)
            make_room(ax, 1.0)
            ax.annotate("pile-up ↑ / sink-in ↓", (0.98, 1.0), xycoords=("axes fraction", "data"), ha="right",
                        va="bottom", color="#555555", fontsize=plt.rcParams["legend.fontsize"], bbox=NOTE_BOX)
        material = base_case.get("material", {})
        # The specimen's E/(1 - nu^2) where no swept key changes it; a coated specimen has none:
        # the surface layer's and the substrate's, named (its elastic stiffness lies between them;
        # its Oliver-Pharr E_r need not, as A_c errs by the pile-up or sink-in).
        layers = ip.layers_of(base_case)
        references = [("", material, "material.")] if not layers else [
            (f"{ip.region_names(len(layers) + 1)[1]}: ", layers[0]["material"], "layer.1.material."),
            ("substrate: ", material, "material.")]
        for words, m, prefix in references:
            if name.startswith("reduced") and plotted and not {prefix + "E", prefix + "nu"} & set(keys) and \
                    m.get("E") and base_case.get("analysis", {}).get("indenter_E") in (None, "rigid"):
                e_star = m["E"] / (1 - m.get("nu", 0.3) ** 2)
                ax.axhline(e_star / e_unit.scale, color="#777777", ls=":", lw=1.2)
                make_room(ax, e_star / e_unit.scale)
                ax.annotate(f"{words}$E/(1-ν^2)$ = {e_unit.text(e_star)}", (0.98, e_star / e_unit.scale),
                            xycoords=("axes fraction", "data"), ha="right", va="bottom", color="#555555",
                            fontsize=plt.rcParams["legend.fontsize"], bbox=NOTE_BOX)
        if not plotted:  # the panel says why it is empty
            ax.text(0.5, 0.5, textwrap.fill(empty.replace("\n", " "), 30), ha="center", va="center",
                    transform=ax.transAxes, color="#555555", fontsize=plt.rcParams["legend.fontsize"])
            ax.set_xticks([])
            ax.set_yticks([])
            for spine in ax.spines.values():
                spine.set_color("#dddddd")
        short, _, note = name.partition(" (")
        ax.set_title(short)
        ax.set_ylabel(f"{short} {unit}".strip())
        if note:
            ax.annotate("(" + note, (0.98, 0.02), xycoords="axes fraction", ha="right", va="bottom", color="#555555",
                        fontsize=plt.rcParams["legend.fontsize"])
        ax.set_xlabel(x_label if plotted else "")
        if log_x and plotted:
            ax.set_xscale("log")
            if len(numbers) <= 6:  # a grid's few values as the ticks; else the axis's own
                ax.set_xticks([x_unit(v) for v in numbers])
                ax.get_xaxis().set_minor_formatter(plt.NullFormatter())
            ax.get_xaxis().set_major_formatter(plt.FuncFormatter(lambda v, _: ip.number(v, 3)))
        if not numeric[x_key]:
            ax.set_xticks(range(len(distinct[x_key])), distinct[x_key])
    handles, labels = axes[0].get_legend_handles_labels()
    if labels:
        axes[0].legend(loc="best")
    counts = {s: sum(1 for r in rows if r["status"] == s) for s in ("finished", "not_converged", "failed", "pending")}
    status = f"{counts['finished']} of {len(rows)} runs finished" + "".join(
        f", {v} {k.replace('_', ' ')}" for k, v in counts.items() if k != "finished" and v)
    without = sum(1 for r in done if not r["H"])
    if without:
        status += f"; {without} without Oliver-Pharr numbers (results.csv: message)"
    varied = " × ".join(f"{ip.key_words(k)[0]} {ip.key_words(k)[1]}" if ip.key_words(k) else k for k in keys)
    ip.run_title(fig, f"sweep over {varied} ({status})",
                 ip.describe_run(base_case, omit=keys) if base_case else "")
    figures = folder / "figures"
    figures.mkdir(exist_ok=True)
    ip.save(fig, figures, "sweep")


NOTE_BOX = {"boxstyle": "square,pad=0.15", "facecolor": "white", "edgecolor": "none", "alpha": 0.8}


def make_room(ax, y):
    """y-limits that hold a reference line at y with room for its label above."""
    lo, hi = ax.get_ylim()
    lo, hi = min(lo, y), max(hi, y)
    ax.set_ylim(lo, max(hi, y + 0.12 * (hi - lo)))


# --- main -------------------------------------------------------------------------------------------

def is_sweep(folder):
    return (folder / "results.csv").is_file()


def read_measured(args, axisymmetric):
    """The --data curve: (depth [m], force [N, or N/m in plane strain], legend name)."""
    try:
        h, p, (du, fu) = ip.read_measured_curve(args.data, args.depth_column, args.force_column, args.depth_unit,
                                                args.force_unit)
    except ip.CurveFileError as e:
        print(f"error: {e}", file=sys.stderr)
        sys.exit(2)
    # A plane-strain run's P is a force per unit thickness (N/m), an axisymmetric one's a force (N):
    # a curve in the other kind of unit is data of the other scene (as `indentsim fit` says).
    if fu.endswith("/m") == axisymmetric:
        scene, wanted = ("axisymmetric", "a force (N, mN, ...)") if axisymmetric else \
            ("plane strain", "a force per unit thickness (N/m, mN/m, ...)")
        print(f"error: {args.data}: the forces are in {fu}, but the run is {scene}, whose P is {wanted}: give the "
              "curve of such a scene (or its unit with --force-unit)", file=sys.stderr)
        sys.exit(2)
    return h, p, args.data.name


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("outdir", type=pathlib.Path, nargs="?", help="a run's folder or a sweep's folder")
    parser.add_argument("--step", type=int, help="the increment to show (default: the deepest of the load path)")
    parser.add_argument("--analysis", type=pathlib.Path, help="draw this analysis.json (indentsim analyze) instead")
    parser.add_argument("--data", type=pathlib.Path, help="a measured load-depth CSV to draw over the run's curve")
    parser.add_argument("--depth-column", help="--data: the depth column's header name")
    parser.add_argument("--force-column", help="--data: the force column's header name")
    parser.add_argument("--depth-unit", help="--data: nm, um, mm or m (else from the header)")
    parser.add_argument("--force-unit", help="--data: mN, uN, nN or N (else from the header; N/m... in plane strain)")
    ip.add_size_options(parser)
    args = parser.parse_args()
    ip.use_style(args.size, args.dpi)
    if args.analysis:
        plot_analysis(args.analysis, args.size)
        return
    if args.outdir is None:
        parser.error("give a run's folder, a sweep's folder or --analysis FILE")
    outdir = args.outdir
    if is_sweep(outdir):
        if args.step is not None or args.data is not None:
            parser.error(f"{outdir} is a sweep's folder: --step and --data are for a run's folder")
        plot_sweep(outdir, args.size)
        return
    if not (outdir / "case.toml").is_file() or not (outdir / "curve.csv").is_file():
        sys.exit(f"{outdir}: neither a run's folder (case.toml, curve.csv) nor a sweep's (results.csv)")
    case = tomllib.loads((outdir / "case.toml").read_text())
    curve = read_csv(outdir / "curve.csv")
    summary = json.loads((outdir / "summary.json").read_text()) if (outdir / "summary.json").is_file() else {}
    measured = read_measured(args, ip.is_axisymmetric(case)) if args.data else None
    # The run's deepest state (the end of a hold at the largest target, whose fields it always
    # writes); a folder from before summary.json named it: the deepest row.
    deepest = summary.get("deepest_step", int(max(curve, key=lambda r: float(r["alpha"]))["step"]))
    step = args.step if args.step is not None else int(deepest)
    rows = [r for r in curve if int(r["step"]) == step]
    if not rows:
        sys.exit(f"{outdir}: the run has no step {step} (steps 0 to {curve[-1]['step']})")
    row = rows[0]
    units = ip.RunUnits.of_curve(column_of(curve, "alpha"), column_of(curve, "P"), column_of(curve, "a"),
                                 ip.is_axisymmetric(case))
    profiles = [r for r in read_csv(outdir / "profiles.csv") if int(r["step"]) == step] \
        if (outdir / "profiles.csv").is_file() else []
    fields = read_vtu(vtu_of_step(outdir, step))
    figures = outdir / "figures"
    figures.mkdir(exist_ok=True)
    plot_curve(case, summary, curve, units, args.size, figures, measured)
    plot_pressure(case, summary, row, profiles, fields["surface_pressure"], units, args.size, figures)
    if profiles:
        plot_profiles(case, summary, row, profiles, units, args.size, figures)
    else:
        print(f"no layer view tabulated for step {step} (profiles.csv holds the deepest and the final state): "
              "no profiles figure")
    before = [float(r["alpha"]) for r in curve if int(r["step"]) <= step]
    plot_plastic_zone(case, summary, row, fields, units, args.size, figures, deepest=max(before))
    if (outdir / "analysis.json").is_file():
        plot_analysis(outdir / "analysis.json", args.size)


if __name__ == "__main__":
    main()
