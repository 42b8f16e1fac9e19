"""End to end, regression: MGA smoothing of the femur (libcgal-demo) converted to quads never leaves an
invalid quad. The converted femur has quads with a nearly flat corner (a valence-2 node) that are already
folded against the surface normal at a neighbouring node; an invalid star ranks first by its elements
invalid in themselves, so such a quad is never traded for a reflex quad (Knupp beta 0). Skipped without
libcgal-demo."""
import os
import re

import numpy as np

import pectus_mlx as mlx
from pectus_meshes import beta, read_off
from harness import SOURCE, cgal_meshes, check, finish, run, workdir

d = workdir("mga_femur_quads")
femur = cgal_meshes(d, "femur")["femur"]

ex = lambda *p: os.path.join(SOURCE, *p)  # noqa: E731
convert = mlx.load_script(ex("filter_quad_convert", "examples", "tri_to_quad.mlx"))
mga = [f.set(maxSweeps=1) if f.name == "Pectus: MGA Surface Mesh Smoothing" else f
       for f in mlx.load_script(ex("filter_mga_smooth", "examples", "mga_smooth.mlx"))]
save = lambda out: [f.set(fileName=out, format=1)  # noqa: E731
                    for f in mlx.load_script(ex("filter_quad_convert", "examples", "save_polygonal.mlx"))]
outs = {name: os.path.join(d, name + ".off") for name in ("converted", "smoothed")}
# one meshlabserver run: convert, save, smooth (one sweep), save
r = run([femur], mlx.Script(convert + save(outs["converted"]) + mga + save(outs["smoothed"])))
check(r.rc == 0 and all(os.path.exists(p) for p in outs.values()), "meshlabserver exit 0 and both polygon files",
      r.stdout[-1500:])
outs = {k: read_off(p) for k, p in outs.items()}
(V0, F0), (V1, F1) = outs["converted"], outs["smoothed"]
check(F0 == F1 and all(len(f) == 4 for f in F1), "same quads before and after smoothing", f"{len(F0)} / {len(F1)}")
b0 = np.array([beta(V0[f]) for f in F0])
b1 = np.array([beta(V1[f]) for f in F1])
check((b0 <= 0).sum() == 0, "the conversion leaves no invalid quad", str((b0 <= 0).sum()))
check((b1 <= 0).sum() == 0, "MGA smoothing leaves no invalid quad (beta <= 0)",
      f"{(b1 <= 0).sum()} invalid, min beta {b1.min():.4f}")
check(b1.mean() > b0.mean() + 0.03, "mean beta rises", f"{b0.mean():.4f} -> {b1.mean():.4f}")
check(b1.min() >= b0.min(), "min beta does not drop", f"{b0.min():.4f} -> {b1.min():.4f}")
# folds are tested against the surface normal at every node of an element, so no move folds a
# neighbour's element: the count the Log gives can only fall
m = re.search(r"folded against a node's surface normal (\d+) -> (\d+)", r.stdout)
check(m is not None and 0 < int(m[1]) and int(m[2]) < int(m[1]),
      "MGA lowers the count of quads folded against a node's surface normal",
      m[0] if m else r.stdout[-800:])
finish()
