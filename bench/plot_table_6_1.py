#!/usr/bin/python3
"""The calibrated force against the measured elevation of the lower sternum end, for the rows of one or more
bench/table_6_1.py runs, beside the thesis' five patients and the published band of forces.

    bench/table_6_1.py > rib.txt
    bench/table_6_1.py --cartilage-section ct --cartilage-e 12.25,32.9 > ct.txt
    bench/plot_table_6_1.py out.png rib.txt ct.txt
"""
import argparse
import re
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

PUBLISHED = (68, 250)  # N: Fonkalsrud's children to the instrumented bar (biomechanics notes)


def rows(path):
    """{method: [(case, target elevation mm, force N, thesis force N)]} of the table's calibrated rows"""
    out = defaultdict(list)
    for line in open(path):
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) < 8 or not cells[0].isdigit() or cells[6] != "calibrated":
            continue
        m = re.match(r"([\d.]+) \(([\d.]+)\)", cells[7])
        out[cells[4]].append((int(cells[0]), float(cells[3]), float(m.group(1)), float(m.group(2))))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("png")
    ap.add_argument("tables", nargs="+")
    a = ap.parse_args()
    series = {}
    for t in a.tables:
        series.update(rows(t))
    fig, ax = plt.subplots(figsize=(7.5, 4.8))
    ax.axhspan(*PUBLISHED, color="0.9", label=f"published forces, {PUBLISHED[0]}-{PUBLISHED[1]} N")
    thesis = sorted({(c, e, tf) for pts in series.values() for c, e, _, tf in pts})
    ax.scatter([e for _, e, _ in thesis], [tf for *_, tf in thesis], marker="s", color="black", label="thesis (CT models)", zorder=3)
    for c, e, tf in thesis:
        ax.annotate(f"{c}", (e, tf), textcoords="offset points", xytext=(6, 2), fontsize=8)
    for method, pts in series.items():
        pts = sorted(pts, key=lambda p: p[1])
        ax.plot([p[1] for p in pts], [p[2] for p in pts], "o", label=f"generated cage: {method}", zorder=3)
    ax.set_xlabel("measured elevation of the lower sternum end (mm)")
    ax.set_ylabel("calibrated elevating force Fe (N)")
    ax.set_ylim(0, 260)
    ax.set_title("Table 6-1: the thesis' five patients")
    ax.legend(fontsize=8, loc="upper left")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(a.png, dpi=110)


if __name__ == "__main__":
    main()
