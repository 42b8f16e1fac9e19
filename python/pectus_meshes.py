"""Meshes for tests and benchmarks (numpy): the ones the project builds itself, plain OFF/PLY reading and
writing, and reference implementations of the element qualities (thesis eqs. 3-20, 3-22/3-23) that the
tests and benchmarks check the C++ filters against."""
from __future__ import annotations

import numpy as np


def saddle_mesh(n_side: int = 25, jitter: float = 0.3, seed: int = 7):
    """z = x^2/10 - y^2/4 on [-5,5]^2 (thesis eq. 3-25): n_side^2 nodes (625 by default), interior
    nodes jittered in the plane by up to jitter * spacing; triangles (alternating diagonals)."""
    rng = np.random.default_rng(seed)
    h = 10.0 / (n_side - 1)
    V = []
    for j in range(n_side):
        for i in range(n_side):
            x, y = -5 + i * h, -5 + j * h
            if 0 < i < n_side - 1 and 0 < j < n_side - 1:
                x += rng.uniform(-jitter, jitter) * h
                y += rng.uniform(-jitter, jitter) * h
            V.append((x, y, x * x / 10 - y * y / 4))
    F = []
    for j in range(n_side - 1):
        for i in range(n_side - 1):
            a = j * n_side + i
            b, c, d = a + 1, a + n_side + 1, a + n_side
            F += [[a, b, c], [a, c, d]] if (i + j) % 2 == 0 else [[a, b, d], [b, c, d]]
    return np.array(V), F


def closed_ellipsoid(a, b, c, nth, nph):
    """closed triangulated ellipsoid with semi-axes a, b, c (x, y, z) centred at the origin, outward
    faces: nth vertices around, nph - 1 rings plus the two poles"""
    V = [(0.0, 0.0, -c)]
    for i in range(1, nph):
        ph = -np.pi / 2 + np.pi * i / nph
        for j in range(nth):
            th = 2 * np.pi * j / nth
            V.append((a * np.cos(ph) * np.cos(th), b * np.cos(ph) * np.sin(th), c * np.sin(ph)))
    V.append((0.0, 0.0, c))
    top = len(V) - 1
    idx = lambda i, j: 1 + (i - 1) * nth + (j % nth)
    F = [[0, idx(1, j + 1), idx(1, j)] for j in range(nth)]
    for i in range(1, nph - 1):
        for j in range(nth):
            F += [[idx(i, j), idx(i, j + 1), idx(i + 1, j + 1)], [idx(i, j), idx(i + 1, j + 1), idx(i + 1, j)]]
    F += [[top, idx(nph - 1, j), idx(nph - 1, j + 1)] for j in range(nth)]
    return np.array(V), F


def write_ply(path: str, V, F, vprops=None, fprops=None):
    """ascii PLY, polygons of any size; vprops/fprops: optional per-vertex/per-face properties
    {name: (ply type, values)}, e.g. {"quality": ("float", q), "red": ("uchar", r), ...}"""
    vprops, fprops = vprops or {}, fprops or {}
    with open(path, "w") as fh:
        fh.write(f"ply\nformat ascii 1.0\nelement vertex {len(V)}\nproperty float x\nproperty float y\nproperty float z\n"
                 + "".join(f"property {t} {n}\n" for n, (t, _) in vprops.items())
                 + f"element face {len(F)}\nproperty list uchar int vertex_indices\n"
                 + "".join(f"property {t} {n}\n" for n, (t, _) in fprops.items()) + "end_header\n")
        for i, p in enumerate(V):
            fh.write(f"{p[0]:.9g} {p[1]:.9g} {p[2]:.9g}" + "".join(f" {v[i]:.9g}" for _, v in vprops.values()) + "\n")
        for i, f in enumerate(F):
            fh.write(f"{len(f)} " + " ".join(str(int(k)) for k in f) + "".join(f" {v[i]:.9g}" for _, v in fprops.values())
                     + "\n")
    return path


def write_off(path: str, V, F):
    """OFF, polygons of any size (MeshLab reads quads back with faux edges)"""
    with open(path, "w") as fh:
        fh.write(f"OFF\n{len(V)} {len(F)} 0\n")
        for p in V:
            fh.write(f"{p[0]:.9g} {p[1]:.9g} {p[2]:.9g}\n")
        for f in F:
            fh.write(f"{len(f)} " + " ".join(str(int(i)) for i in f) + "\n")
    return path


def read_off(path: str):
    """(V, F) of an ascii OFF file; F keeps each polygon's size"""
    tok = open(path).read().split()
    assert tok[0].startswith("OFF"), path
    nv, nf = int(tok[1]), int(tok[2])
    V = np.array(tok[4:4 + 3 * nv], float).reshape(nv, 3)
    pos, F = 4 + 3 * nv, []
    for _ in range(nf):
        k = int(tok[pos])
        F.append([int(x) for x in tok[pos + 1:pos + 1 + k]])
        pos += 1 + k
    return V, F


def alpha(a, b, c):
    """triangle quality alpha (thesis eq. 3-20), as pectus::triangleAlpha"""
    return 2 * np.sqrt(3) * np.linalg.norm(np.cross(b - a, c - a)) / (
        np.sum((b - a) ** 2) + np.sum((c - b) ** 2) + np.sum((a - c) ** 2))


def beta(p):
    """Knupp's quad shape quality along the quad's own normal (diagonals' cross), as pectus::quadBeta;
    0 for a quad with a reflex, folded or degenerate corner"""
    n = np.cross(p[2] - p[0], p[3] - p[1])
    ln = np.linalg.norm(n)
    if ln == 0:
        return 0.0
    n = n / ln
    s = 0.0
    for k in range(4):
        e1, e2 = p[(k + 1) % 4] - p[k], p[(k + 3) % 4] - p[k]
        a = np.dot(np.cross(e1, e2), n)
        if a <= 0:
            return 0.0
        s += (e1 @ e1 + e2 @ e2) / a
    return 8.0 / s
