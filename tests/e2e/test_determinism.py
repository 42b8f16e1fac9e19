"""E2E, determinism: every filter, run by meshlabserver with OMP_NUM_THREADS=1 and =2 on the
same input and seed (the valid inputs of the bad-input matrix, 6x finer, and the example parameters; the Nuss FE
analysis on the coarse 8 mm cage, linear TET4 with the example's tet quality, calibrated to 10 mm; the Nuss Bar Planner likewise, quick mode,
space 4 with one and with two bars, writing its CSV; Pectus: Prepare Patient Rib Cage on the CT phantom's messy export,
a 5-year-old's cage on a 1.5 mm grid), gives byte-identical outputs: every layer saved after it, every file it
writes, and its Log lines with timings masked."""
import csv
import glob
import io
import os
import re
import subprocess

import bad_input_matrix as bim
import harness as h
import pectus_mlx as mlx
from harness import check, finish
from pectus_filters import import_ct_segmentation, prepare_patient_rib_cage

runner = bim.Runner(size=6)  # 1250 and 10k triangles: enough work for the threads to share
W = runner.dir
# beyond the matrix's valid cell: the planner compares two options (one bar and two bars at space 4), so the
# choice of the best option and the second bar's load are covered too
OVERRIDES = {"planner": dict(bars=0)}


def example_value(key: str, name: str):
    """the value of parameter `name` in the filter's shipped example"""
    spec = bim.FILTERS[key]
    return mlx.load_script(bim._ex(spec["mlx"]))[spec.get("index", 0)].params[name].value


# the FE and the planner mesh with the examples' tet quality, not the matrix's 0 (no refinement): without
# refinement, the 8 mm cage of MeshLab 2025.07 meshes with flat tets (docs/hosts.md)
for k in ("nuss", "planner"):
    OVERRIDES.setdefault(k, {})["tetQuality"] = example_value(k, "tetQuality")


# a time among the values a filter returns: "seconds = 0.52" in the Log's Results line, "seconds": 0.52 in JSON
RESULT_TIME = re.compile(r'(\w*seconds"?(?: =|:)) [-+0-9.eE]+')


def masked(name: str, data: bytes) -> bytes:
    """the file's bytes; in a CSV the wall-clock column ("seconds", the planner's time per option) is masked, in
    the results JSON (BASE_results.json) the times"""
    if name.endswith("_results.json"):
        return RESULT_TIME.sub(r"\1 <t>", data.decode()).encode()
    if not name.endswith(".csv"):
        return data
    rows = list(csv.reader(io.StringIO(data.decode())))
    timed = [i for i, h in enumerate(rows[0]) if h == "seconds"] if rows else []
    out = io.StringIO()
    csv.writer(out, lineterminator="\n").writerows([[("<t>" if i in timed and r is not rows[0] else c)
                                                      for i, c in enumerate(r)] for r in rows])
    return out.getvalue().encode()


def outputs_of(key: str, threads: int):
    """{output name: bytes} and the Log (timings and the output folder masked) of one run"""
    inputs, _, place = runner.layout(key, "valid")
    d = os.path.join(W, f"threads{threads}", key)
    os.makedirs(d)
    f = bim.base_filter(key).set(**place).set(**OVERRIDES.get(key, {}))
    if "fileName" in f.params:
        f.set(fileName=mlx.SaveFile(os.path.join(d, "file.obj"), ".obj"))
    if "resultBase" in f.params:
        f.set(resultBase=mlx.SaveFile(os.path.join(d, "file.vtu"), ".vtu"))
    if "csvFile" in f.params:
        f.set(csvFile=mlx.SaveFile(os.path.join(d, "file.csv"), ".csv"))
    layers = [(os.path.join(d, f"layer{i}.ply"), bim.MASK, i) for i in range(len(inputs) + 3)]
    r = runner.run(inputs, mlx.Script([f]), layers, env={"OMP_NUM_THREADS": str(threads)}, timeout=300)
    files = {os.path.basename(p): masked(p, open(p, "rb").read()) for p in sorted(glob.glob(os.path.join(d, "*")))}
    # the folder first: its random name may look like a time
    log = [RESULT_TIME.sub(r"\1 <t>", bim.TIMING.sub("<t>", l.replace(d, "<dir>"))) for l in r.log]
    return r.rc, files, log


for key in bim.FILTERS:
    name = bim.filter_title(key)
    if bim.FILTERS[key].get("refusal"):  # the matrix's input is one the filter must refuse: nothing to compare
        print(f"--   {name}: no valid input in the matrix, not compared")
        continue
    rc1, f1, log1 = outputs_of(key, 1)
    rc2, f2, log2 = outputs_of(key, 2)
    if not check(rc1 == 0 and rc2 == 0 and f1, f"{name}: runs with 1 and 2 threads", f"rc {rc1}, {rc2}; files {list(f1)}"):
        continue
    if "csvFile" in bim.base_filter(key).params:  # the planner: one row per option (one and two bars)
        n = len(f1.get("file.csv", b"").decode().splitlines()) - 1
        check(n == 2, f"{name}: CSV written with one row per option", f"{n} rows")
    differ = sorted(k for k in set(f1) | set(f2) if f1.get(k) != f2.get(k))
    check(not differ, f"{name}: {len(f1)} outputs byte-identical with 1 and 2 threads ({', '.join(sorted(f1))})",
          f"differ: {differ}")
    dl = [(a, b) for a, b in zip(log1, log2) if a != b]
    check(log1 == log2, f"{name}: Log identical with 1 and 2 threads (timings masked)", f"{dl[:3]}")

# Pectus: Prepare Patient Rib Cage, whose matrix cell is a refusal: on a messy export of the CT phantom
phantom = os.path.join(os.path.dirname(h.PREFIX), "tools", "pectus_ct_phantom")
P = os.path.join(W, "patient")
g = subprocess.run([phantom, P, "--only", "messy", "--age", "5", "--spacing", "1.5"], capture_output=True, text=True)
check(g.returncode == 0, "pectus_ct_phantom: a messy export", g.stderr[-500:])
script = mlx.Script([import_ct_segmentation(path=os.path.join(P, "stl_messy")), prepare_patient_rib_cage()])
runs = []
for threads in (1, 2):
    d = os.path.join(W, f"prepare{threads}")
    os.makedirs(d)
    outs = [(os.path.join(d, "cage.ply"), "fc fq", 3), (os.path.join(d, "landmarks.ply"), "vq", 4)]
    r = mlx.run([], script, outs, prefix=h.PREFIX, timeout=900, env={"OMP_NUM_THREADS": str(threads)})
    files = {os.path.basename(p): open(p, "rb").read() for p, _, _ in outs if os.path.exists(p)}
    runs.append((r.rc, files, [RESULT_TIME.sub(r"\1 <t>", bim.TIMING.sub("<t>", l)) for l in r.log]))
(rc1, f1, log1), (rc2, f2, log2) = runs
name = "Pectus: Prepare Patient Rib Cage"
if check(rc1 == 0 and rc2 == 0 and len(f1) == 2, f"{name}: runs with 1 and 2 threads", f"rc {rc1}, {rc2}; {log1[-3:]}"):
    check(f1 == f2, f"{name}: the cage and its landmarks byte-identical with 1 and 2 threads")
    dl = [(a, b) for a, b in zip(log1, log2) if a != b]
    check(log1 == log2, f"{name}: Log identical with 1 and 2 threads (timings masked)", f"{dl[:3]}")
finish()
