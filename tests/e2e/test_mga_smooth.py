"""End to end: 'Pectus: MGA Surface Mesh Smoothing' and 'Pectus: Gradient Surface Mesh Smoothing (Baseline)' through the
real meshlabserver, each from its example script."""
import os
import re

import numpy as np

from pectus_meshes import alpha
from harness import SOURCE, check, check_refused, example_script, finish, grid, read_ply, run, workdir, write_off, write_ply

EXAMPLES = {"MGA": os.path.join(SOURCE, "filter_mga_smooth", "examples", "mga_smooth.mlx"),
            "Gradient": os.path.join(SOURCE, "filter_mga_smooth", "examples", "gradient_smooth.mlx")}
d = workdir("mga")


def script(name: str, example: str = "MGA", **values) -> str:
    """an example script with some parameter values replaced"""
    return example_script(EXAMPLES[example], d, name, **values)




def log_numbers(log, what):
    """(before, after) of 'worst alpha 0.1 -> 0.5' style Log entries"""
    m = re.search(what + r" (\d+\.\d+) -> (\d+\.\d+)", log)
    return (float(m.group(1)), float(m.group(2))) if m else None


# 1. a jittered triangle grid on a smooth dome: quality rises, boundary fixed, nodes stay on the surface
def dome(x, y):
    return 0.02 * ((x - 5) ** 2 + (y - 5) ** 2)


results, logs = {}, {}
for ex in EXAMPLES:
    V, F = grid(10, quads=False, jitter=0.35, seed=4, z=dome)
    inp = write_ply(os.path.join(d, "tri.ply"), V, F)
    out = os.path.join(d, f"tri_{ex}.ply")
    r = run([inp], script("tri" + ex, ex, maxSweeps=6, **({"seed": 3} if ex == "MGA" else {})), [(out, "vq fq fc sa")])
    check(r.rc == 0, f"{ex}: triangle mesh: meshlabserver exit 0", r.stdout[-2000:])
    m = read_ply(out)
    W = np.array(m["V"], float)
    check(W.shape == V.shape, f"{ex}: same vertex count", str(W.shape))
    Fo = m["F"]
    check([list(f) for f in Fo] == [list(f) for f in F], f"{ex}: connectivity unchanged")
    before = np.array([alpha(*(V[i] for i in f)) for f in F])
    after = np.array([alpha(*(W[i] for i in f)) for f in F])
    check(after.mean() > before.mean() + 0.02, f"{ex}: mean alpha rises", f"{before.mean():.4f} -> {after.mean():.4f}")
    check(after.min() > before.min(), f"{ex}: min alpha rises", f"{before.min():.4f} -> {after.min():.4f}")
    bnd = [j * 11 + i for j in range(11) for i in range(11) if i in (0, 10) or j in (0, 10)]
    check(np.allclose(W[bnd], V[bnd], atol=1e-5), f"{ex}: boundary nodes do not move")
    moved = np.linalg.norm(W - V, axis=1) > 1e-4
    check(moved.sum() > 40, f"{ex}: interior nodes moved", str(moved.sum()))
    dev = np.max(np.abs(W[:, 2] - dome(W[:, 0], W[:, 1])))
    check(dev < 2e-3, f"{ex}: nodes stay on the surface (max |z - dome| small)", str(dev))
    q = m["face"]["quality"]
    check(np.allclose(q, after, atol=1e-4), f"{ex}: face quality = alpha after smoothing", str(np.max(np.abs(q - after))))
    check("red" in m["face"], f"{ex}: face colours saved")
    log = "\n".join(r.log)
    wa, ma = log_numbers(log, "worst alpha"), log_numbers(log, "mean alpha")
    check(wa is not None and ma is not None, f"{ex}: Log line with worst/mean alpha before and after", log)
    if ma:
        check(abs(ma[0] - before.mean()) < 1e-3 and abs(ma[1] - after.mean()) < 1e-3, f"{ex}: Log mean matches", log)
    check(re.search(r"nodes moved \d+ of 81 free; folds \(elements facing against their edge neighbours\) 0 -> 0, "
                    r"0 new; sweeps \d+; time", log) is not None, f"{ex}: Log: nodes moved, folds, sweeps, time", log)
    check(re.search(ex + r" smoothing: fixed nodes: 40 boundary, 0 feature, 0 singular, 0 by the selection", log)
          is not None, f"{ex}: Log: fixed nodes by class", log)
    check(re.search(r"elements folded against a node's surface normal 0 -> 0", log) is not None,
          f"{ex}: Log: no folded element before or after", log)
    results[ex], logs[ex] = W, log
    print(log)

# 1b. the final worst-element pass: Log says so, the minimum does not drop below the default run's
out3 = os.path.join(d, "tri_pass.ply")
r = run([inp], script("triPass", "Gradient", maxSweeps=6, minPassBelow=0.95), [(out3, "vq sa")])
log = "\n".join(r.log)
check(r.rc == 0 and re.search(r"sweeps \d+ \+ [1-3] worst-element; time", log) is not None,
      "final worst-element pass runs and is logged", log)
if r.rc == 0:
    W3 = np.array(read_ply(out3)["V"], float)
    a3 = np.array([alpha(*(W3[i] for i in f)) for f in F])
    a2 = np.array([alpha(*(results["Gradient"][i] for i in f)) for f in F])
    check(a3.min() >= a2.min() - 1e-6, "final pass: min alpha not below the run without it", f"{a2.min():.4f} -> {a3.min():.4f}")

def run_alpha(name, script_path):
    """meshlabserver on the dome grid with a script: (exit code, Log text, per-triangle alpha of the result or None)"""
    out = os.path.join(d, name + ".ply")
    r = run([inp], script_path, [(out, "vq sa")])
    log = "\n".join(r.log)
    if r.rc != 0:
        return r.rc, log, None
    W = np.array(read_ply(out)["V"], float)
    return r.rc, log, np.array([alpha(*(W[i] for i in f)) for f in F])


def evaluations(log):
    return int(re.search(r"(\d+) fitness evaluations", log).group(1))


# 1c. the guided element search: named in the Log, fewer fitness evaluations than every element, still improves
rc, log, ag = run_alpha("tri_guided", script("triGuided", "MGA", maxSweeps=6, seed=3, elementSearch=1))
check(rc == 0 and "MGA smoothing, guided element search" in log, "guided element search runs and is logged", log)
if rc == 0:
    a1 = np.array([alpha(*(results["MGA"][i] for i in f)) for f in F])
    check(ag.mean() > a1.mean() - 0.005 and ag.min() > before.min(), "guided: mean alpha near the full search's, min rises",
          f"{a1.mean():.4f} / {ag.mean():.4f}, min {ag.min():.4f}")
    ev = [evaluations(logs["MGA"]), evaluations(log)]
    check(ev[1] < 0.7 * ev[0], "guided: fewer fitness evaluations than every element", str(ev))
    # 1d. the guided local search: logged, improves, fewer evaluations again
    rc, logl, al = run_alpha("tri_local", script("triLocal", "MGA", maxSweeps=6, seed=3, elementSearch=2))
    check(rc == 0 and "MGA smoothing, guided local element search" in logl, "guided local search runs and is logged", logl)
    if rc == 0:
        check(al.mean() > before.mean() + 0.02 and al.min() > before.min(), "guided local: mean and min alpha rise",
              f"{before.mean():.4f} -> {al.mean():.4f}, min {al.min():.4f}")
        check(evaluations(logl) < ev[1], "guided local: fewer fitness evaluations than guided", f"{evaluations(logl)} / {ev[1]}")
    # 1e. the fast example as shipped (guided local, 5 sweeps x 3 generations)
    rc, logf, af = run_alpha("tri_fast", os.path.join(SOURCE, "filter_mga_smooth", "examples", "mga_smooth_fast.mlx"))
    check(rc == 0 and "guided local element search" in logf and "sweeps 5" in logf,
          "mga_smooth_fast.mlx runs: guided local, 5 sweeps", logf[-600:])
    if rc == 0:
        check(af.mean() > before.mean() + 0.02 and af.min() > before.min(), "fast example: mean and min alpha rise",
              f"{before.mean():.4f} -> {af.mean():.4f}, min {af.min():.4f}")

# 2. the same seed gives the same file; another seed another result
out2 = os.path.join(d, "tri_s2.ply")
r = run([inp], script("triMGA", "MGA", maxSweeps=6, seed=3), [(out2, "vq sa")])
check(r.rc == 0 and np.array_equal(np.array(read_ply(out2)["V"]), results["MGA"]), "reproducible with the same seed")
r = run([inp], script("triMGA4", "MGA", maxSweeps=6, seed=4), [(out2, "vq sa")])
check(r.rc == 0 and not np.array_equal(np.array(read_ply(out2)["V"]), results["MGA"]), "another seed, another result")

Vq, Fq = grid(8, quads=True, jitter=0.3, seed=6)
inq = write_off(os.path.join(d, "quad.off"), Vq, Fq)
one = write_ply(os.path.join(d, "one.ply"), np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float), [[0, 1, 2]])
nmV = np.vstack([V, [[0.5, 0.5, 1.0]]])
nm = write_ply(os.path.join(d, "nonmanifold.ply"), nmV, F + [[0, 12, len(V)]])
for ex in EXAMPLES:
    # 3. quads (OFF sets faux edges): Auto picks beta, quality rises
    outq = os.path.join(d, f"quad_{ex}.ply")
    r = run([inq], script("quad" + ex, ex, maxSweeps=6), [(outq, "fq sa")])
    check(r.rc == 0, f"{ex}: quad mesh: exit 0", r.stdout[-2000:])
    log = "\n".join(r.log)
    mb, wb = log_numbers(log, "mean beta"), log_numbers(log, "worst beta")
    check(mb is not None and mb[1] > mb[0] + 0.02 and wb[1] > wb[0], f"{ex}: quads: mean and worst beta rise", log)
    check("64 elements" in log, f"{ex}: 64 quads", log)
    qq = read_ply(outq)["face"]["quality"]
    check(len(qq) == 128 and abs(np.mean(qq) - mb[1]) < 1e-3 if mb else False, f"{ex}: per-face beta written", str(np.mean(qq)))

    # 4. bad input: a clear message, non-zero exit
    bad = {
        "quads asked of triangles": (inp, script("b1" + ex, ex, elementType=2), "holds only triangles"),
        **({"population 2": (inp, script("b2" + ex, ex, population=2), "population"),
            "accuracy 0": (inp, script("b3" + ex, ex, accuracy=0), "accuracy")} if ex == "MGA" else
           {"CG iterations 0": (inp, script("b2" + ex, ex, cgIterations=0), "cgIterations"),
            "NaN tolerance": (inp, script("b3" + ex, ex, tolerance="nan"), "tolerance")}),
        "singular angle 0": (inp, script("b7" + ex, ex, singularAngle=0), "singularAngle"),
        "guard 2": (inp, script("b8" + ex, ex, worstGuard=2), "worstGuard"),
        "final pass below -1": (inp, script("b9" + ex, ex, minPassBelow=-1), "minPassBelow"),
        "no free node": (one, script("b4" + ex, ex), "no free node"),
        "non-manifold edge": (nm, script("b5" + ex, ex), "manifold"),
        "smooth only selected, nothing selected": (inp, script("b6" + ex, ex, selectionMode=1), "no selected vertex"),
    }
    for what, (path, s, msg) in bad.items():
        o = os.path.join(d, "bad.ply")
        if os.path.exists(o):
            os.remove(o)
        r = run([path], s, [(o, "sa")])
        check_refused(r, msg, f"{ex}: {what}")
finish()
