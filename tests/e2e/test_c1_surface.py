"""E2E: the C1 surface filters in the real meshlabserver, driven by the shipped example scripts."""
import os
import re

import numpy as np

import harness as h
import pectus_mlx as mlx

EX = os.path.join(h.SOURCE, "filter_c1_surface", "examples")
W = h.workdir("c1")
AXES = np.array([1.0, 0.8, 0.6])


def ellipsoid(level):
    t = (1 + 5 ** 0.5) / 2
    V = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
         (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    V = [np.array(v) / np.linalg.norm(v) for v in V]
    F = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6),
         (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10),
         (8, 6, 7), (9, 8, 1)]
    for _ in range(level):
        mid = {}

        def m(i, j):
            k = (min(i, j), max(i, j))
            if k not in mid:
                p = V[i] + V[j]
                V.append(p / np.linalg.norm(p))
                mid[k] = len(V) - 1
            return mid[k]
        NF = []
        for a, b, c in F:
            x, y, z = m(a, b), m(b, c), m(c, a)
            NF += [(a, x, z), (b, y, x), (c, z, y), (x, y, z)]
        F = NF
    return np.array(V) * AXES, F


def volume(V, F):
    return sum(np.dot(V[a], np.cross(V[b], V[c])) for a, b, c in F) / 6.0


def script(name, **override):
    """the shipped example with some parameters changed (every parameter stays present and typed)"""
    with open(os.path.join(EX, name)) as fh:
        text = fh.read()
    for k, v in override.items():
        text, n = re.subn(rf'(<Param name="{k}" type="\w+" value=")[^"]*(")', rf"\g<1>{v}\g<2>", text)
        assert n == 1, k
    path = os.path.join(W, name)
    with open(path, "w") as fh:
        fh.write(text)
    return path


exact = 4.0 / 3.0 * np.pi * AXES.prod()
V, F = ellipsoid(2)
src = h.write_ply(os.path.join(W, "ellipsoid.ply"), V, F)
flat_err = abs(volume(V, F) - exact) / exact

# 1. refinement of a closed coarse ellipsoid (320 faces), k = 6, new layer
out = os.path.join(W, "refined.ply")
r = h.run([src], script("c1_refine.mlx", subdivisions=8), outputs=[(out, "vn", 1)])
h.check(r.rc == 0, "refine exits 0", r.stdout[-2000:])
h.check(any("C1 refine" in line and "320 patches" in line for line in r.log), "refine logs what it did", str(r.log))
if os.path.exists(out):
    m = h.read_ply(out)
    RV, RF = m["V"], m["F"]
    h.check(len(RF) == 320 * 64, f"320 faces split 8x8 -> {len(RF)} faces")
    h.check(len(RV) == 162 + 480 * 7 + 320 * 21, f"shared edge vertices: {len(RV)} vertices")
    edges = {}
    for f in RF:
        for i in range(3):
            e = (min(f[i], f[(i + 1) % 3]), max(f[i], f[(i + 1) % 3]))
            edges[e] = edges.get(e, 0) + 1
    h.check(all(c == 2 for c in edges.values()), "refined mesh is closed and conforming (every edge in 2 faces)")
    err = abs(volume(RV, RF) - exact) / exact
    print(f"volume error: flat {100 * flat_err:.3f}%  C1 8x8 {100 * err:.4f}%")
    h.check(err < flat_err / 20, f"volume error {100 * err:.4f}% far below the flat mesh's {100 * flat_err:.3f}%")
    h.check(err < 0.0014, f"volume error {100 * err:.4f}% below PN triangles' 0.14%")
    # refined vertices near the ellipsoid: algebraic distance
    q = np.sqrt(((RV / AXES) ** 2).sum(axis=1))
    h.check(np.abs(q - 1).max() < 0.01, f"refined vertices on the ellipsoid within 1% ({np.abs(q - 1).max():.4f})")
else:
    h.check(False, "refined mesh saved")

# 2. projection of a finer, inflated ellipsoid onto the C1 surface of the coarse one
V2, F2 = ellipsoid(3)
pts = h.write_ply(os.path.join(W, "points.ply"), V2 * 1.05, F2)
out2 = os.path.join(W, "projected.ply")
r = h.run([src, pts], script("c1_project.mlx", surfaceMesh=0), outputs=[(out2, "vn", 1)])
h.check(r.rc == 0, "project exits 0", r.stdout[-2000:])
h.check(any("C1 project" in line and "displacement" in line for line in r.log), "project logs displacements", str(r.log))
if os.path.exists(out2):
    P = h.read_ply(out2)["V"]
    q = np.sqrt(((P / AXES) ** 2).sum(axis=1))
    h.check(len(P) == len(V2), "projected layer keeps its vertices")
    h.check(np.abs(q - 1).max() < 0.01, f"projected vertices on the ellipsoid within 1%: {np.abs(q - 1).max():.4f}")
    # projecting the projection changes nothing (the points are on the surface)
    out3 = os.path.join(W, "projected2.ply")
    r2 = h.run([src, out2], script("c1_project.mlx", surfaceMesh=0), outputs=[(out3, "", 1)])
    P3 = h.read_ply(out3)["V"] if os.path.exists(out3) else np.zeros((0, 3))
    h.check(r2.rc == 0 and len(P3) == len(P) and np.abs(P3 - P).max() < 1e-5, "projection is idempotent")
else:
    h.check(False, "projected mesh saved")

# 3. height field: a quadratic z(x, y) on a jittered grid is reproduced (the local quadratic fit is exact for quadratics)
GV, GF = h.grid(6, quads=False, jitter=0.3, seed=4)
GV = GV / 6.0
GV[:, 2] = 0.3 + 0.5 * GV[:, 0] - GV[:, 1] + 0.8 * GV[:, 0] ** 2 - 0.6 * GV[:, 0] * GV[:, 1] + 0.4 * GV[:, 1] ** 2
hf = h.write_ply(os.path.join(W, "height.ply"), GV, GF)
out4 = os.path.join(W, "height_refined.ply")
r = h.run([hf], script("c1_refine.mlx", subdivisions=4, frame=1, newLayer="false", gradientMethod=2), outputs=[(out4, "", 0)])
h.check(r.rc == 0, "height-field refine exits 0", r.stdout[-2000:])
if os.path.exists(out4):
    R = h.read_ply(out4)["V"]
    x, y = R[:, 0], R[:, 1]
    z = 0.3 + 0.5 * x - y + 0.8 * x ** 2 - 0.6 * x * y + 0.4 * y ** 2
    h.check(len(h.read_ply(out4)["F"]) == len(GF) * 16, "height field split 4x4 in place")
    h.check(np.abs(R[:, 2] - z).max() < 2e-6, f"quadratic height field reproduced (float output): {np.abs(R[:, 2] - z).max():.2e}")
# thesis gradients: no NaN, output saved
out5 = os.path.join(W, "height_thesis.ply")
r = h.run([hf], script("c1_refine.mlx", subdivisions=2, gradientMethod=1), outputs=[(out5, "", 1)])
h.check(r.rc == 0 and os.path.exists(out5) and np.isfinite(h.read_ply(out5)["V"]).all(), "thesis gradients refine")

# 4. bad input: a non-manifold edge is refused with a message, and the layer is left alone
bad = h.write_ply(os.path.join(W, "bad.ply"), [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1), (0, -1, 0.5)],
                  [(0, 1, 2), (0, 1, 3), (0, 1, 4)])
r = h.run([bad], script("c1_refine.mlx"))
h.check(r.rc != 0, "non-manifold input fails the filter")
h.check(any("non-manifold edge" in line for line in r.log), "the Log names the non-manifold edge", str(r.log))
# a folded mesh in height-field mode is refused
r = h.run([src], script("c1_refine.mlx", frame=1))
h.check(r.rc != 0 and any("not a height field" in line for line in r.log), "height-field mode refuses a closed surface")
h.finish()
