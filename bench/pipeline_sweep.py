#!/usr/bin/python3
"""The whole pipeline across the rib cage generator's range, each filter with its defaults. One table.

For every (age, pectus index, edge length) of a grid, one MeshLab script through the real meshlabserver
(under xvfb-run, as the end-to-end tests run it; the script is assembled like the main job's pipeline.mlx):

  'Pectus: Create Rib Cage' (the age, the pectus (Haller) index, the edge length; the rest its defaults)
  -> 'Pectus: MGA Surface Mesh Smoothing' (its defaults)
  -> 'Pectus: Nuss Procedure FE Analysis' (its defaults: calibrated to the target from the model, the rise that brings the
     lower sternum end onto the chest line; large displacement, neo-Hookean, TET10, displacement control; --order
     changes the element only)
  -> 'Pectus: Thoracic Volume (Slice Method)', 'Pectus: Thoracic Volume (Ferguson Envelope)', 'Pectus: Pectus Index' (their defaults,
     before = the smoothed cage, after = the FE result).

Each row: success, refused (the FE filter refused the cell before any solve with a message that names the
parameter to change: the target elevation against the chest line, or the joint or sternum load radius; the
message is printed below the table) or failed (any other non-zero exit, the --timeout limit, a missing figure); the calibrated force Fe, the simulated
elevation of the lower sternum end, the volume gain (slice method and Ferguson envelope), the pectus index before
and after, the time of each stage as the filters log it (the volumes: both methods, before and after) and the
wall time of the meshlabserver run.

    /usr/bin/python3 bench/pipeline_sweep.py [--ages 5,8,11,14,17] [--indices 3,4,5,6,7] [--edges 2,5,8]
                                             [--corners] [--order default|tet10|tet4] [--jobs 1]
                                             [--timeout 14400] [--out DIR]

--corners: only the 8 corners of the range (age 5/17 x index 3/7 x edge 2/8). Exit code 1 if a cell failed
(a refusal is not a failure). Needs the plugins and meshlabserver of build/prefix (scripts/setup.sh), or
PECTUS_PREFIX.
"""
from __future__ import annotations

import argparse
import concurrent.futures
import itertools
import os
import platform
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, os.path.join(ROOT, "python"))
import pectus_filters as pf  # noqa: E402
import pectus_mlx as mlx  # noqa: E402
import pipeline  # noqa: E402

CAGE, LANDMARKS = pipeline.CAGE, pipeline.LANDMARKS
CORNERS = dict(ages="5,17", indices="3,7", edges="2,8")
ORDERS = {"default": {}, "tet10": dict(order=0), "tet4": dict(order=1)}
# the checks that refuse a cell before any solve, by the parameter their message tells to change: the target
# against the chest line (before TetGen), the load and support placement (after TetGen, before the first solve)
REFUSALS = {"lies beyond what the model reaches": "targetElevation",
            "no depression to correct": "targetElevation",
            "increase the joint radius": "jointRadius",
            "increase the sternum load radius": "sternumLoadRadius"}


def script(age: float, index: float, edge: float, order: str) -> mlx.Script:
    cage = pf.create_ribcage(age=age, hallerIndex=index, edgeLength=edge)
    mga = pipeline.example("mga", "Pectus: MGA Surface Mesh Smoothing")
    fe = pf.nuss_fea(landmarkLayer=LANDMARKS, **ORDERS[order])
    return mlx.Script([cage, mga, fe] + pipeline.measure_filters(CAGE, LANDMARKS))


def error_of(res: mlx.Result) -> str:
    """the message of the filter that failed ('<filter> failed: <message>' in the Log), else the last line printed"""
    for l in res.log:
        if " failed: " in l:
            return l
    lines = [l.strip() for l in res.stdout.splitlines() if l.strip()]
    return lines[-1] if lines else ""


def run_cell(age: float, index: float, edge: float, order: str, out: str, timeout: float) -> dict:
    name = f"age{age:g}_index{index:g}_edge{edge:g}"
    t0 = time.time()
    try:
        res = mlx.run([], script(age, index, edge, order), timeout=timeout)
    except subprocess.TimeoutExpired:
        return dict(age=age, index=index, edge=edge, status="failed", wall=time.time() - t0,
                    why=f"no result within the time limit of {timeout:.0f} s (--timeout)")
    wall = time.time() - t0
    with open(os.path.join(out, name + ".log"), "w") as fh:
        fh.write(res.stdout)
    r = pipeline.parse(res)
    slice_s, env_s = ([v for k in ("before_seconds", "seconds") for v in res.values(k, pipeline.MEASURES[m])]
                      for m in ("slice", "envelope"))
    row = dict(age=age, index=index, edge=edge, wall=wall, rc=res.rc, force=r["force"], elevation=r["elevation"],
               target=res.get("target_elevation_mm", pipeline.FE),
               target_from=res.get("target_from", pipeline.FE), tets=r["tets"], element=r["element"],
               slice=r["slice_change_cm3"], slice_pct=r["slice_change_pct"], envelope=r["envelope_change_cm3"],
               envelope_pct=r["envelope_change_pct"], haller=r["haller"],
               t_cage=res.get("seconds", pipeline.RIBCAGE), t_mga=res.get("seconds", pipeline.MGA),
               t_fe=r["fe_seconds"], t_volumes=sum(slice_s + env_s) if slice_s or env_s else None, why="")
    figures = (row["force"], row["elevation"], row["slice"], row["envelope"]) + tuple((r["haller"] + [None, None])[:2])
    if res.rc == 0 and None not in figures:
        row["status"] = "success"
    else:
        row["why"] = error_of(res) or f"meshlabserver exit {res.rc}, a figure missing from the Log"
        row["parameter"] = next((p for k, p in REFUSALS.items() if k in row["why"]), None)
        refused = res.rc != 0 and row["tets"] is None and row["parameter"] is not None
        row["status"] = "refused" if refused else "failed"
    return row


def cells(a) -> list[tuple[float, float, float]]:
    ages, indices, edges = ((CORNERS[k] if a.corners else getattr(a, k)) for k in ("ages", "indices", "edges"))
    fl = lambda s: [float(x) for x in s.split(",") if x]  # noqa: E731
    return [(age, ix, e) for e, age, ix in itertools.product(fl(edges), fl(ages), fl(indices))]


def fmt(v, spec="{:.1f}") -> str:
    return "–" if v is None else spec.format(v)


def table(rows: list[dict]) -> list[str]:
    out = [f"| age | index | edge mm | result | Fe N | elevation / target mm | volume gain slice cm³ (%) | "
           f"volume gain envelope cm³ (%) | index before → after | cage s | MGA s | FE s | volumes s | total s |",
           "|---:|---:|---:|---|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|"]
    for r in rows:
        hb, ha = (r.get("haller", []) + [None, None])[:2]
        ok = r["status"] == "success"
        out.append(
            f"| {r['age']:g} | {r['index']:g} | {r['edge']:g} | {r['status']}"
            f"{' (' + fmt(r.get('tets'), '{:,.0f}') + ' ' + r['element'] + ')' if ok else ''} | "
            f"{fmt(r.get('force') if ok else None, '{:.2f}')} | "
            f"{fmt(r.get('elevation') if ok else None, '{:.2f}')} / {fmt(r.get('target'), '{:.1f}')}"
            f"{' (model)' if r.get('target_from') == 'from the model' else ''} | "
            f"{fmt(r.get('slice') if ok else None, '{:.2f}')} ({fmt(r.get('slice_pct') if ok else None, '{:.2f}')}) | "
            f"{fmt(r.get('envelope') if ok else None, '{:.2f}')} ({fmt(r.get('envelope_pct') if ok else None, '{:.2f}')}) | "
            f"{fmt(hb, '{:.2f}')} → {fmt(ha if ok else None, '{:.2f}')} | {fmt(r.get('t_cage'))} | {fmt(r.get('t_mga'))} | "
            f"{fmt(r.get('t_fe'))} | {fmt(r.get('t_volumes'))} | {r['wall']:.0f} |")
    notes = [f"age {r['age']:g}, index {r['index']:g}, edge {r['edge']:g} mm, {r['status']}"
             f"{' (parameter ' + r['parameter'] + ')' if r.get('parameter') and r['status'] == 'refused' else ''}: {r['why']}"
             for r in rows if r["status"] != "success"]
    return out + [""] + notes if notes else out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--ages", default="5,8,11,14,17")
    ap.add_argument("--indices", default="3,4,5,6,7")
    ap.add_argument("--edges", default="2,5,8")
    ap.add_argument("--corners", action="store_true", help="only the 8 corners: age 5/17 x index 3/7 x edge 2/8 mm")
    ap.add_argument("--order", choices=sorted(ORDERS), default="default",
                    help="the FE element: the filter's default (TET10), tet10 or tet4")
    ap.add_argument("--jobs", type=int, default=1, help="cells run at the same time (each FE uses the cores it finds)")
    ap.add_argument("--timeout", type=float, default=4 * 3600, help="limit of one cell's meshlabserver run, s")
    ap.add_argument("--out", default=None, help="folder for each cell's meshlabserver output (default: a new temporary one)")
    a = ap.parse_args()
    out = a.out or tempfile.mkdtemp(prefix="pectus-pipeline-sweep-")
    os.makedirs(out, exist_ok=True)
    grid = cells(a)
    load0 = os.getloadavg()[0]
    with concurrent.futures.ThreadPoolExecutor(max(1, a.jobs)) as ex:
        # the coarse cells first (minutes), the 2 mm ones (the FE of tens of thousands of tets) last
        futures = {c: ex.submit(run_cell, *c, a.order, out, a.timeout) for c in sorted(grid, key=lambda c: -c[2])}
        for fut in concurrent.futures.as_completed(futures.values()):
            r = fut.result()
            print(f"age {r['age']:g}, index {r['index']:g}, edge {r['edge']:g} mm: {r['status']}, {r['wall']:.0f} s"
                  + (f"; {r['why']}" if r["why"] else ""), file=sys.stderr, flush=True)
        rows = [futures[c].result() for c in grid]
    print(f"Pipeline sweep, each filter's defaults (FE element: {a.order}); {platform.node()}, {os.cpu_count()} cores, "
          f"{time.strftime('%Y-%m-%d')}, {a.jobs} job(s); load average before/after {load0:.1f} / {os.getloadavg()[0]:.1f}; "
          f"logs in {out}")
    print("\n".join(table(rows)))
    n = {s: sum(r["status"] == s for r in rows) for s in ("success", "refused", "failed")}
    print(f"{n['success']} success, {n['refused']} refused, {n['failed']} failed")
    return 1 if n["failed"] else 0


if __name__ == "__main__":
    sys.exit(main())
