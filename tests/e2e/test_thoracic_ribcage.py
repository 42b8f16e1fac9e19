"""E2E: the rib cage generator (filter_nuss_fea, 'Pectus: Create Rib Cage') followed by the
thoracic volume filters on its cage and landmarks layers (labels.h codes), then a before/after
comparison against a copy of the cage whose anterior wall is lifted around the funnel (a stand-in
for the FE correction): positive volume change by both methods, smaller Haller index."""
import os

import numpy as np

import harness as h
import pectus_mlx as mlx
from pectus_filters import create_ribcage
from harness import check

W = h.workdir("thoracic-ribcage")
GEN = create_ribcage(edgeLength=3.0)
R = ["Landmarks", "Given heights"]
LOW = ["700 dome of the diaphragm", "500 lower end of the sternum"]


def common(lower, compare=False, before=0, landmarks=1):
    return dict(compare=mlx.Bool(compare), beforeLayer=mlx.Mesh(before), rangeSource=mlx.Enum(0, R),
                landmarkLayer=mlx.Mesh(landmarks), lowerLimit=mlx.Enum(lower, LOW), zLow=mlx.Float(0.0),
                zHigh=mlx.Float(200.0))


def filters(compare=False, before=0, landmarks=1):
    c = dict(compare=compare, before=before, landmarks=landmarks)
    return [mlx.Filter("Pectus: Thoracic Volume (Slice Method)", **common(1, **c), spacing=mlx.Float(2.6),
                       resolution=mlx.Int(512), rays=mlx.Int(720)),
            mlx.Filter("Pectus: Thoracic Volume (Ferguson Envelope)", **common(1, **c), patchesLong=mlx.Int(16),
                       patchesAround=mlx.Int(16), initialStep=mlx.Float(0.0), minStep=mlx.Float(0.05),
                       smoothing=mlx.Bool(True), tessellation=mlx.Int(8)),
            mlx.Filter("Pectus: Pectus Index", compare=mlx.Bool(compare), beforeLayer=mlx.Mesh(before),
                       levelSource=mlx.Enum(0, ["Landmarks 501/503", "Automatic (deepest slice)"]),
                       landmarkLayer=mlx.Mesh(landmarks), zLow=mlx.Float(0.0), zHigh=mlx.Float(200.0),
                       rays=mlx.Int(720))]




cage, lms = os.path.join(W, "cage.ply"), os.path.join(W, "cage_landmarks.ply")
r = h.run([], mlx.Script([GEN] + filters()), [(cage, "", 0), (lms, "vq", 1)])
check(r.rc == 0, "generator + thoracic volume filters run", r.stdout[-1500:])
gen_h = r.values("haller_index_measured", "Pectus: Create Rib Cage")
sl = r.values("volume_cm3", "Pectus: Thoracic Volume (Slice Method)")
en = r.values("volume_cm3", "Pectus: Thoracic Volume (Ferguson Envelope)")
hi = r.values("haller_index", "Pectus: Pectus Index")
print("\n".join(l for l in r.log if "volume" in l or "index" in l))
check(len(sl) == 1 and len(en) == 1 and 0.4 * en[0] < sl[0] < en[0],
      f"same range (500..701): intrathoracic {sl} cm3 inside the envelope {en} cm3")
check(len(gen_h) == 1 and len(hi) == 1 and abs(hi[0] - gen_h[0]) < 0.03 * gen_h[0],
      f"Haller index on the model {hi} agrees with the generator's own measure {gen_h} (3 %)")

# before/after: lift the anterior wall around the funnel (smooth bump centred on landmark 501)
if os.path.exists(cage) and os.path.exists(lms):
    P = h.read_ply(cage)
    L = h.read_ply(lms)
    q = np.rint(L["vertex"]["quality"]).astype(int)
    deep = L["V"][q == 501][0]
    V = P["V"].copy()
    bump = 15.0 * np.exp(-(V[:, 0] - deep[0]) ** 2 / (2 * 35.0 ** 2) - (V[:, 2] - deep[2]) ** 2 / (2 * 35.0 ** 2))
    V[:, 1] += np.where(V[:, 1] > 0.3 * deep[1], bump, 0.0)
    after = h.write_ply(os.path.join(W, "cage_after.ply"), V, P["F"])
    r = h.run([cage, lms, after], mlx.Script(filters(compare=True, before=0, landmarks=1)))
    check(r.rc == 0, "before/after comparison runs", r.stdout[-1500:])
    print("\n".join(l for l in r.log if "change" in l))
    d_sl = r.values("volume_change_cm3", "Pectus: Thoracic Volume (Slice Method)")
    d_en = r.values("volume_change_cm3", "Pectus: Thoracic Volume (Ferguson Envelope)")
    hh = r.values("before_haller_index", "Pectus: Pectus Index") + r.values("haller_index", "Pectus: Pectus Index")
    check(len(d_sl) == 1 and d_sl[0] > 0, f"slice method: positive volume change {d_sl} cm3")
    check(len(d_en) == 1 and d_en[0] > 0, f"envelope: positive volume change {d_en} cm3")
    check(len(hh) == 2 and hh[1] < hh[0], f"Haller index before/after {hh} falls")
else:
    check(False, "cage and landmarks saved")
h.finish()
