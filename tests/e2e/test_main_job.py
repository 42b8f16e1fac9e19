"""The README's main job runs and its printed table agrees with the files it writes."""
import csv
import os
import subprocess

import numpy as np

from harness import SOURCE, check, finish, read_ply, workdir

out = workdir("main")
p = subprocess.run(["/usr/bin/python3", os.path.join(SOURCE, "python", "run_main.py"), out],
                   stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=1800)
check(p.returncode == 0, "main job exits 0", p.stdout[-3000:])
check(f"output folder: {out}" in p.stdout, "main job names its output folder")
rows = list(csv.DictReader(open(os.path.join(out, "quality.csv"))))
check(len(rows) >= 1, "quality.csv has rows")
q = read_ply(os.path.join(out, "saddle_quality.ply"))["face"]["quality"]
saddle = rows[0]
check(abs(float(saddle["mean"]) - float(np.mean(q))) < 1e-3, "CSV mean = mean of the saved per-face quality",
      f"{saddle['mean']} vs {np.mean(q)}")
check(f"{float(saddle['min']):7.4f}" in p.stdout, "printed table shows the min")
check(os.path.getsize(os.path.join(out, "quality_histograms.png")) > 5000, "histogram plot written")
finish()
