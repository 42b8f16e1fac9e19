#!/usr/bin/env python3
"""The main job (README, first command): the whole thesis pipeline on the default rib cage through the
real meshlabserver and one .mlx script (python/pipeline.py), then plots. Writes everything into one
output folder (default out/main-<timestamp>) and prints a table shaped like the thesis' Table 6-1.

    python3 python/run_main.py [OUTDIR] [--quick] [--case NAME] [--planner [--planner-levels 3,4,5] [--planner-bars both|one|two]]

--planner adds the 'Pectus: Nuss Bar Planner' (filter_nuss_fea) to the same script, on the smoothed cage with the main job's
FE settings, and prints its table (planner.csv in the output folder). Full mode takes ~4 min per option.
Every run ends with report.html, one page for the surgeon (python/report.py).
"""
from __future__ import annotations

import argparse
import datetime
import os
import shlex
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
import pipeline  # noqa: E402
import report  # noqa: E402


def plot_histograms(path: str, hists: list[list[int]], labels: list[str]):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        import numpy as np
    except ImportError:
        return None
    fig, ax = plt.subplots(figsize=(7, 4))
    w = 0.8 / max(len(hists), 1) * 0.1
    for k, (h, lab) in enumerate(zip(hists, labels)):
        ax.bar(np.arange(len(h)) * 0.1 + 0.05 + (k - (len(hists) - 1) / 2) * w, h, width=w, label=lab)
    ax.set_xlabel("triangle quality alpha (thesis eq. 3-20)")
    ax.set_ylabel("triangles")
    ax.set_xlim(0, 1)
    ax.legend()
    ax.set_title("Rib cage element quality before / after MGA smoothing")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def print_planner(r: dict, out: str):
    print(f"\nNuss bar planner ({r['planner_header'].split(': ', 1)[-1]})")
    for line in r["planner_table"]:
        print("  " + line)
    print(f"{r['planner_best']}\n(* = best; table in {os.path.join(out, 'planner.csv')})")


def parse_args(argv: list[str]) -> argparse.Namespace:
    ap = argparse.ArgumentParser(prog="run_main.py", description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("outdir", nargs="?", help="output folder (default: out/main-<date>-<time> in the clone)")
    ap.add_argument("--quick", action="store_true",
                    help="a coarse TET4 small-strain model in seconds: its figures are not results to report")
    ap.add_argument("--case", default="case1",
                    help="summary.csv's case column (default case1: the thesis' patient 1, as cohort.py demo names it)")
    ap.add_argument("--planner", action="store_true", help="add the Nuss Bar Planner to the same script")
    ap.add_argument("--planner-levels", default="3,4,5", help="planner: intercostal spaces, comma-separated (default 3,4,5)")
    ap.add_argument("--planner-bars", default="both", choices=["both", "one", "two"],
                    help="planner: one bar, two bars or both (default both)")
    return ap.parse_args(argv[1:])


def main(argv: list[str]) -> int:
    a = parse_args(argv)
    levels, bars, quick, with_planner = a.planner_levels, {"both": 0, "one": 1, "two": 2}[a.planner_bars], a.quick, a.planner
    stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S")
    out = os.path.abspath(a.outdir or os.path.join(ROOT, "out", f"main-{stamp}"))
    print("pectus-meshlab main job: create the rib cage of the thesis' patient 1 (M/8, pectus index 5.3) -> element "
          "quality -> MGA smoothing -> Nuss FE with the force calibrated to 44.7 mm -> thoracic volume (slice, "
          "envelope) and pectus index before/after, through MeshLab " + pipeline.mlx.default_host() + " headless ...", flush=True)
    rc, r, res = pipeline.run_pipeline(out, quick=quick, planner=dict(levels=levels, bars=bars) if with_planner else None,
                                       case=a.case)
    command = shlex.join(["python3"] + argv)
    if rc != 0:
        print(res.stdout[-4000:], file=sys.stderr)
        print(f"pipeline failed (MeshLab {pipeline.mlx.default_host()} exit {rc}); log in {out}/meshlabserver.log", file=sys.stderr)
        print(f"Report: {report.write_report(out, command)}", file=sys.stderr)
        return 1
    print(pipeline.table(r, 8, "M", 44.7))
    q = {k: round(r[k], 4) for k in ("quality_mean_before", "quality_mean_after", "quality_min_before", "quality_min_after")}
    print(f"\nElement quality (alpha) of the cage: mean {q['quality_mean_before']} -> {q['quality_mean_after']}, "
          f"min {q['quality_min_before']} -> {q['quality_min_after']} ({r['mga']})")
    print(f"FE: {r['tets']} {r['element']} elements, force calibrated in {r['solves']} solves, {round(r['fe_seconds'], 1)} s; "
          f"whole pipeline {r['seconds']:.0f} s")
    if with_planner:
        print_planner(r, out)
    if len(r["histograms"]) >= 2:
        plot_histograms(os.path.join(out, "quality_histograms.png"), r["histograms"][:2], ["before MGA", "after MGA"])
    path = report.write_report(out, command)
    print(f"Output folder: {out}")
    for f in sorted(os.listdir(out)):
        print(f"  {f}")
    print(f"Report (one page, for the surgeon; open it in a browser): {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
