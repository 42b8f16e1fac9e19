"""End to end: 'Pectus: Element Quality (Triangle Alpha / Quad Beta)' through the real meshlabserver."""
import math
import os

import numpy as np

from pectus_meshes import alpha
from harness import SOURCE, check, check_refused, finish, grid, read_ply, run, workdir, write_off, write_ply

NAME = "Pectus: Element Quality (Triangle Alpha / Quad Beta)"
EXAMPLE = os.path.join(SOURCE, "filter_mga_smooth", "examples", "element_quality.mlx")
d = workdir("quality")


def script(element_type: int, colorize: bool = True) -> str:
    path = os.path.join(d, f"q{element_type}{int(colorize)}.mlx")
    text = open(EXAMPLE).read().replace('value="0" enum_cardinality="3"', f'value="{element_type}" enum_cardinality="3"')
    text = text.replace('name="colorize" type="RichBool" value="true"', f'name="colorize" type="RichBool" value="{"true" if colorize else "false"}"')
    open(path, "w").write(text)
    return path




# 1. jittered triangle grid: per-face alpha written as face quality, matches Python's alpha
V, F = grid(6, quads=False, jitter=0.3, seed=3)
inp = write_ply(os.path.join(d, "tri.ply"), V, F)
out = os.path.join(d, "tri_q.ply")
r = run([inp], script(0), [(out, "fq fc sa")])
check(r.rc == 0, "triangle mesh: meshlabserver exit 0", r.stdout[-2000:])
m = read_ply(out)
q = m["face"]["quality"]
expected = np.array([alpha(*(V[i] for i in f)) for f in F])
check(len(q) == len(F), "one quality per face", f"{len(q)} vs {len(F)}")
check(np.allclose(q, expected, atol=1e-5), "face quality = alpha of eq. 3-20", f"max diff {np.max(np.abs(q - expected))}")
check("red" in m["face"], "face colours saved")
# red-to-blue ramp: the worst face is the reddest
worst, best = int(np.argmin(q)), int(np.argmax(q))
check(m["face"]["red"][worst] >= m["face"]["red"][best] and m["face"]["blue"][best] >= m["face"]["blue"][worst],
      "quality colours: low quality redder than high quality")
log = "\n".join(r.log)
check(f"min {np.min(expected):.4f}" in log and f"mean {np.mean(expected):.4f}" in log,
      "Log line with min and mean", log)
hist = np.histogram(np.clip(expected, 0, 1 - 1e-12), bins=10, range=(0, 1))[0]
check("histogram, 10 bins on [0,1]: " + " ".join(str(h) for h in hist) in log, "Log histogram matches", log)

# 2. quads in OFF (MeshLab sets faux edges): beta per quad on both triangles; a square grid gives 1
Vq, Fq = grid(4, quads=True)
Vq[12] = (2.3, 2.2, 0.0)  # move the centre vertex: four quads lose quality, all stay convex
inp = write_off(os.path.join(d, "quad.off"), Vq, Fq)
out = os.path.join(d, "quad_q.ply")
r = run([inp], script(0), [(out, "fq sa")])
check(r.rc == 0, "quad mesh: exit 0", r.stdout[-2000:])
q = read_ply(out)["face"]["quality"]
check(len(q) == 2 * len(Fq), "quads saved as triangle pairs")
check(int(np.sum(np.isclose(q, 1.0, atol=1e-5))) == 2 * 12, "12 untouched unit quads have beta = 1 on both triangles",
      str(sorted(q)))
check(np.min(q) < 0.95 and np.min(q) > 0.5, "moved-vertex quads have 0.5 < beta < 0.95", str(np.min(q)))
check(any("quad beta): 16 quads" in l for l in r.log), "Log names 16 quads", "\n".join(r.log))

# 3. Triangles mode on the quad mesh: alpha of right isosceles triangles
r = run([inp], script(1), [(out, "fq sa")])
q = read_ply(out)["face"]["quality"]
check(r.rc == 0 and int(np.sum(np.isclose(q, math.sqrt(3) / 2, atol=1e-5))) >= 24,
      "Triangles mode ignores faux edges (untouched halves have alpha = sqrt(3)/2)", str(sorted(q)))

# 4. bad input: each a clear message and a non-zero exit
bad = {}
bad["quad request on triangles"] = (write_ply(os.path.join(d, "t.ply"), V, F), 2, "holds only triangles")
pts = os.path.join(d, "points.ply")
write_ply(pts, V, [])
bad["points only"] = (pts, 0, "no faces")
nm_V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1]], float)
nm = write_ply(os.path.join(d, "nonmanifold.ply"), nm_V, [[0, 1, 2], [1, 0, 3], [0, 1, 4]])
deg = write_ply(os.path.join(d, "degenerate.ply"), np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0]], float),
                [[0, 1, 2], [0, 1, 3]])
for what, (path, et, msg) in bad.items():
    r = run([path], script(et), [(os.path.join(d, "bad.ply"), "fq sa")])
    check_refused(r, msg, what)
# defined results (documented in the tool-tip): non-manifold edges and degenerate faces are measured
r = run([nm], script(0), [(os.path.join(d, "nm_q.ply"), "fq sa")])
check(r.rc == 0 and len(read_ply(os.path.join(d, "nm_q.ply"))["face"]["quality"]) == 3, "non-manifold edge: measured, exit 0")
r = run([deg], script(0), [(os.path.join(d, "deg_q.ply"), "fq sa")])
qd = read_ply(os.path.join(d, "deg_q.ply"))["face"]["quality"]
check(r.rc == 0 and qd[0] == 0.0 and qd[1] > 0.5, "degenerate face: alpha = 0, exit 0", str(qd))
# a quad request on a non-manifold faux edge is refused
nmq = os.path.join(d, "nmq.off")
write_off(nmq, np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float), [[0, 1, 2, 3]])
r = run([nmq], script(2), [(os.path.join(d, "nmq_q.ply"), "fq sa")])
check(r.rc == 0, "single quad from OFF accepted")
finish()
