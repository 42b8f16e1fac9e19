"""E2E: a CT export whose files say nothing of what they hold, as 3D Slicer names segments ('Segment_1',
'Segment_2', ...), imported and prepared with no manual step.

The patient is pectus_ct_phantom's clean STL export (24 ribs, costal cartilages, sternum, vertebrae T1-T12,
both scapulae: 40 files) with every file renamed Segment_N in a shuffled order. Checks:
  - every layer classified by its shape as its original name would (ribs, vertebrae, sternum, cartilages;
    the scapulae left out);
  - 12 ribs per side, numbered by their place;
  - the landmarks where the phantom's truth puts them (mapped by the transform the Log gives)."""
import json
import os
import random
import re
import shutil
import subprocess

import numpy as np

import harness as h
import pectus_mlx as mlx
from harness import check
from pectus_filters import import_ct_segmentation, prepare_patient_rib_cage

PHANTOM = os.path.join(os.path.dirname(h.PREFIX), "tools", "pectus_ct_phantom")
W = h.workdir("patient_unnamed")

r = subprocess.run([PHANTOM, os.path.join(W, "patient"), "--only", "stl"], capture_output=True, text=True, timeout=600)
check(r.returncode == 0, "pectus_ct_phantom --only stl", r.stdout[-500:] + r.stderr[-500:])
with open(os.path.join(W, "patient", "truth.json")) as f:
    truth = json.load(f)

clean = os.path.join(W, "patient", "stl_clean")
unnamed = os.path.join(W, "unnamed")
shutil.rmtree(unnamed, ignore_errors=True)
os.makedirs(unnamed)
files = sorted(f for f in os.listdir(clean) if f.endswith(".stl"))
order = list(range(1, len(files) + 1))
random.Random(3).shuffle(order)
original = {}  # Segment_N -> the structure's name
for f, n in zip(files, order):
    shutil.copy(os.path.join(clean, f), os.path.join(unnamed, f"Segment_{n}.stl"))
    original[f"Segment_{n}"] = f[:-4]

r = h.run([], mlx.Script([import_ct_segmentation(path=unnamed), prepare_patient_rib_cage()]))
log = r.log
print("\n".join(l for l in log if "by its shape" in l or "numbered" in l or "Patient rib cage" in l))
check(r.rc == 0, f"{len(files)} Segment_N files imported and prepared", r.stdout[-3000:])

# each layer's decision against its original name
expected = {"rib": "rib", "vertebrae": "vertebra", "sternum": "sternum", "costal": "costal cartilage",
            "scapula": "not rib cage"}
decided = dict(re.findall(r"^'(Segment_\d+)': ([a-z ]+?) \(by its shape", "\n".join(log), re.M))
wrong = [f"{s} ({original[s]}): {decided.get(s, 'no decision')}" for s in original
         if decided.get(s) != next(v for k, v in expected.items() if original[s].startswith(k))]
check(not wrong, f"every one of the {len(original)} layers classified by its shape as its name would",
      "; ".join(wrong))
check(any("12 right and 12 left ribs" in l for l in log), "12 ribs numbered on each side")

# the landmarks against the phantom's truth, mapped into the result frame by the Log's transform
line = next((l for l in log if "input -> result transform" in l), "")
T = np.eye(4)
for i, row in enumerate(line.split("):", 1)[1].split(";")[:3] if "):" in line else []):
    T[i, :] = [float(x) for x in row.split()]
line = next((l for l in log if l.startswith("landmarks (code (x y z) mm, result frame):")), "")
got = {int(c): np.array([float(x), float(y), float(z)]) for c, x, y, z in re.findall(r"(\d+) \((\S+) (\S+) (\S+)\)", line)}
ref = {int(l["code"]): (T @ np.append(np.array(l["xyz"]), 1.0))[:3] for l in truth["landmarks"]}
for codes, tol, name in (([100 * s + k for s in (1, 2) for k in range(1, 13)], 3.0, "costovertebral joints"),
                         ([614, 615, 624, 625], 6.0, "bar exits"), ([500], 6.0, "lower sternum end"),
                         ([501], 12.0, "deepest funnel point")):
    err, worst = max(((np.linalg.norm(got[c] - ref[c]) if c in got and c in ref else 1e9), c) for c in codes)
    check(err < tol, f"{name} within {tol} mm of the truth (worst {err:.1f} mm, landmark {worst})",
          f"prepared {got.get(worst)}, truth {ref.get(worst)}")

h.finish()
