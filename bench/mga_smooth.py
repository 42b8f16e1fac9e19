#!/usr/bin/python3
"""Surface mesh smoothing with fixed connectivity, side by side in one run on the same inputs:
our MGA smoothing (thesis 4.2) and its conjugate gradient baseline (Table 4-1) against MeshLab's Laplacian
and Taubin smooth (through the same meshlabserver), OpenMesh-Smoothing (libopenmesh-apps), and CGAL 5.5's
tangential_relaxation (each iteration projected onto the input by an AABB tree) and
angle_and_area_smoothing (Delaunay flips off, projection on).

Inputs: the jittered saddle z = x^2/10 - y^2/4 on [-5,5]^2 (611 nodes, triangles; the lattice of the unit
test), a jittered 25x25 quad grid on the same saddle (576 quads; triangle-only peers smooth its
triangulation, the quads are measured); from Debian's libcgal-demo the organic (CT and scanned) meshes
femur.off, bunny00.off, elephant.off, hand.off and cow.off, and the CAD parts fandisk.off, anchor_dense.off and
cube-meshed.off.
Columns: element quality (alpha for triangles, Knupp's beta for quads, the project's own code for every
row), max deviation from the exact saddle (|z - saddle(x, y)|) or, for the CGAL meshes, max distance to the
input surface over its bbox diagonal, time of the smoothing (our rows: the smoothing call alone, from the
filter's Log; CGAL: the call alone; MeshLab's rows: wall time minus a no-op meshlabserver run on the same
file; OpenMesh: the process), and on the CAD
parts the largest change of the dihedral angle of a crease edge (an edge of the input bent by 20 degrees or
more; these parts have no noise) and how many crease nodes moved.

    bench/mga_smooth.py [--build build-mga] [--only saddle,quad,femur,bunny,elephant,hand,cow,fandisk,anchor,cube]
                        [--repeat N]

--repeat N runs every row N times and prints its fastest time (the results are the same each time): on a
shared machine the fastest run is the one least slowed by other work.

Needs the targets filter_mga_smooth, prefix and bench_mga_smooth built in --build, and the packages
libopenmesh-apps and libcgal-demo.
"""
import argparse
import os
import re
import subprocess
import sys
import tarfile
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, os.path.join(ROOT, "python"))
import pectus_mlx as mlx  # noqa: E402
import pectus_meshes  # noqa: E402  (the main job's saddle grid)
from pectus_meshes import read_off, write_off  # noqa: E402


def saddle(x, y):
    return x * x / 10 - y * y / 4


def saddle_triangles(seed=3):
    """23/22-node rows with alternating offsets (611 nodes), interior nodes jittered by +-0.3 h in the plane,
    rows zipped into triangles: the mesh of filter_mga_smooth/tests (its own random numbers)."""
    rng = np.random.default_rng(seed)
    nx, ny = 23, 26
    h = 10.0 / (nx - 1)
    V, rows = [], []
    for j in range(ny):
        y = -5 + 10.0 * j / (ny - 1)
        xs = [-5 + h * i for i in range(nx)] if j % 2 == 0 else [-5] + [-5 + h * (i + 0.5) for i in range(nx - 1)] + [5]
        row = []
        for i, x in enumerate(xs):
            yy = y
            if 0 < j < ny - 1 and 0 < i < len(xs) - 1:
                x += rng.uniform(-0.3 * h, 0.3 * h)
                yy += rng.uniform(-0.3 * h, 0.3 * h)
            row.append(len(V))
            V.append((x, yy, saddle(x, yy)))
        rows.append(row)
    F = []
    for j in range(ny - 1):
        A, B = rows[j], rows[j + 1]
        i = k = 0
        while i + 1 < len(A) or k + 1 < len(B):
            adv_a = k + 1 >= len(B) or (i + 1 < len(A) and V[A[i + 1]][0] < V[B[k + 1]][0])
            if adv_a:
                F.append([A[i], A[i + 1], B[k]])
                i += 1
            else:
                F.append([A[i], B[k + 1], B[k]])
                k += 1
    return np.array(V), F


def saddle_quads(n=25, jitter=0.3, seed=5):
    """the main job's jittered saddle grid (python/pectus_meshes.py), its cells as quads: 625 nodes, 576 quads"""
    V, _ = pectus_meshes.saddle_mesh(n_side=n, jitter=jitter, seed=seed)
    F = [[j * n + i, j * n + i + 1, (j + 1) * n + i + 1, (j + 1) * n + i] for j in range(n - 1) for i in range(n - 1)]
    return V, F






def triangulate(F):
    return [t for f in F for t in ([f] if len(f) == 3 else [[f[0], f[1], f[2]], [f[0], f[2], f[3]]])]


class Bench:
    def __init__(self, build, work):
        self.tool = os.path.join(build, "bench", "bench_mga_smooth")
        self.prefix = os.path.join(build, "prefix")
        self.work = work

    def meshlab(self, inp, out, filters):
        """wall time of meshlabserver with the filters minus a no-op run on the same file; and the run's Result"""
        t0 = time.perf_counter()
        r = mlx.run([inp], mlx.Script(filters), [(out, "sa")], prefix=self.prefix)
        wall = time.perf_counter() - t0
        if r.rc != 0 or not os.path.exists(out):
            raise RuntimeError(f"meshlabserver failed ({r.rc}): " + "\n".join(r.log[-5:]))
        t0 = time.perf_counter()
        noop = os.path.join(self.work, "noop.off")
        mlx.run([inp], None, [(noop, "sa")], prefix=self.prefix)
        base = time.perf_counter() - t0
        return max(wall - base, 0.0), r

    def tool_out(self, *args):
        p = subprocess.run([self.tool, *args], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        if p.returncode != 0:
            raise RuntimeError(p.stdout.strip())
        return p.stdout


def laplacian():
    return [mlx.Filter("Laplacian Smooth", stepSmoothNum=mlx.Int(3), Boundary=mlx.Bool(False),
                       cotangentWeight=mlx.Bool(True), Selected=mlx.Bool(False))]


def taubin():
    return [mlx.Filter("Taubin Smooth", **{"lambda": mlx.Float(0.5)}, mu=mlx.Float(-0.53), stepSmoothNum=mlx.Int(10),
                       Selected=mlx.Bool(False))]


ENUM3 = ["Auto", "Triangles (alpha)", "Quads (beta)"]


SEARCH = ["Every adjacent element (thesis)", "Guided (faster)", "Guided, local (fastest)"]


FEATURES = ["Crease chains", "Feature and singular angles"]


GUARD = 0.7  # the filters' default worst-element guard


def ours(mga, sweeps, guard=GUARD, min_pass=0.0, feature=None, singular=None, guided=False, search=None, generations=20):
    """search: 0 every element, 1 guided, 2 guided local (default: guided -> 1, else 0); feature, singular:
    angles (feature detection by angles), None: crease chains (the default)"""
    angles = feature is not None or singular is not None
    feature = 60.0 if feature is None else feature
    singular = 90.0 if singular is None else singular
    common = dict(elementType=mlx.Enum(0, ENUM3), maxSweeps=mlx.Int(sweeps), tolerance=mlx.Float(1e-4))
    tail = dict(worstGuard=mlx.Float(guard), minPassBelow=mlx.Float(min_pass),
                featureDetection=mlx.Enum(int(angles), FEATURES), featureAngle=mlx.Float(feature),
                singularAngle=mlx.Float(singular),
                selectionMode=mlx.Enum(0, ["None", "Smooth only selected vertices", "Keep selected vertices fixed"]))
    if mga:
        if search is None:
            search = int(guided)
        return [mlx.Filter("Pectus: MGA Surface Mesh Smoothing", **common, accuracy=mlx.Float(1e-3),
                           generations=mlx.Int(generations),
                           restarts=mlx.Int(4), population=mlx.Int(5),
                           selection=mlx.Enum(0, ["Roulette wheel", "Tournament"]),
                           elementSearch=mlx.Enum(search, SEARCH),
                           **tail, seed=mlx.Int(1))]
    return [mlx.Filter("Pectus: Gradient Surface Mesh Smoothing (Baseline)", **common, cgIterations=mlx.Int(10), **tail)]


CREASE_DEG = 20.0  # a CAD part's edge bent at least this much is a crease edge


def dihedrals(V, F):
    """per undirected edge with two triangles: (a, b) -> dihedral angle in degrees"""
    V = np.asarray(V, float)
    T = np.array(triangulate(F))
    n = np.cross(V[T[:, 1]] - V[T[:, 0]], V[T[:, 2]] - V[T[:, 0]])
    n /= np.maximum(np.linalg.norm(n, axis=1), 1e-300)[:, None]
    faces = {}
    for fi, t in enumerate(T):
        for k in range(3):
            a, b = int(t[k]), int(t[(k + 1) % 3])
            faces.setdefault((min(a, b), max(a, b)), []).append(fi)
    return {e: float(np.degrees(np.arccos(np.clip(n[f[0]] @ n[f[1]], -1, 1)))) for e, f in faces.items() if len(f) == 2}


def crease_change(V, W, F, creases):
    """largest change of a crease edge's dihedral angle (degrees), and how many crease nodes moved
    (more than 1e-6 of the bbox diagonal) from V to W"""
    after = dihedrals(W, F)
    change = max(abs(after[e] - d) for e, d in creases.items())
    nodes = sorted({v for e in creases for v in e})
    diag = float(np.linalg.norm(np.ptp(np.asarray(V, float), axis=0)))
    moved = int(np.sum(np.linalg.norm(np.asarray(W, float)[nodes] - np.asarray(V, float)[nodes], axis=1) > 1e-6 * diag))
    return change, moved


def run_row(b, how, out):
    """one run of a row: its time in seconds"""
    if how[0] == "ml":
        secs, r = b.meshlab(how[1], out, how[2])
        own = r.get("seconds")  # our filters time their own call, as the CGAL driver does
        return own if own is not None else secs
    if how[0] == "om":
        t0 = time.perf_counter()
        p = subprocess.run(["OpenMesh-Smoothing", "-t", "10", how[1], out], stdout=subprocess.PIPE,
                           stderr=subprocess.STDOUT, text=True)
        secs = time.perf_counter() - t0
        if p.returncode != 0 or not os.path.exists(out):
            raise RuntimeError(p.stdout[-300:])
        return secs
    return float(re.search(r"seconds (\S+)", b.tool_out(how[2], how[1], out, "10")).group(1))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default=os.path.join(ROOT, "build-mga"))
    ap.add_argument("--only", default="saddle,quad,femur,bunny,elephant,hand,cow,fandisk,anchor,cube")
    ap.add_argument("--mga-sweeps-large", type=int, default=10,
                    help="MGA/CG default-row sweeps on meshes over 10k nodes (10: MGA's default; the gradient's is 15)")
    ap.add_argument("--repeat", type=int, default=1, help="runs per row; the fastest time is printed")
    args = ap.parse_args()
    if args.repeat < 1:
        ap.error("--repeat must be at least 1")
    work = tempfile.mkdtemp(prefix="mga_bench_")
    b = Bench(os.path.abspath(args.build), work)
    for need in (b.tool, os.path.join(b.prefix, "bin", "meshlabserver")):
        if not os.path.exists(need):
            sys.exit(f"missing {need}: build the targets filter_mga_smooth prefix bench_mga_smooth")

    inputs = []
    if "saddle" in args.only:
        V, F = saddle_triangles()
        inputs.append(("saddle, triangles", V, F, True))
    if "quad" in args.only:
        V, F = saddle_quads()
        inputs.append(("saddle, quads", V, F, True))
    data = "/usr/share/doc/libcgal-dev/data.tar.gz"
    cgal = [("femur", "femur", False), ("bunny", "bunny00", False), ("elephant", "elephant", False),
            ("hand", "hand", False), ("cow", "cow", False), ("fandisk", "fandisk", True), ("anchor", "anchor_dense", True),
            ("cube", "cube-meshed", True)]
    for key, name, cad in cgal:
        if key not in args.only.split(","):
            continue
        if not os.path.exists(data):
            print(f"({name}: install libcgal-demo)")
            continue
        with tarfile.open(data) as tf:
            tf.extract(f"data/meshes/{name}.off", work)
        V, F = read_off(os.path.join(work, "data", "meshes", f"{name}.off"))
        inputs.append((name + (" (CAD)" if cad else ""), V, F, False))

    rows = []
    load0 = os.getloadavg()
    for label, V, F, is_saddle in inputs:
        base = os.path.join(work, re.sub(r"\W+", "_", label))
        elems = write_off(base + "_elements.off", V, F)      # the measured elements (quads stay quads)
        tris = write_off(base + "_tri.off", V, triangulate(F))  # what triangle-only peers smooth
        large = len(V) > 10000
        sweeps_mga = args.mga_sweeps_large if large else 10
        sweeps_cg = args.mga_sweeps_large if large else 15
        cad = label.endswith("(CAD)")
        creases = {e: d for e, d in dihedrals(V, F).items() if d >= CREASE_DEG} if cad else None
        short = f" ({sweeps_mga} sweeps)" if sweeps_mga != 10 else ""
        short_cg = f" ({sweeps_cg} sweeps)" if sweeps_cg != 15 else ""
        runs = [("input", None)]
        runs += [("MeshLab Laplacian (3 steps, cotangent)", ("ml", tris, laplacian())),
                 ("MeshLab Taubin (10 steps)", ("ml", tris, taubin())),
                 ("OpenMesh-Smoothing (tangential, 10 its)", ("om", tris)),
                 ("CGAL tangential_relaxation (10 its, projected)", ("cgal", tris, "tangential")),
                 ("CGAL angle_and_area_smoothing (10 its)", ("cgal", tris, "angle_area")),
                 (f"ours: Gradient baseline, defaults{short_cg}", ("ml", elems, ours(False, sweeps_cg))),
                 (f"ours: MGA, defaults{short}", ("ml", elems, ours(True, sweeps_mga))),
                 (f"ours: MGA, guided search{short}", ("ml", elems, ours(True, sweeps_mga, guided=True))),
                 ("ours: MGA, guided local, 5 sw x 3 gens", ("ml", elems, ours(True, 5, search=2, generations=3)))]
        if not is_saddle:
            # the other feature rule: every node on an edge bent over 60 degrees, or with a normal cone over 90
            runs += [("ours: MGA, features by angles 60/90", ("ml", elems, ours(True, sweeps_mga, feature=60, singular=90)))]
        # settings beyond the defaults, the same for both methods where both are run (named in the row)
        if label == "saddle, triangles":
            runs += [("ours: Gradient, 30 sw, guard .3, pass .32", ("ml", elems, ours(False, 30, 0.3, 0.32))),
                     ("ours: MGA, 30 sw, guard .3, pass .32", ("ml", elems, ours(True, 30, 0.3, 0.32))),
                     ("ours: MGA, 30 sweeps", ("ml", elems, ours(True, 30)))]
        elif label == "saddle, quads":
            runs += [("ours: Gradient, guard .4, pass .45", ("ml", elems, ours(False, 15, 0.4, 0.45))),
                     ("ours: MGA, guard .4, pass .45", ("ml", elems, ours(True, 10, 0.4, 0.45)))]
        elif label == "femur":
            # the peers fix no feature node: the same here, plain sum (guard 0) and a final pass below 0.2
            runs += [("ours: Gradient, no feature, guard 0, pass .2", ("ml", elems, ours(False, 40, 0.0, 0.2, 180, 180))),
                     ("ours: MGA, no feature, guard 0, pass .2", ("ml", elems, ours(True, 30, 0.0, 0.2, 180, 180))),
                     ("ours: MGA guided, no feature, guard 0, pass .2",
                      ("ml", elems, ours(True, 30, 0.0, 0.2, 180, 180, guided=True)))]
        for name, how in runs:
            out = base + "_" + re.sub(r"\W+", "_", name) + ".off"
            secs = 0.0
            try:
                if how is None:
                    out = elems
                else:
                    secs = min(run_row(b, how, out) for _ in range(args.repeat))
                W = read_off(out)[0]
                if W.shape != V.shape:
                    raise RuntimeError(f"vertex count changed {V.shape} -> {W.shape}")
                q = b.tool_out("quality", elems, out).split()
                qmin, qmean = float(q[2]), float(q[3])
                fo = b.tool_out("folds", elems, out).split()  # folds IN OUT NEW
                folded = fo[2] if how is None else f"{fo[3]} / {fo[2]}"
                if is_saddle:
                    dev = float(np.max(np.abs(W[:, 2] - saddle(W[:, 0], W[:, 1]))))
                else:
                    dev = float(b.tool_out("distance", elems, out).split()[1])
                crease = "-"
                if creases:
                    change, moved = crease_change(V, W, F, creases)
                    crease = f"{change:.2f} / {moved}"
                rows.append((label, name, qmin, qmean, dev, secs, len(V), len(F), folded, crease))
            except Exception as e:  # noqa: BLE001  (a failed peer is a row, not the end of the table)
                msg = str(e).splitlines()[-1] if str(e) else repr(e)
                rows.append((label, name, None, None, None, None, len(V), len(F), "-", "-", msg[:120]))
            print(f"  {label:18s} {name:46s} done", file=sys.stderr, flush=True)

    print(f"load average before/after the run: {load0[0]:.1f} / {os.getloadavg()[0]:.1f} ({os.cpu_count()} cores; "
          "other jobs on the machine inflate the times)")
    print(f"{'method':48s} {'q min':>7s} {'q mean':>7s} {'max dev':>9s} {'time s':>8s} {'folds':>9s} {'crease':>11s}")
    last = None
    for r in rows:
        if r[0] != last:
            print(f"{r[0]} ({r[6]} nodes, {r[7]} {'quads, beta' if 'quads' in r[0] else 'triangles, alpha'})")
        last = r[0]
        if r[2] is None:
            print(f"  {r[1]:46s} failed: {r[10]}")
        else:
            print(f"  {r[1]:46s} {r[2]:7.4f} {r[3]:7.4f} {r[4]:9.2e} {r[5]:8.2f} {r[8]:>9s} {r[9]:>11s}")
    print("max dev: saddle rows |z - saddle(x, y)|; libcgal-demo rows distance to the input surface / bbox diagonal")
    print("folds: elements facing against the mean normal of their edge neighbours; input: how many, others: new / left")
    print(f"crease (CAD parts): largest change of a crease edge's dihedral angle in degrees (crease edges: bent "
          f"{CREASE_DEG:g} degrees or more in the input) / crease nodes moved")
    for r in rows:
        if r[1].startswith("ours: MGA, defaults") and r[5]:
            print(f"MGA time per element on {r[0]}: {1e3 * r[5] / r[7]:.3f} ms (thesis: 150 s / 51354 triangles "
                  f"= {1e3 * 150.05 / 51354:.3f} ms, rat skin, dual-core AMD 2 GHz)")


if __name__ == "__main__":
    main()
