#!/usr/bin/python3
"""The FE example as shipped (filter_nuss_fea/examples/nuss_fea.mlx: the thesis' patient 1, TET10, large
displacement, calibrated to 44.7 mm) and the full main job (python/run_main.py) on every MeshLab release that
is made here (2020.09 always; 2022.02 and 2025.07 when scripts/host.sh made them), side by side, with each
figure's largest difference from 2020.09.

    bench/hosts_fe.py [--hosts 2020.09,2025.07] [--skip-main] [--out /tmp/pectus-hosts-fe]

Needs build/prefix (scripts/setup.sh) and, for a newer release, its userland and build (scripts/host.sh).
"""
import argparse
import csv
import json
import os
import platform
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, os.path.join(ROOT, "python"))
import pectus_mlx as mlx  # noqa: E402

FE = "Pectus: Nuss Procedure FE Analysis"
EXAMPLE = os.path.join(ROOT, "filter_nuss_fea", "examples", "nuss_fea.mlx")
FE_KEYS = (("tets", "tets", "{:,.0f}"), ("force_N", "Fe N", "{:.4f}"), ("max_strain", "max strain", "{:.4f}"),
           ("newton_iterations", "Newton it.", "{:.0f}"))
MAIN_KEYS = (("fe_tets", "tets", "{:,.0f}"), ("force_N", "Fe N", "{:.4f}"), ("slice_change_cm3", "slice gain cm³", "{:.2f}"),
             ("envelope_change_cm3", "envelope gain cm³", "{:.2f}"), ("haller_index_after", "index after", "{:.3f}"))


def fe_example(host: str, out: str) -> dict:
    """the FE example's values on one release, and its wall time"""
    cwd = os.path.join(out, f"fe-{host}")
    os.makedirs(cwd, exist_ok=True)
    t0 = time.time()
    r = mlx.run([], EXAMPLE, [], host=host, cwd=cwd, timeout=4 * 3600)
    values = {k: r.get(k, FE) for k, _, _ in FE_KEYS}
    values["wall"] = time.time() - t0
    values["rc"] = r.rc
    return values


def main_job(host: str, out: str) -> dict:
    """summary.csv of the full main job on one release, and its wall time"""
    folder = os.path.join(out, f"main-{host}")
    t0 = time.time()
    p = subprocess.run(["/usr/bin/python3", os.path.join(ROOT, "python", "run_main.py"), folder],
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                       env=dict(os.environ, PECTUS_MESHLAB_HOST=host))
    rows = list(csv.DictReader(open(os.path.join(folder, "summary.csv")))) if p.returncode == 0 else [{}]
    values = {k: float(rows[0][k]) if rows[0].get(k) not in (None, "") else None for k, _, _ in MAIN_KEYS}
    if p.returncode == 0:  # the force unrounded (summary.csv has it to 0.01 N): the FE filter's own results file
        with open(os.path.join(folder, "nuss_results.json")) as fh:
            values["force_N"] = json.load(fh)["results"]["force_N"]
    values["wall"] = time.time() - t0
    values["rc"] = p.returncode
    return values


def table(title: str, keys, results: dict) -> None:
    """one row per release, then the largest relative difference from 2020.09 per column"""
    hosts = list(results)
    print(f"\n{title}")
    print("| MeshLab | " + " | ".join(name for _, name, _ in keys) + " | wall s |")
    print("|---|" + "---:|" * (len(keys) + 1))
    for h in hosts:
        v = results[h]
        cells = ["failed" if v["rc"] or v[k] is None else spec.format(v[k]) for k, _, spec in keys]
        print(f"| {h} | " + " | ".join(cells) + f" | {v['wall']:.0f} |")
    ref = results.get("2020.09")
    if ref and len(hosts) > 1:
        diffs = []
        for k, _, _ in keys:
            d = [abs(results[h][k] - ref[k]) / abs(ref[k]) for h in hosts[1:]
                 if results[h][k] is not None and ref[k] not in (None, 0)]
            diffs.append(f"{100 * max(d):.2g} %" if d else "—")
        print("| largest difference from 2020.09 | " + " | ".join(diffs) + " | |")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--hosts", default=",".join(h for h in mlx.HOSTS if mlx.host_made(h)),
                    help="the releases to run (default: every one made here)")
    ap.add_argument("--skip-main", action="store_true", help="only the FE example")
    ap.add_argument("--out", default="/tmp/pectus-hosts-fe")
    a = ap.parse_args()
    hosts = a.hosts.split(",")
    missing = [h for h in hosts if not mlx.host_made(h)]
    if missing:
        ap.error(f"not made here: {', '.join(missing)} (scripts/host.sh {missing[0]})")
    os.makedirs(a.out, exist_ok=True)
    fe = {}
    main_results = {}
    for h in hosts:
        fe[h] = fe_example(h, a.out)
        print(f"FE example on {h}: rc {fe[h]['rc']}, Fe {fe[h]['force_N']} N, {fe[h]['wall']:.0f} s", flush=True)
        if not a.skip_main:
            main_results[h] = main_job(h, a.out)
            print(f"main job on {h}: rc {main_results[h]['rc']}, Fe {main_results[h]['force']} N, "
                  f"{main_results[h]['wall']:.0f} s", flush=True)
    print(f"\n{platform.node()}, {os.cpu_count()} cores, {time.strftime('%Y-%m-%d')}")
    table("The FE example as shipped (nuss_fea.mlx: TET10, large displacement, calibrated to 44.7 mm)", FE_KEYS, fe)
    if main_results:
        table("The main job (python/run_main.py)", MAIN_KEYS, main_results)
    failed = any(v["rc"] for v in list(fe.values()) + list(main_results.values()))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
