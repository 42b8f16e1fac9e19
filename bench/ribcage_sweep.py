#!/usr/bin/env python3
"""Rib cage generator sweep: for every (age, pectus index, edge length) of a grid, generate the cage
with pectus_ribcage_cli --check and print one table row: faces, decimation passes, time, the index measured on
the mesh, and the self-intersecting faces by CGAL's exact check (must be 0), non-manifold edges, components.

    bench/ribcage_sweep.py [--build build] [--ages 5,8,11,14,17] [--indices 3,4,5,6,7] [--edges 2,6,8]
"""
import argparse
import os
import re
import subprocess
import sys
import time


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--build", default=os.path.join(os.path.dirname(__file__), "..", "build"))
    ap.add_argument("--ages", default="5,8,11,14,17")
    ap.add_argument("--indices", default="3,4,5,6,7")
    ap.add_argument("--edges", default="2,6,8")
    a = ap.parse_args()
    cli = os.path.join(a.build, "tools", "pectus_ribcage_cli")
    print(f"{'age':>4} {'index':>5} {'edge':>4} {'faces':>7} {'passes':>6} {'time s':>7} {'index mesh':>10} {'self-int':>8} "
          f"{'nm edges':>8} {'comps':>5}")
    bad = 0
    for edge in a.edges.split(","):
        for age in a.ages.split(","):
            for index in a.indices.split(","):
                t0 = time.time()
                p = subprocess.run([cli, edge, index, age, "12", "--check"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                   text=True)
                secs = time.time() - t0
                m = re.search(r"(\d+) faces \(\d+ raw, (\d+) decimation retries\)", p.stdout)
                h = re.search(r"mesh ([0-9.]+)", p.stdout)
                c = re.search(r"self-intersecting faces (\d+), non-manifold edges (\d+), components (\d+)", p.stdout)
                if p.returncode != 0 or not (m and h and c):
                    print(f"{age:>4} {index:>5} {edge:>4} failed: {p.stdout.strip().splitlines()[-1:]}")
                    bad += 1
                    continue
                bad += int(c.group(1)) > 0 or int(c.group(2)) > 0
                print(f"{age:>4} {index:>5} {edge:>4} {m.group(1):>7} {int(m.group(2)) + 1:>6} {secs:>7.1f} {h.group(1):>10} "
                      f"{c.group(1):>8} {c.group(2):>8} {c.group(3):>5}", flush=True)
    print(f"{bad} case(s) with a failure, a self-intersection or a non-manifold edge")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
