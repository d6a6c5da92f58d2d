#!/usr/bin/env python3
"""The figure of `indentsim fit`: DIR/fit.png (and .svg) from DIR/fit.json and DIR/fit_curves.csv.

    plot_fit.py DIR [--size slide|column]

Per kind of data (force-depth curves, imprint profiles, time histories of the depth or the force
along a protocol in time): the data as measured (markers) with the
fitted model through the same depths (line), and below it the residuals model - data in a unit of
their own scale.  Right: the 1- and 2-standard-error confidence ellipses of the two most
correlated free parameters (linearised, from fit.json's covariance), the parameters' values with
their standard errors beside; with one free parameter, its interval.  Units follow the data's
scale (indentsim_plotting: nm/µm/mm, µN/mN/N or per unit thickness mN/m ... MN/m in plane strain,
MPa/GPa for stresses), the style is plots/indentsim.mplstyle.
"""
import argparse
import csv
import json
import math
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import indentsim_plotting as ip  # noqa: E402

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

COLOURS = [ip.LOADING, ip.UNLOADING, ip.RELOADING, ip.PURPLE, ip.SKY, ip.THEORY, ip.BLACK]


def data_units(kind, rows, axisymmetric):
    """(x label, x unit, y label, y unit, residual unit) of one kind of data set."""
    x = max(abs(float(r["x"])) for r in rows)
    y = max(abs(float(r["data"])) for r in rows)
    e = max(abs(float(r["residual"])) for r in rows) or y
    if kind == "curve":
        xu, yu = ip.length_unit(x), ip.force_unit(y, axisymmetric)
        ru = ip.force_unit(e, axisymmetric)
        return (f"indentation depth $h$ [{xu.name}]", xu,
                f"load $P$ [{yu.name}]" if axisymmetric else f"load $P$ per unit thickness [{yu.name}]", yu, ru)
    if kind.startswith("history"):
        xu = ip.time_unit(x)
        if kind == "history_force":
            yu, ru = ip.force_unit(y, axisymmetric), ip.force_unit(e, axisymmetric)
            return (f"time $t$ [{xu.name}]", xu,
                    f"load $P$ [{yu.name}]" if axisymmetric else f"load $P$ per unit thickness [{yu.name}]", yu, ru)
        yu = ip.length_unit(y)
        return f"time $t$ [{xu.name}]", xu, f"indentation depth $h$ [{yu.name}]", yu, ip.length_unit(e)
    xu, yu = ip.length_unit(x), ip.length_unit(y)
    return (f"radial coordinate $r$ [{xu.name}]", xu, f"imprint depth [{yu.name}]", yu, ip.length_unit(e))


def ellipse_points(centre, cov, k, n=200):
    """The k-standard-error ellipse of a 2x2 covariance: centre + k L (cos u, sin u) with L L^T = cov
    (Cholesky: exact however different the two parameters' scales; an eigen-decomposition of the
    raw covariance loses the small axis to rounding when they differ by 1e8 or more)."""
    a, b, d = cov
    l11 = math.sqrt(max(a, 0.0))
    l21 = b / l11 if l11 > 0 else 0.0
    l22 = math.sqrt(max(d - l21 * l21, 0.0))
    u = np.linspace(0, 2 * math.pi, n)
    return centre[0] + k * l11 * np.cos(u), centre[1] + k * (l21 * np.cos(u) + l22 * np.sin(u))


def parameter_text(key, p):
    """ "σ_y = 412 MPa, 95% [398, 426] MPa: determined to ±3.4%", or "...: NOT determined": the
    interval and the verdict of fit.json (noise and the model's own error together)."""
    value = p["value"]
    unit = ip.key_unit(key, abs(value) or 1.0)
    space = '' if unit.name in ('', '°') else ' '
    scaled = ip.number(value / unit.scale, 4)
    interval = p.get("interval_95") or [None, None]
    if None in interval:
        span = ""
    else:
        span = f", 95% [{ip.number(interval[0] / unit.scale, 3)}, {ip.number(interval[1] / unit.scale, 3)}]"
    if unit.name.startswith("10$"):
        text = f"{ip.key_symbol(key)} = {scaled}{span} ×{unit.name}"
    else:
        text = f"{ip.key_symbol(key)} = {scaled}{span}{space}{unit.name}"
    half = p.get("relative_half_width_95")
    if p.get("determined"):
        return text + f": determined to ±{100 * half:.2g}%"
    return text + ": NOT determined"


def plot_confidence(ax, fit, size):
    keys = fit["free"]
    cov = fit["covariance"]
    params = fit["parameters"]
    lines = [parameter_text(k, params[k]) for k in keys]
    if len(keys) >= 2:
        corr = fit["correlation"]
        best, pair = -1.0, (0, 1)
        for i in range(len(keys)):
            for j in range(i + 1, len(keys)):
                c = corr[i][j]
                if c is not None and abs(c) > best:
                    best, pair = abs(c), (i, j)
        i, j = pair
        xi, xu = ip.key_axis(keys[i], [params[keys[i]]["value"]])
        yi, yu = ip.key_axis(keys[j], [params[keys[j]]["value"]])
        centre = (params[keys[i]]["value"], params[keys[j]]["value"])
        a, b, d = cov[i][i], cov[i][j], cov[j][j]
        if None not in (a, b, d):
            for k, style, colour in ((1, "-", ip.LOADING), (2, "--", ip.UNLOADING)):
                xs, ys = ellipse_points(centre, (a, b, d), k)
                ax.plot(xu(xs), yu(ys), style, color=colour)
                right = int(np.argmax(xs))  # named where the ellipse reaches furthest right
                ax.annotate(f" {k} s.e.", (xu(xs[right]), yu(ys[right])), ha="left", va="center", color=colour,
                            fontsize=plt.rcParams["legend.fontsize"])
            # The whole ellipse in view with a margin, whatever the parameters' scales.
            xs, ys = ellipse_points(centre, (a, b, d), 2)
            for setter, v, unit, room in ((ax.set_xlim, xs, xu, 0.35), (ax.set_ylim, ys, yu, 0.12)):
                lo, hi = unit(v.min()), unit(v.max())
                pad = (hi - lo) or abs(lo) * 0.1 or 1.0
                setter(lo - 0.12 * pad, hi + room * pad)
        # The 95% intervals of noise and model together (fit.json's interval_95): the box the
        # verdicts are read from, wider than the noise's ellipses where the model's error counts.
        box = [params[keys[i]].get("interval_95"), params[keys[j]].get("interval_95")]
        if all(b and None not in b for b in box):
            (x0, x1), (y0, y1) = box
            ax.plot(xu(np.array([x0, x1, x1, x0, x0])), yu(np.array([y0, y0, y1, y1, y0])), ":", color=ip.BLACK,
                    label="95% intervals (noise and model)")
            ax.legend(loc="best")
            for get, set_, lo, hi in ((ax.get_xlim, ax.set_xlim, xu(x0), xu(x1)), (ax.get_ylim, ax.set_ylim, yu(y0), yu(y1))):
                a, b = get()
                a, b = min(a, lo), max(b, hi)
                set_(a - 0.06 * (b - a), b + 0.06 * (b - a))
        # Where the model's error exceeded the noise: the optimum with that error taken off, the
        # end of the shift the interval holds (fit.json's values_with_the_model_error_taken_off).
        corrected = fit.get("values_with_the_model_error_taken_off")
        if corrected:
            ax.plot(xu(corrected[i]), yu(corrected[j]), "x", color=ip.UNLOADING, ms=plt.rcParams["lines.markersize"] * 2,
                    mew=2, linestyle="none", label="with the model's own error taken off")
            ax.legend(loc="best")
        ax.plot(xu(centre[0]), yu(centre[1]), "+", color=ip.BLACK, ms=plt.rcParams["lines.markersize"] * 2.5, mew=2)
        ax.set_xlabel(xi)
        ax.set_ylabel(yi)
        rho = corr[i][j]
        ax.set_title("confidence region\n" + (f"ρ = {rho:.3f}".replace("-", "−") if rho is not None
                                                else "ρ undetermined"))
        if rho is not None and abs(rho) > 0.999:
            lines.append(f"only a combination of {ip.key_symbol(keys[i])} and {ip.key_symbol(keys[j])} is determined "
                         f"(ρ = {rho:.4f})")
        ax.ticklabel_format(useOffset=False)
    else:
        key = keys[0]
        p = params[key]
        label, unit = ip.key_axis(key, [p["value"]])
        interval = p.get("interval_95") or [None, None]
        if None not in interval:
            below, above = p["value"] - interval[0], interval[1] - p["value"]
            ax.errorbar([0], [unit(p["value"])], yerr=[[unit(below)], [unit(above)]], fmt="o", color=ip.LOADING,
                        capsize=6)
        else:
            ax.plot([0], [unit(p["value"])], "o", color=ip.LOADING)
        ax.set_xticks([])
        ax.set_xlim(-1, 1)
        ax.set_ylabel(label)
        ax.set_title("value and its 95% interval\n(noise and model)")
    return lines


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("folder", type=pathlib.Path, help="the folder of indentsim fit (fit.json, fit_curves.csv)")
    ip.add_size_options(parser)
    args = parser.parse_args()
    ip.use_style(args.size, args.dpi)
    folder = args.folder
    fit = json.loads((folder / "fit.json").read_text())
    with open(folder / "fit_curves.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    kinds = [k for k in ("curve", "imprint", "history_depth", "history_force") if any(r["kind"] == k for r in rows)]
    n = len(kinds)
    slide = args.size == "slide"
    if slide:
        fig = plt.figure(figsize=(ip.SLIDE_WIDTH, ip.SLIDE_WIDTH * 9 / 16))
        grid = fig.add_gridspec(2, n + 1, height_ratios=[2.6, 1],
                                width_ratios=[1.25] * n + [1 if len(fit["free"]) >= 2 else 0.45])
        panels = [(fig.add_subplot(grid[0, c]), None) for c in range(n)]
        panels = [(top, fig.add_subplot(grid[1, c], sharex=top)) for c, (top, _) in enumerate(panels)]
        confidence = fig.add_subplot(grid[:, n])
    else:
        fig = plt.figure(figsize=(ip.COLUMN_WIDTH, 3.4 * n + 2.8))
        grid = fig.add_gridspec(2 * n + 1, 1, height_ratios=[2.4, 1] * n + [2.8])
        panels = []
        for c in range(n):
            top = fig.add_subplot(grid[2 * c, 0])
            panels.append((top, fig.add_subplot(grid[2 * c + 1, 0], sharex=top)))
        confidence = fig.add_subplot(grid[-1, 0])
    for kind, (ax, res) in zip(kinds, panels):
        mine = [r for r in rows if r["kind"] == kind]
        sets = sorted({int(r["data_set"]) for r in mine})
        axisymmetric = all(fit["data"][s - 1].get("rms_residual_unit", "N") != "N/m" for s in sets)
        x_label, xu, y_label, yu, ru = data_units(kind, mine, axisymmetric)
        for n_set, s in enumerate(sets):
            part = [r for r in mine if int(r["data_set"]) == s]
            colour = COLOURS[n_set % len(COLOURS)]
            name = pathlib.Path(fit["data"][s - 1]["file"]).name
            x = xu(np.array([float(r["x"]) for r in part]))
            ax.plot(x, yu(np.array([float(r["data"]) for r in part])), "o", color=colour, mfc="none",
                    label=f"data: {name}")
            ax.plot(x, yu(np.array([float(r["model"]) for r in part])), "-", color=colour,
                    label="model" if len(sets) == 1 else f"model: {name}")
            res.plot(x, ru(np.array([float(r["residual"]) for r in part])), "o", color=colour)
        ax.set_ylabel(y_label)
        ax.set_title({"curve": "force–depth curve", "imprint": "residual imprint",
                      "history_depth": "depth in time (force control)",
                      "history_force": "force in time (depth control)"}[kind])
        ax.legend(loc="lower right" if kind == "curve" else "best")
        ax.tick_params(labelbottom=False)
        res.axhline(0.0, color="#555555", lw=0.8)
        res.set_xlabel(x_label)
        res.set_ylabel(f"model − data\n[{ru.name}]")
    values = plot_confidence(confidence, fit, args.size)
    verdict = "every parameter determined" if fit["identifiable"] else "NOT every parameter determined"
    runs = f"{fit['forward_runs']} forward runs"
    if fit.get("coarse_runs", 0):
        runs += f" (+{fit['coarse_runs']} coarse)"
    quality = fit.get("quality")
    first = (f"indentsim fit of {', '.join(ip.key_symbol(k) for k in fit['free'])}: relative rms residual "
             f"{100 * fit['rms_residual']['relative']:.3g}%, condition number {fit['condition_number']:.3g} "
             f"({verdict})" + (f", fit {quality}" if quality else ""))
    ip.run_title(fig, first, "; ".join(values) + f"; {runs}, {fit['wall_s']:.1f} s")
    for suffix in ("png", "svg"):
        fig.savefig(folder / f"fit.{suffix}")
    plt.close(fig)
    print(f"figure: {folder / 'fit.png'}")


if __name__ == "__main__":
    main()
