"""E2E: 'Pectus: Nuss Bar Planner' through the real meshlabserver on a coarse generated rib cage (linear TET4).

Checks: the CSV has one row per option (levels 4 and 5, one and two bars), every option reaches the target
elevation, the one-bar row of level 4 needs the force the single 'Pectus: Nuss Procedure FE Analysis' at level 4
needs (within 1 %), two bars need another force, the volume gains are positive and the Haller index drops,
the best row is the lowest force and its layer (the deformed cage coloured by stress) is added; bad input
(empty levels, a level outside the ribs, nonsense numbers) fails with a message, a non-zero exit and no
table written."""
import csv
import os

import numpy as np

import harness as h
import pectus_mlx as mlx
from harness import check
from pectus_filters import create_ribcage, nuss_bar_planner, nuss_fea

W = h.workdir("nuss-planner")
FAST = dict(analysis=1, order=1, tetQuality=0.0, targetElevation=20.0)  # linear TET4, no TetGen refinement

cage, lms = os.path.join(W, "cage.ply"), os.path.join(W, "cage_landmarks.ply")
r = h.run([], mlx.Script([create_ribcage(edgeLength=5.0)]), [(cage, "fc fq", 0), (lms, "vq", 1)])
check(r.rc == 0 and os.path.exists(cage) and os.path.exists(lms), "rib cage generated and saved", r.stdout[-800:])

# the planner (landmarks loaded first, the cage last: the cage is current)
table = os.path.join(W, "plan.csv")
best = os.path.join(W, "best.ply")
r = h.run([lms, cage], mlx.Script([nuss_bar_planner(landmarkLayer=0, levels="4,5", csvFile=mlx.SaveFile(table, ".csv"), **FAST)]),
          [(best, "vq vc", 2)])
print("\n".join(l for l in r.log if l.startswith(("Nuss bar planner", "Planner |", "Planner best"))))
check(r.rc == 0, "the planner runs (levels 4,5; one and two bars)", r.stdout[-1500:])
rows = list(csv.DictReader(open(table))) if os.path.exists(table) else []
check([x["option"] for x in rows] == ["1 bar, space 4", "2 bars, spaces 4 + 3", "1 bar, space 5", "2 bars, spaces 5 + 4"],
      f"one CSV row per option ({[x['option'] for x in rows]})")
check(sum(l.startswith("Planner option") for l in r.log) == len(rows) and len(rows) == 4, "one Log line per option")
if rows:
    F = {x["option"]: float(x["force_N"]) for x in rows}
    check(all(abs(float(x["elevation_mm"]) - 20.0) <= 0.1 for x in rows), "every option reaches 20 mm within 0.1 mm")
    check(abs(F["2 bars, spaces 4 + 3"] - F["1 bar, space 4"]) > 0.01 * F["1 bar, space 4"],
          f"two bars need another force than one ({F})")
    check(all(float(x["slice_gain_cm3"]) > 0 and float(x["envelope_gain_cm3"]) > 0 for x in rows), "volume gains > 0 (both methods)")
    check(all(float(x["haller_after"]) < float(x["haller_before"]) for x in rows), "the Haller index drops for every option")
    check(all(float(x["max_stress_MPa"]) > 0 and " rib " in " " + x["max_stress_at"] or "sternum" in x["max_stress_at"]
              or "cartilage" in x["max_stress_at"] for x in rows), "max stress and where")
    flagged = [x["option"] for x in rows if x["best"] == "1"]
    check(flagged == [min(F, key=F.get)], f"the best row is the lowest force ({flagged})")
    check(any(f"layer 'nuss planner best: {flagged[0] if flagged else ''}'" in l for l in r.log), "the best option's layer is named after it")
if os.path.exists(best):
    B, C = h.read_ply(best), h.read_ply(cage)
    q = B["vertex"]["quality"]
    check(len(B["V"]) == len(C["V"]) and np.abs(B["V"] - C["V"]).max() > 5.0, "best layer: the cage, deformed")
    check(q.min() >= 0 and q.max() > 0, f"best layer coloured by von Mises stress [{q.min():.3g}, {q.max():.3g}] MPa")
else:
    check(False, "best layer saved")

# the single FE analysis at level 4 needs the same force as the planner's one-bar row
r = h.run([lms, cage], mlx.Script([nuss_fea(landmarkLayer=0, intercostalSpace=4, **FAST)]))
single = r.values("force_N", "Pectus: Nuss Procedure FE Analysis")
check(r.rc == 0 and len(single) == 1 and rows and abs(F["1 bar, space 4"] - single[0]) <= 0.01 * single[0],
      f"one bar at level 4: planner {rows and F['1 bar, space 4']} N, single FE analysis {single} N (within 1 %)")

# bad input: a message, a non-zero exit, nothing written (the adapter base rolls the layers back; meshlabserver
# saves nothing after a failed script, so the file is what can be observed)
for what, kw, msg in [("empty levels", dict(levels=" "), "no level"),
                      ("a level outside the ribs", dict(levels="4,12"), "outside the ribs"),
                      ("a level that is not a number", dict(levels="4,x"), "not a whole number"),
                      ("a nonsense share", dict(secondShare=1.5), "secondShare"),
                      ("a negative target", dict(targetElevation=-5.0), "targetElevation")]:
    bad = os.path.join(W, "bad.csv")
    r = h.run([lms, cage], mlx.Script([nuss_bar_planner(landmarkLayer=0, csvFile=mlx.SaveFile(bad, ".csv"), **{**FAST, **kw})]))
    check(r.rc != 0 and any(msg in l for l in r.log), f"{what}: non-zero exit and a message naming it", "\n".join(r.log[-3:]))
    check(not os.path.exists(bad), f"{what}: no table written")
h.finish()
