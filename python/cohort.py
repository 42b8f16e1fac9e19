#!/usr/bin/env python3
"""Run the Nuss analysis and the volume/index measures over a cohort of patient rib cages, one meshlabserver
per patient, and collect one summary CSV. Standard library only (+ the project's pectus_mlx).

A cohort folder holds patients.csv (columns: case,sex,age,elevation_mm) and, per case, CASE.ply (the closed
rib cage with tissue labels as face colour + face quality, e.g. from 'Pectus: Create Rib Cage' saved
with -m fc fq, or from a segmentation tool relabelled so) and CASE_landmarks.ply (landmark points, code in
the vertex quality; labels.h).

    python3 python/cohort.py demo DIR [--edge MM] [--cases N]   # synthetic patients shaped like the thesis' Table 6-1
    python3 python/cohort.py run DIR CASE OUTDIR   # one patient -> OUTDIR/CASE/ (what GNU parallel / an array job calls)
    python3 python/cohort.py collect DIR OUTDIR    # OUTDIR/cohort_summary.csv from every OUTDIR/*/summary.csv
    scripts/cohort.sh DIR [OUTDIR] [--quick]       # all of it in parallel (GNU parallel); cluster: scripts/cohort_array.sh
"""
from __future__ import annotations

import argparse
import csv
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import pectus_mlx as mlx  # noqa: E402
import pipeline  # noqa: E402

# Table 6-1: sex/age, pectus index, measured elevation of the end of the sternum (mm)
THESIS = [("case1", "M", 8, 5.3, 44.7), ("case2", "F", 7, 4.7, 34.0), ("case3", "M", 7, 5.2, 39.9),
          ("case4", "M", 6, 3.7, 35.4), ("case5", "M", 5, 3.6, 37.5)]


def patients(folder: str) -> list[dict]:
    with open(os.path.join(folder, "patients.csv")) as fh:
        return list(csv.DictReader(fh))


def demo(folder: str, edge: float = 5.0, cases: int = len(THESIS)) -> int:
    os.makedirs(folder, exist_ok=True)
    chosen = THESIS[:max(1, min(cases, len(THESIS)))]
    with open(os.path.join(folder, "patients.csv"), "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["case", "sex", "age", "elevation_mm"])
        for case, sex, age, haller, elev in chosen:
            w.writerow([case, sex, age, elev])
    for case, sex, age, haller, elev in chosen:
        gen = pipeline.example("ribcage", "Pectus: Create Rib Cage").set(age=age, hallerIndex=haller, edgeLength=edge)
        res = mlx.run([], mlx.Script([gen]), [(os.path.join(folder, f"{case}.ply"), "fc fq", 0),
                                             (os.path.join(folder, f"{case}_landmarks.ply"), "vq", 1)])
        print(f"{case}: {'ok' if res.rc == 0 else 'FAILED'}", flush=True)
        if res.rc != 0:
            print(res.stdout[-2000:], file=sys.stderr)
            return 1
    return 0


def run_one(folder: str, case: str, outdir: str, quick: bool = False) -> int:
    row = next((p for p in patients(folder) if p["case"] == case), None)
    if row is None:
        print(f"case {case} is not in {folder}/patients.csv", file=sys.stderr)
        return 2
    out = os.path.join(os.path.abspath(outdir), case)
    os.makedirs(out, exist_ok=True)
    elev = float(row["elevation_mm"])
    # inputs: landmarks (layer 0), then the cage (layer 1, current); the FE adds layers 2 and 3
    script = mlx.Script(pipeline.analysis_filters(out, elev, quick, cage=1, landmarks=0))
    path = script.write(os.path.join(out, "analysis.mlx"))
    t0 = time.time()
    res = mlx.run([os.path.join(folder, f"{case}_landmarks.ply"), os.path.join(folder, f"{case}.ply")], path,
                  [(os.path.join(out, "nuss_result.ply"), "vq vc fc fq", 2)])
    with open(os.path.join(out, "meshlabserver.log"), "w") as fh:
        fh.write(res.stdout)
    r = pipeline.parse(res)
    r["seconds"] = time.time() - t0
    summary = os.path.join(out, "summary.csv")
    if res.rc == 0:
        pipeline.write_summary(summary, r, row["sex"], float(row["age"]), elev, case, pipeline.run_settings(script, quick))
    else:  # no summary row for a failed case (collect reports it); the reason is in meshlabserver.log
        if os.path.exists(summary):
            os.remove(summary)
        for line in res.log:
            if "failed" in line:
                print(f"{case}: {line}", file=sys.stderr)
    p = {k: None if r[k] is None else round(r[k], 2)  # as the Log prints them
         for k in ("force", "elevation", "slice_change_pct", "envelope_change_pct")}
    print(f"{case}: rc {res.rc}, Fe {p['force']} N, elevation {p['elevation']} mm, slice {p['slice_change_pct']} %, "
          f"envelope {p['envelope_change_pct']} %", flush=True)
    return 0 if res.rc == 0 else 1


def collect(folder: str, outdir: str) -> int:
    """OUTDIR/cohort_summary.csv: every case's summary.csv in patients.csv's order, in pipeline.SUMMARY_COLUMNS
    (a case's summary.csv may have these columns or the older ones: pipeline.read_summary reads both)"""
    rows = []
    for p in patients(folder):
        s = os.path.join(outdir, p["case"], "summary.csv")
        if not os.path.exists(s):
            print(f"{p['case']}: no summary (failed or not run)", file=sys.stderr)
            continue
        rows.append(pipeline.read_summary(s))
    path = os.path.join(outdir, "cohort_summary.csv")
    header = [name for name, _, _ in pipeline.SUMMARY_COLUMNS]
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=header)
        w.writeheader()
        w.writerows(rows)
    keys = ["case", "sex", "age_years", "target_elevation_mm", "force_N", "elevation_mm", "max_stress_MPa", "max_strain",
            "slice_change_pct", "envelope_change_pct", "haller_index_before", "haller_index_after"]
    if rows:
        print(" ".join(f"{k:>12.12s}" for k in keys))
        for r in rows:
            print(" ".join(f"{r[k][:12]:>12s}" for k in keys))
    print(f"cohort summary: {path} ({len(rows)} cases)")
    return 0 if rows else 1


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(prog="cohort.py", description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="command", required=True)
    d = sub.add_parser("demo", help="write synthetic patients shaped like the thesis' Table 6-1 into DIR")
    d.add_argument("dir")
    d.add_argument("--edge", type=float, default=5.0, help="the cages' surface edge length, mm (default 5)")
    d.add_argument("--cases", type=int, default=len(THESIS), help=f"how many patients (default {len(THESIS)})")
    r = sub.add_parser("run", help="one patient of DIR into OUTDIR/CASE/")
    r.add_argument("dir")
    r.add_argument("case")
    r.add_argument("outdir")
    r.add_argument("--quick", action="store_true", help="coarse TET4 small strain: not results to report")
    c = sub.add_parser("collect", help="OUTDIR/cohort_summary.csv from every OUTDIR/*/summary.csv")
    c.add_argument("dir")
    c.add_argument("outdir")
    a = ap.parse_args(argv[1:])
    if a.command == "demo":
        return demo(a.dir, a.edge, a.cases)
    if a.command == "run":
        return run_one(a.dir, a.case, a.outdir, a.quick)
    return collect(a.dir, a.outdir)


if __name__ == "__main__":
    sys.exit(main(sys.argv))
