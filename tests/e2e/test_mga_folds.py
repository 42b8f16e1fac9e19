"""End to end: a scan with folds injected (libcgal-demo's cow, nodes pushed past a neighbour) smoothed by
'Pectus: MGA Surface Mesh Smoothing' and 'Pectus: Gradient Surface Mesh Smoothing (Baseline)' with their example
scripts through meshlabserver comes out with no fold it did not have and no more folds than it went in
with. A fold: an element whose normal points against the mean of its edge neighbours' unit normals,
counted here independently of the filters' code. Skipped without libcgal-demo."""
import os
import re

import numpy as np

from pectus_meshes import read_off, write_off
from harness import SOURCE, cgal_meshes, check, example_script, finish, run, workdir

d = workdir("mga_folds")
cow = cgal_meshes(d, "cow")["cow"]


def folds(V, F):
    """per face: True if its unit normal points against the sum of its edge neighbours' unit normals"""
    V, F = np.asarray(V, float), np.asarray(F)
    n = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    ln = np.linalg.norm(n, axis=1)
    n = np.where(ln[:, None] > 0, n / np.maximum(ln, 1e-300)[:, None], 0.0)
    by_edge = {}
    for fi, f in enumerate(F):
        for k in range(3):
            by_edge.setdefault(tuple(sorted((int(f[k]), int(f[(k + 1) % 3])))), []).append(fi)
    mean = np.zeros_like(n)
    for fs in by_edge.values():
        for a in fs:
            for b in fs:
                if a != b:
                    mean[a] += n[b]
    return np.einsum("ij,ij->i", n, mean) < 0


V, F = read_off(cow)
V, F = np.asarray(V, float), np.asarray(F)
folded0 = folds(V, F)
# inject folds: every 150th node (stars apart) moves 1.6 times the way to its first neighbour, past it
rng = np.random.default_rng(7)
nbr = {}
for f in F:
    for k in range(3):
        nbr.setdefault(int(f[k]), []).append(int(f[(k + 1) % 3]))
W = V.copy()
for v in range(0, len(V), 150):
    w = nbr[v][int(rng.integers(len(nbr[v])))]
    W[v] = V[v] + 1.6 * (V[w] - V[v])
inp = write_off(os.path.join(d, "cow_folded.off"), W, F.tolist())
folded_in = folds(read_off(inp)[0], F)  # as written, to the digits in the file
check(folded_in.sum() >= folded0.sum() + 20, "folds injected into the cow", f"{folded0.sum()} -> {folded_in.sum()}")

EXAMPLES = {"MGA": os.path.join(SOURCE, "filter_mga_smooth", "examples", "mga_smooth.mlx"),
            "Gradient": os.path.join(SOURCE, "filter_mga_smooth", "examples", "gradient_smooth.mlx")}
for ex, path in EXAMPLES.items():
    out = os.path.join(d, f"cow_{ex}.off")
    r = run([inp], example_script(path, d, ex), [(out, "")])
    check(r.rc == 0 and os.path.exists(out), f"{ex}: meshlabserver exit 0", r.stdout[-1500:])
    if r.rc != 0 or not os.path.exists(out):
        continue
    U = np.asarray(read_off(out)[0], float)
    folded_out = folds(U, F)
    new = folded_out & ~folded_in
    check(new.sum() == 0, f"{ex}: no new fold", f"{new.sum()} new, faces {np.flatnonzero(new)[:10]}")
    check(folded_out.sum() <= folded_in.sum(), f"{ex}: no more folds out than in ({folded_in.sum()} -> {folded_out.sum()})",
          f"{folded_in.sum()} -> {folded_out.sum()}")
    m = re.search(r"folds \(elements facing against their edge neighbours\) (\d+) -> (\d+), (\d+) new", r.stdout)
    check(m is not None and (int(m[1]), int(m[2]), int(m[3])) == (folded_in.sum(), folded_out.sum(), 0),
          f"{ex}: the Log counts the folds as this test does",
          (m[0] if m else r.stdout[-800:]) + f"; counted {folded_in.sum()} -> {folded_out.sum()}")
finish()
