"""E2E: 'Pectus: Nuss Procedure FE Analysis' through the real meshlabserver on a coarse generated rib cage.

Checks: the result layer is the cage displaced (same vertex count, the sternum end moved by the logged
elevation along +y, the costovertebral joints still), vertex quality = von Mises stress >= 0; the files
(.vtu with the tets, .inp deck, force-displacement CSV/PNG, rib strain CSV) exist and agree with the Log;
calibration to a target lands within the tolerance; the figures the filter returns (the results file on
2020.09, pectus-mlrun's from the return values on the newer hosts, and BASE_results.json beside the files)
are the Log's, to its printed digits; bad input (unlabelled layer, no landmarks) fails
with a message and a non-zero exit, and the cage layer saved after the failure is unchanged."""
import csv
import os
import re

import numpy as np

import harness as h
import pectus_mlx as mlx
from harness import as_printed, check
from harness import log_figures as grab
from pectus_filters import create_ribcage, nuss_fea

W = h.workdir("nuss-fea")
GEN = create_ribcage(edgeLength=5.0)
FAST = dict(analysis=1, order=1, tetQuality=0.0)  # linear TET4, no TetGen refinement: seconds




cage, lms = os.path.join(W, "cage.ply"), os.path.join(W, "cage_landmarks.ply")
r = h.run([], mlx.Script([GEN]), [(cage, "fc fq", 0), (lms, "vq", 1)])
check(r.rc == 0 and os.path.exists(cage) and os.path.exists(lms), "rib cage generated and saved", r.stdout[-800:])

# calibrated (linear, fast) with files
base = os.path.join(W, "nuss")
# meshlabserver makes the last loaded layer current: landmarks first, then the cage
r = h.run([lms, cage], mlx.Script([nuss_fea(landmarkLayer=0, targetElevation=20.0, resultBase=mlx.SaveFile(base + ".vtu"),
                                            **FAST)]),
          [(os.path.join(W, "result.ply"), "vq", 2)])
print("\n".join(l for l in r.log if "Nuss" in l or "Max" in l or "Force" in l))
check(r.rc == 0, "Nuss FE analysis runs (calibrate to 20 mm, linear TET4)", r.stdout[-1500:])
FE = "Pectus: Nuss Procedure FE Analysis"
force = r.values("force_N", FE)
elev = r.values("elevation_mm", FE)
# every figure the filter returns is the Log's, to its printed digits
for key, pattern, decimals in [
        ("force_N", r"Fe = ([0-9.]+) N \(Fs", 2),
        ("elevation_mm", r"sternum end displacement ([0-9.]+) mm", 2),
        ("target_elevation_mm", r"Target elevation ([0-9.]+) mm", 2),
        ("solves", r"in ([0-9]+) solves", 0),
        ("tets", r"Nuss FE model: ([0-9]+) TET4", 0),
        ("nodes", r"Nuss FE model: [0-9]+ TET4 elements, ([0-9]+) nodes", 0),
        ("linear_compliance_mm_per_N", r"linear compliance ([0-9.]+) mm/N", 4),
        ("max_stress_MPa", r"Max von Mises stress ([0-9.]+) MPa at", 2),
        ("max_stress_all_MPa", r"; ([0-9.]+) MPa including them", 2),
        ("max_stress_body_MPa", r"Max von Mises stress away from the tissue junctions ([0-9.]+) MPa", 2),
        ("max_strain", r"Max equivalent strain ([0-9.]+) at", 4),
        ("max_strain_cartilage", r"max in cartilage ([0-9.]+),", 4),
        ("newton_iterations", r"([0-9]+) Newton iterations", 0),
        ("seconds", r"total ([0-9.]+) s", 1)]:
    v, printed = r.get(key, FE), grab(r.log, pattern)
    check(len(printed) == 1 and as_printed(v, printed[0], decimals), f"returned {key} = {v}: the Log's {printed}")
for where, pattern in [("max_stress_where", r"Max von Mises stress [0-9.]+ MPa at the (.*?) at \("),
                       ("max_stress_body_where", r"away from the tissue junctions [0-9.]+ MPa at the (.*?) at \("),
                       ("max_strain_where", r"Max equivalent strain [0-9.]+ at the (.*?) at \(")]:
    m = [re.search(pattern, l) for l in r.log]
    m = [x.group(1) for x in m if x]
    check(m == [r.get(where, FE)], f"returned {where} {r.get(where, FE)!r}: the Log's {m}")
at = r.get("max_stress_at_mm", FE)
check(isinstance(at, list) and len(at) == 3 and all(isinstance(x, float) for x in at), f"max_stress_at_mm is a place: {at}")
check(r.get("element", FE) == "TET4" and r.get("target_from", FE) == "as given", "element TET4, the target as given")
# the same values beside the files
if os.path.exists(base + "_results.json"):
    beside = mlx.read_results(base + "_results.json")
    check(len(beside) == 1 and beside[0]["filter"] == FE and beside[0]["results"] == r.results[-1]["results"]
          if mlx.default_host() == "2020.09" else beside[0]["results"]["force_N"] == force[0],
          f"{base}_results.json: the values the filter returned", str(beside)[:400])
else:
    check(False, f"{base}_results.json written")
check(len(elev) == 1 and abs(elev[0] - 20.0) <= 0.1, f"calibrated elevation {elev} within 0.1 mm of 20")
check(len(force) == 1 and force[0] > 0, f"calibrated force {force} N")
peak = grab(r.log, r"Max von Mises stress ([0-9.]+) MPa at")
inner = grab(r.log, r"Max von Mises stress away from the tissue junctions ([0-9.]+) MPa at the .*(?:bone|sternum|cartilage)")
check(len(peak) == 1 and len(inner) == 1 and 0 < inner[0] <= peak[0],
      f"the Log's largest stress away from the tissue junctions {inner} MPa, at most the largest {peak}")
C = h.read_ply(cage)
R = h.read_ply(os.path.join(W, "result.ply")) if os.path.exists(os.path.join(W, "result.ply")) else None
L = h.read_ply(lms)
if R is not None:
    check(len(R["V"]) == len(C["V"]), f"result layer has the cage's {len(C['V'])} vertices")
    d = R["V"] - C["V"]
    q = np.rint(L["vertex"]["quality"]).astype(int)
    end = L["V"][q == 500][0]
    near = np.linalg.norm(C["V"] - end, axis=1) < 8.0
    check(near.any() and abs(d[near, 1].mean() - elev[0]) < 0.25 * elev[0],
          f"the sternum end moved +y by {d[near, 1].mean():.2f} mm (Log: {elev})")
    joints = L["V"][(q > 100) & (q < 300)]
    jd = np.min(np.linalg.norm(C["V"][:, None, :] - joints[None, :, :], axis=2), axis=1)
    check(np.abs(d[jd < 3.0]).max() < 1e-4, "vertices at the costovertebral joints stay fixed")
    vq = R["vertex"]["quality"]
    check(vq.min() >= 0 and vq.max() > 0, f"vertex quality = von Mises stress in [{vq.min():.3g}, {vq.max():.3g}] MPa")
else:
    check(False, "result layer saved")
for ext in (".vtu", ".inp", "_force_displacement.csv", "_force_displacement.png", "_rib_strain.csv"):
    check(os.path.exists(base + ext) and os.path.getsize(base + ext) > 30, f"file {base + ext} written")
if os.path.exists(base + ".vtu"):
    head = open(base + ".vtu").read(4000)
    m = re.search(r'NumberOfPoints="(\d+)" NumberOfCells="(\d+)"', head)
    tets = r.values("tets", FE)
    check(m is not None and tets and int(m.group(2)) == tets[0], f"vtu cells {m and m.group(2)} = returned tets {tets}")
if os.path.exists(base + ".inp"):
    inp = open(base + ".inp").read()
    check("*ELEMENT, TYPE=C3D4" in inp and "*CLOAD" in inp and "*BOUNDARY" in inp, "CalculiX deck has elements, loads, BCs")
if os.path.exists(base + "_force_displacement.csv"):
    rows = list(csv.DictReader(open(base + "_force_displacement.csv")))
    F = [float(x["force_N"]) for x in rows]
    D = [float(x["elevation_mm"]) for x in rows]
    check(F[0] == 0 and abs(F[-1] - force[0]) < 0.006 and abs(D[-1] - elev[0]) < 0.006 and all(np.diff(D) > 0),
          f"force-displacement curve from 0 to the calibrated point ({len(rows)} points)")
if os.path.exists(base + "_rib_strain.csv"):
    rows = list(csv.DictReader(open(base + "_rib_strain.csv")))
    tissues = {x["tissue"] for x in rows}
    check({"cartilage", "bone"} <= tissues, f"rib path crosses cartilage and bone ({tissues})")

# bad input 1: the landmark (points only) layer is current
r = h.run([cage, lms], mlx.Script([nuss_fea(landmarkLayer=0, **FAST)]))
check(r.rc != 0 and any("no faces" in l or "tissue labels" in l for l in r.log),
      "points-only layer: non-zero exit and a message", "\n".join(r.log[-5:]))
# bad input 2: cage without the landmark layer (landmarkLayer = the cage itself)
r = h.run([cage], mlx.Script([nuss_fea(landmarkLayer=0, **FAST)]), [(os.path.join(W, "cage_after_fail.ply"), "fc fq", 0)])
check(r.rc != 0 and any("landmark layer" in l for l in r.log), "no landmark layer: non-zero exit and a message",
      "\n".join(r.log[-5:]))
if os.path.exists(os.path.join(W, "cage_after_fail.ply")):
    A = h.read_ply(os.path.join(W, "cage_after_fail.ply"))
    check(np.array_equal(A["V"], C["V"]) and np.array_equal(A["F"], C["F"]), "the cage layer is unchanged after the failure")
# bad input 3: unreachable target
r = h.run([lms, cage], mlx.Script([nuss_fea(landmarkLayer=0, targetElevation=60.0, maxForce=1.0, **FAST)]))
check(r.rc != 0 and any("reaches the target" in l for l in r.log), "unreachable target: message", "\n".join(r.log[-5:]))

# a coarse cage smoothed by MGA (age 5, index 3, 8 mm edges, made on MeshLab 2025.07; the generator's tissue
# labels put back on the smoothed vertices): its floating ribs are pieces of their own, and the mesh nodes
# nearest to the joints of ribs 12 belong to ribs 11. Each joint is fixed on its own rib, so every piece is
# held and the analysis solves (fixed at the nodes nearest to the joints, ribs 12 were free: a singular stiffness)
r = h.run([os.path.join(h.DATA, "smoothed_cage_age5_landmarks.ply"), os.path.join(h.DATA, "smoothed_cage_age5.ply")],
          mlx.Script([nuss_fea(landmarkLayer=0, targetElevation=5.0, analysis=1, order=1)]))
check(r.rc == 0 and any(l.startswith("Nuss FE result") for l in r.log),
      "smoothed coarse cage with floating ribs apart: the FE solves", "\n".join(r.log[-4:]))
check(any("nodes of their rib within the joint radius" in l for l in r.log), "smoothed coarse cage: the widened joints are logged")
h.finish()
