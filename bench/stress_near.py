#!/usr/bin/python3
"""The stress around one point of a Nuss FE result: is a peak one tet's, or a whole region's?

Reads the .vtu the FE filter writes (resultBase) and, for the tets whose centroid lies within 2, 4, 6, 10,
15 and 25 mm of the point (e.g. the Log's "Max von Mises stress ... at (x, y, z) mm"), prints how many there
are, their largest, 90th percentile and median von Mises stress, and how many carry no stress at all (a tet
whose four corners are all fixed: the point lies at the edge of a fixed joint); then the mean edge length of
the tets within 6 mm, against that of the whole bone. A peak far above the 90th percentile of its
neighbourhood, on tets much smaller than the rest, belongs to the few tets at a singular place (a tissue
junction, the edge of a fixed joint or of a load patch) and grows as they get smaller.

    bench/stress_near.py RESULT.vtu X Y Z

Needs numpy.
"""
import argparse
import re

import numpy as np

RADII = (2, 4, 6, 10, 15, 25)  # mm
BONE = 1  # the .vtu's tissue id of bone (the FE filter's Tissue::Bone)


def read_vtu(path):
    """the named DataArrays of an ASCII .vtu (the points under "points")"""
    out = {}
    for m in re.finditer(r"<DataArray([^>]*)>(.*?)</DataArray>", open(path).read(), re.S):
        name = re.search(r'Name="([^"]+)"', m.group(1))
        out[name.group(1) if name else "points"] = np.array(m.group(2).split(), float)
    return out


def mean_edge(P, tets):
    """mean length of the six corner-to-corner edges of the tets"""
    if len(tets) == 0:
        return float("nan")
    pairs = [(i, j) for i in range(4) for j in range(i + 1, 4)]
    return float(np.mean([np.linalg.norm(P[tets[:, i]] - P[tets[:, j]], axis=1) for i, j in pairs]))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("vtu")
    ap.add_argument("point", type=float, nargs=3, metavar=("X", "Y", "Z"), help="the point, mm")
    a = ap.parse_args()
    point = np.array(a.point)
    d = read_vtu(a.vtu)
    for need in ("points", "connectivity", "offsets", "von_mises", "tissue"):
        if need not in d:
            ap.error(f"{a.vtu} has no {need} array: give the .vtu the Nuss FE filter writes")
    P = d["points"].reshape(-1, 3)
    per = int(d["offsets"][0])
    T = d["connectivity"].astype(int).reshape(-1, per)[:, :4]  # the corners (TET10: the first four nodes)
    vm, tissue = d["von_mises"], d["tissue"].astype(int)
    dist = np.linalg.norm(P[T].mean(axis=1) - point, axis=1)
    print(f"{a.vtu}: {len(T)} tets; around ({point[0]:.1f}, {point[1]:.1f}, {point[2]:.1f}) mm")
    print(f"{'within mm':>9s} {'tets':>6s} {'max MPa':>8s} {'p90 MPa':>8s} {'median MPa':>10s} {'unstressed':>10s}")
    for r in RADII:
        s = vm[dist < r]
        if len(s) == 0:
            print(f"{r:9d} {0:6d}")
            continue
        print(f"{r:9d} {len(s):6d} {s.max():8.1f} {np.percentile(s, 90):8.1f} {np.median(s):10.1f} {int(np.sum(s == 0)):10d}")
    print(f"mean tet edge: {mean_edge(P, T[dist < 6]):.2f} mm within 6 mm, "
          f"{mean_edge(P, T[tissue == BONE]):.2f} mm over the bone")


if __name__ == "__main__":
    main()
