"""End to end: 'Pectus: Convert Triangles to Quads', 'Pectus: Quad Mesh Structure Improvement' and 'Pectus: Save Polygonal Mesh' through the
real meshlabserver (filter_quad_convert)."""
import os
import re
import sys

import numpy as np

from harness import SOURCE, check, check_refused, finish, grid, read_ply, run, workdir, write_off, write_ply

sys.path.insert(0, os.path.join(SOURCE, "python"))
from pectus_meshes import beta, saddle_mesh  # noqa: E402  (the project's jittered saddle, thesis eq. 3-25)

EX = os.path.join(SOURCE, "filter_quad_convert", "examples")
d = workdir("quad")


def script(example: str, name: str, **values) -> str:
    """an example script with some parameter values replaced (every parameter stays typed)"""
    text = open(os.path.join(EX, example)).read()
    for k, v in values.items():
        text, n = re.subn(f'(name="{k}" type="\\w+" value=")[^"]*"', f'\\g<1>{v}"', text)
        assert n >= 1, k
    path = os.path.join(d, name + ".mlx")
    open(path, "w").write(text)
    return path


def read_poly_off(path):
    with open(path) as fh:
        tok = fh.read().split()
    assert tok[0] == "OFF", tok[0]
    nv, nf = int(tok[1]), int(tok[2])
    pos = 4
    V = np.array(tok[pos:pos + 3 * nv], float).reshape(nv, 3)
    pos += 3 * nv
    F = []
    for _ in range(nf):
        k = int(tok[pos])
        F.append([int(x) for x in tok[pos + 1:pos + 1 + k]])
        pos += 1 + k
    return V, F




def quad_betas(V, F):
    return np.array([beta(V[f]) for f in F if len(f) == 4])


def saddle_z(x, y):
    return x * x / 10 - y * y / 4


def log_of(r):
    return "\n".join(r.log)


V, F = saddle_mesh()
saddle = write_ply(os.path.join(d, "saddle.ply"), V, F)

# 1. optimal, all quads, on the jittered saddle: 100% quads, none invalid, mean beta >= 0.70; saved as OFF quads
off = os.path.join(d, "saddle_quads.off")
s = script("tri_to_quad_and_save.mlx", "opt", edgeSwap="false", nodeElimination="false", edgeDividing="false",
           fileName=off)
r = run([saddle], s, [(os.path.join(d, "opt.ply"), "fq sa")])
check(r.rc == 0, "optimal: meshlabserver exit 0", r.stdout[-2000:])
Q, QF = read_poly_off(off)
b = quad_betas(Q, QF)
check(len(QF) == 576 and all(len(f) == 4 for f in QF), "saddle: 1152 triangles -> 576 quads (100%)", str(len(QF)))
check(b.min() > 0, "no quad with beta <= 0", str(b.min()))
check(b.mean() >= 0.70, "mean beta >= 0.70 straight from conversion", f"{b.mean():.4f}")
check(np.allclose(Q, V, atol=1e-5), "conversion keeps the nodes (no node added or moved)")
log = log_of(r)
m = re.search(r"Quads: ([\d.]+)% quads .*invalid quads \(beta <= 0\): (\d+); beta min ([\d.]+) mean ([\d.]+); time", log)
check(m is not None and float(m.group(1)) == 100.0 and int(m.group(2)) == 0, "Log: 100% quads, 0 invalid, time", log)
if m:
    check(abs(float(m.group(4)) - b.mean()) < 1e-3 and abs(float(m.group(3)) - b.min()) < 1e-3,
          "Log mean/min beta = beta of the saved quads", f"{m.group(3)} {m.group(4)} vs {b.min():.4f} {b.mean():.4f}")
fq = read_ply(os.path.join(d, "opt.ply"))["face"]["quality"]
check(len(fq) == 1152 and abs(fq.mean() - b.mean()) < 1e-3, "per-face quality = beta of each face's quad", str(fq.mean()))
opt_mean = b.mean()
print(log)

# 2. greedy, quad-dominant: valid quads, total quality never above the optimum
offg = os.path.join(d, "saddle_greedy.off")
r = run([saddle], script("tri_to_quad_and_save.mlx", "greedy", pairing=1, leftovers=1, edgeSwap="false",
                         nodeElimination="false", edgeDividing="false", fileName=offg), [])
check(r.rc == 0, "greedy: exit 0", r.stdout[-2000:])
G, GF = read_poly_off(offg)
bg = quad_betas(G, GF)
check(len(bg) > 0 and bg.min() > 0, "greedy: no quad with beta <= 0", str(bg.min() if len(bg) else None))
check(bg.sum() <= b.sum() + 1e-6, "greedy total beta <= optimal total beta", f"{bg.sum():.3f} vs {b.sum():.3f}")
check("greedy, quad-dominant" in log_of(r), "Log names the mode", log_of(r))
print(log_of(r))

# 3. no perfect matching (one triangle removed): quad-dominant keeps a triangle; all quads splits on the C1 surface
odd = write_ply(os.path.join(d, "saddle_odd.ply"), V, F[:500] + F[501:])
offd = os.path.join(d, "odd_qd.off")
r = run([odd], script("tri_to_quad_and_save.mlx", "oddqd", leftovers=1, edgeSwap="false", nodeElimination="false",
                      edgeDividing="false", fileName=offd), [])
_, DF = read_poly_off(offd)
ntri = sum(len(f) == 3 for f in DF)
check(r.rc == 0 and ntri >= 1, "odd count, quad-dominant: leftover triangles kept", str(ntri))
offa = os.path.join(d, "odd_all.off")
r = run([odd], script("tri_to_quad_and_save.mlx", "oddall", edgeSwap="false", nodeElimination="false",
                      edgeDividing="false", fileName=offa), [])
check(r.rc == 0, "odd count, all quads: exit 0", r.stdout[-2000:])
A, AF = read_poly_off(offa)
ba = quad_betas(A, AF)
check(len(AF) > 0 and all(len(f) == 4 for f in AF), "all quads: 100% quads", str(sum(len(f) == 3 for f in AF)))
check(len(AF) == 4 * (len(DF) - ntri) + 3 * ntri, "all quads: quad -> 4, triangle -> 3", f"{len(AF)}")
check(ba.min() > 0, "all quads: no quad with beta <= 0", str(ba.min()))
new = A[len(V):]
dev = np.max(np.abs(new[:, 2] - saddle_z(new[:, 0], new[:, 1])))
check(dev < 0.02, "new nodes on the surface (|z - saddle| small)", str(dev))
check("split into quads" in log_of(r), "Log reports the split", log_of(r))
print(log_of(r))

# 4. Pectus: Save Polygonal Mesh: OBJ and VTK with real quads; the OFF reads back in MeshLab as quads (faux edges)
obj = os.path.join(d, "q.obj")
r = run([off], script("save_polygonal.mlx", "obj", fileName=obj, format=0), [])
faces = [l.split()[1:] for l in open(obj) if l.startswith("f ")] if os.path.exists(obj) else []
check(r.rc == 0 and len(faces) == 576 and all(len(f) == 4 for f in faces), "OBJ: 576 quad faces", str(len(faces)))
vtk = os.path.join(d, "q.vtk")
r = run([off], script("save_polygonal.mlx", "vtk", fileName=vtk, format=2), [])
text = open(vtk).read() if os.path.exists(vtk) else ""
check(r.rc == 0 and "POLYGONS 576 2880" in text and "POINTS 625" in text, "VTK polydata: 576 quads")
back = os.path.join(d, "back.off")
r = run([off], script("save_polygonal.mlx", "off", fileName=back, format=1), [])
B, BF = read_poly_off(back) if os.path.exists(back) else (np.zeros((0, 3)), [])
def canon(f):
    k = f.index(min(f))
    return tuple(f[k:] + f[:k])


check(r.rc == 0 and sorted(map(canon, BF)) == sorted(map(canon, QF)) and np.allclose(B, Q, atol=1e-6),
      "OFF re-read by MeshLab and re-saved: same quads", f"{len(BF)} faces")

# 5. Pectus: Quad Mesh Structure Improvement: triangles (saddle) and quads
r = run([saddle], script("structure.mlx", "stri"), [(os.path.join(d, "stri.ply"), "fq sa")])
log = log_of(r)
m = re.search(r"edge swaps (\d+), node eliminations (\d+), edge divisions (\d+).*worst alpha ([\d.]+) -> ([\d.]+), "
              r"mean alpha ([\d.]+) -> ([\d.]+)", log)
check(r.rc == 0 and m is not None, "structure (triangles): exit 0, counts in the Log", log)
if m:
    check(int(m.group(1)) + int(m.group(2)) + int(m.group(3)) > 0, "some operations applied", log)
    check(float(m.group(5)) >= float(m.group(4)), "worst alpha not lower", log)


def valence_hist(log, when):
    m = re.search(f"Valence of interior nodes {when}: (.*)", log)
    return {int(k.rstrip("+")): int(v) for k, v in (p.split(":") for p in m.group(1).split(", "))} if m else {}


vb, va = valence_hist(log, "before"), valence_hist(log, "after")
check(vb.get(6, 0) == 0 and va.get(6, 0) > 0.5 * sum(va.values()),
      "triangles: valence histogram logged; most interior nodes reach valence 6 (alternating grid has 4 and 8)",
      f"{vb} -> {va}")
tri_out = read_ply(os.path.join(d, "stri.ply"))
check(abs(len(tri_out["F"]) - 1152) < 100, "structure (triangles): about the same element count", str(len(tri_out["F"])))
print(log)
r = run([off], script("structure.mlx", "squad"), [(os.path.join(d, "squad.ply"), "fq sa")])
log = log_of(r)
m = re.search(r"\(quads\): edge swaps (\d+), node eliminations (\d+), edge divisions (\d+).*worst beta ([\d.]+) -> "
              r"([\d.]+), mean beta ([\d.]+) -> ([\d.]+)", log)
check(r.rc == 0 and m is not None, "structure (quads): exit 0, counts in the Log", log)
if m:
    check(float(m.group(5)) > float(m.group(4)), "quads: worst beta rises", log)
    check(float(m.group(7)) >= float(m.group(6)), "quads: mean beta not lower", log)
fq = read_ply(os.path.join(d, "squad.ply"))["face"]["quality"]
check(len(fq) > 0 and fq.min() > 0, "quads after the operators: every beta > 0", str(fq.min() if len(fq) else None))
print(log)

# 6. bad input: a message in the Log, non-zero exit, nothing written
nmV = np.vstack([V, [[0.0, 0.0, 3.0]]])
inner = next((f[0], f[1]) for f in F if sum(1 for g in F if f[0] in g and f[1] in g) == 2)  # an interior edge
nm = write_ply(os.path.join(d, "nonmanifold.ply"), nmV, F + [[inner[0], inner[1], len(V)]])
Vq, Fq = grid(4, quads=True)
quads_in = write_off(os.path.join(d, "quads_in.off"), Vq, Fq)
iso = write_ply(os.path.join(d, "isolated.ply"), np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [5, 0, 0], [6, 0, 0], [5, 1, 0]], float),
                [[0, 1, 2], [3, 4, 5]])
bad = [
    ("non-manifold edge", nm, script("tri_to_quad.mlx", "b1"), "manifold"),
    ("already quads", quads_in, script("tri_to_quad.mlx", "b2"), "already holds quads"),
    ("isolated triangles", iso, script("tri_to_quad.mlx", "b3"), "isolated triangles"),
    ("minQuality 1", saddle, script("tri_to_quad.mlx", "b4", minQuality=1), "minQuality"),
    ("unwritable path", off, script("save_polygonal.mlx", "b5", fileName="/nonexistent-dir/q.obj"), "cannot write"),
    ("structure on non-manifold", nm, script("structure.mlx", "b6"), "manifold"),
]
for what, path, s, msg in bad:
    o = os.path.join(d, "bad.ply")
    if os.path.exists(o):
        os.remove(o)
    r = run([path], s, [(o, "sa")])
    check_refused(r, msg, what)
finish()
