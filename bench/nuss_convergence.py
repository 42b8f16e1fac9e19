#!/usr/bin/env python3
"""Mesh convergence study of the Nuss FE analysis (thesis Table 6-2): the same rib cage (patient 1: boy of 8,
pectus index 5.3, 5 mm surface edges) meshed ever finer by TetGen's maximum tet volume, the same elevating
force, the sternum-end displacement per mesh and its change from the previous mesh (the thesis accepted
< 1 %). Prints one table, with each run's peak memory (maximum resident set size from wait4; the FE
analysis' memory budget: 3 GB for a ~300k-tet model).

    python3 bench/nuss_convergence.py [--tool build/tools/pectus_nuss_cli] [--order 2] [--force 10] [--nonlinear]
                                      [--maxvol none,default,40,15,6,2.5]

--maxvol lists the meshes: "none" is TetGen without refinement (tet quality 0, the quick main job's), "default"
the FE filter's default (tet quality 2.0, no volume bound), a number that volume bound in mm^3 with quality 2.0.
"""
import argparse
import os
import re
import subprocess
import time

ap = argparse.ArgumentParser()
ap.add_argument("--tool", default="build/tools/pectus_nuss_cli")
ap.add_argument("--order", type=int, default=2)
ap.add_argument("--force", type=float, default=10.0)
ap.add_argument("--nonlinear", action="store_true")
ap.add_argument("--maxvol", default="none,default,40,15,6,2.5")
a = ap.parse_args()


def run_measured(cmd):
    """Runs cmd; returns (CompletedProcess with stdout+stderr in stdout, peak resident set size in kB)."""
    with subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True) as proc:
        out = proc.stdout.read()
        _, status, usage = os.wait4(proc.pid, 0)
        proc.returncode = os.waitstatus_to_exitcode(status)
    return subprocess.CompletedProcess(cmd, proc.returncode, out), usage.ru_maxrss


print(f"Nuss FE mesh convergence, TET{4 if a.order == 1 else 10}, {'large displacement' if a.nonlinear else 'small strain'}, "
      f"Fe = {a.force} N (thesis Table 6-2: 97,939 -> 443,470 TET4, 4.304 -> 4.519 cm, last change 0.649 %)")
print(f"{'max tet vol mm3':>15} {'tets':>8} {'nodes':>8} {'dofs':>8} {'elevation mm':>13} {'change %':>9} {'solve s':>8} {'peak MB':>8}")
prev = None
for mv in a.maxvol.split(","):
    quality, bound = {"none": ("0", "0"), "default": ("2.0", "0")}.get(mv, ("2.0", mv))
    cmd = [a.tool, "--edge", "5", "--haller", "5.3", "--age", "8", "--quality", quality,
           "--maxvol", bound, "--order", str(a.order), "--force", str(a.force)] + ([] if a.nonlinear else ["--linear"])
    t0 = time.time()
    p, peak_kb = run_measured(cmd)
    peak_mb = f"{peak_kb / 1024:8.0f}"
    kv = dict(re.findall(r"(\w+)=([-0-9.e]+)", p.stdout.splitlines()[0] if p.stdout else ""))
    if p.returncode != 0 or "elevation" not in kv:
        print(f"{mv:>15} failed: {p.stdout.strip()[-200:]}")
        continue
    e = float(kv["elevation"])
    ch = "" if prev is None else f"{100 * (e - prev) / prev:9.3f}"
    print(f"{mv:>15} {kv['tets']:>8} {kv['nodes']:>8} {kv['dofs']:>8} {e:13.3f} {ch:>9} {float(kv['tSolve']):8.1f} {peak_mb}")
    prev = e
