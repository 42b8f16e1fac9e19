"""E2E: the main pipeline (python/pipeline.py, one .mlx through meshlabserver) in its quick form (small-strain
TET4 FE), and its table's figures against the individual filters run alone on the layers it saved:
the calibrated force and elevation (Nuss FE on the saved smoothed cage) and the volume changes (slice method
and envelope on the saved before/after layers)."""
import os
import re
import sys

import harness as h
import pectus_mlx as mlx
from harness import check

sys.path.insert(0, os.path.join(os.environ.get("PECTUS_SOURCE", "."), "python"))
import pipeline  # noqa: E402

W = h.workdir("pipeline")
rc, r, res = pipeline.run_pipeline(W, quick=True)
check(rc == 0, "pipeline runs", res.stdout[-2000:])
print(pipeline.table(r, 8, "M", 44.7))
check(r["elevation"] is not None and abs(r["elevation"] - 44.7) <= 0.1, f"simulated elevation {r['elevation']} mm = 44.7 +- 0.1")
check(r["force"] is not None and r["force"] > 0, f"calibrated force {r['force']} N")
check(r["slice_change_cm3"] is not None and r["slice_change_cm3"] > 0, f"slice volume change {r['slice_change_cm3']} cm3 > 0")
check(r["envelope_change_cm3"] is not None and r["envelope_change_cm3"] > 0, f"envelope change {r['envelope_change_cm3']} cm3 > 0")
check(len(r["haller"]) == 2 and r["haller"][1] < r["haller"][0], f"Haller index falls {r['haller']}")
check(r["quality_mean_after"] is not None and r["quality_mean_after"] > r["quality_mean_before"],
      f"MGA raised the mean alpha {r['quality_mean_before']} -> {r['quality_mean_after']}")
for f in ("pipeline.mlx", "nuss.vtu", "nuss.inp", "nuss_force_displacement.csv", "nuss_force_displacement.png",
          "nuss_rib_strain.csv", "ribcage_smoothed.ply", "nuss_result.ply", "summary.csv", "envelope_before.ply"):
    check(os.path.exists(os.path.join(W, f)), f"{f} written")

# the individual filters give the table's figures: the FE alone after the same cage and smoothing (the saved
# cage PLY has lost its label colours to the quality colours, so the cage is rebuilt in the same script)
steps = {f.name: f for f in mlx.load_script(os.path.join(W, "pipeline.mlx"))}
nuss = steps["Pectus: Nuss Procedure FE Analysis"].set(resultBase=mlx.SaveFile("", ".vtu"))
alone = h.run([], mlx.Script([steps["Pectus: Create Rib Cage"], steps["Pectus: MGA Surface Mesh Smoothing"], nuss]))
force = alone.get("force_N", "Pectus: Nuss Procedure FE Analysis")
check(alone.rc == 0 and force is not None and r["force"] is not None and abs(force - r["force"]) <= 0.01 * r["force"],
      f"Nuss FE alone after the same cage and smoothing: Fe {force} N vs the pipeline's {r['force']} N (1 %)")
cage, lms, after = (os.path.join(W, f) for f in ("ribcage_smoothed.ply", "ribcage_landmarks.ply", "nuss_result.ply"))
sl = [f for f in mlx.load_script(os.path.join(W, "pipeline.mlx")) if f.name == "Pectus: Thoracic Volume (Slice Method)"][0]
sl.set(beforeLayer=1, landmarkLayer=0)
alone = h.run([lms, cage, after], mlx.Script([sl]))
d = alone.get("volume_change_cm3", "Pectus: Thoracic Volume (Slice Method)")
check(alone.rc == 0 and d is not None and abs(d - r["slice_change_cm3"]) <= 0.005 * abs(r["slice_change_cm3"]) + 0.5,
      f"slice method alone: change {d} cm3 vs the pipeline's {r['slice_change_cm3']} cm3")
h.finish()
