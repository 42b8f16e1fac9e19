"""The filter dialogs in MeshLab's real GUI, under Xvfb on a screen 1,000 px tall (scripts/screenshot_dialogs.sh):
every analysis and creation dialog opens from MeshLab's filter search by the filter's name, and fits the screen
(its Apply button within reach), with and without every parameter's help shown. Runs on the release that
PECTUS_MESHLAB_HOST names (2020.09 by default)."""
from __future__ import annotations

import os
import re
import subprocess

import numpy as np

import pectus_mlx as mlx
from harness import SOURCE, check, finish, workdir, write_ply

SCREEN_HEIGHT = 1000  # px
FILTERS = [
    "Pectus: Create Rib Cage", "Pectus: Import CT Segmentation", "Pectus: Prepare Patient Rib Cage",
    "Pectus: Nuss Procedure FE Analysis", "Pectus: Nuss Bar Planner", "Pectus: Thoracic Volume (Slice Method)",
    "Pectus: Thoracic Volume (Ferguson Envelope)", "Pectus: Pectus Index",
    "Pectus: Element Quality (Triangle Alpha / Quad Beta)", "Pectus: MGA Surface Mesh Smoothing",
]

host = mlx.default_host()
out = workdir("dialogs")
mesh = os.path.join(out, "layer.ply")  # any layer: the filters need a current one to be enabled
v = np.array([[0, 0, 0], [10, 0, 0], [0, 10, 0], [0, 0, 10]], float)
write_ply(mesh, v, np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]))
cmd = [os.path.join(SOURCE, "scripts", "screenshot_dialogs.sh"), "--host", host, "--help", out, mesh, "--", *FILTERS]
r = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
print(r.stdout)
check(r.returncode == 0, f"screenshot_dialogs.sh ran on MeshLab {host}", r.stderr[-2000:])
sizes = {}
for kind, w, h, name in re.findall(r"^(dialog|dialog-help) (\d+)x(\d+) (.+)$", r.stdout, re.M):
    sizes[(kind, name)] = (int(w), int(h))
for name in FILTERS:
    for kind, what in (("dialog", "the dialog"), ("dialog-help", "the dialog with every parameter's help")):
        size = sizes.get((kind, name))
        if not check(size is not None, f"{name}: {what} opens from the filter search", r.stdout[-800:]):
            continue
        check(100 <= size[1] <= SCREEN_HEIGHT, f"{name}: {what} fits {SCREEN_HEIGHT} px ({size[0]} x {size[1]} px)")
finish()
