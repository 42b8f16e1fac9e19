#!/usr/bin/python3
"""Triangle-to-quad conversion benchmark (filter_quad_convert, thesis 4.1.2), one table, peers in the same run:

  inputs: the project's jittered saddle z = x^2/10 - y^2/4 on [-5,5]^2 (625 nodes, python/run_main.py) and
          femur.off of Debian's libcgal-demo (/usr/share/doc/libcgal-dev/data.tar.gz)
  rows:   ours (optimal = max-weight matching, greedy; all quads), MeshLab's 'Tri to Quad by smart triangle
          pairing' and 'Turn into Quad-Dominant mesh' (meshlabserver), gmsh 4.8 Blossom recombination of the same
          triangles (Mesh.RecombinationAlgorithm=1, RecombineOptimizeTopology=0), and ours followed by 'MGA Surface
          Mesh Smoothing' (quads) with and without 'Pectus: Quad Mesh Structure Improvement' first.
  columns: elements, % quads, invalid quads (beta <= 0), mean and min beta (Knupp, along each quad's own normal,
          computed here from the written files), filter time from the Log (ours) and the wall time of the
          whole process (load, filter, save).

Every quad mesh is written as a real polygon file (our 'Pectus: Save Polygonal Mesh'; gmsh: .msh) and measured here.

    PECTUS_PREFIX=build-quad/prefix bench/quad_convert.py [--no-mga] [--out DIR]
"""
import argparse
import os
import re
import subprocess
import sys
import tarfile
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, os.path.join(ROOT, "python"))
import pectus_mlx as mlx  # noqa: E402
from pectus_meshes import beta, read_off, saddle_mesh, write_ply  # noqa: E402

CGAL_DATA = "/usr/share/doc/libcgal-dev/data.tar.gz"
EX = os.path.join(ROOT, "filter_quad_convert", "examples")






def read_msh22(path):
    lines = open(path).read().splitlines()
    i = lines.index("$Nodes")
    n = int(lines[i + 1])
    ids, P = {}, []
    for k in range(n):
        t = lines[i + 2 + k].split()
        ids[int(t[0])] = k
        P.append([float(x) for x in t[1:4]])
    i = lines.index("$Elements")
    F = []
    for k in range(int(lines[i + 1])):
        t = [int(x) for x in lines[i + 2 + k].split()]
        if t[1] in (2, 3):
            F.append([ids[x] for x in t[3 + t[2]:]])
    return np.array(P), F


def measure(V, F):
    q = [f for f in F if len(f) == 4]
    b = np.array([beta(V[f]) for f in q]) if q else np.zeros(0)
    return dict(elements=len(F), pct=100.0 * len(q) / max(1, len(F)), invalid=int((b <= 0).sum()),
                mean=float(b.mean()) if len(b) else float("nan"), min=float(b.min()) if len(b) else float("nan"))


def param_sub(text, **values):
    for k, v in values.items():
        text, n = re.subn(f'(name="{k}" type="\\w+" value=")[^"]*"', f'\\g<1>{v}"', text)
        assert n >= 1, k
    return text


def filter_block(example, **values):
    text = param_sub(open(os.path.join(EX, example) if not os.path.isabs(example) else example).read(), **values)
    return text.split("<FilterScript>", 1)[1].rsplit("</FilterScript>", 1)[0]


def script(path, *blocks):
    with open(path, "w") as fh:
        fh.write("<!DOCTYPE FilterScript>\n<FilterScript>\n" + "".join(blocks) + "</FilterScript>\n")
    return path


SAVE = lambda out: filter_block("save_polygonal.mlx", fileName=out, format=1)  # noqa: E731
NO_OPS = dict(edgeSwap="false", nodeElimination="false", edgeDividing="false")


def run_meshlab(inp, blocks, out, work, name):
    """(the result's vertices and faces or None, wall s, the Log as text, the time our filters took by their own
    clocks: the sum of the 'seconds' they return)"""
    s = script(os.path.join(work, name + ".mlx"), *blocks, SAVE(out))
    t0 = time.time()
    r = mlx.run([inp], s, [], timeout=7200)
    wall = time.time() - t0
    log = "\n".join(r.log)
    own = sum(x["results"]["seconds"] for x in r.results if "seconds" in x["results"])
    if r.rc != 0 or not os.path.exists(out):
        return None, wall, log + r.stdout[-500:], own
    return read_off(out), wall, log, own


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--no-mga", action="store_true", help="skip the MGA smoothing rows")
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    work = a.out or tempfile.mkdtemp(prefix="quadbench-")
    os.makedirs(work, exist_ok=True)

    V, F = saddle_mesh()
    saddle = os.path.join(work, "saddle.ply")
    write_ply(saddle, V, F)
    inputs = [("saddle", saddle, V, F)]
    if os.path.exists(CGAL_DATA):
        with tarfile.open(CGAL_DATA) as t:
            data = t.extractfile("data/meshes/femur.off").read()
        femur = os.path.join(work, "femur.off")
        open(femur, "wb").write(data)
        FV, FF = read_off(femur)
        inputs.append(("femur", femur, FV, FF))
    else:
        print(f"({CGAL_DATA} missing: apt-get install libcgal-demo; femur skipped)")

    mga = filter_block(os.path.join(ROOT, "filter_mga_smooth", "examples", "mga_smooth.mlx"), elementType=2)
    rows = []
    for name, path, V0, F0 in inputs:
        print(f"{name}: {len(V0)} nodes, {len(F0)} triangles", flush=True)
        conv = lambda **kw: filter_block("tri_to_quad.mlx", **kw)  # noqa: E731
        structure = filter_block("structure.mlx")
        methods = [
            ("ours optimal, all quads", [conv(pairing=0, leftovers=0)], "Quads: "),
            ("ours greedy, all quads", [conv(pairing=1, leftovers=0)], "Quads: "),
            ("ours optimal, quad-dominant", [conv(pairing=0, leftovers=1)], "Quads: "),
            ("MeshLab smart triangle pairing", [' <filter name="Tri to Quad by smart triangle pairing"/>\n'], None),
            ("MeshLab quad-dominant (level 1)", [' <filter name="Turn into Quad-Dominant mesh">\n  <Param name="level" '
                                               'type="RichEnum" value="1" enum_cardinality="3"/>\n </filter>\n'], None),
        ]
        if not a.no_mga:
            methods += [
                ("ours optimal + MGA smoothing", [conv(pairing=0, leftovers=0), mga], "Quads: |MGA smoothing"),
                ("ours optimal + structure + MGA", [conv(pairing=0, leftovers=0), structure, mga],
                 "Quads: |Pectus: Quad Mesh Structure Improvement|MGA smoothing"),
            ]
        for label, blocks, what in methods:
            out = os.path.join(work, f"{name}_{len(rows)}.off")
            res, wall, log, own = run_meshlab(path, blocks, out, work, f"{name}_{len(rows)}")
            if res is None:
                print(f"  {label}: FAILED\n{log}", flush=True)
                rows.append((name, label, None, float("nan"), wall))
                continue
            ft = own if what else float("nan")  # our filters time their own calls
            rows.append((name, label, measure(*res), ft, wall))
            print(f"  {label}: done ({wall:.1f} s)", flush=True)
        # gmsh Blossom on the same triangles (STL)
        stl = os.path.join(work, name + ".stl")
        with open(stl, "w") as fh:
            fh.write("solid s\n")
            for f in F0:
                p = V0[f]
                fh.write(" facet normal 0 0 0\n  outer loop\n" + "".join(f"   vertex {q[0]:.9g} {q[1]:.9g} {q[2]:.9g}\n" for q in p)
                         + "  endloop\n endfacet\n")
            fh.write("endsolid s\n")
        msh = os.path.join(work, name + "_gmsh.msh")
        geo = os.path.join(work, name + "_gmsh.geo")
        open(geo, "w").write(f'Merge "{stl}";\nMesh.RecombinationAlgorithm = 1;\nMesh.RecombineOptimizeTopology = 0;\n'
                             f'RecombineMesh;\nMesh.MshFileVersion = 2.2;\nSave "{msh}";\n')
        t0 = time.time()
        p = subprocess.run(["gmsh", "-nopopup", geo, "-0"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        wall = time.time() - t0
        if p.returncode == 0 and os.path.exists(msh):
            rows.append((name, "gmsh 4.8 Blossom recombination", measure(*read_msh22(msh)), float("nan"), wall))
        else:
            rows.append((name, "gmsh 4.8 Blossom recombination", None, float("nan"), wall))
            print(p.stdout[-1000:])

    print()
    hdr = f"| {'input':7} | {'method':34} | {'elements':>8} | {'% quads':>7} | {'invalid':>7} | {'mean beta':>9} | {'min beta':>8} | {'filter s':>8} | {'wall s':>6} |"
    print(hdr)
    print("|" + "|".join("-" * (len(c)) for c in hdr.split("|")[1:-1]) + "|")
    for name, label, m, ft, wall in rows:
        if m is None:
            print(f"| {name:7} | {label:34} | {'failed':>8} | {'':>7} | {'':>7} | {'':>9} | {'':>8} | {'':>8} | {wall:6.2f} |")
            continue
        fts = f"{ft:8.3f}" if ft == ft else f"{'-':>8}"
        print(f"| {name:7} | {label:34} | {m['elements']:8d} | {m['pct']:7.1f} | {m['invalid']:7d} | {m['mean']:9.4f} | "
              f"{m['min']:8.4f} | {fts} | {wall:6.2f} |")
    print(f"\n(files in {work}; beta of every quad computed here from the written files; wall = whole process)")


if __name__ == "__main__":
    main()
