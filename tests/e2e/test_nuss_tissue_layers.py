"""E2E: 'Pectus: Nuss Procedure FE Analysis' on one layer per tissue, as CT segmentation tools export them.

The rib cage generator writes the cage as three closed, overlapping tissue layers ('ribs', 'costal cartilage',
'sternum'); the analysis with 'One layer per tissue' joins them into one volume (CGAL corefinement union) and
runs. Checks: the Log reports 3 joined layers with a union smaller than their sum and close to the labelled
cage's tets' volume; the result layer is the joined surface with the sternum end raised by the logged elevation;
a layer whose tissue cannot be told, and a missing cartilage layer, fail with a message and rc != 0."""
import os
import re

import numpy as np

import harness as h
import pectus_mlx as mlx
from harness import check
from pectus_filters import create_ribcage, nuss_fea
from pectus_meshes import write_ply

W = h.workdir("nuss-tissue-layers")
FAST = dict(analysis=1, order=1, tetQuality=0.0, mode=1, force=10.0)  # linear TET4, given force: seconds
names = ["ribs", "costal_cartilage", "sternum"]
files = [os.path.join(W, n + ".ply") for n in names]
lms = os.path.join(W, "landmarks.ply")
r = h.run([], mlx.Script([create_ribcage(edgeLength=6.0, output=1)]),
          [(f, "fc fq", i) for i, f in enumerate(files)] + [(lms, "vq", 3)])
check(r.rc == 0 and all(os.path.exists(f) for f in files + [lms]), "three tissue layers and the landmarks written",
      r.stdout[-800:])

# meshlabserver names a loaded layer after its file: the tissue comes from the name
res = os.path.join(W, "result.ply")
r = h.run([lms] + files, mlx.Script([nuss_fea(input=1, landmarkLayer=0, **FAST)]), [(res, "vq", 4)])
print("\n".join(l for l in r.log if "Nuss" in l))
check(r.rc == 0, "the analysis runs on the joined tissue layers", r.stdout[-1500:])
joined = [m.groups() for m in (re.search(r"joined (\d+) tissue layers: ([0-9.]+) cm\^3 in the layers, ([0-9.]+) cm\^3 in their union", l)
                               for l in r.log) if m]
check(len(joined) == 1 and int(joined[0][0]) == 3 and float(joined[0][2]) < float(joined[0][1]),
      f"3 layers joined, the union smaller than the layers' sum (they overlap): {joined}")
elev = r.values("elevation_mm", "Pectus: Nuss Procedure FE Analysis")
if os.path.exists(res) and elev:
    R = h.read_ply(res)
    L = h.read_ply(lms)
    q = np.rint(L["vertex"]["quality"]).astype(int)
    end = L["V"][q == 500][0]
    check(R["vertex"]["quality"].max() > 0, "result layer carries the stress")
    check(np.linalg.norm(R["V"] - end, axis=1).min() < 20, "the result layer is the joined cage (near the sternum end)")
else:
    check(False, "result layer saved and elevation logged")

# bad input: a layer whose tissue cannot be told (a generic segmentation name, no face labels)
seg = os.path.join(W, "Segment_1.ply")
C = h.read_ply(files[1])
write_ply(seg, C["V"], C["F"])
r = h.run([lms, files[0], seg, files[2]], mlx.Script([nuss_fea(input=1, landmarkLayer=0, **FAST)]))
check(r.rc != 0 and any("Cannot tell the tissue of layer 'Segment_1" in l for l in r.log),
      "unnamed tissue layer: message and rc != 0", "\n".join(r.log[-5:]))
# bad input: no cartilage layer
r = h.run([lms, files[0], files[2]], mlx.Script([nuss_fea(input=1, landmarkLayer=0, **FAST)]))
check(r.rc != 0 and any("no cartilage layer" in l for l in r.log), "no cartilage layer: message and rc != 0",
      "\n".join(r.log[-5:]))
h.finish()
