"""E2E: 'Pectus: Create Rib Cage' through meshlabserver at a coarse resolution. Asserts on the
saved PLY files: closed 2-manifold surface, labels on every face (face colour palette + quality code),
the pectus (Haller) index measured geometrically on the saved mesh, landmarks layer, determinism."""
import os

import numpy as np

from harness import check, finish, read_ply, run, workdir, file_digest
import pectus_mlx as mlx
from pectus_filters import create_ribcage

PALETTE = {(235, 222, 190): 1, (90, 160, 235): 2, (215, 110, 95): 3}


def script(haller=4.0, edge=5.0, ribs=12, age=7.0):
    return mlx.Script([create_ribcage(age=age, ribPairs=ribs, hallerIndex=haller, edgeLength=edge)])


def line_hits(V, F, axis, u, v):
    """coordinate `axis` of the intersections of the axis-parallel line through (u, v) (the other two
    coordinates, in cyclic order) with every triangle"""
    i, j = (axis + 1) % 3, (axis + 2) % 3
    A, B, C = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    ax, ay, bx, by, cx, cy = A[:, i] - u, A[:, j] - v, B[:, i] - u, B[:, j] - v, C[:, i] - u, C[:, j] - v
    w0, w1, w2 = bx * cy - by * cx, cx * ay - cy * ax, ax * by - ay * bx
    s = w0 + w1 + w2
    ok = (((w0 >= 0) & (w1 >= 0) & (w2 >= 0)) | ((w0 <= 0) & (w1 <= 0) & (w2 <= 0))) & (s != 0)
    return (w0[ok] * A[ok, axis] + w1[ok] * B[ok, axis] + w2[ok] * C[ok, axis]) / s[ok]


def haller(V, F):
    """inner transverse diameter through each side's lateral-most vertex / smallest distance along +y
    from the vertebra plane y = 0 to the surface at |x| <= 2 mm (frame of common/include/pectus/labels.h)"""
    xin = []
    for sg in (-1, 1):
        p = V[np.argmax(sg * V[:, 0])]
        xs = np.sort(sg * line_hits(V, F, 0, p[1] + 0.011, p[2] + 0.013))[::-1]
        xin.append(sg * xs[1])
    T = xin[1] - xin[0]
    near = (V[F].min(axis=1)[:, 0] < 2.5) & (V[F].max(axis=1)[:, 0] > -2.5) & (V[F].max(axis=1)[:, 1] > 0)
    Fm = F[near]
    zs = V[Fm].reshape(-1, 3)[:, 2]
    ap = np.inf
    for z in np.arange(np.floor(zs.min() * 2) / 2, zs.max(), 0.5):
        for x in range(-2, 3):
            y = line_hits(V, Fm, 1, z, x + 1e-4)
            y = y[y > 0]
            if y.size:
                ap = min(ap, y.min())
    return T / ap, T, ap


def edges_ok(F):
    E = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    _, counts = np.unique(E, axis=0, return_counts=True)
    directed = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    _, dcounts = np.unique(directed, axis=0, return_counts=True)
    return counts, dcounts


def components(nv, F):
    parent = np.arange(nv)

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a
    for f in F:
        ra, rb, rc = find(f[0]), find(f[1]), find(f[2])
        parent[rb] = ra
        parent[find(rc)] = ra
    used = np.unique(F)
    return len({find(v) for v in used})


d = workdir("ribcage")
out = os.path.join(d, "cage.ply")
lms = os.path.join(d, "landmarks.ply")
r = run([], script(), [(out, "fc fq vq", 0), (lms, "vq", 1)])
check(r.rc == 0, "meshlabserver exits 0", r.stdout[-2000:])
log = [l for l in r.log if l.startswith("Rib cage:")]
check(len(log) == 1, "one log line with faces / vertices / Haller index / dimensions", "\n".join(r.log))
if log:
    print(log[0])
    check("Haller index requested 4" in log[0] and "chest width" in log[0], "log names the index and dimensions")
check(os.path.exists(out) and os.path.exists(lms), "both layers saved")
if os.path.exists(out):
    m = read_ply(out)
    V, F = m["V"], np.array(m["F"])
    print(f"{len(F)} faces, {len(V)} vertices")
    check(1000 < len(F) < 30000, "coarse resolution gives a few thousand faces", str(len(F)))
    counts, dcounts = edges_ok(F)
    check(np.all(counts == 2), "every edge shared by exactly two faces (closed, manifold edges)",
          f"{np.sum(counts != 2)} bad edges")
    check(np.all(dcounts == 1), "consistently oriented (each directed edge once)")
    nc = components(len(V), F)
    check(nc == 5, "one component + floating ribs 11 and 12 on both sides", str(nc))
    A, B, C = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    vol = np.einsum("ij,ij->i", A, np.cross(B, C)).sum() / 6
    check(vol > 0, "outward orientation (positive enclosed volume)", str(vol))
    # labels
    fc = m["face"]
    cols = np.stack([fc["red"], fc["green"], fc["blue"]], axis=1).astype(int)
    tissue = np.array([PALETTE.get(tuple(c), 0) for c in cols])
    q = np.rint(fc["quality"]).astype(int)
    check(np.all(tissue > 0), "every face has a tissue colour from the palette", str(np.sum(tissue == 0)))
    check(np.all(q // 1000 == tissue), "face quality code agrees with the colour (tissue*1000+part)")
    parts = set((q % 1000).tolist())
    check({1, 2, 3} <= set(tissue.tolist()), "bone, cartilage and sternum present")
    check(all(100 * s + k in parts for s in (1, 2) for k in range(1, 13)), "every rib of both sides labelled")
    check({301, 302, 303} <= parts, "manubrium, body, xiphoid labelled")
    # Haller index measured on the saved surface
    h, T, ap = haller(V, F)
    print(f"measured Haller {h:.4f} (T {T:.2f} mm, AP {ap:.2f} mm)")
    check(abs(h - 4.0) <= 0.03 * 4.0, "requested Haller index 4.0 reproduced within 3%", f"{h:.4f}")
    # right side at -x
    right = V[np.unique(F[(q % 1000) == 107])]
    check(right[:, 0].max() < 0, "right ribs (side 1) at -x")
if os.path.exists(lms):
    L = read_ply(lms)
    codes = set(np.rint(L["vertex"]["quality"]).astype(int).tolist())
    need = {100 * s + k for s in (1, 2) for k in range(1, 13)} | {500, 501, 502, 503, 614, 615, 624, 625, 700, 701}
    check(need <= codes, "landmark codes present", str(sorted(need - codes)))

# the CT-based costal cartilage section: a circle of twice the rib's section area, named in the Log; the
# cartilages' surface grows with their perimeter (circle against the rib's ellipse: about 1.45 times)
def cartilage_area(path):
    m = read_ply(path)
    V, F = m["V"], np.array(m["F"])
    fc = m["face"]
    cols = np.stack([fc["red"], fc["green"], fc["blue"]], axis=1).astype(int)
    cart = np.array([PALETTE.get(tuple(c)) == 2 for c in cols])  # the costal cartilage's tissue code
    A, B, C = V[F[cart, 0]], V[F[cart, 1]], V[F[cart, 2]]
    counts, _ = edges_ok(F)
    return 0.5 * np.linalg.norm(np.cross(B - A, C - A), axis=1).sum(), bool(np.all(counts == 2))


out_ct = os.path.join(d, "cage_ct.ply")
r3 = run([], mlx.Script([create_ribcage(hallerIndex=4.0, edgeLength=5.0, cartilageSection=1)]), [(out_ct, "fc fq", 0)])
check(r3.rc == 0 and os.path.exists(out_ct), "the CT cartilage section runs", r3.stdout[-1500:])
if r3.rc == 0 and os.path.exists(out_ct) and os.path.exists(out):
    line = next(l for l in r3.log if l.startswith("Rib cage:"))
    rib = [float(v) for v in line.split("rib section ")[1].split(" mm")[0].split(" x ")]
    cart = [float(v) for v in line.split("costal cartilage section ")[1].split(" mm")[0].split(" x ")]
    print(f"rib section {rib}, cartilage section {cart}")
    check(abs(cart[0] - cart[1]) < 1e-3 and abs(cart[0] ** 2 - 2 * rib[0] * rib[1]) < 1e-2,
          "the Log names a circle of twice the rib's section area", line)
    (a_rib, _), (a_ct, closed) = cartilage_area(out), cartilage_area(out_ct)
    print(f"cartilage surface {a_rib:.0f} mm2 (the rib's section) against {a_ct:.0f} mm2 (CT)")
    check(closed, "the cage with CT cartilages is closed and edge-manifold")
    check(1.25 < a_ct / a_rib < 1.7, "the cartilages' surface grows with their perimeter", f"{a_ct / a_rib:.3f}")

# determinism: same parameters, same bytes
out2 = os.path.join(d, "cage2.ply")
r2 = run([], script(), [(out2, "fc fq vq", 0)])
check(r2.rc == 0 and os.path.exists(out2) and os.path.exists(out) and file_digest(out) == file_digest(out2),
      "same parameters give an identical file")
finish()
