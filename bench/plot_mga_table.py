#!/usr/bin/python3
"""Mean quality against time for one mesh section of bench/mga_smooth.py's table.

    bench/mga_smooth.py --build build --only bunny > bunny.txt
    bench/plot_mga_table.py bunny.txt out.png [--plateau 0.956 --target 0.96]
"""
import argparse
import re

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def rows(path):
    """(method, q mean, time s) of the table's method rows"""
    out, title = [], None
    for line in open(path):
        m = re.match(r"^  (.+?)\s{2,}(\d\.\d+)\s+(\d\.\d+)\s+(\S+)\s+(\d+\.\d+)\s+(\S+(?: / \d+)?)(?:\s+\S+(?: / \d+)?)?$", line.rstrip())
        if m and m.group(1) != "input":
            out.append((m.group(1), float(m.group(3)), float(m.group(5))))
        elif re.match(r"^\S.*\(\d+ nodes", line):
            title = line.strip()
    return title, out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("table")
    ap.add_argument("png")
    ap.add_argument("--plateau", type=float, help="measured plateau of fixed connectivity (a dashed line)")
    ap.add_argument("--target", type=float, help="the quality target (a dotted line)")
    ap.add_argument("--ymin", type=float, help="leave out rows whose mean is below this (named in the legend)")
    a = ap.parse_args()
    title, data = rows(a.table)
    fig, ax = plt.subplots(figsize=(8.5, 4.8), dpi=110)
    lo = min(q for _, q, _ in data)
    shown = [(n, q, t) for n, q, t in data if q >= a.ymin] if a.ymin else data
    for i, (name, q, t) in enumerate(shown, 1):
        ours = name.startswith("ours")
        colour = "tab:red" if "MGA" in name else ("tab:orange" if ours else "tab:blue")
        ax.scatter([t], [q], s=60 if ours else 40, marker="o" if ours else "s", color=colour, zorder=3,
                   label=f"{i}  {name.replace('ours: ', 'ours, ')}")
        ax.annotate(str(i), (t, q), textcoords="offset points", xytext=(6, -3) if i % 2 else (-13, 3), fontsize=8)
    left_out = [n for n, q, _ in data if (n, q) not in {(m, r) for m, r, _ in shown}]
    ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5), frameon=False,
              title=("not shown (mean below %.3f): " % a.ymin + ", ".join(left_out)) if left_out else None,
              title_fontsize=6)
    del lo
    if a.plateau:
        ax.axhline(a.plateau, ls="--", color="grey", lw=1)
        ax.text(ax.get_xlim()[0], a.plateau, f" plateau measured {a.plateau}", va="bottom", fontsize=7, color="grey")
    if a.target:
        ax.axhline(a.target, ls=":", color="black", lw=1)
        ax.text(ax.get_xlim()[0], a.target, f" target {a.target}", va="bottom", fontsize=7)
    ax.set_xlabel("time, s (2 cores; the table's time column)")
    ax.set_ylabel("mean element quality")
    ax.set_title(title or a.table, fontsize=9)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(a.png)


if __name__ == "__main__":
    main()
