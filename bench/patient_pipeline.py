#!/usr/bin/env python3
"""Benchmark: a patient's CT export through 'Pectus: Prepare Patient Rib Cage' and the calibrated FE analysis, next to the
generator's own cage of the same child. One table.

The export is the default cage (age 7, pectus index 4) rasterised on a 1 mm CT grid by pectus_ct_phantom and
written as messy STL surfaces with a real export's defects (ribs, spine and scapulae in one surface cut by the
field of view, marrow shells nested in the bones, 900 specks, blocks beside the spine, duplicate faces; the
sternum in pieces with slivers and a self-intersecting patch; every cartilage in one file, three with holes)
and as TotalSegmentator's per-structure NIfTI masks. Rows:
  - preparing it (import + prepare, meshlabserver): wall time, peak memory, faces, the prepare step's own time;
  - the generator making the same cage at the prepared cage's edge length (4 mm);
  - the calibrated analysis (44.7 mm) of each, large displacement TET10 with the FE filter's defaults (neo-Hookean, displacement
    control, line search, adaptive steps): force, wall time, peak memory.

    /usr/bin/python3 bench/patient_pipeline.py [--analysis large|small] [--order 2|1] [--fe messy,masks,generated]
                                               [--out DIR]
"""
from __future__ import annotations

import argparse
import os
import platform
import re
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "python"))
import pectus_mlx as mlx  # noqa: E402
from pectus_filters import create_ribcage, import_ct_segmentation, nuss_fea, prepare_patient_rib_cage  # noqa: E402

BUILD = os.environ.get("PECTUS_BUILD", os.path.join(ROOT, "build"))
SERVER = os.path.join(BUILD, "prefix", "bin", "meshlabserver")


def timed(inputs, script, outputs=()):
    """meshlabserver under /usr/bin/time: (mlx.Result with the filters' results, wall s, peak MB, rc)"""
    fd, path = tempfile.mkstemp(suffix=".mlx")
    os.close(fd)
    script.write(path)
    fd, results = tempfile.mkstemp(prefix="pectus-results-", suffix=".jsonl")
    os.close(fd)
    cmd = ["xvfb-run", "-a", "/usr/bin/time", "-v", SERVER]
    for i in inputs:
        cmd += ["-i", i]
    for p, layer, mask in outputs:
        cmd += ["-o", p, "-l", str(layer), "-m", *mask.split()]
    cmd += ["-s", path]
    t0 = time.time()
    r = subprocess.run(cmd, capture_output=True, text=True, errors="replace",
                       env=dict(os.environ, PECTUS_RESULTS_FILE=results))
    wall = time.time() - t0
    os.remove(path)
    out = r.stdout + r.stderr
    res = mlx.Result(r.returncode, out, mlx.read_results(results))
    os.remove(results)
    rss = re.search(r"Maximum resident set size \(kbytes\): (\d+)", out)
    return res, wall, (int(rss.group(1)) / 1024 if rss else float("nan")), r.returncode


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--analysis", choices=("large", "small"), default="large")
    ap.add_argument("--order", type=int, choices=(1, 2), default=2)
    ap.add_argument("--out", default=tempfile.mkdtemp(prefix="pectus-bench-patient-"))
    ap.add_argument("--fe", default="messy,masks,generated",
                    help="the cages to analyse, comma-separated: messy, masks, generated (default all)")
    a = ap.parse_args()
    fe = dict(targetElevation=44.7, analysis=0 if a.analysis == "large" else 1, order=0 if a.order == 2 else 1,
              resultBase="")
    P = os.path.join(a.out, "patient")
    t0 = time.time()
    subprocess.run([os.path.join(BUILD, "tools", "pectus_ct_phantom"), P, "--only", "messy,masks"],
                   check=True, capture_output=True)
    phantom_s = time.time() - t0
    rows = []
    cages = {}
    for name, folder in (("messy STL export", "stl_messy"), ("NIfTI masks", "masks")):
        src = os.path.join(P, folder)
        n = mlx.run([], mlx.Script([import_ct_segmentation(path=src)])).get("structures")
        cage, lms = os.path.join(a.out, folder + "_cage.ply"), os.path.join(a.out, folder + "_landmarks.ply")
        res, wall, rss, rc = timed([], mlx.Script([import_ct_segmentation(path=src), prepare_patient_rib_cage()]),
                                   [(cage, n, "fc fq"), (lms, n + 1, "vq")])
        step = res.get("seconds", "Pectus: Prepare Patient Rib Cage")
        faces = res.get("faces", "Pectus: Prepare Patient Rib Cage")
        inputs = res.get("faces", "Pectus: Import CT Segmentation")
        rows.append((f"prepare: {name} ({n} layers, {inputs} faces)", f"{faces} faces",
                     f"{step:.1f} s step" if step else "failed", wall, rss))
        cages[name] = (cage, lms)
    gen = os.path.join(a.out, "generated.ply"), os.path.join(a.out, "generated_landmarks.ply")
    edge = prepare_patient_rib_cage().params["edgeLength"].value  # both cages meshed alike
    res, wall, rss, rc = timed([], mlx.Script([create_ribcage(age=7.0, hallerIndex=4.0, edgeLength=edge)]),
                               [(gen[0], 0, "fc fq"), (gen[1], 1, "vq")])
    gen_faces = res.get("faces")
    rows.append(("generator: the same child's cage", f"{gen_faces} faces", "", wall, rss))
    cages["generated cage"] = gen
    kind = f"{'large displacement' if a.analysis == 'large' else 'small strain'} TET{10 if a.order == 2 else 4}"
    keys = {"messy": "messy STL export", "masks": "NIfTI masks", "generated": "generated cage"}
    for name in (keys[k] for k in a.fe.split(",") if k):
        cage, lms = cages[name]
        res, wall, rss, rc = timed([lms, cage], mlx.Script([nuss_fea(landmarkLayer=0, **fe)]))
        force = res.get("force_N")
        tets = res.get("tets")
        rows.append((f"FE {kind}: {name}", f"{tets} tets", f"Fe {force:.2f} N" if force else "failed", wall, rss))

    print(f"\nPatient pipeline benchmark: {platform.node()}, {os.cpu_count()} cores, {time.strftime('%Y-%m-%d')}; "
          f"phantom 1 mm written in {phantom_s:.1f} s")
    print(f"| {'step':52s} | {'size':14s} | {'result':14s} | wall (s) | peak (MB) |")
    print(f"|{'-' * 54}|{'-' * 16}|{'-' * 16}|---------:|----------:|")
    for step, size, result, wall, rss in rows:
        print(f"| {step:52s} | {size:14s} | {result:14s} | {wall:8.1f} | {rss:9.0f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
