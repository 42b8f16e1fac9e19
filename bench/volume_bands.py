#!/usr/bin/python3
"""Where a Nuss repair's volume change comes from, band by band along the cage, and how the sternum moves.

One of the thesis' patients (Table 6-1) built by the generator and calibrated with the FE filter's defaults,
as bench/table_6_1.py runs it; then the slice method over bands of --band mm from the lower sternum end
(landmark 500) to the lung apex (701), before and after, each band's range given as heights. For each band
the table gives the change of the intrathoracic volume and the mean displacement of the sternum's anterior
half in that band (read from the FE result's .vtu). A band that loses volume while the lower sternum end
rises shows where the cage gives way. The slice method sums its slices, so the bands add up to about the
change over the whole range (each band fits its own whole number of slices); the Ferguson envelope is fitted
to the range it is given and does not add up over bands, so it is left out.

    bench/volume_bands.py [--case 1] [--edge 5] [--band 15] [--out /tmp/pectus-bands]

Needs the plugins and meshlabserver of build/prefix (scripts/setup.sh), and numpy.
"""
import argparse
import os
import platform
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "python"))
import pectus_filters as pf  # noqa: E402
import pectus_mlx as mlx  # noqa: E402
import pipeline  # noqa: E402
from cohort import THESIS  # noqa: E402
from stress_near import read_vtu  # noqa: E402

CAGE, LANDMARKS = 0, 1
STERNUM = 3  # the .vtu's tissue id of the sternum (the FE filter's Tissue::Sternum)


def slice_method(**range_):
    return pipeline.measure_filter("slice", CAGE, LANDMARKS, **range_)


def sternum_motion(vtu, bands):
    """mean (y, z) displacement of the sternum nodes in the anterior half of each band (mm)"""
    d = read_vtu(vtu)
    P, U = d["points"].reshape(-1, 3), d["displacement"].reshape(-1, 3)
    tets = d["connectivity"].astype(int).reshape(len(d["tissue"]), -1)
    nodes = np.unique(tets[d["tissue"].astype(int) == STERNUM])
    out = []
    for lo, hi in bands:
        k = nodes[(P[nodes, 2] >= lo) & (P[nodes, 2] < hi)]
        k = k[P[k, 1] >= np.median(P[k, 1])] if len(k) else k
        out.append(U[k].mean(axis=0) if len(k) else None)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--case", type=int, default=1, choices=range(1, len(THESIS) + 1))
    ap.add_argument("--edge", type=float, default=5.0)
    ap.add_argument("--band", type=float, default=15.0, help="band height, mm")
    ap.add_argument("--out", default="/tmp/pectus-bands")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    case, sex, age, index, elevation = THESIS[a.case - 1]
    make = [pf.create_ribcage(age=age, hallerIndex=index, edgeLength=a.edge)]
    # the range: the slice method over the envelope's, on the cage alone (seconds)
    probe = mlx.run([], mlx.Script(make + [slice_method(lowerLimit=1).set(compare=False)]))
    # the range to the hundredth of a mm, as the Log gives it
    lo, hi = (None if v is None else round(v, 2) for v in (probe.get("z_low_mm"), probe.get("z_high_mm")))
    if probe.rc or lo is None or hi is None:
        sys.exit(f"the slice method did not measure the cage (exit {probe.rc})")
    edges = list(np.arange(lo, hi, a.band)) + [hi]
    if edges[-1] - edges[-2] < a.band / 3:
        del edges[-2]  # no sliver at the top
    bands = list(zip(edges[:-1], edges[1:]))
    base = os.path.join(a.out, f"{case}_bands")
    fe = pf.nuss_fea(landmarkLayer=LANDMARKS, targetElevation=elevation, resultBase=mlx.SaveFile(base + ".vtu", ".vtu"))
    volumes = [slice_method(rangeSource=1, zLow=float(b0), zHigh=float(b1)) for b0, b1 in bands]
    t0 = time.time()
    res = mlx.run([], mlx.Script(make + [fe] + volumes), timeout=4 * 3600)
    with open(base + ".log", "w") as fh:
        fh.write(res.stdout)
    if res.rc:
        sys.exit(f"{case}: the script stopped (exit {res.rc}); its output is in {base}.log")
    force = round(res.value("force_N", "Pectus: Nuss Procedure FE Analysis"), 2)
    # each band's change (cm3, %) and its volume before (cm3)
    slices = [(r["results"]["volume_change_cm3"], r["results"]["volume_change_pct"], r["results"]["before_volume_cm3"])
              for r in res.results if r["filter"] == "Pectus: Thoracic Volume (Slice Method)"]
    motion = sternum_motion(base + ".vtu", bands)

    print(f"{case} ({sex}/{age}, index {index}), lifted {elevation} mm by Fe = {force} N; generated cage, {a.edge:g} mm edges; "
          f"{platform.node()}, {os.cpu_count()} cores, {time.strftime('%Y-%m-%d')}, {time.time() - t0:.0f} s")
    print("| z from, to mm | intrathoracic volume before cm³ | change cm³ (%) | sternum's anterior half: mean displacement forward, up mm |")
    print("|---|---:|---:|---|")
    before = change = 0.0
    for (b0, b1), s, m in zip(bands, slices, motion):
        d, pct, v = s
        before, change = before + v, change + d
        mv = "—" if m is None else f"{m[1]:+.1f}, {m[2]:+.1f}"
        print(f"| {b0:.1f}, {b1:.1f} | {v:.1f} | {d:+.1f} ({pct:+.2f}) | {mv} |")
    print(f"| all | {before:.1f} | {change:+.1f} ({100 * change / before:+.2f}) | |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
