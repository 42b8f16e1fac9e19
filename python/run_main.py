#!/usr/bin/env python3
"""The main job: the pectus-meshlab pipeline through the real meshlabserver, on meshes the project
generates, writing everything into one output folder and printing what it found.

Stages run when their filters are installed in the prefix (the pipeline grows as capabilities land):
  1. a jittered saddle surface (thesis eq. 3-25), its element quality (alpha), MGA smoothing, quality after
  2. the default pectus-excavatum rib cage (if 'Create Pectus Excavatum Rib Cage' is available)
"""
from __future__ import annotations

import datetime
import os
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
import pectus_mlx as mlx  # noqa: E402

QUALITY = "Compute Element Quality (Triangle Alpha / Quad Beta)"


def saddle_mesh(n_side: int = 25, jitter: float = 0.3, seed: int = 7):
    """z = x^2/10 - y^2/4 on [-5,5]^2 (thesis eq. 3-25): n_side^2 nodes (625 by default), interior
    nodes jittered in the plane by up to jitter * spacing; triangles (alternating diagonals)."""
    rng = np.random.default_rng(seed)
    h = 10.0 / (n_side - 1)
    V = []
    for j in range(n_side):
        for i in range(n_side):
            x, y = -5 + i * h, -5 + j * h
            if 0 < i < n_side - 1 and 0 < j < n_side - 1:
                x += rng.uniform(-jitter, jitter) * h
                y += rng.uniform(-jitter, jitter) * h
            V.append((x, y, x * x / 10 - y * y / 4))
    F = []
    for j in range(n_side - 1):
        for i in range(n_side - 1):
            a = j * n_side + i
            b, c, d = a + 1, a + n_side + 1, a + n_side
            F += [[a, b, c], [a, c, d]] if (i + j) % 2 == 0 else [[a, b, d], [b, c, d]]
    return np.array(V), F


def write_ply(path, V, F):
    with open(path, "w") as fh:
        fh.write(f"ply\nformat ascii 1.0\nelement vertex {len(V)}\nproperty float x\nproperty float y\n"
                 f"property float z\nelement face {len(F)}\nproperty list uchar int vertex_indices\nend_header\n")
        fh.writelines(f"{p[0]:.7g} {p[1]:.7g} {p[2]:.7g}\n" for p in V)
        fh.writelines(f"{len(f)} " + " ".join(map(str, f)) + "\n" for f in F)


def available_filters() -> set[str]:
    """Filter names registered by this project's plugins (read from the plugin binaries)."""
    names = set()
    plug = os.path.join(os.environ.get("PECTUS_PREFIX", ""), "lib", "x86_64-linux-gnu", "meshlab", "plugins")
    for f in os.listdir(plug) if os.path.isdir(plug) else []:
        if not f.startswith("libfilter_") or not os.path.islink(os.path.join(plug, f)):
            continue
        target = os.path.realpath(os.path.join(plug, f))
        if target.startswith("/usr/"):
            continue
        data = open(target, "rb").read()
        for cand in (QUALITY, "Create Pectus Excavatum Rib Cage", "MGA Surface Mesh Smoothing",
                     "Nuss Procedure FE Analysis", "Thoracic Volume (Slice Method)",
                     "Thoracic Volume (Ferguson Envelope)", "Pectus Index"):
            if cand.encode("utf-16-le") in data or cand.encode() in data:
                names.add(cand)
    return names


def quality_script(element_type: int) -> mlx.Script:
    return mlx.Script([mlx.Filter(QUALITY, elementType=mlx.Enum(element_type, ["Auto", "Triangles (alpha)", "Quads (beta)"]),
                                  colorize=mlx.Bool(True))])


def parse_quality(log: list[str]) -> dict:
    out = {}
    for line in log:
        if line.startswith("Element quality (") and "; min " in line:
            parts = line.split("; min ")[1].split()
            out.update(min=float(parts[0]), mean=float(parts[2]), max=float(parts[4].rstrip(";")))
            out["invalid"] = int(line.rsplit(":", 1)[1])
        if line.startswith("Element quality histogram"):
            out["histogram"] = [int(x) for x in line.split(":", 1)[1].split()]
    return out


def plot_histograms(path: str, rows: list[tuple[str, dict]]):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return None
    fig, ax = plt.subplots(figsize=(7, 4))
    width = 0.8 / max(len(rows), 1)
    for k, (label, q) in enumerate(rows):
        h = q.get("histogram", [])
        ax.bar(np.arange(len(h)) * 0.1 + 0.05 + (k - (len(rows) - 1) / 2) * width * 0.1, h, width=width * 0.1, label=label)
    ax.set_xlabel("element quality (alpha for triangles, beta for quads)")
    ax.set_ylabel("elements")
    ax.set_xlim(0, 1)
    ax.legend()
    ax.set_title("Element quality histograms")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def main(argv: list[str]) -> int:
    stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S")
    out = os.path.abspath(argv[1] if len(argv) > 1 else os.path.join(ROOT, "out", f"main-{stamp}"))
    os.makedirs(out, exist_ok=True)
    have = available_filters()
    if QUALITY not in have:
        print(f"the plugins are not in the prefix {os.environ.get('PECTUS_PREFIX')}: run scripts/setup.sh", file=sys.stderr)
        return 1
    rows = []

    # 1. saddle (thesis eq. 3-25), triangles
    V, F = saddle_mesh()
    saddle = os.path.join(out, "saddle.ply")
    write_ply(saddle, V, F)
    res = mlx.run([saddle], quality_script(1), [(os.path.join(out, "saddle_quality.ply"), "fq fc")])
    if res.rc != 0:
        print(res.stdout, file=sys.stderr)
        return 1
    rows.append((f"saddle, {len(F)} triangles (alpha)", parse_quality(res.log)))

    # 1b. MGA smoothing of the saddle (thesis ch. 4.2), then its quality
    if "MGA Surface Mesh Smoothing" in have:
        smoothed = os.path.join(out, "saddle_mga.ply")
        res = mlx.run([saddle], os.path.join(ROOT, "filter_mga_smooth", "examples", "mga_smooth.mlx"), [(smoothed, "fq fc")])
        if res.rc == 0:
            res = mlx.run([smoothed], quality_script(1), [(os.path.join(out, "saddle_mga_quality.ply"), "fq fc")])
        if res.rc != 0:
            print(res.stdout[-3000:], file=sys.stderr)
            return 1
        rows.append(("saddle after MGA smoothing (alpha)", parse_quality(res.log)))

    # 2. default rib cage, when its filter is installed
    if "Create Pectus Excavatum Rib Cage" in have:
        cage = os.path.join(out, "ribcage.ply")
        script = os.path.join(ROOT, "filter_nuss_fea", "examples", "create_ribcage.mlx")
        if os.path.exists(script):
            # the example creates the cage; a second script measures it
            res = mlx.run([], script, [(cage, "fc fq", 0), (os.path.join(out, "ribcage_landmarks.ply"), "vq", 1)])
            if res.rc == 0 and os.path.exists(cage):
                res = mlx.run([cage], quality_script(1), [(os.path.join(out, "ribcage_quality.ply"), "fq fc")])
                if res.rc == 0:
                    rows.append(("default rib cage (alpha)", parse_quality(res.log)))
            if res.rc != 0:
                print(res.stdout[-3000:], file=sys.stderr)
                return 1

    csv = os.path.join(out, "quality.csv")
    with open(csv, "w") as fh:
        fh.write("mesh,min,mean,max,invalid," + ",".join(f"bin{i}" for i in range(10)) + "\n")
        for label, q in rows:
            fh.write(f"\"{label}\",{q['min']},{q['mean']},{q['max']},{q['invalid']}," + ",".join(map(str, q['histogram'])) + "\n")
    png = plot_histograms(os.path.join(out, "quality_histograms.png"), rows)

    print("pectus-meshlab main job")
    print(f"{'mesh':42s} {'min':>7s} {'mean':>7s} {'max':>7s} {'invalid':>7s}")
    for label, q in rows:
        print(f"{label:42s} {q['min']:7.4f} {q['mean']:7.4f} {q['max']:7.4f} {q['invalid']:7d}")
    print(f"output folder: {out}")
    for f in sorted(os.listdir(out)):
        print(f"  {f}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
