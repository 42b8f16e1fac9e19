#!/usr/bin/env python3
"""A patient's CT segmentation, from its files to the thesis' Table 6-1 results, through the real meshlabserver:

  Pectus: Import CT Segmentation (a folder of STL/OBJ/PLY/OFF files, TotalSegmentator's NIfTI masks, or one label map)
  -> Pectus: Prepare Patient Rib Cage (classify, repair, frame, number, join, landmark)
  -> Pectus: Nuss Procedure FE Analysis with the force calibrated to the measured elevation, or by default to the
     elevation that brings the lower sternum end onto the chest line (from the model)
  -> thoracic volume by the slice and the Ferguson envelope methods, before and after
  -> pectus index before and after.

Two meshlabserver runs: the first imports and prepares, and saves the labelled cage and its landmarks; the
second analyses them (so the layer numbers of the analysis never depend on how many files the folder holds).
Both scripts are written next to the results (prepare.mlx, analyse.mlx) and run unchanged in the GUI. Every
filter's parameters come from its example script, with the values below overridden.

    python3 python/patient.py SEGMENTATION OUTDIR [--elevation MM] [--order 2] [--analysis large|small]
"""
from __future__ import annotations

import argparse
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
import pectus_mlx as mlx  # noqa: E402
from pectus_filters import import_ct_segmentation, prepare_patient_rib_cage  # noqa: E402


def example(plugin: str, name: str) -> mlx.Filter:
    return mlx.load_script(os.path.join(ROOT, plugin, "examples", name + ".mlx"))[-1]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("segmentation", help="a folder of structure files, or one file")
    ap.add_argument("out", help="folder for the results")
    ap.add_argument("--elevation", type=float, default=0.0,
                    help="measured rise of the lower sternum end (mm); 0 (default): to the chest line (from the model)")
    ap.add_argument("--order", type=int, choices=(1, 2), default=2, help="1: TET4, 2: TET10 (default)")
    ap.add_argument("--analysis", choices=("large", "small"), default="large",
                    help="large displacement (default, with the FE filter's defaults: neo-Hookean, the elevation "
                         "prescribed, Newton with line search and adaptive steps; minutes) or small strain (seconds)")
    ap.add_argument("--edge", type=float, default=4.0, help="edge length of the prepared cage (mm)")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    cage, lms = os.path.join(a.out, "cage.ply"), os.path.join(a.out, "cage_landmarks.ply")

    t0 = time.time()
    imp = import_ct_segmentation(path=os.path.abspath(a.segmentation))
    # the prepared cage and its landmarks come after the imported structures: count those first
    n = mlx.run([], mlx.Script([imp])).get("structures")
    if n is None:
        print(f"nothing imported from {a.segmentation}")
        return 1
    prep = mlx.Script([imp, prepare_patient_rib_cage(edgeLength=a.edge)])
    prep.write(os.path.join(a.out, "prepare.mlx"))
    r = mlx.run([], prep, [(cage, "fc fq", n), (lms, "vq", n + 1)])
    for line in r.log:
        print("  " + line)
    if r.rc != 0 or not os.path.exists(cage):
        print("preparation failed (the reason is in the Log above)")
        return 1

    fe = example("filter_nuss_fea", "nuss_fea").set(
        landmarkLayer=0, targetElevation=a.elevation, order=0 if a.order == 2 else 1,
        analysis=0 if a.analysis == "large" else 1, resultBase=os.path.join(a.out, "nuss_result.vtu"))
    # the volumes and the index on the deformed cage (current after the FE filter) against the prepared one
    after = [example("filter_thoracic_volume", n).set(compare=True, beforeLayer=1, landmarkLayer=0)
             for n in ("thoracic_volume_slice", "thoracic_volume_envelope", "pectus_index")]
    analyse = mlx.Script([fe, *after])
    analyse.write(os.path.join(a.out, "analyse.mlx"))
    # meshlabserver makes the last input current: the landmarks are layer 0, the cage layer 1 (current)
    r2 = mlx.run([lms, cage], analyse, [(os.path.join(a.out, "after.ply"), "vc vq", 2)])
    for line in r2.log:
        print("  " + line)
    if r2.rc != 0:
        print("the analysis failed (the reason is in the Log above)")
        return 1

    FE, SLICE, ENVELOPE, INDEX = ("Pectus: Nuss Procedure FE Analysis", "Pectus: Thoracic Volume (Slice Method)",
                                  "Pectus: Thoracic Volume (Ferguson Envelope)", "Pectus: Pectus Index")
    rows = [("calibrated elevating force Fe (N)", r2.get("force_N", FE)),
            ("elevation of the lower sternum end (mm)", r2.get("elevation_mm", FE)),
            ("max von Mises stress (MPa)", r2.get("max_stress_MPa", FE)),
            ("  away from the tissue junctions (MPa)", r2.get("max_stress_body_MPa", FE)),
            ("max equivalent strain", r2.get("max_strain", FE)),
            ("pectus (Haller) index before", r2.get("before_haller_index", INDEX)),
            ("pectus (Haller) index after", r2.get("haller_index", INDEX)),
            ("slice method volume gain (cm3)", r2.get("volume_change_cm3", SLICE)),
            ("Ferguson envelope volume gain (cm3)", r2.get("volume_change_cm3", ENVELOPE))]
    print(f"\n{'Table 6-1 quantity':45s} value")
    for k, v in rows:
        print(f"{k:45s} {'n/a' if v is None else f'{v:.2f}'}")
    print(f"\n{time.time() - t0:.0f} s; results in {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
