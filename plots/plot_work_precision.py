#!/usr/bin/env python3
"""Work-precision figure from the benchmark's table.

    python3 plots/plot_work_precision.py out/work_precision.csv [plots/work_precision.png]

Error of the final force against wall time, log-log, one line per case (mesh sweep at 4
increments); the increments sweep is drawn as separate markers.
"""
import csv
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

LABELS = {
    "elastic_hertz": "elastic thick block (vs Hertz P–a)",
    "paper": "paper case, Ilyushin (vs Richardson)",
    "deep_plastic": "deep plastic, Ilyushin (vs Richardson)",
    "deep_plastic_klu": "deep plastic with KLU only",
    "deep_plastic_increments": "deep plastic, 2–16 increments at contact_nodes 16",
    "axi_elastic_sphere": "axisymmetric elastic sphere (vs Richardson)",
    "axi_steel_sphere": "axisymmetric steel sphere, J2 (vs Richardson)",
    "axi_cone": "axisymmetric Berkovich cone, Ilyushin (vs Richardson)",
}


def main():
    table = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "out/work_precision.csv")
    out = pathlib.Path(sys.argv[2] if len(sys.argv) > 2 else "plots/work_precision.png")
    with open(table, newline="") as f:
        rows = list(csv.DictReader(f))
    fig, ax = plt.subplots(figsize=(7, 5))
    for case in LABELS:
        data = [r for r in rows if r["case"] == case and float(r["error"]) > 0]
        if not data:
            continue
        data.sort(key=lambda r: float(r["wall_s"]))
        style = "s" if case.endswith("increments") else ("--o" if case.endswith("klu") else "-o")
        ax.loglog([float(r["wall_s"]) for r in data], [100 * float(r["error"]) for r in data], style, ms=4,
                  label=LABELS[case])
        if not case.endswith("increments"):
            for r in data:
                ax.annotate(r["contact_nodes"], (float(r["wall_s"]), 100 * float(r["error"])), fontsize=6,
                            textcoords="offset points", xytext=(3, 3))
    ax.axhline(0.5, color="grey", lw=0.8, ls=":")
    ax.text(ax.get_xlim()[0] * 1.1, 0.55, "0.5%", color="grey", fontsize=8)
    ax.set_xlabel("wall time per run [s] (2-core machine)")
    ax.set_ylabel("error of the final force P [%]")
    ax.set_title("indentsim work–precision (labels: mesh.contact_nodes)")
    ax.grid(which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out, dpi=150)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
