#!/usr/bin/env python3
"""The figure of `indentsim fit`: DIR/fit.png (and .svg) from DIR/fit.json and DIR/fit_curves.csv.

Left: every data set with the fitted model (forces in mN or mN/mm, depths in um).  Middle: the
residuals.  Right: the 1- and 2-standard-error confidence ellipses of the two most correlated
free parameters (linearised, from fit.json's covariance); with one free parameter, its interval.
"""
import csv
import json
import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(folder):
    folder = Path(folder)
    fit = json.loads((folder / "fit.json").read_text())
    rows = list(csv.DictReader(open(folder / "fit_curves.csv")))
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.5))
    sets = sorted({int(r["data_set"]) for r in rows})
    for s in sets:
        mine = [r for r in rows if int(r["data_set"]) == s]
        kind = mine[0]["kind"]
        x = [float(r["x"]) * 1e6 for r in mine]
        scale = 1e3 if kind == "curve" else 1e6
        data = [float(r["data"]) * scale for r in mine]
        model = [float(r["model"]) * scale for r in mine]
        resid = [float(r["residual"]) * scale for r in mine]
        label = Path(fit["data"][s - 1]["file"]).name
        unit = "mN" if kind == "curve" else "um"
        axes[0].plot(x, data, "o", ms=3, label=f"{label} (data, {unit})")
        axes[0].plot(x, model, "-", label=f"{label} (model)")
        axes[1].plot(x, resid, "o-", ms=3, label=f"{label} ({unit})")
    axes[0].set_xlabel("depth alpha or radius r [um]")
    axes[0].set_ylabel("P [mN] (N/m x 1e3 in plane strain) or imprint depth [um]")
    axes[0].legend(fontsize=7)
    axes[0].set_title("data and fitted model")
    axes[1].axhline(0.0, color="k", lw=0.5)
    axes[1].set_xlabel("depth alpha or radius r [um]")
    axes[1].set_ylabel("model - data")
    axes[1].legend(fontsize=7)
    axes[1].set_title(f"residuals: rms {100 * fit['rms_residual']['relative']:.3g}% (relative)")

    keys = fit["free"]
    ax = axes[2]
    cov = fit["covariance"]
    if len(keys) >= 2:
        corr = fit["correlation"]
        best, pair = -1.0, (0, 1)
        for i in range(len(keys)):
            for j in range(i + 1, len(keys)):
                c = corr[i][j]
                if c is not None and abs(c) > best:
                    best, pair = abs(c), (i, j)
        i, j = pair
        vi, vj = fit["parameters"][keys[i]]["value"], fit["parameters"][keys[j]]["value"]
        a, b, d = cov[i][i], cov[i][j], cov[j][j]
        if None not in (a, b, d):
            # Eigen-decomposition of the 2x2 covariance: the ellipse's axes.
            tr, det = a + d, a * d - b * b
            l1 = tr / 2 + math.sqrt(max(tr * tr / 4 - det, 0.0))
            l2 = tr / 2 - math.sqrt(max(tr * tr / 4 - det, 0.0))
            angle = 0.5 * math.atan2(2 * b, a - d)
            for k, style in ((1, "-"), (2, "--")):
                xs, ys = [], []
                for t in range(101):
                    u = 2 * math.pi * t / 100
                    p = k * math.sqrt(max(l1, 0.0)) * math.cos(u)
                    q = k * math.sqrt(max(l2, 0.0)) * math.sin(u)
                    xs.append(vi + p * math.cos(angle) - q * math.sin(angle))
                    ys.append(vj + p * math.sin(angle) + q * math.cos(angle))
                ax.plot(xs, ys, style, label=f"{k} standard error(s)")
        ax.plot([vi], [vj], "k+", ms=10, label="fit")
        ax.set_xlabel(keys[i])
        ax.set_ylabel(keys[j])
        ax.legend(fontsize=7)
        ax.set_title(f"correlation {corr[i][j]:.3f}" if corr[i][j] is not None else "correlation undetermined")
    else:
        v = fit["parameters"][keys[0]]
        se = v["std_error"] or 0.0
        ax.errorbar([0], [v["value"]], yerr=[2 * se], fmt="o", capsize=6)
        ax.set_xticks([])
        ax.set_ylabel(keys[0])
        ax.set_title("value +- 2 standard errors")
    verdict = "identifiable" if fit["identifiable"] else "NOT identifiable"
    runs = f"{fit['forward_runs']} forward runs"
    if fit.get("coarse_runs", 0):
        runs += f" (+{fit['coarse_runs']} coarse)"
    fig.suptitle(f"indentsim fit: {runs}, {fit['wall_s']:.1f} s; condition number "
                 f"{fit['condition_number']:.3g} ({verdict})")
    fig.tight_layout()
    for ext in ("png", "svg"):
        fig.savefig(folder / f"fit.{ext}", dpi=120)
    print(f"figure: {folder / 'fit.png'}")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: plot_fit.py DIR (the folder of indentsim fit)")
    main(sys.argv[1])
