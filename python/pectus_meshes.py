"""Test and benchmark meshes the project builds itself (standard library + numpy)."""
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


def write_ply(path, V, F):
    with open(path, "w") as fh:
        fh.write(f"ply\nformat ascii 1.0\nelement vertex {len(V)}\nproperty float x\nproperty float y\n"
                 f"property float z\nelement face {len(F)}\nproperty list uchar int vertex_indices\nend_header\n")
        fh.writelines(f"{p[0]:.7g} {p[1]:.7g} {p[2]:.7g}\n" for p in V)
        fh.writelines(f"{len(f)} " + " ".join(map(str, f)) + "\n" for f in F)
