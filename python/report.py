#!/usr/bin/env python3
"""One-page report of a main-job run, for a surgeon: OUTDIR/report.html, one self-contained page (the pictures
are embedded) that opens in any browser and prints on one A4 sheet.

    python3 python/report.py OUTDIR

It reads what the main job (python/run_main.py) wrote into OUTDIR: summary.csv (the figures), nuss_results.json
(where the peaks lie), nuss_result.ply (the corrected rib cage, vertex quality = von Mises stress in MPa),
ribcage_smoothed.ply (the cage before), ribcage_landmarks.ply (landmark 501, the level of the pectus index) and
nuss_force_displacement.png. The pictures are drawn with matplotlib (Agg); without it, or without a file, the
page says which picture is missing and still gives every figure.
"""
from __future__ import annotations

import argparse
import base64
import datetime
import html
import io
import json
import os
import shlex
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import pipeline  # noqa: E402  (read_summary: summary.csv in its current column names)

FUNNEL_DEEPEST = 501  # landmark codes (common/include/pectus/labels.h): deepest point of the funnel
VERTEBRA_AT_DEEPEST = 503  # anterior surface of the vertebral body at that level
STRESS_CAP_PERCENTILE = 98  # the colour scale ends here, as the FE filter's own vertex colours do

# ---------------------------------------------------------------------------------------------
# PLY (ascii and binary, as the MeshLab hosts write it)

PLY_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
              "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
              "float": "f4", "float32": "f4", "double": "f8", "float64": "f8"}


def ply_header(data: bytes):
    """(format, [(element, count, [(property, type or ('list', count type, item type))])], body offset)"""
    end = data.index(b"end_header") + len(b"end_header")
    end = data.index(b"\n", end) + 1
    fmt, elements = "ascii", []
    for line in data[:end].decode("ascii", "replace").splitlines():
        t = line.split()
        if not t:
            continue
        if t[0] == "format":
            fmt = t[1]
        elif t[0] == "element":
            elements.append((t[1], int(t[2]), []))
        elif t[0] == "property" and elements:
            elements[-1][2].append((t[4], ("list", t[2], t[3])) if t[1] == "list" else (t[2], t[1]))
    return fmt, elements, end


def _ply_ascii(np, body: bytes, elements) -> dict:
    tokens, pos, out = body.split(), 0, {}
    for name, count, props in elements:
        cols = {p: [] for p, _ in props}
        for _ in range(count):
            for pname, ptype in props:
                if isinstance(ptype, tuple):
                    n = int(tokens[pos])
                    cols[pname].append([int(x) for x in tokens[pos + 1:pos + 1 + n]])
                    pos += 1 + n
                else:
                    cols[pname].append(float(tokens[pos]))
                    pos += 1
        out[name] = {k: v if props and isinstance(dict(props)[k], tuple) else np.array(v, dtype=float)
                     for k, v in cols.items()}
    return out


def _ply_binary_element(np, body: bytes, pos: int, count: int, props, order: str):
    """One element's columns and the offset after it. Fast path: every list of the element has the length of the
    first one (MeshLab's triangles), read as one record array; otherwise record by record."""
    if count == 0:
        return {p: ([] if isinstance(t, tuple) else np.zeros(0)) for p, t in props}, pos
    lengths, fields, probe = {}, [], pos
    for pname, ptype in props:
        if isinstance(ptype, tuple):
            ct = np.dtype(order + PLY_TYPES[ptype[1]])
            lengths[pname] = int(np.frombuffer(body, ct, 1, probe)[0])
            fields += [(pname + "#n", ct), (pname, np.dtype(order + PLY_TYPES[ptype[2]]), (lengths[pname],))]
            probe += ct.itemsize + lengths[pname] * fields[-1][1].itemsize
        else:
            fields.append((pname, np.dtype(order + PLY_TYPES[ptype])))
            probe += fields[-1][1].itemsize
    dt = np.dtype(fields)
    if pos + count * dt.itemsize <= len(body):
        rec = np.frombuffer(body, dt, count, pos)
        if all((rec[p + "#n"] == n).all() for p, n in lengths.items()):
            return {p: (rec[p].astype(int) if p in lengths else rec[p].astype(float)) for p, _ in props}, \
                pos + count * dt.itemsize
    cols = {p: [] for p, _ in props}
    for _ in range(count):
        for pname, ptype in props:
            if isinstance(ptype, tuple):
                ct, it = order + PLY_TYPES[ptype[1]], order + PLY_TYPES[ptype[2]]
                n = int(np.frombuffer(body, ct, 1, pos)[0])
                pos += np.dtype(ct).itemsize
                cols[pname].append(np.frombuffer(body, it, n, pos).astype(int))
                pos += n * np.dtype(it).itemsize
            else:
                t = np.dtype(order + PLY_TYPES[ptype])
                cols[pname].append(float(np.frombuffer(body, t, 1, pos)[0]))
                pos += t.itemsize
    return {p: (cols[p] if isinstance(t, tuple) else np.array(cols[p])) for p, t in props}, pos


def read_ply(path: str) -> dict:
    """{'V': (n, 3) vertices, 'F': faces (an (m, k) array, or a list of index arrays of mixed sizes),
    'vertex': {property: array}, 'face': {property: array}} of an ascii or binary PLY file."""
    import numpy as np
    with open(path, "rb") as fh:
        data = fh.read()
    fmt, elements, start = ply_header(data)
    body = data[start:]
    if fmt == "ascii":
        out = _ply_ascii(np, body, elements)
    else:
        order = {"binary_little_endian": "<", "binary_big_endian": ">"}[fmt]
        out, pos = {}, 0
        for name, count, props in elements:
            out[name], pos = _ply_binary_element(np, body, pos, count, props, order)
    v = out.get("vertex", {})
    out["V"] = np.stack([v["x"], v["y"], v["z"]], axis=1).astype(float) if "x" in v else np.zeros((0, 3))
    faces = out.get("face", {}).get("vertex_indices", [])
    out["F"] = faces if isinstance(faces, np.ndarray) else (np.array(faces, dtype=int) if faces and len({len(f) for f in faces}) == 1 else faces)
    return out


def triangles(F):
    """(m, 3) triangles of faces (polygons split as fans)"""
    import numpy as np
    if isinstance(F, np.ndarray) and F.ndim == 2 and F.shape[1] == 3:
        return F
    return np.array([[f[0], f[i], f[i + 1]] for f in F for i in range(1, len(f) - 1)], dtype=int).reshape(-1, 3)


def landmarks(path: str) -> dict:
    """{code: (x, y, z)} of a landmark layer (vertex quality = code)"""
    p = read_ply(path)
    return {int(round(c)): tuple(x) for c, x in zip(p["vertex"].get("quality", []), p["V"])}


# ---------------------------------------------------------------------------------------------
# pictures (matplotlib, Agg)

def _png(fig, dpi: int) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    return buf.getvalue()


# views (screen x axis, its sign, screen y axis, depth axis, depth sign: +1 when larger is nearer). The frame:
# +x the patient's left, +y anterior, +z superior (common/include/pectus/labels.h)
FRONT = (0, +1, 2, 1, +1)  # from the front: the patient's left on the viewer's right, anterior nearest
LEFT_SIDE = (1, -1, 2, 0, +1)  # from the patient's left: anterior on the viewer's left, the left side nearest


def _screen(P, view):
    """(n, 2) screen coordinates of points (n, 3) in a view"""
    return P[..., [view[0], view[2]]] * [view[1], 1]


def _draw_cage(ax, np, V, T, value, norm, cmap, view):
    """The cage in one view, back to front (painter's order), shaded by how squarely each face looks at the
    viewer."""
    depth, sign = view[3], view[4]
    tri = V[T]
    order = np.argsort(sign * tri[:, :, depth].mean(axis=1))
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    facing = np.abs(n[:, depth]) / np.maximum(np.linalg.norm(n, axis=1), 1e-12)
    rgba = cmap(norm(value[T].mean(axis=1)))
    rgba[:, :3] *= (0.6 + 0.4 * facing)[:, None]
    from matplotlib.collections import PolyCollection
    pc = PolyCollection(_screen(tri[order], view), facecolors=rgba[order], edgecolors=rgba[order], linewidths=0.15)
    ax.add_collection(pc)
    xy = _screen(V, view)
    ax.set_xlim(xy[:, 0].min() - 5, xy[:, 0].max() + 5)
    ax.set_ylim(xy[:, 1].min() - 5, xy[:, 1].max() + 5)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])
    for s in ax.spines.values():
        s.set_visible(False)


def peak_places(peaks: dict, V_after, before_ply: str | None) -> dict:
    """{key: (x, y, z) on the corrected cage} of the FE filter's peak places, which it gives on the cage before
    the repair: each moved as the nearest vertex of the cage before (the corrected cage is the same mesh moved);
    as given when the two meshes differ"""
    import numpy as np
    V_before = read_ply(before_ply)["V"] if before_ply and os.path.exists(before_ply) else None
    out = {}
    for key in ("max_stress_at_mm", "max_strain_at_mm"):
        at = peaks.get(key)
        if not (isinstance(at, list) and len(at) == 3 and all(isinstance(c, (int, float)) for c in at)):
            continue
        at = np.array(at, dtype=float)
        if V_before is not None and len(V_before) == len(V_after):
            i = int(np.argmin(np.linalg.norm(V_before - at, axis=1)))
            at = at + (V_after[i] - V_before[i])
        out[key] = at
    return out


def stress_picture(result_ply: str, peaks: dict, before_ply: str | None = None) -> tuple[bytes, float]:
    """(PNG, where its colour scale ends in MPa): the corrected cage from the front and from the patient's left,
    coloured by von Mises stress, with a colour bar, the highest stress and strain marked."""
    import numpy as np
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import Normalize
    p = read_ply(result_ply)
    V, T = p["V"], triangles(p["F"])
    q = np.asarray(p["vertex"]["quality"], dtype=float)
    cap = float(np.percentile(q, STRESS_CAP_PERCENTILE))
    norm, cmap = Normalize(0.0, cap if cap > 0 else 1.0), matplotlib.colormaps["turbo"]
    fig = plt.figure(figsize=(6.4, 5.0))
    width_front = np.ptp(V[:, 0])
    width_side = np.ptp(V[:, 1])
    grid = fig.add_gridspec(1, 3, width_ratios=[width_front, width_side, 0.06 * width_front], wspace=0.08,
                            left=0.01, right=0.88, top=0.95, bottom=0.02)
    front, side, bar = fig.add_subplot(grid[0]), fig.add_subplot(grid[1]), fig.add_subplot(grid[2])
    _draw_cage(front, np, V, T, q, norm, cmap, FRONT)
    _draw_cage(side, np, V, T, q, norm, cmap, LEFT_SIDE)
    front.set_title("from the front", fontsize=10)
    side.set_title("from the left side", fontsize=10)
    front.text(0.02, 0.02, "R", transform=front.transAxes, fontsize=10, weight="bold")
    front.text(0.95, 0.02, "L", transform=front.transAxes, fontsize=10, weight="bold")
    side.text(0.02, 0.02, "front", transform=side.transAxes, fontsize=8)
    side.text(0.98, 0.02, "back", transform=side.transAxes, fontsize=8, ha="right")
    places = peak_places(peaks, V, before_ply)
    for key, marker, label in (("max_stress_at_mm", "o", "highest stress"), ("max_strain_at_mm", "s", "highest strain")):
        if key in places:
            at = places[key]
            for ax, view in ((front, FRONT), (side, LEFT_SIDE)):
                x, y = _screen(at, view)
                ax.plot([x], [y], marker=marker, ms=9, ls="none", mfc="none", mec="black", mew=2.0,
                        label=label if ax is front else None)
    if front.get_legend_handles_labels()[0]:
        front.legend(loc="upper center", fontsize=8, frameon=True, ncol=2, bbox_to_anchor=(0.5, 0.0), borderaxespad=0.2)
    cb = fig.colorbar(matplotlib.cm.ScalarMappable(norm=norm, cmap=cmap), cax=bar, extend="max")
    cb.set_label("von Mises stress (MPa)", fontsize=9)
    cb.ax.tick_params(labelsize=8)
    png = _png(fig, 150)
    plt.close(fig)
    return png, norm.vmax


def section_segments(V, T, z: float):
    """(k, 2, 2) segments (x, y) where the horizontal plane at height z cuts the triangles"""
    import numpy as np
    s = V[:, 2] - z
    pos = s[T] > 0
    cut = pos.any(axis=1) & ~pos.all(axis=1)
    Tc, pc = T[cut], pos[cut]
    pts = []
    crosses = []
    for i, j in ((0, 1), (1, 2), (2, 0)):
        a, b = V[Tc[:, i]], V[Tc[:, j]]
        sa, sb = s[Tc[:, i]], s[Tc[:, j]]
        t = np.where(sa != sb, sa / np.where(sa != sb, sa - sb, 1.0), 0.0)
        pts.append((a + (b - a) * t[:, None])[:, :2])
        crosses.append(pc[:, i] != pc[:, j])
    pts, crosses = np.stack(pts, axis=1), np.stack(crosses, axis=1)  # (k, 3, 2), (k, 3): two edges cross each
    return pts[crosses].reshape(-1, 2, 2)


def sections_picture(before_ply: str, after_ply: str, lms: dict, haller: tuple) -> bytes:
    """PNG: the horizontal section at the level of the pectus index (landmark 501 before the repair) through
    the cage before (grey) and after (red), seen from the feet as a CT slice (anterior up, the patient's right
    on the left)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection
    z = float(lms[FUNNEL_DEEPEST][2])
    fig, ax = plt.subplots(figsize=(5.0, 4.3))
    # after first, before on top of it: where the cage did not move (the back), the thin grey line lies on the red
    for path, colour, width, label, index in ((after_ply, "#d62728", 2.6, "after", haller[1]),
                                               (before_ply, "0.25", 1.1, "before", haller[0])):
        p = read_ply(path)
        seg = section_segments(p["V"], triangles(p["F"]), z)
        ax.add_collection(LineCollection(seg, colors=colour, linewidths=width))
        ax.plot([], [], color=colour, lw=width, label=f"{label}" + (f": pectus index {index}" if index else ""))
    if VERTEBRA_AT_DEEPEST in lms:
        vx, vy = lms[VERTEBRA_AT_DEEPEST][:2]
        ax.plot([vx], [vy], marker="^", color="black", ms=6, ls="none", label="front of the vertebra")
    ax.autoscale()
    ax.set_aspect("equal")
    ax.margins(0.04)
    ax.set_xlabel("mm")
    ax.set_ylabel("mm (front up)")
    ax.tick_params(labelsize=8)
    ax.text(0.01, 0.97, "R", transform=ax.transAxes, va="top", weight="bold")
    ax.text(0.99, 0.97, "L", transform=ax.transAxes, va="top", ha="right", weight="bold")
    ax.legend(loc="lower center", fontsize=8, ncol=2, frameon=False, bbox_to_anchor=(0.5, 1.0))
    ax.grid(alpha=0.25)
    fig.tight_layout()
    png = _png(fig, 150)
    plt.close(fig)
    return png


def force_picture(csv_path: str, target_mm: str) -> bytes:
    """PNG: the elevation of the lower sternum against the elevating force (the FE's load steps), the target
    elevation dashed"""
    import csv
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    with open(csv_path, newline="") as fh:
        rows = [(float(r["force_N"]), float(r["elevation_mm"])) for r in csv.DictReader(fh)]
    fig, ax = plt.subplots(figsize=(5.0, 4.3))
    ax.plot([f for f, _ in rows], [e for _, e in rows], "o-", color="#1f77b4", ms=4)
    if target_mm:
        ax.axhline(float(target_mm), color="#d62728", ls="--", lw=1)
        ax.text(0.02, float(target_mm), f" target {target_mm} mm", color="#d62728", va="bottom", fontsize=9,
                transform=ax.get_yaxis_transform())
    ax.set_xlabel("force on the lower end of the sternum (N)")
    ax.set_ylabel("elevation of the lower end of the sternum (mm)", fontsize=9)
    ax.set_xlim(left=0)
    ax.set_ylim(bottom=0, top=max([e for _, e in rows] + [float(target_mm or 0)]) * 1.12 or 1)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    png = _png(fig, 150)
    plt.close(fig)
    return png


# ---------------------------------------------------------------------------------------------
# the page

CSS = """
@page { size: A4; margin: 10mm; }
html { font-family: "DejaVu Sans", "Helvetica Neue", Arial, sans-serif; color: #111; }
@media screen { html { font-size: 18.75px; } body { margin: 0; } .sheet { max-width: 1240px; box-sizing: border-box; padding: 3.15rem; margin: 0 auto; } }
@media print { html { font-size: 12px; } body { margin: 0; } .sheet { padding: 0; } }
h1 { font-size: 1.45rem; margin: 0 0 0.2rem 0; }
.case { font-size: 1.05rem; margin: 0 0 0.6rem 0; }
.banner { border: 0.2rem solid #b00020; background: #fde8ea; color: #b00020; padding: 0.5rem 0.8rem;
  margin: 0 0 0.7rem 0; font-size: 0.95rem; }
.banner strong { font-size: 1.15rem; display: block; margin-bottom: 0.15rem; }
.banner .why { color: #5a0010; font-size: 0.8rem; }
.row { display: flex; gap: 1.2rem; margin-bottom: 0.7rem; align-items: flex-start; }
.col { flex: 1 1 0; min-width: 0; }
.wide { flex: 1.45 1 0; }
h2 { font-size: 1.0rem; margin: 0 0 0.3rem 0; border-bottom: 0.08rem solid #999; }
table.figures { border-collapse: collapse; width: 100%; font-size: 0.86rem; }
table.figures td { padding: 0.22rem 0.3rem; border-bottom: 0.05rem solid #ddd; vertical-align: top; }
table.figures td.v { text-align: right; white-space: nowrap; font-weight: bold; }
table.figures .where { display: block; font-size: 0.72rem; color: #444; font-weight: normal; }
img { width: 100%; height: auto; display: block; }
.caption { font-size: 0.72rem; color: #333; margin: 0.2rem 0 0 0; }
.missing { border: 0.1rem dashed #999; color: #555; padding: 1.5rem 0.8rem; font-size: 0.85rem; text-align: center; }
.small { font-size: 0.68rem; color: #444; border-top: 0.08rem solid #999; padding-top: 0.3rem; }
.small p { margin: 0.1rem 0; }
code { font-size: 0.66rem; word-break: break-all; }
"""


def _e(x) -> str:
    return html.escape(str(x))


def _num(s: dict, key: str, unit: str = "", sign: bool = False) -> str:
    """summary.csv's figure as written there (the filters' rounding), with its unit; 'n/a' when there is none"""
    v = s.get(key, "")
    if v == "":
        return "n/a"
    if sign and not v.startswith("-"):
        v = "+" + v
    return f"{v} {unit}".strip()


def _ordinal(n: str) -> str:
    try:
        k = int(n)
    except ValueError:
        return n
    return f"{k}{'th' if 10 <= k % 100 <= 20 else {1: 'st', 2: 'nd', 3: 'rd'}.get(k % 10, 'th')}"


def case_line(s: dict) -> str:
    sex = {"M": "male", "F": "female"}.get(s.get("sex", ""), s.get("sex", "") or "sex not given")
    age = f"{s['age_years']} years" if s.get("age_years") else "age not given"
    parts = [f"Case <b>{_e(s.get('case') or 'unnamed')}</b>", f"{_e(sex)}, {_e(age)}",
             f"target elevation of the lower end of the sternum <b>{_e(_num(s, 'target_elevation_mm', 'mm'))}</b>"]
    if s.get("bar_intercostal_space"):
        k = s["bar_intercostal_space"]
        nxt = str(int(k) + 1) if k.isdigit() else "next"
        parts.append(f"Nuss bar in the <b>{_e(_ordinal(k))} intercostal space</b> (between ribs {_e(k)} and {_e(nxt)})")
    return " &middot; ".join(parts)


def not_reportable(s: dict) -> list[str]:
    """Plain reasons why the figures are not a result to report ([] when they are)"""
    reasons = []
    # fe_converged is 0 when the FE analysis returned no figures; a summary.csv older than the column has no value
    failed = s.get("fe_converged") == "0" or (s.get("fe_converged", "") == "" and s.get("force_N", "") == "")
    if failed:
        reasons.append("The simulation gave no valid result: it did not finish, or it did not reach a balanced "
                       "(converged) state.")
    if s.get("run_mode") == "quick":
        reasons.append("This is a quick test run on a coarse model, which is stiffer than the real chest: "
                       "its forces are too high and its stresses not reliable.")
    elif not failed and s.get("reportable") == "":
        reasons.append("The run does not say whether its model is fine enough for its figures to be reported.")
    elif not failed and s.get("reportable") != "1":
        reasons.append("The model is coarser than the one the figures were checked against.")
    return reasons


def banner(s: dict) -> str:
    reasons = not_reportable(s)
    if not reasons:
        return ""
    why = s.get("not_reportable_because", "")
    return ("<div class='banner' id='not-reportable'><strong>NOT A RESULT TO REPORT &mdash; do not use these figures "
            "for treatment planning</strong>" + " ".join(_e(r) for r in reasons)
            + (f"<div class='why'>Technical reason: {_e(why)}</div>" if why else "") + "</div>")


def _where(s: dict, key: str) -> str:
    return f"<span class='where'>at the {_e(s[key])}</span>" if s.get(key) else ""


def figures_table(s: dict) -> str:
    try:
        strain_pct = f" ({float(s.get('max_strain', '')) * 100:.1f} %)"
    except ValueError:
        strain_pct = ""
    hb, ha = s.get("haller_index_before", ""), s.get("haller_index_after", "")
    rows = [
        ("Force needed to lift the sternum (on its lower end)", _num(s, "force_N", "N"), ""),
        ("Elevation of the lower end of the sternum", _num(s, "elevation_mm", "mm"), ""),
        ("Highest stress in the rib cage (von Mises)", _num(s, "max_stress_MPa", "MPa"), _where(s, "max_stress_where")),
        ("Highest stress away from the rib&ndash;cartilage junctions", _num(s, "max_stress_body_MPa", "MPa"),
         _where(s, "max_stress_body_where")),
        ("Highest strain (stretch)", _num(s, "max_strain") + strain_pct, _where(s, "max_strain_where")),
        ("Change of the thoracic volume, slice method",
         f"{_num(s, 'slice_change_cm3', 'cm&sup3;', True)} ({_num(s, 'slice_change_pct', '%', True)})", ""),
        ("Change of the thoracic volume, Ferguson envelope",
         f"{_num(s, 'envelope_change_cm3', 'cm&sup3;', True)} ({_num(s, 'envelope_change_pct', '%', True)})", ""),
        ("Pectus (Haller) index, before &rarr; after", f"{hb or 'n/a'} &rarr; {ha or 'n/a'}", ""),
    ]
    body = "".join(f"<tr><td>{a}{w}</td><td class='v'>{v}</td></tr>" for a, v, w in rows)
    return f"<table class='figures' id='figures'>{body}</table>"


def _figure(png: bytes | None, alt: str, caption: str, missing: str, ident: str) -> str:
    if png is None:
        return f"<div class='missing' id='{ident}-missing'>Picture missing: {_e(missing)}</div>"
    data = base64.b64encode(png).decode("ascii")
    return (f"<img id='{ident}' alt='{_e(alt)}' src='data:image/png;base64,{data}'>"
            f"<p class='caption'>{caption}</p>")


def settings_text(s: dict) -> str:
    g = lambda k, unit="": (s.get(k) or "n/a") + (f" {unit}" if unit and s.get(k) else "")  # noqa: E731
    mesh = (f"{g('fe_tets')} {g('fe_element')} tetrahedra, {g('fe_nodes')} nodes, from a surface of {g('cage_faces')} "
            f"triangles with {g('surface_edge_mm', 'mm')} edges, tet quality bound {g('tet_quality_radius_edge')} "
            f"(0: none), largest tet volume {g('max_tet_volume_mm3', 'mm&sup3;')} (0: none)")
    return (f"<p><b>Analysis:</b> finite elements, {_e(g('fe_analysis'))}, {_e(g('fe_material'))} tissues; the force on "
            f"the lower sternum (load radius {_e(g('sternum_load_radius_mm', 'mm'))}) calibrated to the target elevation in "
            f"{_e(g('fe_solves'))} solve(s); ribs held at their costovertebral joints (radius {_e(g('joint_radius_mm', 'mm'))}), "
            f"bar support radius on the ribs {_e(g('rib_support_radius_mm', 'mm'))}.</p>"
            f"<p><b>Material:</b> bone E = {_e(g('bone_E_MPa', 'MPa'))}, &nu; = {_e(g('bone_nu'))}; costal cartilage "
            f"E = {_e(g('cartilage_E_MPa', 'MPa'))}, &nu; = {_e(g('cartilage_nu'))}.</p>"
            f"<p><b>Mesh:</b> {mesh}. Analysis time {_e(g('fe_time_s', 's'))}, whole run {_e(g('pipeline_time_s', 's'))}; "
            f"run mode {_e(g('run_mode'))}.</p>")


def _peaks(outdir: str) -> dict:
    """the FE filter's values (nuss_results.json: one JSON line), {} when missing"""
    try:
        with open(os.path.join(outdir, "nuss_results.json")) as fh:
            return json.loads(fh.readline()).get("results", {})
    except (OSError, ValueError):
        return {}


def can_draw() -> bool:
    """matplotlib and numpy import"""
    try:
        import matplotlib  # noqa: F401
        import numpy  # noqa: F401
    except ImportError:
        return False
    return True


def _picture(make, needs: list[str], what: str):
    """(make(), None) or (None, why the picture is missing)"""
    absent = [os.path.basename(p) for p in needs if not os.path.exists(p)]
    if absent:
        return None, f"{what}: the run wrote no {', '.join(absent)}."
    if not can_draw():
        return None, f"{what}: drawing it needs matplotlib and numpy (Debian: python3-matplotlib python3-numpy)."
    return make(), None


def pictures(outdir: str, s: dict) -> dict:
    """{name: (png or None, why it is missing or None, caption)} of the page's three pictures"""
    j = lambda name: os.path.join(outdir, name)  # noqa: E731
    stress, why = _picture(lambda: stress_picture(j("nuss_result.ply"), _peaks(outdir), j("ribcage_smoothed.ply")),
                           [j("nuss_result.ply")], "the rib cage coloured by stress")
    stress, cap = stress if stress else (None, 0.0)
    out = {"stress": (stress, why, "Colours: von Mises stress on the surface of the bone and cartilage, in MPa (blue "
                      f"low, red high). The scale ends at {cap:.1f} MPa ({STRESS_CAP_PERCENTILE} % of the surface lies "
                      "below it) so that the peaks do not wash out the picture; the peaks are in the table and marked.")}
    lms = landmarks(j("ribcage_landmarks.ply")) if os.path.exists(j("ribcage_landmarks.ply")) and can_draw() else {}
    needs = [j("ribcage_smoothed.ply"), j("nuss_result.ply"), j("ribcage_landmarks.ply")]
    if all(os.path.exists(p) for p in needs) and can_draw() and FUNNEL_DEEPEST not in lms:
        sec, why = None, "the sections: the landmarks have no deepest point of the funnel (code 501)."
    else:
        sec, why = _picture(lambda: sections_picture(j("ribcage_smoothed.ply"), j("nuss_result.ply"), lms,
                                                     (s.get("haller_index_before"), s.get("haller_index_after"))),
                            needs, "the sections before and after")
    level = f"{lms[FUNNEL_DEEPEST][2]:.1f} mm" if FUNNEL_DEEPEST in lms else "n/a"
    out["sections"] = (sec, why, "Horizontal section of the rib cage at the height of the deepest point of the "
                       f"funnel before the repair ({level} above the model's origin), where the pectus index is "
                       "measured; seen from the feet, as a CT slice.")
    fd, why = _picture(lambda: force_picture(j("nuss_force_displacement.csv"), s.get("target_elevation_mm", "")),
                       [j("nuss_force_displacement.csv")], "the force and elevation plot")
    if fd is None and os.path.exists(j("nuss_force_displacement.png")):  # the FE filter's own plot
        fd, why = open(j("nuss_force_displacement.png"), "rb").read(), None
    out["force"] = (fd, why, "How far the lower end of the sternum rises (mm) as the force on it grows (N), up to "
                    "the target elevation.")
    return out


GLOSSARY = ("Stress: how hard the bone and cartilage are loaded (1 MPa = 1 N/mm&sup2;). Strain: how much the tissue "
            "is stretched (0.10 = 10 %). Thoracic volume: the space inside the rib cage, after minus before. Pectus "
            "index: inner width of the chest / distance from the sternum to the spine (normal about 2.5).")


def write_report(outdir: str, command: str | None = None) -> str:
    """Writes OUTDIR/report.html from the run's files; returns its path. command: the command line the page
    names (default: this process's)."""
    summary = os.path.join(outdir, "summary.csv")
    s = pipeline.read_summary(summary) if os.path.exists(summary) else {}
    pic = pictures(outdir, s)

    def figure(name: str, alt: str) -> str:
        png, why, caption = pic[name]
        return _figure(png, alt, caption, why or "", f"{name}-picture")

    run_date = (datetime.datetime.fromtimestamp(os.path.getmtime(summary)).strftime("%Y-%m-%d %H:%M")
                if os.path.exists(summary) else "n/a")
    now = datetime.datetime.now().strftime("%Y-%m-%d %H:%M")
    command = command or shlex.join(["python3"] + sys.argv)
    body = f"""<div class='sheet'>
<h1>Nuss procedure: simulated correction of the funnel chest</h1>
<p class='case' id='case'>{case_line(s)}</p>
{banner(s)}
<div class='row'>
 <div class='col'><h2>Results</h2>{figures_table(s)}<p class='caption'>{GLOSSARY}</p></div>
 <div class='col wide'><h2>Stress in the rib cage after the repair</h2>
  {figure("stress", "The corrected rib cage coloured by von Mises stress")}</div>
</div>
<div class='row'>
 <div class='col'><h2>Cross-section before and after</h2>
  {figure("sections", "Horizontal section of the rib cage before and after")}</div>
 <div class='col'><h2>Force and elevation</h2>
  {figure("force", "Elevating force against the elevation of the lower sternum")}</div>
</div>
<div class='small' id='settings'>
{settings_text(s)}
<p><b>Run:</b> {_e(run_date)} (summary.csv), output folder <code>{_e(os.path.abspath(outdir))}</code>.
Report made on {_e(now)} by <code>{_e(command)}</code>.</p>
</div>
</div>"""
    title = f"Nuss simulation report: {s.get('case') or 'unnamed case'}"
    page = (f"<!DOCTYPE html>\n<html lang='en'><head><meta charset='utf-8'><title>{_e(title)}</title>"
            f"<style>{CSS}</style></head><body>\n{body}\n</body></html>\n")
    path = os.path.join(outdir, "report.html")
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(page)
    return path


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="report.py", description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("outdir", help="a main job's output folder (python/run_main.py OUTDIR)")
    a = ap.parse_args(argv)
    if not os.path.exists(os.path.join(a.outdir, "summary.csv")):
        print(f"report.py: {a.outdir} has no summary.csv (not a main job's output folder)", file=sys.stderr)
        return 2
    print(write_report(a.outdir))
    return 0


if __name__ == "__main__":
    sys.exit(main())
