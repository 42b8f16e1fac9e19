"""E2E: a patient's CT segmentation, messy as real exports are, through import -> prepare -> calibrated FE ->
thoracic volumes -> pectus index in one meshlabserver script, with no manual step.

The patient is the project's own default cage rasterised on a 1 mm CT grid by pectus_ct_phantom (each rib,
the costal cartilages and the sternum as their own labels, vertebrae T1-T12 touching the rib heads, scapulae,
stray voxels) and exported as STL surfaces with a real export's defects (pectus_ct_phantom's messy export): the
ribs, spine and scapulae in one 'bone' file cut flat by the field of view, with marrow shells nested inside
the ribs and vertebrae, 900 specks, two blocks of bone beside the spine and faces written twice; a sternum in
pieces (manubrium and body apart, marrow shells, slivers, a self-intersecting patch); every cartilage in one
file, three with a hole; RAS axes and a shifted origin. Checks:
  - every structure classified, the spine cut, 12 ribs per side numbered, the scapulae and the blocks left out;
  - the landmarks where the phantom's truth puts them (mapped by the transform the Log gives);
  - the calibrated force within 10 % of the generated cage's with the same FE settings;
  - both volume methods and the pectus index run on the prepared cage and landmarks;
  - the same export in metres and LPS axes, and TotalSegmentator's per-structure NIfTI masks, give the same cage;
  - no sternum, one side only, a missing rib: a message naming what to fix and a non-zero exit."""
import json
import os
import re
import shutil
import subprocess

import numpy as np

import harness as h
import pectus_mlx as mlx
from harness import check, check_refused, log_figure
from pectus_filters import create_ribcage, import_ct_segmentation, nuss_fea, prepare_patient_rib_cage

PHANTOM = os.path.join(os.path.dirname(h.PREFIX), "tools", "pectus_ct_phantom")
W = h.workdir("patient")
FE = dict(analysis=1, order=0, targetElevation=44.7, resultBase="")  # small strain TET10: no locking


def phantom(out, *args):
    r = subprocess.run([PHANTOM, out, *args], capture_output=True, text=True, timeout=600)
    check(r.returncode == 0, f"pectus_ct_phantom {' '.join(args)}", r.stdout[-500:] + r.stderr[-500:])
    with open(os.path.join(out, "truth.json")) as f:
        return json.load(f)


def transform(log):
    """the input -> result transform the Log gives (4x4)"""
    line = next((l for l in log if "input -> result transform" in l), "")
    rows = line.split("):", 1)[1].split(";") if "):" in line else []
    T = np.eye(4)
    for i, row in enumerate(rows[:3]):
        T[i, :] = [float(x) for x in row.split()]
    return T


def landmarks(log):
    line = next((l for l in log if l.startswith("landmarks (code (x y z) mm, result frame):")), "")
    return {int(c): np.array([float(x), float(y), float(z)])
            for c, x, y, z in re.findall(r"(\d+) \((\S+) (\S+) (\S+)\)", line)}


def check_landmarks(log, truth, what, joints=3.0, first=None):
    """the prepared landmarks against the phantom's truth (scanner frame) mapped into the result frame; where
    the spine is cut away, the joints sit on the cut, up to 16 mm from the rib heads inside it (the rib runs
    back from its head before it leaves the cut band, and a thin wedge of it along the cut goes with the column),
    and the 1st ribs', which run inside the cut band for a stretch behind their heads, where they leave it
    (first = 20 mm; by default as the others)"""
    T, got = transform(log), landmarks(log)
    unit = 0.001 if truth.get("stlMessyUnit") == "m" and "metres" in what else 1.0  # truth in mm, the files in m
    ref = {int(l["code"]): (T @ np.append(unit * np.array(l["xyz"]), 1.0))[:3] for l in truth["landmarks"]}
    for codes, tol, name in (([100 * s + k for s in (1, 2) for k in range(2, 13)], joints, "costovertebral joints 2-12"),
                             ([101, 201], first or joints, "1st ribs' costovertebral joints"),
                             ([614, 615, 624, 625], 6.0, "bar exits"), ([500], 6.0, "lower sternum end"),
                             ([501], 12.0, "deepest funnel point")):
        err, worst = max(((np.linalg.norm(got[c] - ref[c]) if c in got and c in ref else 1e9), c) for c in codes)
        check(err < tol, f"{what}: {name} within {tol} mm of the truth (worst {err:.1f} mm, landmark {worst})",
              f"prepared {got.get(worst)}, truth {ref.get(worst)}")


def volumes(cage, landmarks):
    """both volume methods and the pectus index on the current layer (the FE result) against the prepared
    cage, as their example scripts set them"""
    out = []
    for name in ("thoracic_volume_slice", "thoracic_volume_envelope", "pectus_index"):
        f = mlx.load_script(os.path.join(h.SOURCE, "filter_thoracic_volume", "examples", name + ".mlx"))[0]
        out.append(f.set(compare=mlx.Bool(True), beforeLayer=mlx.Mesh(cage), landmarkLayer=mlx.Mesh(landmarks)))
    return out


def prepare_script(path, *more):
    return mlx.Script([import_ct_segmentation(path=path), prepare_patient_rib_cage(), *more])


# --- the messy STL export, in RAS mm with a shifted origin -----------------------------------------------------
P = os.path.join(W, "patient")
truth = phantom(P, "--only", "messy,masks")
messy = os.path.join(P, "stl_messy")
n_files = len([f for f in os.listdir(messy) if f.endswith(".stl")])
cage, lmk = (os.path.join(W, n) for n in ("cage.ply", "landmarks.ply"))
after = os.path.join(W, "after.ply")
fe = nuss_fea(landmarkLayer=n_files + 1, **FE)
r = h.run([], prepare_script(messy, fe, *volumes(n_files, n_files + 1)),
          [(cage, "fc fq", n_files), (lmk, "vq", n_files + 1)], timeout=1800)
log = r.log
print("\n".join(l for l in log if not l.startswith("landmark")))
check(r.rc == 0, "import -> prepare -> FE -> volumes -> index runs as one script", r.stdout[-3000:])
check(any("vertebral column found" in l and "cut at the costovertebral joints" in l for l in log),
      "the spine fused to the ribs is found and cut")
left_out = [float(v) for v in re.findall(r"'bone': left out a piece of ([0-9.]+) cm3 .*(?:does not reach the spine|is too short "
                                         r"for a rib)", "\n".join(log))]
check(sorted(v > 5 for v in left_out) == [False, False, True, True],
      f"the scapulae (over 5 cm3) and the two blocks beside the spine are left out: {left_out} cm3")
check(any("12 right and 12 left ribs" in l for l in log), "12 ribs numbered on each side")
pieces = log_figure(log, r"joined on the grid: (\d+) connected pieces", int)
check(pieces == 5, f"the joined cage is one piece and the four floating ribs, as the generator's: {pieces} pieces")
check_landmarks(log, truth, "messy STL export", joints=16.0, first=20.0)
force = r.get("force_N", "Pectus: Nuss Procedure FE Analysis")

# the generator at the prepared cage's edge length, so that both are meshed alike
edge = prepare_patient_rib_cage().params["edgeLength"].value
g = h.run([], mlx.Script([create_ribcage(age=truth["generator"]["age"], hallerIndex=truth["generator"]["hallerIndex"],
                                         edgeLength=edge),
                          nuss_fea(landmarkLayer=1, **FE)]), timeout=1800)
ref = g.get("force_N", "Pectus: Nuss Procedure FE Analysis")
print(f"calibrated force: prepared export {force} N, generated cage {ref} N")
check(force is not None and ref is not None and abs(force - ref) <= 0.10 * ref,
      f"calibrated force on the prepared export within 10 % of the generated cage's ({force} N vs {ref} N)")
for what, key, filter in (("slice method", "volume_change_cm3", "Pectus: Thoracic Volume (Slice Method)"),
                          ("envelope", "volume_change_cm3", "Pectus: Thoracic Volume (Ferguson Envelope)"),
                          ("pectus index", "haller_index", "Pectus: Pectus Index")):
    v = r.get(key, filter)
    check(v is not None and v > 0, f"{what} before and after on the prepared cage: {v}", "\n".join(log[-12:]))

# --- the same export in metres and LPS axes: units and frame found, the same landmarks --------------------------
M = os.path.join(W, "metres")
truth_m = phantom(M, "--only", "messy", "--metres", "--axes", "LPS")
r = h.run([], prepare_script(os.path.join(M, "stl_messy")))
check(r.rc == 0, "metres, LPS: prepared", r.stdout[-2000:])
check(any("units: metres" in l for l in r.log), "metres detected and scaled to mm")
check_landmarks(r.log, truth_m, "metres, LPS", joints=16.0, first=20.0)
column = r"vertebral column found \(posterior midline, ([0-9.]+) mm wide\)"
check(log_figure(r.log, column) == log_figure(log, column) is not None,
      f"metres, LPS: the same column as in RAS ({log_figure(log, column)} mm)", "\n".join(l for l in r.log if "column" in l))

# --- TotalSegmentator's output: one NIfTI mask per structure --------------------------------------------------
masks = os.path.join(P, "masks")
r = h.run([], prepare_script(masks))
check(r.rc == 0 and any("12 right and 12 left ribs" in l for l in r.log), "NIfTI masks: prepared, 12 ribs a side",
      r.stdout[-2000:])
check_landmarks(r.log, truth, "NIfTI masks")

# --- bad input: a message naming what to fix, non-zero exit ------------------------------------------------------
def variant(name, drop):
    d = os.path.join(W, name)
    shutil.copytree(masks, d)
    for f in drop:
        os.remove(os.path.join(d, f))
    return d


r = h.run([], prepare_script(variant("no-sternum", ["sternum.nii.gz"])))
check_refused(r, "No sternum", "no sternum")
r = h.run([], prepare_script(variant("one-side", [f"rib_left_{k}.nii.gz" for k in range(1, 13)])))
check_refused(r, "side only", "ribs on one side only")
r = h.run([], prepare_script(variant("rib-missing", ["rib_right_4.nii.gz"])))
check_refused(r, "Ribs missing on the right side: 4", "a missing rib")
r = h.run([], prepare_script(variant("no-cartilage", ["costal_cartilages.nii.gz"])))
check_refused(r, "No costal cartilage", "no cartilage")

h.finish()
