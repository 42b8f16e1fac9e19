"""The README's main job (python/run_main.py, here with --quick: the same one-script pipeline with a
small-strain TET4 FE) runs, names its output folder, and its printed Table 6-1 agrees with summary.csv
and the files it writes. summary.csv names its case, carries the units in its headers, counts as integers,
times to 0.1 s, the run's settings and whether the FE converged; the saved meshlabserver log has each
progress message on a line of its own. With --planner (one bar at space 4, the FE's own level) the planner's row needs the
force of the table. --help prints the usage."""
import csv
import os
import re
import subprocess

import pectus_mlx as mlx
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
    check(m is not None and abs(float(m.group(1)) - float(s["force_N"])) < 0.051, f"printed force {m and m.group(1)} = summary {s['force_N']}")
    m = re.search(r"slice method \(cm3\)\s+([0-9.-]+)", p.stdout)
    check(m is not None and abs(float(m.group(1)) - float(s["slice_change_cm3"])) < 0.006, "printed slice change = summary")
    m = re.search(r"Haller\) index before -> after\s+([0-9.]+) -> ([0-9.]+)", p.stdout)
    check(m is not None and abs(float(m.group(1)) - float(s["haller_index_before"])) < 0.006 and float(m.group(2)) < float(m.group(1)),
          "printed pectus index before/after = summary, and it falls")
    # ready for a paper: the case named, units in the headers, counts as integers, times to 0.1 s
    check(s.get("case") == "case1", f"summary.csv names the case (default case1): {s.get('case')!r}")
    with_units = ("age_years", "target_elevation_mm", "force_N", "elevation_mm", "max_stress_MPa", "max_stress_body_MPa",
                  "slice_change_cm3", "slice_change_pct", "envelope_change_cm3", "envelope_change_pct", "surface_edge_mm",
                  "bone_E_MPa", "cartilage_E_MPa", "fe_time_s", "pipeline_time_s")
    check(all(k in s for k in with_units) and not any(k in s for k in ("age", "force", "elevation", "max_stress", "seconds", "fe_seconds")),
          "summary.csv's headers carry their units", ",".join(s))
    counts = ("cage_faces", "fe_tets", "fe_nodes", "fe_solves", "fe_nonlinear_solves", "fe_newton_iterations", "mga_sweeps")
    bad = [f"{k}={s.get(k)!r}" for k in counts if not re.fullmatch(r"[0-9]+", s.get(k) or "")]
    check(not bad and int(s["fe_tets"]) > 1000, "summary.csv's counts are integers", ", ".join(bad))
    check(all(re.fullmatch(r"[0-9]+(\.[0-9])?", s.get(k) or "") for k in ("fe_time_s", "pipeline_time_s")),
          f"summary.csv's times to 0.1 s ({s.get('fe_time_s')!r}, {s.get('pipeline_time_s')!r})")
    # the settings the run used, and what its figures are worth
    check((s.get("run_mode"), s.get("fe_analysis"), s.get("fe_element"), s.get("fe_material"), s.get("tet_quality_radius_edge"))
          == ("quick", "small strain", "TET4", "linear elastic", "0"), "summary.csv: the quick run's settings",
          str({k: s.get(k) for k in ("run_mode", "fe_analysis", "fe_element", "fe_material", "tet_quality_radius_edge")}))
    check(s.get("fe_converged") == "1" and s.get("fe_newton_iterations") == "0",
          f"summary.csv: fe_converged 1 (the FE returned its result), no Newton iterations for the small-strain solve "
          f"({s.get('fe_converged')!r}, {s.get('fe_newton_iterations')!r})")

# meshlabserver prints its progress messages without newlines: each on a line of its own in the saved log and
# in what the job printed, the filters' LOG lines never cutting a line
PROGRESS = ("calibrating funnel depth", "extracting the surface", "labelling", "measuring elements", "writing quality",
            "building the C1 surface", "TetGen (after checking the surface)", "Factorising (CHOLMOD)", "Calibrating the force",
            "Stress and strain", "cutting the planes", "slice regions", "rasterising", "envelope samples",
            "envelope convergence", "pectus index", "done", "Done")
log_path = os.path.join(out, "meshlabserver.log")
saved = open(log_path).read().splitlines() if os.path.exists(log_path) else []
for where, lines in (("meshlabserver.log", saved), ("the job's output", p.stdout.splitlines())):
    # a line that begins with a progress message is that message alone; no two messages follow one another on a line
    joined = [l for l in lines if any(l.startswith(m) for m in PROGRESS) and l not in PROGRESS
              and not re.fullmatch(r"Calibrating the force: Fe = [0-9.]+ N", l)
              or any(a + b in l for a in PROGRESS for b in PROGRESS)]
    check(not joined, f"{where}: no line holds two progress messages", "\n".join(l[:200] for l in joined[:5]))
    cut = [l for l in lines if "LOG: " in l and not l.startswith("LOG: ")]
    check(not cut, f"{where}: no LOG line inside another line", "\n".join(l[:200] for l in cut[:5]))
# meshlabserver 2020.09 prints the filters' progress; pectus-mlrun (the newer releases) prints none
if mlx.default_host() == "2020.09":
    check(all(m in saved for m in ("calibrating funnel depth", "extracting the surface", "labelling", "Factorising (CHOLMOD)"))
          and saved.count("envelope convergence") > 1 and re.search(r"^sweep 2, mean quality [0-9.]+$", "\n".join(saved), re.M),
          "meshlabserver.log: the progress messages, each a line")
plan = list(csv.DictReader(open(os.path.join(out, "planner.csv")))) if os.path.exists(os.path.join(out, "planner.csv")) else []
check(len(plan) == 1 and plan[0]["option"] == "1 bar, space 4", "planner.csv: one option, one bar at space 4")
if plan and rows:
    check(abs(float(plan[0]["force_N"]) - float(rows[0]["force_N"])) <= 0.01 * float(rows[0]["force_N"]),
          f"planner force {plan[0]['force_N']} N = the pipeline's FE force {rows[0]['force_N']} N (1 %)")
    check("1 bar, space 4 *" in p.stdout, "the planner table is printed, its only row marked best")
for f in ("quality_histograms.png", "nuss_force_displacement.png", "nuss.vtu", "pipeline.mlx"):
    check(os.path.exists(os.path.join(out, f)) and os.path.getsize(os.path.join(out, f)) > 1000, f"{f} written")
finish()
