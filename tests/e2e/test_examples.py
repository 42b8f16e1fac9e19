"""E2E: every shipped example script of the surface, quad, rib cage, FE and volume filters runs unchanged
through meshlabserver, on the inputs its docs page names, and gives a figure in range:
  - the C1 examples on closed ellipsoids (refine: 168 patches split 3x3; project: points moved by < 4 mm);
  - the smoothing, quality and quad examples on the jittered 625-node saddle (mean alpha up by more than
    0.03, every element valid, the quads saved);
  - create_ribcage.mlx: the requested pectus index within 2 %;
  - nuss_fea.mlx (thesis patient 1: age 8, index 5.3, calibrated to 44.7 mm in large displacement): it
    calibrates on the converged mesh (the filter's `reportable`), and its three layers feed the three
    thoracic volume examples (the envelope's volume up, the slice method's within 5 %, the index down);
  - nuss_bar_planner.mlx: every option calibrated, on the converged mesh.
The patient examples run in test_examples_patient.py."""
import os

import numpy as np

import harness as h
from examples import check_converged, check_coverage, check_range, number, run
from harness import check
from pectus_meshes import closed_ellipsoid, saddle_mesh, write_off

W = h.workdir("examples")
paths = check_coverage("examples")
check(len(paths) == 16, f"{len(paths)} examples in this test")

# --- C1 surface: a coarse closed ellipsoid, and a finer one to project onto it (docs/filters/c1_*.md)
surface, points = os.path.join(W, "surface.off"), os.path.join(W, "points.off")
write_off(surface, *closed_ellipsoid(30, 20, 15, 12, 8))
write_off(points, *closed_ellipsoid(33, 22, 16.5, 48, 32))
r = run("c1_refine.mlx", [surface])
check_range(r, "c1_refine.mlx", r"C1 refine .* ([0-9]+) patches", 168, 168, "patches")
check_range(r, "c1_refine.mlx", r"-> ([0-9]+) vertices", 700, 800, "refined vertices")
r = run("c1_project.mlx", [surface, points])
check_range(r, "c1_project.mlx", r"displacement mean [0-9.]+ max ([0-9.]+)", 0.5, 4.0, "largest move (mm)")

# --- smoothing, quality and quads on the jittered saddle (docs/filters/element_quality.md and others)
saddle = os.path.join(W, "saddle.off")
write_off(saddle, *saddle_mesh())
r = run("element_quality.mlx", [saddle])
alpha0 = check_range(r, "element_quality.mlx", r"Element quality \(triangle alpha\): .* mean ([0-9.]+)", 0.5, 0.8, "mean alpha")
check_range(r, "element_quality.mlx", r"invalid \(not positive\): ([0-9]+)", 0, 0, "invalid elements")
for name in ("mga_smooth.mlx", "mga_smooth_fast.mlx", "gradient_smooth.mlx"):
    r = run(name, [saddle])
    after = number(r, r"mean alpha [0-9.]+ -> ([0-9.]+)")
    check(after is not None and alpha0 is not None and after > alpha0 + 0.03, f"{name}: mean alpha {alpha0} -> {after}")
r = run("tri_to_quad.mlx", [saddle])
check_range(r, "tri_to_quad.mlx", r"Quads: ([0-9.]+)% quads", 95, 100, "% quads")
check_range(r, "tri_to_quad.mlx", r"invalid quads \(beta <= 0\): ([0-9]+)", 0, 0, "invalid quads")
r = run("structure.mlx", [saddle])
check_range(r, "structure.mlx", r"Pectus: Quad Mesh Structure Improvement .* mean alpha [0-9.]+ -> ([0-9.]+)", alpha0 or 0, 1, "mean alpha after")
# the two saving examples write quads.obj and quads.off into the working directory
for name, saved in (("save_polygonal.mlx", "quads.obj"), ("tri_to_quad_and_save.mlx", "quads.off")):
    d = os.path.join(W, name[:-4])
    os.makedirs(d)
    r = run(name, [saddle], cwd=d)
    n = number(r, r"Pectus: Save Polygonal Mesh: wrote ([0-9]+) vertices")
    path = os.path.join(d, saved)
    check(n is not None and 625 <= n < 800 and os.path.exists(path) and os.path.getsize(path) > 10000,
          f"{name}: {saved} with {n} vertices")

# --- the rib cage, the FE analysis of thesis patient 1 and the volumes of its result
r = run("create_ribcage.mlx")
asked = number(r, r"Haller index requested ([0-9.]+)")
got = number(r, r"measured on mesh ([0-9.]+)")
check(asked and got and abs(got / asked - 1) < 0.02, f"create_ribcage.mlx: index {got} for {asked}")

before, lms, after = (os.path.join(W, f) for f in ("before.ply", "landmarks.ply", "after.ply"))
r = run("nuss_fea.mlx", outputs=[(before, "fc fq", 0), (lms, "vq", 1), (after, "fc fq vq", 2)], cwd=W)
check_range(r, "nuss_fea.mlx", r"Fe = ([0-9.]+) N \(Fs", 5, 500, "calibrated Fe (N)")
check_range(r, "nuss_fea.mlx", r"sternum end displacement ([0-9.]+) mm", 44.6, 44.8, "elevation (mm)")
check(os.path.getsize(os.path.join(W, "nuss_result.vtu")) > 100000, "nuss_fea.mlx: nuss_result.vtu written")
check(all(os.path.exists(p) for p in (before, lms, after)), "nuss_fea.mlx: the cage, its landmarks and the result saved")
check_converged(r, "nuss_fea.mlx", "Pectus: Nuss Procedure FE Analysis")

# the envelope (from the lower sternum end) gains volume; the slice method measures from the dome of the
# diaphragm, above the funnel's deepest part, where the bar's supports pressing the sides in can outweigh
# the lifted front (docs/validation.md, Table 6-1): its change is only bounded
r = run("thoracic_volume_envelope.mlx", [before, lms, after])
check_range(r, "thoracic_volume_envelope.mlx", r"Ferguson envelope thoracic volume change: \+?(-?[0-9.]+) cm3", 1, 500,
            "volume gain (cm3)")
r = run("thoracic_volume_slice.mlx", [before, lms, after])
v0 = check_range(r, "thoracic_volume_slice.mlx", r"Slice method intrathoracic volume change: .* before ([0-9.]+) cm3",
                 1000, 2500, "volume before (cm3)")
check_range(r, "thoracic_volume_slice.mlx", r"Slice method intrathoracic volume change: \+?(-?[0-9.]+) cm3",
            -0.05 * (v0 or 0), 0.05 * (v0 or 0), "volume change (cm3), within 5 % of the volume before")
r = run("pectus_index.mlx", [before, lms, after])
hb = number(r, r"Pectus index change: Haller ([0-9.]+) ->")
ha = number(r, r"Pectus index change: Haller [0-9.]+ -> ([0-9.]+)")
check(hb and ha and hb > 4.5 and 1.8 < ha < hb - 1, f"pectus_index.mlx: Haller index {hb} -> {ha}")

# --- the bar planner: every option calibrated to the target
r = run("nuss_bar_planner.mlx", cwd=W)
forces = [float(x) for x in np.array([l.split("Fe = ")[1].split(" N")[0] for l in r.log if l.startswith("Planner option '")])]
check(len(forces) == 6 and all(5 < f < 500 for f in forces), f"nuss_bar_planner.mlx: 6 options calibrated, Fe {forces}")
check_converged(r, "nuss_bar_planner.mlx", "Pectus: Nuss Bar Planner")
h.finish()
