"""E2E: the thoracic volume filters through meshlabserver on analytic cages built here.
Slice method within 0.2 % and Ferguson envelope within 1 % of the exact volumes; the divergence
volumes of closed meshes equal MeshLab's 'Compute Geometric Measures' to 1e-6; ranges from a
landmark layer (labels.h codes); before/after change; bad input refused with a message and rollback.
The figures are read from the values the filters return (2020.09: the results file the plugins write;
newer hosts: pectus-mlrun's, from the return values), and each agrees with the Log line's printed figure."""
import math
import os

import numpy as np

import harness as h
import pectus_mlx as mlx
from harness import as_printed, check
from harness import log_figures as grab
from pectus_meshes import closed_ellipsoid

W = h.workdir("thoracic")
A, B, T = 130.0, 90.0, 8.0  # inner semi-axes (x, y) and rib thickness of the banded cylinder


def rib_mask(th, z, pitch=24.0, frac=0.6, tilt=30.0, strip=0.22):
    d1 = np.abs(np.remainder(th - np.pi / 2 + np.pi, 2 * np.pi) - np.pi)
    d2 = np.abs(np.remainder(th + np.pi / 2 + np.pi, 2 * np.pi) - np.pi)
    u = (z + tilt * np.sin(th)) / pitch
    return (d1 < strip) | (d2 < strip) | (u - np.floor(u) < frac)


def banded_cylinder(a, b, t, z0, z1, nth, nz, stretch_anterior=1.0):
    """inner and outer elliptic sheets cut into tilted rib bands (sternum and spine strips kept)"""
    V, F = [], []
    for off in (0.0, t):
        base = len(V)
        th = 2 * np.pi * np.arange(nth) / nth
        for i in range(nz + 1):
            z = z0 + (z1 - z0) * i / nz
            y = (b + off) * np.sin(th)
            y = np.where(y > 0, y * stretch_anterior, y)
            V += list(zip((a + off) * np.cos(th), y, np.full(nth, z)))
        for i in range(nz):
            zc = z0 + (z1 - z0) * (i + 0.5) / nz
            thc = 2 * np.pi * (np.arange(nth) + 0.5) / nth
            keep = rib_mask(thc, zc)
            for j in np.nonzero(keep)[0]:
                p, q = base + i * nth + j, base + i * nth + (j + 1) % nth
                F += [[p, q, q + nth], [p, q + nth, p + nth]]
    return np.array(V), F


def write_landmarks(path, lms):
    with open(path, "w") as fh:
        fh.write(f"ply\nformat ascii 1.0\nelement vertex {len(lms)}\nproperty float x\nproperty float y\n"
                 "property float z\nproperty float quality\nend_header\n")
        for code, (x, y, z) in lms:
            fh.write(f"{x} {y} {z} {code}\n")
    return path


RANGE_SRC = ["Landmarks", "Given heights"]
LOWER = ["700 dome of the diaphragm", "500 lower end of the sternum"]


def common(compare=False, before=0, source=1, landmarks=0, lower=0, z0=0.0, z1=200.0):
    return dict(compare=mlx.Bool(compare), beforeLayer=mlx.Mesh(before), rangeSource=mlx.Enum(source, RANGE_SRC),
                landmarkLayer=mlx.Mesh(landmarks), lowerLimit=mlx.Enum(lower, LOWER), zLow=mlx.Float(z0),
                zHigh=mlx.Float(z1))


def slice_filter(**kw):
    return mlx.Filter("Pectus: Thoracic Volume (Slice Method)", **common(**kw), spacing=mlx.Float(2.6),
                      resolution=mlx.Int(512), rays=mlx.Int(720))


def envelope_filter(**kw):
    return mlx.Filter("Pectus: Thoracic Volume (Ferguson Envelope)", **common(**kw), patchesLong=mlx.Int(16),
                      patchesAround=mlx.Int(16), initialStep=mlx.Float(0.0), minStep=mlx.Float(0.05),
                      smoothing=mlx.Bool(True), tessellation=mlx.Int(8))


def index_filter(compare=False, before=0, level=0, landmarks=0, z0=0.0, z1=200.0):
    return mlx.Filter("Pectus: Pectus Index", compare=mlx.Bool(compare), beforeLayer=mlx.Mesh(before),
                      levelSource=mlx.Enum(level, ["Landmarks 501/503", "Automatic (deepest slice)"]),
                      landmarkLayer=mlx.Mesh(landmarks), zLow=mlx.Float(z0), zHigh=mlx.Float(z1), rays=mlx.Int(720))




def rel(v, e):
    return abs(v - e) / abs(e)


# ---------------------------------------------------------------------------------------------
cageV, cageF = banded_cylinder(A, B, T, 0.0, 240.0, 360, 120)
cage = h.write_ply(os.path.join(W, "cage.ply"), cageV, cageF)
afterV, _ = banded_cylinder(A, B, T, 0.0, 240.0, 360, 120, stretch_anterior=1.1)
after = h.write_ply(os.path.join(W, "cage_after.ply"), afterV, cageF)
lms = write_landmarks(os.path.join(W, "cage_landmarks.ply"),
                      [(700, (0, -50, 20.0)), (500, (0, B, 40.0)), (701, (0, 0, 220.0)), (501, (0, B, 120.0)),
                       (503, (0, -B, 120.0))])

SLICE, ENVELOPE, INDEX = "Pectus: Thoracic Volume (Slice Method)", "Pectus: Thoracic Volume (Ferguson Envelope)", "Pectus: Pectus Index"


def agree(r, key, filter, pattern, decimals):
    """the values of `key` the runs of `filter` returned are the Log's figures (printed with `decimals`)"""
    values, printed = r.values(key, filter), grab(r.log, pattern)
    ok = len(values) == len(printed) > 0 and all(as_printed(v, p, decimals) for v, p in zip(values, printed))
    check(ok, f"{filter}: {key} returned {values}, the Log's figures {printed}")


# 1. slice method, given heights, exact inner volume
r = h.run([cage], mlx.Script([slice_filter(source=1, z0=20.0, z1=220.0)]))
v = r.values("volume_cm3", SLICE)
agree(r, "volume_cm3", SLICE, r"Slice method, layer .*intrathoracic volume ([0-9.]+) cm3", 3)
agree(r, "slices", SLICE, r"Slice method, layer .*cm3 \((\d+) slices", 0)
agree(r, "pixel_mm", SLICE, r"Slice method, layer .*pixel ([0-9.]+) mm", 3)
check(r.value("z_low_mm") == 20.0 and r.value("z_high_mm") == 220.0 and r.value("seconds") >= 0,
      "slice method: the range and the time returned", str(r.results))
exact_inner = math.pi * A * B * 200.0 / 1000.0
check(r.rc == 0 and len(v) == 1, "slice method runs", r.stdout[-800:])
if v:
    check(rel(v[0], exact_inner) < 2e-3, f"slice volume {v[0]:.3f} cm3 within 0.2 % of {exact_inner:.3f}",
          f"rel {rel(v[0], exact_inner):.5f}")

# 2. ranges from the landmark layer (700 .. 701): same range as above; 500 .. 701 is smaller
r = h.run([lms, cage], mlx.Script([slice_filter(source=0, landmarks=0, lower=0),
                                   slice_filter(source=0, landmarks=0, lower=1)]))
v = r.values("volume_cm3", SLICE)
check(r.rc == 0 and len(v) == 2, "slice method with landmark ranges runs", r.stdout[-800:])
if len(v) == 2:
    check(rel(v[0], exact_inner) < 2e-3, f"landmarks 700..701: {v[0]:.3f} cm3 within 0.2 %")
    check(rel(v[1], math.pi * A * B * 180.0 / 1000.0) < 2e-3, f"landmarks 500..701: {v[1]:.3f} cm3 within 0.2 %")

# 3. envelope on the banded cylinder (outer sheet) and before/after change for both methods
r = h.run([cage, lms, after], mlx.Script([
    envelope_filter(compare=True, before=0, source=0, landmarks=1, lower=0),
    slice_filter(compare=True, before=0, source=0, landmarks=1, lower=0),
    index_filter(compare=True, before=0, level=0, landmarks=1)]),
    outputs=[(os.path.join(W, "envelope.ply"), "", 4)])
check(r.rc == 0, "envelope + slice + index before/after run", r.stdout[-1500:])
env = r.values("before_volume_cm3", ENVELOPE) + r.values("volume_cm3", ENVELOPE)
for key, pattern, decimals in [
        ("volume_cm3", r"Ferguson envelope, layer 'cage_after.*thoracic volume ([0-9.]+) cm3", 3),
        ("before_volume_cm3", r"Ferguson envelope, layer 'cage\.ply.*thoracic volume ([0-9.]+) cm3", 3),
        ("volume_change_cm3", r"Ferguson envelope thoracic volume change: \+?(-?[0-9.]+) cm3", 3),
        ("volume_change_pct", r"Ferguson envelope thoracic volume change: \S+ cm3 \(\+?(-?[0-9.]+) %", 2),
        ("envelope_mesh_volume_mm3", r"Envelope layer 'cage_after.*mesh volume ([0-9.]+) mm3", 6)]:
    agree(r, key, ENVELOPE, pattern, decimals)
for key, pattern, decimals in [
        ("volume_cm3", r"Slice method, layer 'cage_after.*intrathoracic volume ([0-9.]+) cm3", 3),
        ("before_volume_cm3", r"Slice method, layer 'cage\.ply.*intrathoracic volume ([0-9.]+) cm3", 3),
        ("volume_change_cm3", r"Slice method intrathoracic volume change: \+?(-?[0-9.]+) cm3", 3),
        ("volume_change_pct", r"Slice method intrathoracic volume change: \S+ cm3 \(\+?(-?[0-9.]+) %", 2)]:
    agree(r, key, SLICE, pattern, decimals)
for key, pattern, decimals in [
        ("haller_index", r"Pectus index, layer 'cage_after.*Haller index ([0-9.]+)", 3),
        ("before_haller_index", r"Pectus index, layer 'cage\.ply.*Haller index ([0-9.]+)", 3),
        ("correction_index_pct", r"Pectus index, layer 'cage_after.*correction index ([0-9.]+) %", 2),
        ("level_z_mm", r"Pectus index, layer 'cage_after.* at z = (-?[0-9.]+) mm", 2),
        ("sternum_vertebra_mm", r"Pectus index, layer 'cage_after.*sternum-vertebra ([0-9.]+) mm", 2)]:
    agree(r, key, INDEX, pattern, decimals)
exact_outer = math.pi * (A + T) * (B + T) * 200.0 / 1000.0
if len(env) == 2:
    check(rel(env[0], exact_outer) < 1e-2, f"envelope volume {env[0]:.3f} cm3 within 1 % of {exact_outer:.3f}",
          f"rel {rel(env[0], exact_outer):.5f}")
    check(env[1] > env[0], "envelope volume grows after the anterior wall moves out")
sl_change = r.values("volume_change_cm3", SLICE)
sl_pct = r.values("volume_change_pct", SLICE)
# exact: the anterior half of the inner ellipse stretched by 10 % -> +5 %
check(len(sl_pct) == 1 and abs(sl_pct[0] - 5.0) < 0.2, f"slice change {sl_pct} % is +5 % (exact)")
check(len(sl_change) == 1 and rel(sl_change[0], 0.05 * exact_inner) < 0.05, f"slice change {sl_change} cm3")
env_pct = r.values("volume_change_pct", ENVELOPE)
check(len(env_pct) == 1 and env_pct[0] > 0, f"envelope change {env_pct} % positive")
haller = r.values("before_haller_index", INDEX) + r.values("haller_index", INDEX)
check(len(haller) == 2 and abs(haller[0] - 2 * A / (2 * B)) < 0.02, f"Haller index before {haller} = 2a/2b")
check(len(haller) == 2 and haller[1] < haller[0], "Haller index falls after the correction")
if os.path.exists(os.path.join(W, "envelope.ply")):
    e = h.read_ply(os.path.join(W, "envelope.ply"))
    check(len(e["F"]) == 16 * 8 * 16 * 8 * 2 + 2 * 16 * 8, f"envelope layer saved with {len(e['F'])} triangles")
else:
    check(False, "envelope layer saved")

# 4. closed ellipsoid: envelope within 1 %; divergence volumes equal Compute Geometric Measures
ea, eb, ec = 120.0, 90.0, 150.0
eV, eF = closed_ellipsoid(ea, eb, ec, 160, 80)
ell = h.write_ply(os.path.join(W, "ellipsoid.ply"), eV, eF)
envfile = os.path.join(W, "ellipsoid_envelope.ply")  # binary PLY: the float coordinates unchanged
r = h.run([ell], mlx.Script([mlx.Filter("Compute Geometric Measures"),
                             envelope_filter(source=1, z0=-90.0, z1=90.0)]), outputs=[(envfile, "", 1)])
check(r.rc == 0, "envelope on a closed ellipsoid runs", r.stdout[-800:])
ml = grab(r.log, r"Mesh Volume\s+is\s+([0-9.]+)")
ours_in = r.values("layer_divergence_volume_mm3", ENVELOPE)
ours_env = r.values("envelope_mesh_volume_mm3", ENVELOPE)
envv = r.values("volume_cm3", ENVELOPE)
agree(r, "layer_divergence_volume_mm3", ENVELOPE, r"is closed: divergence volume ([0-9.]+) mm3", 6)
r2 = h.run([envfile], mlx.Script([mlx.Filter("Compute Geometric Measures")]))
ml += grab(r2.log, r"Mesh Volume\s+is\s+([0-9.]+)")
if len(ml) == 2 and ours_in and ours_env:
    check(rel(ours_in[0], ml[0]) < 1e-6, f"closed input: divergence {ours_in[0]} = MeshLab {ml[0]} (1e-6)",
          f"rel {rel(ours_in[0], ml[0]):.2e}")
    check(rel(ours_env[0], ml[1]) < 1e-6, f"envelope layer: divergence {ours_env[0]} = MeshLab {ml[1]} (1e-6)",
          f"rel {rel(ours_env[0], ml[1]):.2e}")
else:
    check(False, "volumes logged", f"{ml} {ours_in} {ours_env}")
seg = math.pi * ea * eb * (180.0 - (90.0 ** 3 * 2) / (3 * ec * ec)) / 1000.0
check(len(envv) == 1 and rel(envv[0], seg) < 1e-2, f"ellipsoid envelope {envv} cm3 within 1 % of {seg:.3f}")

# 5. bad input: a before layer that is another mesh; a range with no geometry; missing landmark
other = h.write_ply(os.path.join(W, "other.ply"), eV, eF)
r = h.run([other, cage], mlx.Script([slice_filter(compare=True, before=0, source=1, z0=20.0, z1=220.0)]),
          outputs=[(os.path.join(W, "bad.ply"), "")])
check(r.rc != 0 and any("not the same model" in l for l in r.log), "mismatched before/after refused with a message",
      r.stdout[-600:])
r = h.run([cage], mlx.Script([envelope_filter(source=1, z0=400.0, z1=500.0)]))
check(r.rc != 0 and any("no geometry in the measured range" in l for l in r.log), "empty range refused",
      r.stdout[-600:])
r = h.run([cage], mlx.Script([slice_filter(source=1, z0=100.0, z1=100.0)]))
check(r.rc != 0 and any("degenerate long axis" in l for l in r.log), "degenerate range refused")
r = h.run([cage, cage], mlx.Script([slice_filter(source=0, landmarks=0)]))
check(r.rc != 0 and any("landmark 700" in l for l in r.log), "missing landmark refused")
# rollback: a failing envelope adds no layer (saving layer 1 fails: only the cage is there)
r = h.run([cage], mlx.Script([envelope_filter(source=1, z0=400.0, z1=500.0)]),
          outputs=[(os.path.join(W, "rolled.ply"), "", 1)])
check(not os.path.exists(os.path.join(W, "rolled.ply")), "no envelope layer left after a failure")

h.finish()
