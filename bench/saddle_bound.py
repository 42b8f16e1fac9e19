#!/usr/bin/python3
"""How good can fixed-connectivity smoothing get on the benchmark's triangle saddle? A slow, exact
optimiser on the same input (bench/mga_smooth.py's saddle_triangles): every free node (x, y) at once, on
the exact saddle z = x^2/10 - y^2/4, boundary nodes fixed, maximising the mean alpha with scipy's L-BFGS-B
and analytic gradients, restarted while it gains; folded triangles (signed area in the plane <= 0) are
penalised. A local optimum of the plain mean (what the thesis' fitness sums node by node), not a proof
of an upper bound. Started from the
input and from MGA's result (if given). Prints the mean/min alpha reached, and the min alpha of the
triangles whose three nodes are all fixed (no smoother with these fixed nodes can change them).

    bench/saddle_bound.py [--start mga_result.off]
"""
import argparse
import os
import sys
from collections import Counter

import numpy as np
from scipy.optimize import minimize

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mga_smooth import read_off, saddle, saddle_triangles  # noqa: E402

K = 2 * np.sqrt(3)


def alpha_and_grad(P, T):
    a, b, c = P[T[:, 0]], P[T[:, 1]], P[T[:, 2]]
    n = np.cross(b - a, c - a)
    A = np.linalg.norm(n, axis=1)
    S = np.sum((b - a) ** 2, 1) + np.sum((c - b) ** 2, 1) + np.sum((a - c) ** 2, 1)
    al = K * A / S
    nh = n / np.maximum(A, 1e-300)[:, None]
    dA = [np.cross(b - c, nh), np.cross(c - a, nh), np.cross(a - b, nh)]
    dS = [2 * (2 * a - b - c), 2 * (2 * b - c - a), 2 * (2 * c - a - b)]
    G = np.zeros_like(P)
    for k in range(3):
        g = K * (dA[k] * S[:, None] - A[:, None] * dS[k]) / (S ** 2)[:, None]
        np.add.at(G, T[:, k], g)
    signed = (b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0]
    return al, G, signed


def optimise(V, T, free, start_xy):
    xy0 = start_xy[free, :2].ravel()
    nT = len(T)

    def f(v):
        P = V.copy()
        P[free, :2] = v.reshape(-1, 2)
        P[free, 2] = saddle(P[free, 0], P[free, 1])
        al, G, signed = alpha_and_grad(P, T)
        folded = signed <= 0
        val = -al.sum() / nT + 10.0 * folded.sum()
        g = np.zeros((len(free), 2))
        Gf = G[free]
        g[:, 0] = Gf[:, 0] + Gf[:, 2] * P[free, 0] / 5
        g[:, 1] = Gf[:, 1] - Gf[:, 2] * P[free, 1] / 2
        return val, -g.ravel() / nT

    # the fold penalty is discontinuous, so the line search may give up: restart from where it stopped
    nit, last = 0, None
    for _ in range(50):
        r = minimize(f, xy0, jac=True, method="L-BFGS-B", options={"maxiter": 20000, "maxfun": 40000, "ftol": 1e-14, "gtol": 1e-10})
        nit += r.nit
        if last is not None and r.fun > last - 1e-9:
            break
        last, xy0 = r.fun, r.x
    P = V.copy()
    P[free, :2] = r.x.reshape(-1, 2)
    P[free, 2] = saddle(P[free, 0], P[free, 1])
    al, _, signed = alpha_and_grad(P, T)
    return al, int((signed <= 0).sum()), f"{nit} iterations"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--start", help="an OFF with the same vertices (e.g. MGA's output) as a second start")
    args = ap.parse_args()
    V, F = saddle_triangles()
    T = np.array(F)
    edges = Counter(tuple(sorted((f[i], f[(i + 1) % 3]))) for f in F for i in range(3))
    boundary = {v for e, c in edges.items() if c == 1 for v in e}
    free = np.array([i for i in range(len(V)) if i not in boundary])
    al0, _, _ = alpha_and_grad(V, T)
    allfixed = np.array([all(v in boundary for v in f) for f in F])
    print(f"saddle: {len(V)} nodes, {len(F)} triangles, {len(free)} free; input alpha mean {al0.mean():.4f} min {al0.min():.4f}")
    print(f"triangles with all three nodes fixed: {allfixed.sum()}, their min alpha {al0[allfixed].min():.4f} "
          f"(a bound on the mesh minimum for any smoother that keeps the boundary)")
    starts = [("input", V)]
    if args.start:
        starts.append((os.path.basename(args.start), read_off(args.start)))
    for name, S in starts:
        al, folded, nit = optimise(V, T, free, S)
        print(f"L-BFGS-B on the exact saddle from {name}: alpha mean {al.mean():.4f} min {al.min():.4f}, "
              f"{folded} folded, {nit}")


if __name__ == "__main__":
    main()
