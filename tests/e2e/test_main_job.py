"""The README's main job (python/run_main.py, here with --quick: the same one-script pipeline with a
small-strain TET4 FE) runs, names its output folder, and its printed Table 6-1 agrees with summary.csv
and the files it writes. With --planner (one bar at space 4, the FE's own level) the planner's row needs the
force of the table. --help prints the usage."""
import csv
import os
import re
import subprocess

from harness import SOURCE, check, finish, workdir

out = workdir("main")
# --help prints the usage and runs nothing (no folder named '--help')
h = subprocess.run(["/usr/bin/python3", os.path.join(SOURCE, "python", "run_main.py"), "--help"], cwd=out,
                   stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=60)
check(h.returncode == 0 and h.stdout.startswith("usage: run_main.py") and "--quick" in h.stdout
      and not os.path.exists(os.path.join(out, "--help")), "run_main.py --help prints the usage and runs nothing", h.stdout[-800:])
p = subprocess.run(["/usr/bin/python3", os.path.join(SOURCE, "python", "run_main.py"), out, "--quick",
                    "--planner", "--planner-levels", "4", "--planner-bars", "one"],
                   stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=1800)
print(p.stdout[-3500:])
check(p.returncode == 0, "main job exits 0", p.stdout[-3000:])
check(f"Output folder: {out}" in p.stdout, "main job names its output folder")
rows = list(csv.DictReader(open(os.path.join(out, "summary.csv")))) if os.path.exists(os.path.join(out, "summary.csv")) else []
check(len(rows) == 1, "summary.csv has one row")
if rows:
    s = rows[0]
    # quick settings say on their output that they are not a result to report: the table's first line and a
    # column of summary.csv (the FE filter's own verdict on its mesh)
    check(p.stdout.count("NOT A RESULT TO REPORT: linear TET4 locks in bending") == 1
          and "tets without quality refinement" in p.stdout, "--quick: the table is marked not a result to report")
    check(s.get("reportable") == "0" and "TET4" in s.get("not_reportable_because", ""),
          f"--quick: summary.csv says reportable 0 ({s.get('reportable')!r}, {s.get('not_reportable_because')!r})")
    m = re.search(r"loading force at sternum end \(N\)\s+([0-9.]+)", p.stdout)
    check(m is not None and abs(float(m.group(1)) - float(s["force"])) < 0.051, f"printed force {m and m.group(1)} = summary {s['force']}")
    m = re.search(r"slice method \(cm3\)\s+([0-9.-]+)", p.stdout)
    check(m is not None and abs(float(m.group(1)) - float(s["slice_change_cm3"])) < 0.006, "printed slice change = summary")
    m = re.search(r"Haller\) index before -> after\s+([0-9.]+) -> ([0-9.]+)", p.stdout)
    check(m is not None and abs(float(m.group(1)) - float(s["haller_before"])) < 0.006 and float(m.group(2)) < float(m.group(1)),
          "printed pectus index before/after = summary, and it falls")
plan = list(csv.DictReader(open(os.path.join(out, "planner.csv")))) if os.path.exists(os.path.join(out, "planner.csv")) else []
check(len(plan) == 1 and plan[0]["option"] == "1 bar, space 4", "planner.csv: one option, one bar at space 4")
if plan and rows:
    check(abs(float(plan[0]["force_N"]) - float(rows[0]["force"])) <= 0.01 * float(rows[0]["force"]),
          f"planner force {plan[0]['force_N']} N = the pipeline's FE force {rows[0]['force']} N (1 %)")
    check("1 bar, space 4 *" in p.stdout, "the planner table is printed, its only row marked best")
for f in ("quality_histograms.png", "nuss_force_displacement.png", "nuss.vtu", "pipeline.mlx"):
    check(os.path.exists(os.path.join(out, f)) and os.path.getsize(os.path.join(out, f)) > 1000, f"{f} written")
finish()
