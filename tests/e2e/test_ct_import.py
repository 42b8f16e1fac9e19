"""E2E: 'Pectus: Import CT Segmentation' through meshlabserver on a folder of small files (binary STL cube with a
'solid' header, ASCII STL tetrahedron, OBJ cube of quads with v/vt/vn and negative indices, PLY cube): one
layer per file in name order, named after the file, with the shared vertices; the example script; a missing
folder refused with no layer saved; an OBJ with a bad index refused naming the file and line."""
import os
import struct

import numpy as np

from harness import SOURCE, check, check_refused, finish, read_ply, run, workdir, write_ply
import pectus_mlx as mlx
from pectus_filters import import_ct_segmentation

CUBE_V = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
CUBE_T = [(0, 2, 1), (0, 3, 2), (4, 5, 6), (4, 6, 7), (0, 1, 5), (0, 5, 4),
          (1, 2, 6), (1, 6, 5), (2, 3, 7), (2, 7, 6), (3, 0, 4), (3, 4, 7)]
TETRA_V = [(0, 0, 0), (2, 0, 0), (0, 2, 0), (0, 0, 2)]
TETRA_T = [(0, 2, 1), (0, 1, 3), (1, 2, 3), (2, 0, 3)]


def binary_stl(path, V, T, header=b"solid exported as binary"):
    with open(path, "wb") as f:
        f.write(header.ljust(80, b" ") + struct.pack("<I", len(T)))
        for t in T:
            f.write(struct.pack("<12fH", 0, 0, 0, *[float(c) for k in t for c in V[k]], 0))


def ascii_stl(path, V, T):
    with open(path, "w") as f:
        f.write("solid tetra\n")
        for t in T:
            f.write("facet normal 0 0 0\nouter loop\n")
            for k in t:
                f.write("vertex %g %g %g\n" % V[k])
            f.write("endloop\nendfacet\n")
        f.write("endsolid tetra\n")


def obj_cube(path):
    lines = ["# cube of quads", "o cube"] + ["v %g %g %g" % v for v in CUBE_V] + ["vt 0 0", "vt 1 0", "vn 0 0 1"]
    lines += ["f 1 4 3 2", "f 5/1 6/2 7/1 8/2", "f 1//1 2//1 6//1 5//1", "f 2/1/1 3/2/1 7/1/1 6/2/1",
              "f -6 -5 -1 -2", "f -8 -4 -1 -5"]
    with open(path, "w", newline="") as f:
        f.write("\r\n".join(lines))  # CRLF, no final newline


d = workdir("ct-import")
seg = os.path.join(d, "seg")
os.makedirs(seg)
binary_stl(os.path.join(seg, "rib_left_3.stl"), CUBE_V, CUBE_T)
ascii_stl(os.path.join(seg, "costal_cartilage_4.stl"), TETRA_V, TETRA_T)
obj_cube(os.path.join(seg, "sternum.obj"))
write_ply(os.path.join(seg, "b_vertebra.ply"), np.array(CUBE_V, float) + 5, [list(t) for t in CUBE_T])
with open(os.path.join(seg, "notes.txt"), "w") as f:
    f.write("not a mesh\n")

expected = [("b_vertebra", 12, 8), ("costal_cartilage_4", 4, 4), ("rib_left_3", 12, 8), ("sternum", 12, 8)]
outs = [(os.path.join(d, f"layer{i}.ply"), "", i) for i in range(len(expected))]
r = run([], mlx.Script([import_ct_segmentation(path=seg)]), outs)
check(r.rc == 0, "meshlabserver exits 0", r.stdout[-2000:])
summary = [l for l in r.log if l.startswith("Imported ")]
check(len(summary) == 1 and "Imported 4 structures" in summary[0] and "40 faces, 28 vertices" in summary[0],
      "one summary line: 4 structures, 40 faces, 28 vertices", "\n".join(r.log))
for i, (name, nf, nv) in enumerate(expected):
    line = [l for l in r.log if l.startswith(name + ":")]
    check(len(line) == 1 and f"{nf} faces, {nv} vertices, 1 component, from " in line[0],
          f"Log line of {name}", "\n".join(r.log))
    path = outs[i][0]
    if not check(os.path.exists(path), f"layer {i} saved"):
        continue
    m = read_ply(path)
    check(len(m["F"]) == nf and len(m["V"]) == nv, f"layer {i} is {name}: {nf} faces, {nv} vertices",
          f"{len(m['F'])} faces, {len(m['V'])} vertices")
check(any("skipped 1 file" in l and "notes.txt" in l for l in r.log), "the other file is listed as skipped",
      "\n".join(r.log))

# the layer names: meshlabserver saves files, not names; the Log names each structure in layer order
order = [l.split(":")[0] for l in r.log if any(l.startswith(e[0] + ":") for e in expected)]
check(order == [e[0] for e in expected], "structures in name order", str(order))

# the example script runs as shipped (its folder is the docs' folder): every parameter is present
ex = os.path.join(SOURCE, "filter_patient", "examples", "import_ct_segmentation.mlx")
[f] = mlx.load_script(ex)
check(sorted(f.params) == ["labelTable", "minVoxels", "path"], "the example lists every parameter", str(f.params))
r = run([], mlx.Script([f.set(path=os.path.join(seg, "sternum.obj"))]), [(os.path.join(d, "one.ply"), "", 0)])
check(r.rc == 0 and any(l.startswith("sternum: 12 faces, 8 vertices") for l in r.log),
      "the example script imports one file", "\n".join(r.log))

# bad input: nothing saved, the reason in the Log
missing = os.path.join(d, "nowhere")
out = os.path.join(d, "bad.ply")
r = run([], mlx.Script([import_ct_segmentation(path=missing)]), [(out, "", None)])
check_refused(r, "does not exist", "missing folder")
check(not os.path.exists(out), "no layer saved after a missing folder")
bad = os.path.join(d, "bad")
os.makedirs(bad)
with open(os.path.join(bad, "rib.obj"), "w") as f:
    f.write("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n")
r = run([], mlx.Script([import_ct_segmentation(path=bad)]), [(out, "", None)])
check_refused(r, "rib.obj' line 4: face refers to vertex 4", "OBJ with a bad index")
check(not os.path.exists(out), "no layer saved after a bad OBJ")
empty = os.path.join(d, "empty")
os.makedirs(empty)
r = run([], mlx.Script([import_ct_segmentation(path=empty)]), [(out, "", None)])
check_refused(r, "found nothing", "empty folder")

finish()
