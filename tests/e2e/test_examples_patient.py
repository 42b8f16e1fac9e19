"""E2E: the three patient example scripts run unchanged through meshlabserver on the folders they name,
written first as their docs page does (docs/filters/import_ct_segmentation.md, prepare_patient_rib_cage.md):
  - import_ct_segmentation.mlx imports every file of its folder (the phantom's messy STL export);
  - prepare_patient_rib_cage.mlx prepares that export into one cage of 12 ribs per side, with landmarks;
  - patient_nuss_analysis.mlx takes the same export through the FE analysis calibrated to the target from the
    model (the chest line: the phantom's lower sternum end lies behind it), both volumes and the pectus index:
    the volume grows and the index falls."""
import glob
import os
import shutil
import subprocess

import harness as h
from examples import check_converged, check_coverage, check_range, number, run
from harness import check

paths = check_coverage("patient")
check(len(paths) == 3, f"{len(paths)} examples in this test")
PHANTOM = os.path.join(os.path.dirname(h.PREFIX), "tools", "pectus_ct_phantom")
DOCS = "/tmp/pectus-docs"
PATIENT = os.path.join(DOCS, "patient")
IMPORT = os.path.join(DOCS, "import_ct_segmentation")

r = subprocess.run([PHANTOM, PATIENT, "--only", "messy"], capture_output=True, text=True, timeout=900)
check(r.returncode == 0, "pectus_ct_phantom writes the messy export", r.stderr[-500:])
messy = sorted(glob.glob(os.path.join(PATIENT, "stl_messy", "*.stl")))

# the import example's folder: the messy export's files
shutil.rmtree(IMPORT, ignore_errors=True)
os.makedirs(IMPORT)
for f in messy:
    shutil.copy(f, IMPORT)
r = run("import_ct_segmentation.mlx")
check(number(r, r"Imported ([0-9]+) structures") == len(messy) == 3, f"import_ct_segmentation.mlx: {len(messy)} files imported",
      "\n".join(r.log[-5:]))
shutil.rmtree(IMPORT, ignore_errors=True)

W = h.workdir("examples-patient")
cage, lms = os.path.join(W, "cage.ply"), os.path.join(W, "cage_landmarks.ply")
layers = len(messy)  # the prepared cage and its landmarks follow the imported layers
r = run("prepare_patient_rib_cage.mlx", outputs=[(cage, "fc fq", layers), (lms, "vq", layers + 1)])
check_range(r, "prepare_patient_rib_cage.mlx", r"Patient rib cage: [0-9]+ faces, ([0-9]+) right", 12, 12, "right ribs")
check_range(r, "prepare_patient_rib_cage.mlx", r"Patient rib cage: [0-9]+ faces, [0-9]+ right and ([0-9]+) left", 12, 12, "left ribs")
check(os.path.getsize(cage) > 100000 and os.path.getsize(lms) > 300, "prepare_patient_rib_cage.mlx: cage and landmarks saved")

r = run("patient_nuss_analysis.mlx")
check_range(r, "patient_nuss_analysis.mlx", r"Target elevation ([0-9.]+) mm, from the model", 5, 80,
            "target from the model, the chest line depth (mm)")
target = number(r, r"calibrated to ([0-9.]+) mm")
check_range(r, "patient_nuss_analysis.mlx", r"sternum end displacement ([0-9.]+) mm", (target or 0) - 0.1,
            (target or 0) + 0.1, "elevation (mm), within the calibration tolerance of the target")
check_range(r, "patient_nuss_analysis.mlx", r"Fe = ([0-9.]+) N \(Fs", 1, 500, "calibrated Fe (N)")
check_converged(r, "patient_nuss_analysis.mlx", "Pectus: Nuss Procedure FE Analysis")
check_range(r, "patient_nuss_analysis.mlx", r"Slice method intrathoracic volume change: \+?(-?[0-9.]+) cm3", 1, 500,
            "slice volume gain (cm3)")
hb = number(r, r"Pectus index change: Haller ([0-9.]+) ->")
ha = number(r, r"Pectus index change: Haller [0-9.]+ -> ([0-9.]+)")
check(hb and ha and ha < hb - 0.5, f"patient_nuss_analysis.mlx: Haller index {hb} -> {ha}")
h.finish()
