"""End to end: MGA smoothing's default feature detection (crease chains) through the real meshlabserver, on
a CT surface and on CAD parts of Debian's libcgal-demo. On the femur (CT) it takes the noise for noise:
few nodes fixed, a higher mean alpha than with the feature and singular angles 60/90, and above OpenMesh's
tangential smoothing. On the meshed cube it finds the 12 edges as crease chains and no crease node moves;
on the fandisk no node of a crease edge moves, and the crease edges' dihedral angles change less than with
the feature angle 60. A mesh that is all creases is refused with what the detection found. Skipped without libcgal-demo."""
import os
import re
import shutil
import subprocess

import numpy as np

from pectus_meshes import alpha, read_off, write_off
from harness import SOURCE, cgal_meshes, check, example_script, finish, read_ply, run, workdir

d = workdir("mga_creases")
mesh = cgal_meshes(d, "femur", "cube-meshed", "fandisk", "cube")
EXAMPLE = os.path.join(SOURCE, "filter_mga_smooth", "examples", "mga_smooth.mlx")


def script(name, **values):
    return example_script(EXAMPLE, d, name, **values)


def smooth(inp, name, **values):
    out = os.path.join(d, name + ".ply")
    r = run([inp], script(name, **values), [(out, "")])
    log = "\n".join(r.log)
    V = np.array(read_ply(out)["V"]) if r.rc == 0 and os.path.exists(out) else None
    return r, log, V


def mean_alpha(V, F):
    return float(np.mean([alpha(*V[f]) for f in F]))


def dihedrals(V, F):
    n = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    n /= np.linalg.norm(n, axis=1)[:, None]
    faces = {}
    for fi, t in enumerate(F):
        for k in range(3):
            faces.setdefault(tuple(sorted((int(t[k]), int(t[(k + 1) % 3])))), []).append(fi)
    return {e: float(np.degrees(np.arccos(np.clip(n[f[0]] @ n[f[1]], -1, 1)))) for e, f in faces.items() if len(f) == 2}


# 1. the femur: crease chains against the angles 60/90, and against OpenMesh's tangential smoothing
V0, F0 = read_off(mesh["femur"])
F0 = np.array(F0)
r, log, V = smooth(mesh["femur"], "femur_creases")
fixed = re.search(r"fixed nodes: 0 boundary, (\d+) feature, (\d+) singular", log)
check(r.rc == 0 and V is not None and fixed is not None, "femur: defaults run, fixed nodes logged", log[-1500:])
check(re.search(r"features: \d+ crease chains \(\d+ edges, \d+ nodes, \d+ corners\); \d+ of \d+ sharp edges taken for noise",
                log) is not None, "femur: the crease detection's finding is logged", log[-1500:])
if fixed:
    nfixed = int(fixed.group(1)) + int(fixed.group(2))
    check(nfixed < 0.15 * len(V0), "femur: crease chains fix under 15 % of the nodes", f"{nfixed} of {len(V0)}")
ra, loga, Va = smooth(mesh["femur"], "femur_angles", featureDetection=1)
fixed_a = re.search(r"fixed nodes: 0 boundary, (\d+) feature, (\d+) singular", loga)
check(ra.rc == 0 and Va is not None and fixed_a is not None, "femur: angles 60/90 run", loga[-1500:])
if V is not None and Va is not None and fixed and fixed_a:
    m0, mc, ma = mean_alpha(V0, F0), mean_alpha(V, F0), mean_alpha(Va, F0)
    check(int(fixed_a.group(1)) + int(fixed_a.group(2)) > 3 * nfixed, "femur: the angles fix many more nodes",
          f"{fixed_a.group(0)} / {fixed.group(0)}")
    check(mc > ma + 0.02, "femur: crease chains reach a mean alpha well above the angles'", f"{m0:.4f} -> {mc:.4f} / {ma:.4f}")
    om = shutil.which("OpenMesh-Smoothing")
    if om:
        out = os.path.join(d, "femur_openmesh.off")
        subprocess.run([om, "-t", "10", mesh["femur"], out], capture_output=True, check=True)
        mo = mean_alpha(read_off(out)[0], F0)
        check(mc > mo, "femur: defaults above OpenMesh's tangential smoothing (10 iterations)", f"{mc:.4f} / {mo:.4f}")

# 2. the meshed cube: 12 crease chains, 8 corners; no crease node moves, the faces' nodes do
V0, F0 = read_off(mesh["cube-meshed"])
F0 = np.array(F0)
r, log, V = smooth(mesh["cube-meshed"], "cube_creases")
check(r.rc == 0 and V is not None and "features: 12 crease chains" in log and ", 8 corners)" in log,
      "meshed cube: 12 crease chains and 8 corners found and logged", log[-1500:])
if V is not None:
    lo, hi = V0.min(axis=0), V0.max(axis=0)
    tol = 1e-6 * np.linalg.norm(hi - lo)
    on_side = (np.abs(V0 - lo) < tol) | (np.abs(V0 - hi) < tol)
    edge_nodes = on_side.sum(axis=1) >= 2
    moved = np.linalg.norm(V - V0, axis=1) > tol
    check(edge_nodes.sum() > 12 and not moved[edge_nodes].any(), "meshed cube: no node on a cube edge moves",
          f"{moved[edge_nodes].sum()} of {edge_nodes.sum()}")
    check(moved[~edge_nodes].sum() > 0.5 * (~edge_nodes).sum(), "meshed cube: the faces' nodes move",
          f"{moved[~edge_nodes].sum()} of {(~edge_nodes).sum()}")
    check(mean_alpha(V, F0) > mean_alpha(V0, F0), "meshed cube: mean alpha rises")

# 3. the fandisk: no node of a crease edge (bent 20 degrees or more) moves; the crease edges' dihedral
#    angles change less than with the feature angle 60 (which leaves the creases under 60 degrees free)
V0, F0 = read_off(mesh["fandisk"])
F0 = np.array(F0)
before = dihedrals(V0, F0)
creases = [e for e, a in before.items() if a >= 20]
crease_nodes = sorted({v for e in creases for v in e})
change = {}
for rule, values in (("crease chains", {}), ("angles 60/90", {"featureDetection": 1})):
    r, log, V = smooth(mesh["fandisk"], "fandisk_" + rule.split()[0], maxSweeps=3, **values)
    check(r.rc == 0 and V is not None, f"fandisk, {rule}: runs", log[-1500:])
    if V is None:
        continue
    after = dihedrals(V, F0)
    change[rule] = max(abs(after[e] - before[e]) for e in creases)
    moved = int(np.sum(np.linalg.norm(V[crease_nodes] - V0[crease_nodes], axis=1) > 1e-5))
    if rule == "crease chains":
        check(len(creases) > 500 and moved == 0, "fandisk: no node of a crease edge moves", f"{moved} of {len(crease_nodes)}")
        check(change[rule] < 10, "fandisk: crease edges' dihedral angles change by less than 10 degrees",
              f"{change[rule]:.2f} degrees")
        check(mean_alpha(V, F0) > mean_alpha(V0, F0) + 0.03, "fandisk: mean alpha rises")
    else:
        check(moved > 50, "fandisk: the feature angle 60 lets the nodes of creases under 60 degrees move",
              f"{moved} of {len(crease_nodes)}")
if len(change) == 2:
    check(change["crease chains"] < change["angles 60/90"] - 2, "fandisk: crease chains keep the creases better than the angles",
          str(change))

# 4. all creases: the 8-node cube has no free node; refused with the detection's finding
r, log, V = smooth(mesh["cube"], "cube8")
check(r.rc != 0 and "no free node" in log and "12 crease chains" in log,
      "8-node cube (all creases): refused, naming the crease chains found", log[-1500:])

finish()
