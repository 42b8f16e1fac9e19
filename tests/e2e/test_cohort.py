"""Cohort scripts: a two-patient demo cohort at a coarse edge length runs through
scripts/cohort.sh (GNU parallel) in quick mode; cohort_summary.csv has one row per patient, each reaching
its own target elevation, rows equal to the per-case summaries; collect reads a summary.csv with the older
column names too; the job-array script run for task 2 alone gives the same calibrated force as the parallel run."""
import csv
import os
import subprocess

from harness import PREFIX, SOURCE, check, finish, workdir

d = workdir("cohort")
cohort, out, out_array = os.path.join(d, "cohort"), os.path.join(d, "out"), os.path.join(d, "out_array")
env = dict(os.environ, PECTUS_PREFIX=PREFIX, PECTUS_JOBS="1")
p = subprocess.run(["/usr/bin/python3", os.path.join(SOURCE, "python", "cohort.py"), "demo", cohort, "--edge", "6",
                    "--cases", "2"], env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=600)
check(p.returncode == 0, "demo cohort written", p.stdout[-2000:])
patients = list(csv.DictReader(open(os.path.join(cohort, "patients.csv"))))
check([r["case"] for r in patients] == ["case1", "case2"], "demo --cases 2 lists two patients")

p = subprocess.run(["sh", os.path.join(SOURCE, "scripts", "cohort.sh"), cohort, out, "--quick"], env=env,
                   stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=1200)
print(p.stdout[-3000:])
check(p.returncode == 0, "cohort.sh exits 0", p.stdout[-2000:])
path = os.path.join(out, "cohort_summary.csv")
rows = list(csv.DictReader(open(path))) if os.path.exists(path) else []
check(len(rows) == 2, f"cohort_summary.csv has 2 rows ({len(rows)})")
for row, pat in zip(rows, patients):
    case = pat["case"]
    check(row["case"] == case, f"row order follows patients.csv ({row['case']})")
    target = float(pat["elevation_mm"])
    check(abs(float(row["elevation_mm"]) - target) <= 0.1, f"{case}: elevation {row['elevation_mm']} mm = target {target} mm")
    check(0 < float(row["force_N"]) < 500, f"{case}: calibrated force {row['force_N']} N is positive and finite")
    one = list(csv.DictReader(open(os.path.join(out, case, "summary.csv"))))
    check(len(one) == 1 and one[0] == row, f"{case}: cohort row equals the case's summary.csv")
if len(rows) == 2:
    check(rows[0]["force_N"] != rows[1]["force_N"], "the two patients need different forces")

# collect reads a case's summary.csv with the older columns too (no units in the names, counts as floats,
# figures unrounded) and writes it in the new ones
if len(rows) == 2:
    old_out = os.path.join(d, "out_old")
    os.makedirs(os.path.join(old_out, "case1"), exist_ok=True)
    new = rows[0]
    old = {"case": new["case"], "sex": new["sex"], "age": str(float(new["age_years"])),
           "target_elevation_mm": new["target_elevation_mm"], "tets": str(float(new["fe_tets"])), "element": new["fe_element"],
           "force": str(float(new["force_N"]) + 0.0001234), "elevation": new["elevation_mm"] + "000321", "reportable": new["reportable"],
           "haller_before": new["haller_index_before"], "seconds": "12.345678901234"}
    with open(os.path.join(old_out, "case1", "summary.csv"), "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(old))
        w.writeheader()
        w.writerow(old)
    p = subprocess.run(["/usr/bin/python3", os.path.join(SOURCE, "python", "cohort.py"), "collect", cohort, old_out],
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=60)
    got = list(csv.DictReader(open(os.path.join(old_out, "cohort_summary.csv")))) if p.returncode == 0 else []
    want = {k: new[k] for k in ("case", "sex", "age_years", "target_elevation_mm", "fe_tets", "fe_element", "force_N",
                                "elevation_mm", "reportable", "haller_index_before")}
    check(len(got) == 1 and {k: got[0][k] for k in want} == want and got[0]["pipeline_time_s"] == "12.3"
          and list(got[0]) == list(rows[0]), "collect reads a summary.csv with the older columns into the new ones",
          p.stdout[-1500:] + (str(got[0]) if got else ""))

env_array = dict(env, TASK="2")
p = subprocess.run(["sh", os.path.join(SOURCE, "scripts", "cohort_array.sh"), cohort, out_array, "--quick"], env=env_array,
                   stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=1200)
check(p.returncode == 0, "cohort_array.sh task 2 exits 0", p.stdout[-2000:])
arr = os.path.join(out_array, "case2", "summary.csv")
check(not os.path.exists(os.path.join(out_array, "case1")), "array task 2 ran only case2")
if os.path.exists(arr) and len(rows) == 2:
    a = list(csv.DictReader(open(arr)))[0]
    check(abs(float(a["force_N"]) - float(rows[1]["force_N"])) <= 1e-6 * max(1.0, float(a["force_N"])),
          f"array job force {a['force_N']} N = parallel run {rows[1]['force_N']} N")
finish()
