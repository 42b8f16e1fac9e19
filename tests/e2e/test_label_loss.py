"""E2E: tissue labels and the filters that overwrite face colour and quality.
The rib cage generator keeps the labels as named face attributes and writes them as face colour/quality
for files. 'Pectus: Element Quality' (and MGA/gradient smoothing, which call it, and the quad filters)
overwrite face colour and quality: in the same meshlabserver run the Nuss FE analysis still reads the
attributes; a cage saved after such a filter has lost its labels, and the analysis says so and why."""
import os

import harness as h
import pectus_mlx as mlx
from harness import check
from pectus_filters import create_ribcage, nuss_fea

W = h.workdir("label-loss")
GEN = create_ribcage(edgeLength=8.0)
QUALITY = mlx.load_script(os.path.join(h.SOURCE, "filter_mga_smooth", "examples", "element_quality.mlx"))[0]
# small strain TET4 with the default tet quality (without refinement, 2025.07's 8 mm cage meshes with flat tets)
FAST = dict(analysis=1, order=1, targetElevation=10.0)
cage, lms = os.path.join(W, "cage_coloured.ply"), os.path.join(W, "cage_landmarks.ply")

# one run: generate, colour the cage by element quality, analyse (labels from the attributes)
r = h.run([], mlx.Script([GEN, QUALITY, nuss_fea(landmarkLayer=1, **FAST)]), [(cage, "fc fq", 0), (lms, "vq", 1)])
check(r.rc == 0, "same run: the analysis runs after the cage is coloured by quality", "\n".join(r.log[-4:]))

# the coloured cage saved and loaded again: the labels are gone, and the message says why
r = h.run([lms, cage], mlx.Script([nuss_fea(landmarkLayer=0, **FAST)]))
msg = [l for l in r.log if "no tissue labels" in l]
check(r.rc != 0 and msg and "are not tissue colours" in msg[0] and "Pectus: Element Quality" in msg[0],
      "saved after colouring: non-zero exit, the message names the lost labels and the cause", "\n".join(r.log[-3:]))
h.finish()
