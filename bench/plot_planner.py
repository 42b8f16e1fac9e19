#!/usr/bin/python3
"""The Nuss Bar Planner's table as a picture: one bar chart per column (calibrated force, largest stress,
volume gains by the slice method and the Ferguson envelope), one bar per option, the best option in red.

    bench/plot_planner.py PLANNER.csv OUT.png [--title TEXT]

PLANNER.csv is the planner's `csvFile` (docs/filters/nuss_bar_planner.md, "Files it writes")."""
from __future__ import annotations

import argparse
import csv

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

COLUMNS = [("force_N", "calibrated total Fe (N)", "{:.1f}"),
           ("max_stress_MPa", "max von Mises stress (MPa)", "{:.1f}"),
           ("slice_gain_percent", "volume gain, slice method (%)", "{:.1f}"),
           ("envelope_gain_percent", "volume gain, Ferguson envelope (%)", "{:.1f}")]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("csv")
    ap.add_argument("out")
    ap.add_argument("--title", default="Pectus: Nuss Bar Planner: each option calibrated to the same elevation; red: the best")
    a = ap.parse_args()
    with open(a.csv, newline="") as f:
        rows = list(csv.DictReader(f))
    names = [r["option"].replace("spaces ", "").replace("space ", "") for r in rows]
    colours = ["tab:red" if r["best"] == "1" else ("tab:blue" if r["bars"] == "1" else "#6baed6") for r in rows]
    fig, axes = plt.subplots(1, len(COLUMNS), figsize=(11, 3.2), sharey=True)
    for ax, (key, label, fmt) in zip(axes, COLUMNS):
        values = [float(r[key]) for r in rows]
        ys = range(len(rows))
        ax.barh(ys, values, color=colours)
        for y, v in zip(ys, values):
            ax.text(v, y, " " + fmt.format(v), va="center", fontsize=8)
        ax.set_title(label, fontsize=9)
        ax.set_xlim(min(0, min(values) * 1.2), max(values) * 1.2 if max(values) > 0 else 1)
        ax.grid(axis="x", alpha=0.3)
    axes[0].set_yticks(range(len(rows)))
    axes[0].set_yticklabels(names)
    axes[0].invert_yaxis()
    fig.suptitle(a.title, fontsize=10)
    fig.tight_layout()
    fig.savefig(a.out, dpi=100)


if __name__ == "__main__":
    main()
