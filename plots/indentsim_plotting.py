"""What every indentsim figure shares: the style, the sizes, the units, the words and the curve.

    import indentsim_plotting as ip
    ip.use_style("slide")                  # or "column"; loads indentsim.mplstyle (beside this file)
    units = ip.RunUnits.of_curve(depth, force, contact, axisymmetric)
    ip.draw_load_depth(ax, depth, force, contact_nodes, units)

Units are chosen from the scale of the run -- its peak depth (nm, µm, mm), its peak force (µN, mN,
N; in plane strain per unit thickness, mN/m, N/m, kN/m, MN/m), its contact (positions x, r, z:
from three times the peak contact radius) and its mean contact pressure at the peak (MPa, GPa) --
once per run, so that every figure of a run (curve, analysis, pressure, profiles, plastic zone)
speaks the same units.  A stiffness is written in the plot's own units (force unit per depth
unit: mN/µm, (kN/m)/µm) so that its tangent can be read off the axes.

Only Debian's python3 packages: matplotlib, numpy and the standard library.
"""
import csv
import math
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

STYLE = pathlib.Path(__file__).resolve().with_name("indentsim.mplstyle")

# The journal column: 3.5 in (89 mm) wide, 8 pt type, 300 dpi.  The slide is the style sheet's own.
COLUMN = {
    "figure.figsize": (3.5, 2.6), "savefig.dpi": 300, "font.size": 8, "axes.titlesize": 8.5,
    "figure.titlesize": 8.5, "axes.labelsize": 8, "xtick.labelsize": 7, "ytick.labelsize": 7,
    "legend.fontsize": 6.5, "legend.title_fontsize": 6.5, "lines.linewidth": 1.2, "lines.markersize": 3.2,
    "lines.markeredgewidth": 0.5, "axes.linewidth": 0.7, "grid.linewidth": 0.4, "xtick.major.size": 2.5,
    "ytick.major.size": 2.5, "axes.titlepad": 4, "legend.borderaxespad": 0.4, "legend.handlelength": 1.8,
    "figure.constrained_layout.h_pad": 0.03, "figure.constrained_layout.w_pad": 0.03,
}
SIZES = ("slide", "column")
SLIDE_WIDTH, COLUMN_WIDTH = 10.0, 3.5  # inches

# Colours of the style sheet's cycle, by role.
LOADING, UNLOADING, RELOADING, THEORY = "#0072B2", "#E69F00", "#009E73", "#D55E00"
PURPLE, SKY, BLACK, SEPARATED, MEASURED = "#CC79A7", "#56B4E9", "#000000", "#8c8c8c", "#444444"


def add_size_options(parser):
    """The --size and --dpi options every figure script takes (use_style's arguments)."""
    parser.add_argument("--size", choices=SIZES, default="slide",
                        help="slide (16:9, default) or column (a journal column, 3.5 in wide)")
    parser.add_argument("--dpi", type=float, help="the PNGs' resolution (default: slide 192, i.e. 1920 x 1080 px; "
                                                  "column 300)")


def use_style(size="slide", dpi=None):
    """Loads the style sheet and the size ("slide": 16:9, or "column"); `dpi` overrides the PNGs'
    resolution (slide 192: 1920 x 1080 px; column 300)."""
    if size not in SIZES:
        raise ValueError(f"size must be one of {', '.join(SIZES)}, not {size!r}")
    if STYLE.is_file():
        plt.style.use(str(STYLE))
    else:  # a copy of the script without its style sheet still draws, in matplotlib's defaults
        print(f"warning: the style sheet {STYLE.name} is not beside {pathlib.Path(__file__).name}", file=sys.stderr)
    if size == "column":
        plt.rcParams.update(COLUMN)
    if dpi:
        plt.rcParams["savefig.dpi"] = dpi


def figure(size, columns=1, rows=1, width_ratios=None, slide_height=None, column_panel_height=2.4, legend_row=0.0,
           **kwargs):
    """A figure of `columns` panels side by side on a slide; in a journal column the same panels
    stacked (one column of `columns * rows` panels).  Returns (fig, flat list of axes); with
    `legend_row` (a height in inches) also an empty strip of that height along the bottom, across
    every panel, for a shared legend: (fig, axes, strip)."""
    if size == "column":
        n = columns * rows
        ratios = list(width_ratios) if width_ratios and rows == 1 else [1] * n
        panels = column_panel_height * n
        fig = plt.figure(figsize=(COLUMN_WIDTH, panels + legend_row))
        heights = [r * panels / sum(ratios) for r in ratios] + ([legend_row] if legend_row else [])
        grid = fig.add_gridspec(n + (1 if legend_row else 0), 1, height_ratios=heights)
        axes = [fig.add_subplot(grid[k, 0]) for k in range(n)]
    else:
        height = slide_height or SLIDE_WIDTH * 9 / 16
        fig = plt.figure(figsize=(SLIDE_WIDTH, height))
        heights = [(height - legend_row) / rows] * rows + ([legend_row] if legend_row else [])
        grid = fig.add_gridspec(rows + (1 if legend_row else 0), columns, width_ratios=width_ratios,
                                height_ratios=heights)
        axes = [fig.add_subplot(grid[r, c]) for r in range(rows) for c in range(columns)]
    if not legend_row:
        return fig, axes
    strip = fig.add_subplot(grid[-1, :])
    strip.axis("off")
    return fig, axes, strip


def legend_height(entries, size, columns=1):
    """The height [in] of a legend strip for so many entries."""
    rows = math.ceil(entries / columns)
    font = plt.rcParams["legend.fontsize"]
    return rows * font * 1.5 / 72 + 0.05


def strip_legend(strip, handles, size, columns=None):
    """A shared legend in the strip of figure(..., legend_row=...): up to three columns on a slide,
    one in a journal column (unless `columns`)."""
    columns = columns or (min(len(handles), 3) if size == "slide" else 1)
    return strip.legend(handles=handles, loc="center", ncol=columns, frameon=False)


def save(fig, folder, name, quiet=False):
    """FOLDER/NAME.png and .svg."""
    folder = pathlib.Path(folder)
    for suffix in ("png", "svg"):
        fig.savefig(folder / f"{name}.{suffix}")
    plt.close(fig)
    if not quiet:
        print(f"wrote {folder / name}.png")


def run_title(fig, *lines):
    """The run's description (and what the figure shows) above the panels, each line wrapped at
    spaces to the figure's width, a little smaller than the panels' titles."""
    size = plt.rcParams["axes.titlesize"] * 0.92 if fig.get_figwidth() > 5 else plt.rcParams["legend.fontsize"]
    renderer = fig.canvas.get_renderer()
    room = fig.get_figwidth() * fig.dpi * 0.96
    probe = fig.text(0, 0, "", fontsize=size)

    def width(text):
        probe.set_text(text)
        return probe.get_window_extent(renderer).width

    wrapped = []
    for line in lines:
        if not line:
            continue
        # Break after "; " where possible, else between words.
        pieces = [p + ";" for p in line.split("; ")[:-1]] + [line.split("; ")[-1]]
        words = [w for p in pieces for w in ([p] if width(p) <= room else p.split(" "))]
        current = ""
        for word in words:
            candidate = f"{current} {word}" if current else word
            if current and width(candidate) > room:
                wrapped.append(current)
                current = word
            else:
                current = candidate
        wrapped.append(current)
    probe.remove()
    fig.suptitle("\n".join(wrapped), fontsize=size, color="#333333")


def legend(ax, size, outside=True, strip=None, **kwargs):
    """The legend of a panel: on a slide beside it (right) when `outside`, in a journal column in
    the figure's legend strip when there is one (figure(..., legend_row=...)); else inside."""
    if size == "slide" and outside:
        kwargs.pop("loc", None)
        return ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0, **kwargs)
    if size == "column" and strip is not None:
        return strip_legend(strip, ax.get_legend_handles_labels()[0], size)
    return ax.legend(**kwargs)


# --- Units ---------------------------------------------------------------------------------------

class Unit:
    """A unit: its name and its size in SI (value_in_unit = value_si / scale)."""

    def __init__(self, name, scale):
        self.name, self.scale = name, scale

    def __call__(self, value_si):
        """The value in this unit (a number, a list or an array)."""
        if isinstance(value_si, (list, tuple)):
            return [v / self.scale for v in value_si]
        return value_si / self.scale

    def text(self, value_si, digits=3):
        """ "12.3 µm" """
        return f"{number(value_si / self.scale, digits)} {self.name}"

    def __repr__(self):
        return f"Unit({self.name!r}, {self.scale:g})"


def number(value, digits=3):
    """A number to `digits` significant digits ("2.7", "449", "0.913", "12345", "−1.2"), with a
    power of ten only outside 0.001 to 1e6 ("4.5×10⁻⁵", in mathtext); minus signs as the axes
    write them (U+2212)."""
    if value is None or not math.isfinite(value):
        return "–"
    if value == 0:
        return "0"
    if 10**digits <= abs(value) < 1e6:
        text = f"{value:.0f}"
    elif 1e-3 <= abs(value) < 10**digits:
        text = f"{value:.{digits}g}"
        if "e" in text:  # 999.7 rounds to "1e+03"
            text = f"{float(text):.0f}"
    else:
        mantissa, exponent = f"{value:.{digits - 1}e}".split("e")
        mantissa = mantissa.rstrip("0").rstrip(".").replace("-", "−")
        return f"{mantissa}$\\times$10$^{{{int(exponent)}}}$"
    return text.replace("-", "−")


def prefixed(value, base, prefixes):
    """The prefixed unit of `base` in which |value| lies in [1, 1000) (or the nearest end)."""
    table = {"n": 1e-9, "µ": 1e-6, "m": 1e-3, "": 1.0, "k": 1e3, "M": 1e6, "G": 1e9}
    chosen = prefixes[0]
    for p in prefixes:
        if value and abs(value) / table[p] >= 1.0 - 1e-9:
            chosen = p
    return Unit(chosen + base, table[chosen])


def length_unit(value):
    """nm, µm, mm or m for a length of this size [m]."""
    return prefixed(value, "m", ("n", "µ", "m", ""))


def force_unit(value, axisymmetric=True):
    """µN, mN, N or kN (axisymmetric); per unit thickness in plane strain: mN/m ... MN/m."""
    if axisymmetric:
        return prefixed(value, "N", ("µ", "m", "", "k"))
    return prefixed(value, "N/m", ("m", "", "k", "M", "G"))


def time_unit(value):
    """µs, ms or s for a time of this size [s]."""
    return prefixed(value, "s", ("µ", "m", ""))


def stress_unit(value):
    """kPa, MPa or GPa for a stress of this size [Pa]."""
    return prefixed(value, "Pa", ("k", "M", "G"))


class RunUnits:
    """The units of one run's figures, from its scale: depth (h), force (P), position (x, r, z),
    stress (p, σ, H) and stiffness (S, in force unit per depth unit)."""

    def __init__(self, axisymmetric, peak_depth, peak_force, contact_radius, mean_pressure):
        self.axisymmetric = axisymmetric
        self.depth = length_unit(peak_depth or 1e-6)
        self.force = force_unit(peak_force or 1.0, axisymmetric)
        self.position = length_unit(3 * contact_radius if contact_radius else (peak_depth or 1e-6))
        self.stress = stress_unit(mean_pressure or 1e6)
        name = f"{self.force.name}/{self.depth.name}" if axisymmetric else f"({self.force.name})/{self.depth.name}"
        self.stiffness = Unit(name, self.force.scale / self.depth.scale)
        self.modulus = stress_unit(1e9)  # moduli: GPa

    @classmethod
    def of_curve(cls, depth, force, contact, axisymmetric):
        """From a curve in SI: depths, forces and contact radii (or half-widths) per row."""
        depth, force = np.asarray(depth, float), np.asarray(force, float)
        contact = np.asarray(contact, float) if contact is not None else np.zeros_like(depth)
        if len(depth) == 0:
            return cls(axisymmetric, 1e-6, 1.0, 0.0, 1e6)
        k = int(np.argmax(force))
        a_peak = float(contact[k]) if len(contact) else 0.0
        a_max = float(contact.max()) if len(contact) else 0.0
        area = (math.pi * a_peak**2 if axisymmetric else 2 * a_peak) if a_peak > 0 else 0.0
        mean = float(force[k]) / area if area > 0 else None
        return cls(axisymmetric, float(depth.max()), float(force.max()), a_max, mean)

    @classmethod
    def of_run(cls, folder):
        """From a run's folder (its curve.csv and case.toml)."""
        import tomllib
        folder = pathlib.Path(folder)
        case = tomllib.loads((folder / "case.toml").read_text())
        rows = read_csv(folder / "curve.csv")
        return cls.of_curve([float(r["alpha"]) for r in rows], [float(r["P"]) for r in rows],
                            [float(r["a"]) for r in rows], is_axisymmetric(case))

    def force_axis(self):
        """ "load P [mN]", "load P per unit thickness [kN/m]" """
        return f"load $P$ [{self.force.name}]" if self.axisymmetric else \
            f"load $P$ per unit thickness [{self.force.name}]"


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


# --- Words: the run described from its case ------------------------------------------------------

def is_axisymmetric(case):
    return case.get("geometry", {}).get("kind", "plane_strain") == "axisymmetric"


def yield_stress(case, summary=None):
    """σ_y [Pa]: summary.json's, or the case's, or 3 μ e0 (the uniaxial stress at e_u = e0)."""
    return material_yield_stress(case.get("material", {}), (summary or {}).get("material"))


def material_yield_stress(material, written=None):
    """σ_y [Pa] of one material block: `written`'s (summary.json's block of it), or the case's, or
    3 μ e0 (the uniaxial stress at e_u = e0)."""
    if written and written.get("yield_stress"):
        return float(written["yield_stress"])
    if material.get("yield_stress"):
        return float(material["yield_stress"])
    if material.get("e0") and material.get("E"):
        return 3 * material["E"] / (2 * (1 + material.get("nu", 0.3))) * material["e0"]
    return None


# --- Coated specimens: the layers over the substrate (docs/MODEL.md §14) -------------------------

def layers_of(case, summary=None):
    """The coating's layers, from the surface down, as summary.json lists them: [{thickness,
    top_depth, bottom_depth, model, material}] (depths [m] below the undeformed surface; material
    the block of [material]'s keys, with e0 and the yield stress where summary.json gives them);
    from the case's [[layer]] tables when summary.json has none (an older run, a sweep's case).
    [] for a homogeneous specimen."""
    written = (summary or {}).get("layers") or []
    tables = case.get("layer") or []
    if not written and not tables:
        return []
    out, top = [], 0.0
    for k in range(max(len(written), len(tables))):
        w = written[k] if k < len(written) else {}
        t = tables[k] if k < len(tables) else {}
        material = dict(t.get("material", {}))
        material.update(w.get("material", {}))
        material.setdefault("model", w.get("model", material.get("model", "elastic")))
        thickness = float(w.get("thickness", t.get("thickness", 0.0)))
        out.append({"thickness": thickness, "top_depth": float(w.get("top_depth", top)),
                    "bottom_depth": float(w.get("bottom_depth", top + thickness)),
                    "model": w.get("model", material["model"]), "material": material})
        top += thickness
    return out


def region_materials(case, summary=None):
    """The material block of each region, as the fields' `region` cell array numbers them: [0] the
    substrate (summary.json's block over the case's), [k] layer k from the surface; each with its
    "model"."""
    substrate = dict(case.get("material", {}))
    substrate.update((summary or {}).get("material", {}))
    substrate["model"] = (summary or {}).get("model", substrate.get("model", "elastic"))
    return [substrate] + [layer["material"] for layer in layers_of(case, summary)]


def region_names(count):
    """What the figures call the regions: [0] "substrate", then "film" for a single layer, else
    "layer 1" (at the surface), "layer 2", ..."""
    if count <= 1:
        return ["specimen"]
    if count == 2:
        return ["substrate", "film"]
    return ["substrate"] + [f"layer {k}" for k in range(1, count)]


def e_star(material):
    """The plane-strain modulus E/(1 - ν²) [Pa] of a material block."""
    return material["E"] / (1 - material.get("nu", 0.3) ** 2)


MODEL_WORDS = {"j2": "J2", "ilyushin": "Ilyushin", "elastic": "elastic"}


def layer_words(layer, k, omit=()):
    """ "1 µm J2 (σ_y = 12 GPa)": layer k (from 1 at the surface) in a few words, its material by
    the number that decides its response (elastic: E and ν; Norton: σ_ref; else σ_y)."""
    m = layer["material"]
    prefix = f"layer.{k}.material."
    model = m.get("model", layer.get("model", "elastic"))
    t = layer["thickness"]
    thickness = "" if f"layer.{k}.thickness" in omit else f"{length_unit(t).text(t, 3)} "
    words = []
    if model == "elastic":
        if m.get("E") and prefix + "E" not in omit:
            words.append(f"E = {stress_unit(m['E']).text(m['E'], 3)}")
        if prefix + "nu" not in omit:
            words.append(f"ν = {number(m.get('nu', 0.3), 3)}")
    elif m.get("rate") == "norton":
        reference = m.get("reference_stress", 0.0)
        if prefix + "reference_stress" not in omit:
            words.append(f"Norton, σ$_{{ref}}$ = {stress_unit(reference).text(reference, 3)}")
    else:
        sy = material_yield_stress(m)
        if sy and not {prefix + key for key in ("yield_stress", "e0", "E", "nu")} & set(omit):
            words.append(f"σ$_y$ = {stress_unit(sy).text(sy, 3)}")
    return thickness, MODEL_WORDS.get(model, model), (f" ({', '.join(words)})" if words else "")


def coating_words(case, summary=None, omit=()):
    """ "1 µm J2 coating (σ_y = 12 GPa)"; several layers: "coating of 0.2 µm elastic (E = 400 GPa,
    ν = 0.25) over 1 µm J2 (σ_y = 3 GPa)", from the surface down; "" for a homogeneous specimen."""
    layers = layers_of(case, summary)
    if not layers:
        return ""
    parts = [layer_words(layer, k, omit) for k, layer in enumerate(layers, start=1)]
    if len(parts) == 1:
        thickness, model, words = parts[0]
        return f"{thickness}{model} coating{words}"
    return "coating of " + " over ".join(f"{t}{m}{w}" for t, m, w in parts)


def indenter_words(case, omit=()):
    """ "Berkovich-equivalent cone (70.3°)", "sphere, R = 0.5 mm", "cylinder, R = 2 mm", ...
    (without the keys in `omit`, e.g. the ones a sweep varies)."""
    punch = case.get("punch", {})
    shape = punch.get("shape", "sphere")
    axi = is_axisymmetric(case)
    if shape == "sphere":
        r = punch.get("radius", 0.0)
        body = "sphere" if axi else "cylinder"
        return body if "punch.radius" in omit else f"{body}, R = {length_unit(r).text(r, 3)}"
    if shape == "flat":
        r = punch.get("radius", 0.0)
        return "flat punch" if "punch.radius" in omit else \
            f"flat punch, {'R' if axi else 'half-width'} = {length_unit(r).text(r, 3)}"
    if shape == "cone":
        angle = punch.get("half_angle", 70.3)
        named = {70.3: "Berkovich-equivalent ", 42.3: "cube-corner-equivalent "}.get(round(angle, 1), "")
        tip = punch.get("tip_radius", 0.0)
        body = "cone" if axi else "wedge"
        body = body if "punch.half_angle" in omit else f"{named}{body} ({number(angle, 3)}°)"
        if tip and "punch.tip_radius" not in omit:
            body += f", tip radius {length_unit(tip).text(tip, 3)}"
        return body
    if shape == "profile":
        points = punch.get("profile_points") or []
        name = pathlib.Path(str(punch["profile"])).name if punch.get("profile") else None
        return "measured tip profile" + (f" ({name})" if name else f" ({len(points)} points)" if points else "")
    if shape == "area_function":
        c = punch.get("area_coefficients") or []
        if "punch.area_coefficients" in omit or not c:
            return "calibrated tip (area function)"
        if not c[0]:
            return "calibrated tip (area function)"
        return f"calibrated tip, A = {number(c[0], 3)} h²" + (" + …" if any(c[1:]) else "")
    return shape


def material_words(case, summary=None, omit=()):
    """ "J2, σ_y = 300 MPa, power-law hardening n = 0.1", "elastic, E = 210 GPa, ν = 0.3", ...
    (without the keys in `omit`, e.g. the ones a sweep varies)."""
    m = case.get("material", {})
    model = m.get("model", "elastic")
    e = m.get("E")
    if model == "elastic":
        words = ["elastic"]
        if e and "material.E" not in omit:
            words.append(f"E = {stress_unit(e).text(e, 3)}")
        if "material.nu" not in omit:
            words.append(f"ν = {number(m.get('nu', 0.3), 3)}")
        return ", ".join(words)
    text = {"j2": "J2", "ilyushin": "Ilyushin"}.get(model, model)
    rate = m.get("rate", "none")
    exponent = "" if "material.rate_exponent" in omit else f" m = {number(m.get('rate_exponent', 0.0), 3)}"
    if rate == "norton":
        reference = m.get("reference_stress", 0.0)
        return (f"{text}, Norton creep{exponent}" +
                ("" if "material.reference_stress" in omit else f", σ$_{{ref}}$ = {stress_unit(reference).text(reference, 3)}"))
    sy = yield_stress(case, summary)
    if sy and not {"material.yield_stress", "material.e0", "material.E", "material.nu"} & set(omit):
        text += f", σ$_y$ = {stress_unit(sy).text(sy, 3)}"
    hardening = m.get("hardening")
    if hardening == "power":
        text += ", power-law hardening" + ("" if "material.n" in omit else f" n = {number(m.get('n', 0.0), 3)}")
    elif hardening == "linear":
        text += ", linear hardening" + ("" if "material.kappa" in omit else f" κ = {number(m.get('kappa', 0.0), 3)}")
    if rate == "perzyna":
        text += f", Perzyna{exponent}"
    return text


def describe_run(case, summary=None, omit=()):
    """One line: the indenter, the specimen's material (a coated one's: its coating on the
    substrate's material), the scene."""
    scene = "axisymmetric" if is_axisymmetric(case) else "plane strain"
    coating = coating_words(case, summary, omit)
    specimen = f"{coating} on {material_words(case, summary, omit)}" if coating else material_words(case, summary, omit)
    return f"{indenter_words(case, omit)}; {specimen}; {scene}"


# --- The load-depth curve --------------------------------------------------------------------------

def separated_rows(force, contact_nodes):
    """Rows where the indenter has left the surface: P = 0 and no contact node (not row 0, the
    first touch)."""
    force = np.asarray(force, float)
    nodes = np.asarray(contact_nodes, float) if contact_nodes is not None else np.where(force == 0, 0.0, 1.0)
    out = (force == 0.0) & (nodes == 0)
    if len(out):
        out[0] = False
    return out


def branch_kinds(depth):
    """For each step k >= 1 (rows k-1 -> k): 'loading', 'unloading' or 'reloading'."""
    kinds, seen_unloading = [], False
    for k in range(1, len(depth)):
        if depth[k] < depth[k - 1]:
            kinds.append("unloading")
            seen_unloading = True
        else:
            kinds.append("reloading" if seen_unloading else "loading")
    return kinds


def draw_load_depth(ax, depth, force, contact_nodes, units, color=None, label=None, markers=True, zorder=3,
                    separated_label=True, error=None):
    """The P-h curve as computed: lines only between consecutive computed rows that both touch
    (loading, unloading and reloading in their colours, or all in `color`), a marker at every
    computed row, and the rows after separation (P = 0, the indenter off the surface) as grey
    crosses -- never a chord across an increment where the indenter left or found the surface,
    nor a line along P = 0.  `error` (the run's P_error_estimate per row): a grey band of P +- it
    along the lines.  Returns {label: handle} of what was drawn."""
    h = units.depth(np.asarray(depth, float))
    P = units.force(np.asarray(force, float))
    E = units.force(np.asarray(error, float)) if error is not None else None
    off = separated_rows(force, contact_nodes)
    kinds = branch_kinds(h)
    colours = {"loading": LOADING, "unloading": UNLOADING, "reloading": RELOADING}
    styles = {"loading": "-", "unloading": "-", "reloading": "--"}
    ms = plt.rcParams["lines.markersize"] * 0.8
    drawn = {}
    # Consecutive segments of one kind, both ends touching: one polyline each.
    k = 1
    while k < len(h):
        kind = kinds[k - 1]
        if off[k - 1] or off[k]:
            k += 1
            continue
        j = k
        while j + 1 < len(h) and kinds[j] == kind and not off[j + 1]:
            j += 1
        c = color or colours[kind]
        name = label if color else kind
        line, = ax.plot(h[k - 1:j + 1], P[k - 1:j + 1], styles[kind] if not color else "-", color=c, zorder=zorder,
                        marker="o" if markers else None, ms=ms, label=None if name in drawn else name)
        drawn.setdefault(name, line)
        if E is not None:
            ax.fill_between(h[k - 1:j + 1], (P - E)[k - 1:j + 1], (P + E)[k - 1:j + 1], color="#999999", alpha=0.3,
                            lw=0, zorder=zorder - 2)
        k = j + 1
    # Isolated touching rows (between separated ones): a marker each.
    for i in range(len(h)):
        alone = not off[i] and (i == 0 or off[i - 1]) and (i + 1 >= len(h) or off[i + 1])
        if alone and len(h) > 1:
            ax.plot(h[i], P[i], "o", color=color or LOADING, ms=ms, zorder=zorder)
    if off.any():
        name = "separated: off the surface, P = 0" if separated_label else None
        line, = ax.plot(h[off], P[off], "x", color=SEPARATED, ms=ms * 1.1, mew=1.2, zorder=zorder - 1, label=name,
                        clip_on=False)
        if name:
            drawn[name] = line
    return drawn


# --- A measured curve, read as `indentsim analyze` reads it (src/input/curve_csv.cpp) ------------

DEPTH_UNITS = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "μm": 1e-6, "nm": 1e-9}
FORCE_UNITS = {"N": 1.0, "mN": 1e-3, "uN": 1e-6, "µN": 1e-6, "μN": 1e-6, "nN": 1e-9}


class CurveFileError(Exception):
    pass


def _name_and_unit(field):
    f = field.strip()
    if f and f[-1] in ")]":
        at = f.rfind("(" if f[-1] == ")" else "[")
        if at >= 0:
            return f[:at].strip(), f[at + 1:-1].strip()
    return f, ""


def _is_number(text):
    try:
        return math.isfinite(float(text.strip()))
    except ValueError:
        return False


def _blank_or_comment(row):
    first = row[0].strip() if row else ""
    return not row or (len(row) == 1 and not first) or first.startswith("#")


def _delimiter(lines):
    """The delimiter that splits the most of the first 400 lines into two or more numbers only
    (an instrument's metadata lines hold none or another); else the first line's."""
    counts = {d: sum(1 for line in lines[:400] if len(line.split(d)) >= 2 and all(_is_number(f) for f in line.split(d)))
              for d in ",\t;"}
    best = max(counts, key=lambda d: counts[d])
    if counts[best] > 0:
        return best
    first = lines[0] if lines else ""
    return next((d for d in ",\t;" if d in first), ",")


def force_unit_factor(unit):
    """N per unit of a force ("mN") or of a force per unit length ("mN/m": N/m); None if neither."""
    if unit in FORCE_UNITS:
        return FORCE_UNITS[unit]
    if unit.endswith("/m") and unit[:-2] in FORCE_UNITS:
        return FORCE_UNITS[unit[:-2]]
    return None


def read_measured_curve(path, depth_column=None, force_column=None, depth_unit=None, force_unit=None):
    """(depth [m], force [N or N/m], (depth unit, force unit)) of a measured load-depth CSV, read
    as `indentsim analyze` reads it (src/input/curve_csv.cpp): comma, tab or semicolon (the one
    that splits the data into numbers), metadata lines before the header, blank lines and "#"
    comments skipped, columns by name ("Depth" matches "Depth (nm)") or a file of two columns,
    units given or from the header ("Depth (nm)", "Load [mN]"), never guessed; a force per unit
    length (N/m, mN/m, ...) for a plane-strain curve.  Raises CurveFileError."""
    path = pathlib.Path(path)
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError as e:
        raise CurveFileError(f"{path}: cannot open: {e.strerror}") from None
    lines = text.splitlines()
    delimiter = _delimiter(lines)
    rows = [r for r in csv.reader(lines, delimiter=delimiter) if r and not (len(r) == 1 and not r[0].strip())]
    if not rows:
        raise CurveFileError(f"{path}: is empty")
    named = bool(depth_column or force_column)
    if named and not (depth_column and force_column):
        raise CurveFileError(f"{path}: name both columns (--depth-column and --force-column), or neither for a "
                             "two-column file")

    def find(header, wanted):
        for c, field in enumerate(header):
            name = wanted.strip().lower()
            if field.strip().lower() == name or _name_and_unit(field)[0].lower() == name:
                return c
        return None

    header = None
    if named:
        for k, row in enumerate(rows):
            d, f = find(row, depth_column), find(row, force_column)
            if d is not None and f is not None:
                header, dcol, fcol = k, d, f
                break
        if header is None:
            raise CurveFileError(f"{path}: no header row names both \"{depth_column}\" and \"{force_column}\" "
                                 f"(the first row holds {', '.join(repr(f.strip()) for f in rows[0])})")
    else:
        first = next((k for k, r in enumerate(rows) if all(_is_number(f) for f in r)), None)
        if first is None:
            raise CurveFileError(f"{path}: holds no row of numbers")
        header = next((k - 1 for k in range(first, 0, -1) if not _blank_or_comment(rows[k - 1])), None)
        if len(rows[first]) != 2:
            raise CurveFileError(f"{path}: has {len(rows[first])} columns: name the depth and the force column "
                                 "(--depth-column and --force-column)")
        dcol, fcol = 0, 1

    def unit_of(given, column, what, accepted, factor):
        unit = (given or "").strip()
        if not unit and header is not None and column < len(rows[header]):
            unit = _name_and_unit(rows[header][column])[1]
        if not unit:
            raise CurveFileError(f"{path}: the {what} unit is missing: give --{what}-unit ({accepted}) or write it "
                                 f"in the header, e.g. \"{what.capitalize()} ({accepted.split(',')[0]})\"")
        if factor(unit) is None:
            raise CurveFileError(f"{path}: \"{unit}\" is not a {what} unit (accepted: {accepted})")
        return unit

    du = unit_of(depth_unit, dcol, "depth", "nm, um, mm, m", DEPTH_UNITS.get)
    fu = unit_of(force_unit, fcol, "force", "mN, uN, nN, N, or per length mN/m, ..., N/m", force_unit_factor)
    depth, force = [], []
    for k in range(0 if header is None else header + 1, len(rows)):
        row = rows[k]
        if _blank_or_comment(row):
            continue
        for col in (dcol, fcol):
            if col >= len(row):
                raise CurveFileError(f"{path}: row {k + 1} has {len(row)} fields; column {col + 1} is missing")
            if not _is_number(row[col]):
                raise CurveFileError(f"{path}: row {k + 1}: \"{row[col].strip()}\" is not a finite number")
        depth.append(float(row[dcol]) * DEPTH_UNITS[du])
        force.append(float(row[fcol]) * force_unit_factor(fu))
    if len(depth) < 2:
        raise CurveFileError(f"{path}: holds {len(depth)} point(s) of depth and force")
    return np.array(depth), np.array(force), (du, fu)


# --- Load-case keys in words (sweeps, fits) -------------------------------------------------------

KEY_WORDS = {  # key: (words, symbol, kind of unit: "stress", "length", "degree" or None)
    "material.yield_stress": ("yield stress", "σ$_y$", "stress"), "material.E": ("Young's modulus", "$E$", "stress"),
    "material.nu": ("Poisson's ratio", "ν", None), "material.e0": ("elastic limit", "e$_0$", None),
    "material.n": ("hardening exponent", "$n$", None), "material.kappa": ("hardening", "κ", None),
    "material.creep_coefficient": ("creep coefficient", "$A$", "rate"),
    "material.reference_stress": ("reference stress", "σ$_\\mathrm{ref}$", "stress"),
    "material.reference_strain_rate": ("reference strain rate", "$\\dot\\varepsilon_0$", "rate"),
    "material.rate_exponent": ("rate exponent", "$m$", None),
    "punch.radius": ("indenter radius", "$R$", "length"),
    "punch.tip_radius": ("tip radius", "$r_\\mathrm{tip}$", "length"),
    "punch.half_angle": ("cone half-angle", "θ", "degree"), "geometry.lx": ("specimen radius", "$l_x$", "length"),
    "geometry.ly": ("specimen height", "$l_y$", "length"),
    "mesh.contact_nodes": ("contact nodes", "$N_\\mathrm{c}$", None),
    "analysis.indenter_E": ("indenter modulus", "$E_\\mathrm{i}$", "stress"),
    "analysis.indenter_nu": ("indenter Poisson's ratio", "ν$_\\mathrm{i}$", None),
}


def key_words(key):
    """(words, symbol, kind of unit) of a load-case key (KEY_WORDS), a coating's keys included:
    layer.K.material.KEY is the [material] key's, of "layer K" (K from 1 at the surface), and
    layer.K.thickness its thickness t_K; None for a key it does not know."""
    if key in KEY_WORDS:
        return KEY_WORDS[key]
    parts = key.split(".")
    if len(parts) >= 3 and parts[0] == "layer" and parts[1].isdigit():
        k = parts[1]
        if parts[2:] == ["thickness"]:
            return (f"layer {k} thickness", f"$t_{{{k}}}$", "length")
        inner = ".".join(["material"] + parts[3:]) if parts[2] == "material" else None
        if inner in KEY_WORDS:
            words, symbol, kind = KEY_WORDS[inner]
            return (f"layer {k} {words}", f"{symbol} (layer {k})", kind)
    return None


def key_unit(key, value):
    """The unit of a load-case key's values of about this size."""
    kind = (key_words(key) or ("", "", None))[2]
    if kind == "stress":
        return stress_unit(value)
    if kind == "length":
        return length_unit(value)
    if kind == "degree":
        return Unit("°", 1.0)
    if kind == "rate":
        return Unit("s$^{-1}$", 1.0)
    if value and abs(value) < 0.01:  # a small number (an elastic limit e0 = 0.004): in thousandths
        return Unit("10$^{-3}$", 1e-3)
    return Unit("", 1.0)


def key_axis(key, values):
    """(axis label, Unit) of a key's values: "yield stress σ_y [MPa]"."""
    words, symbol, _ = key_words(key) or (key, "", None)
    unit = key_unit(key, max((abs(v) for v in values), default=1.0))
    label = f"{words} {symbol}".strip()
    return (f"{label} [{unit.name}]" if unit.name else label), unit


def key_symbol(key):
    return key_words(key)[1] if key_words(key) else key


def key_value_text(key, text, digits=3):
    """ "σ_y = 300 MPa"'s right-hand side for a value (a number or a table's text)."""
    try:
        v = float(text)
    except (TypeError, ValueError):
        return str(text)
    unit = key_unit(key, abs(v))
    if unit.name.startswith("10$"):
        return f"{number(v / unit.scale, digits)}×{unit.name}"
    return f"{number(v / unit.scale, digits)}{'' if unit.name in ('', '°') else ' '}{unit.name}"
