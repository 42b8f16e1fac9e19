#!/usr/bin/python3
"""Thesis Table 3-1, side by side with scipy: C0 (linear) and C1 (Goodman-Said, thesis inverse-area
gradients, the robust default = global minimum-curvature gradients, the per-vertex quadratic fit) against
scipy's LinearNDInterpolator and CloughTocher2DInterpolator, on the same points and the same (scipy Delaunay) triangulation.
Max and mean |error| on the 25x25 grid of the unit square (grid points outside the convex hull of a
point set are left out for every method; the count is printed). Then the ellipsoid volume and the
refinement timing of the C++ core.

    bench/c1_table31.py [--bench build-c1/bench/c1_bench] [--check]

--check exits 1 if a target is missed: thesis-mode C1/C0 max-error ratio in [0.55, 0.65] on the
36-point set (both functions), robust C1 no worse than Clough-Tocher (max and mean, every set and function),
refinement of ~100k faces at k=3 under 1 s.
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile

import numpy as np
from scipy.interpolate import CloughTocher2DInterpolator, LinearNDInterpolator
from scipy.spatial import Delaunay

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
DATA = os.environ.get("PECTUS_DATA", os.path.join(ROOT, "..", "shared", "data"))  # the shared folder beside the repository


def F1(x, y):
    return (0.75 * np.exp(-((9 * x - 2) ** 2 + (9 * y - 2) ** 2) / 4)
            + 0.75 * np.exp(-((9 * x + 1) ** 2) / 49 - (9 * y + 1) / 10)
            + 0.5 * np.exp(-((9 * x - 7) ** 2 + (9 * y - 3) ** 2) / 4)
            - 0.2 * np.exp(-(9 * x - 4) ** 2 - (9 * y - 7) ** 2))


def F2(x, y):
    return (1.25 + np.cos(5.4 * y)) / (6 + 6 * (3 * x - 1) ** 2)


def grid36(seed=36):
    """6x6 grid on the unit square, boundary points on the boundary, interior points jittered."""
    rng = np.random.default_rng(seed)
    pts = []
    for j in range(6):
        for i in range(6):
            x, y = i / 5, j / 5
            if 0 < i < 5 and 0 < j < 5:
                x += rng.uniform(-0.06, 0.06)
                y += rng.uniform(-0.06, 0.06)
            pts.append((x, y))
    return np.array(pts)


def load_csv(name):
    rows = []
    with open(os.path.join(DATA, name)) as fh:
        for line in fh:
            t = line.strip().split(",")
            if len(t) == 2 and not line.startswith("#"):
                try:
                    rows.append((float(t[0]), float(t[1])))
                except ValueError:
                    pass  # header
    return np.array(rows)


def run_core(bench, P, f, tri, Q, simplex):
    with tempfile.NamedTemporaryFile("w", suffix=".txt", delete=False) as fh:
        fh.write(f"{len(P)} {len(tri.simplices)} {len(Q)}\n")
        for p, v in zip(P, f):
            fh.write(f"{p[0]!r} {p[1]!r} {v!r}\n")
        for s in tri.simplices:
            fh.write(f"{s[0]} {s[1]} {s[2]}\n")
        for q, s in zip(Q, simplex):
            fh.write(f"{q[0]!r} {q[1]!r} {s}\n")
        path = fh.name
    try:
        out = subprocess.run([bench, "interp", path], check=True, capture_output=True, text=True).stdout
    finally:
        os.unlink(path)
    return np.array([[float(x) for x in line.split()] for line in out.strip().splitlines()])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bench", default=None)
    ap.add_argument("--check", action="store_true")
    a = ap.parse_args()
    bench = a.bench or next((p for p in [os.environ.get("C1_BENCH", ""),
                                         os.path.join(ROOT, "build-c1", "bench", "c1_bench"),
                                         os.path.join(ROOT, "build", "bench", "c1_bench")] if p and os.path.exists(p)), None)
    if not bench:
        sys.exit("c1_bench not found: build the target c1_bench and pass --bench")

    sets = [("36-point (jittered 6x6)", grid36()), ("Franke 33", load_csv("franke33.csv")),
            ("Franke 100", load_csv("franke100.csv"))]
    g = np.linspace(0, 1, 25)
    GX, GY = np.meshgrid(g, g)
    Q = np.stack([GX.ravel(), GY.ravel()], axis=1)
    failures = []
    print("Thesis Table 3-1 (thesis: F1 C0 max 0.215184 mean 0.027594, C1 max 0.120067 mean 0.022945;")
    print("                          F2 C0 max 0.059769 mean 0.008789, C1 max 0.035420 mean 0.005101)")
    print(f"{'point set':24s} {'fn':3s} {'method':30s} {'max error':>11s} {'mean error':>11s}")
    for sname, P in sets:
        tri = Delaunay(P)
        simplex = tri.find_simplex(Q)
        inside = simplex >= 0
        Qi, si = Q[inside], simplex[inside]
        for fname, F in (("F1", F1), ("F2", F2)):
            f = F(P[:, 0], P[:, 1])
            exact = F(Qi[:, 0], Qi[:, 1])
            core = run_core(bench, P, f, tri, Qi, si)
            res = {
                "C0 linear (ours)": core[:, 0],
                "C0 scipy LinearND": LinearNDInterpolator(tri, f)(Qi),
                "C1 GS thesis (inverse-area)": core[:, 1],
                "C1 GS robust (default)": core[:, 2],
                "C1 GS quadratic fit": core[:, 3],
                "C1 scipy Clough-Tocher": CloughTocher2DInterpolator(tri, f)(Qi),
            }
            err = {k: np.abs(v - exact) for k, v in res.items()}
            for k, e in err.items():
                print(f"{sname:24s} {fname:3s} {k:30s} {e.max():11.6f} {e.mean():11.6f}")
            r = err["C1 GS thesis (inverse-area)"].max() / err["C0 linear (ours)"].max()
            rr = err["C1 GS robust (default)"].max() / err["C0 linear (ours)"].max()
            print(f"{'':24s} {fname:3s} C1/C0 max-error ratio: thesis {r:.3f}, robust {rr:.3f}"
                  f"   ({inside.sum()} of {len(Q)} grid points inside the hull)")
            if sname.startswith("36") and not 0.55 <= r <= 0.65:
                failures.append(f"{sname} {fname}: thesis C1/C0 ratio {r:.3f} outside [0.55, 0.65]")
            ct, rb = err["C1 scipy Clough-Tocher"], err["C1 GS robust (default)"]
            if rb.max() > ct.max() or rb.mean() > ct.mean():
                failures.append(f"{sname} {fname}: robust C1 ({rb.max():.4g}/{rb.mean():.4g}) worse than Clough-Tocher "
                                f"({ct.max():.4g}/{ct.mean():.4g})")
    print()
    print(subprocess.run([bench, "volume"], check=True, capture_output=True, text=True).stdout)
    env = dict(os.environ, OMP_NUM_THREADS=os.environ.get("OMP_NUM_THREADS", "2"))
    t = subprocess.run([bench, "timing"], check=True, capture_output=True, text=True, env=env).stdout
    print(t)
    m = re.search(r"= ([0-9.]+) s", t)
    if m and float(m.group(1)) >= 1.0:
        failures.append(f"refinement took {m.group(1)} s (target < 1 s)")
    for fl in failures:
        print("TARGET MISSED:", fl)
    if a.check and failures:
        sys.exit(1)


if __name__ == "__main__":
    main()
