#!/usr/bin/env python3
"""pectus_fe vs CalculiX (ccx) on the same tetrahedral mesh: the 10 x 10 x 100 mm cantilever
(clamped at z = 0, tip shear load along y), TET4/TET10 (C3D4/C3D10), linear and NLGEOM.

  bench/fe_vs_ccx.py --tool build/tools/pectus_fe_cantilever [--cases small|bench|cage|cage-nl|all] [--check]
                     [--cage-tool build/tools/pectus_nuss_cli] [--solve-tool build/tools/pectus_fe_solve]
                     [--cage-maxvol 2.5] [--deck nuss.inp]

small: accuracy on small meshes (tip-centre displacement within 0.5%, --check makes it an exit code): linear,
       NLGEOM St Venant-Kirchhoff (*ELASTIC) and NLGEOM neo-Hookean (*HYPERELASTIC, NEO HOOKE);
bench: wall time and peak memory (/usr/bin/time -v) of both on a ~300k-tet TET4 mesh (linear) and a
       TET10 mesh of similar DOF count; both solvers get the same number of threads (--threads).
cage:  the same on the Nuss model itself: the default rib cage (thesis patient 1: boy of 8, index 5.3,
       5 mm edges) meshed by TetGen to ~300k TET4 (quality 2.0, max tet volume --cage-maxvol mm3), small
       strain, Fe = 10 N, written as a CalculiX deck by pectus_nuss_cli --inp (as the filter writes BASE.inp;
       not timed); then both programs run on that deck, whole process against whole process: pectus_fe_solve
       (reads the deck, solves, writes a .vtu with displacements, stresses and strains) and ccx (reads the
       deck, solves, writes .dat/.frd). Compared: the mean displacement of the sternal load patch's nodes
       (the quantity the calibration works on), wall time and peak memory.
cage-nl: the main job's own deck (nuss.inp of python/run_main.py: 64k TET10, neo-Hookean, NLGEOM, 10 fixed
       increments; made by a run of the main job, not timed, or given with --deck), both programs on it as
       for cage; also the Newton iterations of each (ours: pectus_fe_solve's count; ccx: its .sta file).
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile


def parse_kv(line):
    return {k: v for k, v in (t.split("=", 1) for t in line.split() if "=" in t)}


def timed(cmd, cwd, env):
    """runs cmd under /usr/bin/time -v; returns (stdout, wall seconds, peak RSS MB)"""
    p = subprocess.run(["/usr/bin/time", "-v"] + cmd, cwd=cwd, env=env, capture_output=True, text=True)
    if p.returncode != 0:
        raise RuntimeError("%s failed (rc %d):\n%s\n%s" % (cmd[0], p.returncode, p.stdout[-3000:], p.stderr[-3000:]))
    wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)", p.stderr).group(1)
    secs = 0.0
    for part in wall.split(":"):
        secs = secs * 60 + float(part)
    rss = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", p.stderr).group(1)) / 1024.0
    return p.stdout, secs, rss


def ccx_tip(dat_path, node):
    """last 'displacements ... for set OUT' block of the .dat file: (ux, uy, uz) of node"""
    txt = open(dat_path).read()
    blocks = re.split(r"\n\s*displacements \(vx,vy,vz\) for set OUT and time\s+\S+\s*\n", txt)
    if len(blocks) < 2:
        raise RuntimeError("no displacement block in " + dat_path)
    for line in blocks[-1].splitlines():
        f = line.split()
        if len(f) == 4 and f[0] == str(node):
            return tuple(float(x) for x in f[1:])
    raise RuntimeError("node %s not in %s" % (node, dat_path))


def run_case(a, work, name, n, order, load, nlgeom, steps, env, bench, material="svk"):
    inp = os.path.join(work, name + ".inp")
    base = [a.tool, "--n"] + [str(x) for x in n] + ["--order", str(order), "--load", str(load), "--steps", str(steps),
                                                    "--material", material]
    if nlgeom:
        base.append("--nlgeom")
    # the deck from our mesh (not timed), then our solve (timed), then ccx on the deck (timed)
    subprocess.run(base + ["--no-solve", "--inp", inp], check=True, capture_output=True, text=True, env=env)
    out, t_ours, m_ours = timed(base, work, env)
    ours = parse_kv(out.strip().splitlines()[-1])
    _, t_ccx, m_ccx = timed([a.ccx, "-i", name], work, env)
    ux, uy, uz = ccx_tip(os.path.join(work, name + ".dat"), ours["tip_node"])
    u_ours = float(ours["tip_uy"])
    rel = abs(u_ours - uy) / abs(uy)
    r = dict(name=name, tets=int(ours["tets"]), dofs=int(ours["dofs"]), ours=u_ours, ccx=uy, rel=rel,
             t_ours=t_ours, t_ccx=t_ccx, m_ours=m_ours, m_ccx=m_ccx, solve_s=float(ours["solve_s"]),
             factor_s=float(ours["last_factor_s"]), it=int(ours["newton_it"]))
    if not bench:  # the deck read back by pectus_fe_solve (its print node is the tip) solves to the same tip
        kv = parse_kv(subprocess.run([a.solve_tool, inp], check=True, capture_output=True, text=True,
                                     env=env).stdout.strip().splitlines()[-1])
        r["deck_rel"] = abs(float(kv["mean_uy"]) - u_ours) / abs(u_ours)
    return r


def ccx_mean_disp(dat_path):
    """mean (ux, uy, uz) over the nodes of the last displacement block of a .dat file"""
    txt = open(dat_path).read()
    blocks = re.split(r"\n\s*displacements \(vx,vy,vz\) for set OUT and time\s+\S+\s*\n", txt)
    if len(blocks) < 2:
        raise RuntimeError("no displacement block in " + dat_path)
    v = [tuple(float(x) for x in f[1:]) for f in (l.split() for l in blocks[-1].splitlines()) if len(f) == 4]
    return tuple(sum(c) / len(v) for c in zip(*v)), len(v)


def run_cage_case(a, work, env):
    name = "cage_lin_tet4"
    inp = os.path.join(work, name + ".inp")
    gen = [a.cage_tool, "--edge", "5", "--haller", "5.3", "--age", "8", "--quality", "2.0", "--maxvol",
           str(a.cage_maxvol), "--order", "1", "--force", "10", "--linear", "--inp", inp]
    subprocess.run(gen, check=True, capture_output=True, text=True, env=env)  # the deck, not timed
    out, t_ours, m_ours = timed([a.solve_tool, inp, "--vtu", os.path.join(work, name + "_ours.vtu")], work, env)
    kv = parse_kv(out.strip().splitlines()[-1])
    u_ours = tuple(float(kv[k]) for k in ("mean_ux", "mean_uy", "mean_uz"))
    _, t_ccx, m_ccx = timed([a.ccx, "-i", name], work, env)
    u_ccx, n = ccx_mean_disp(os.path.join(work, name + ".dat"))
    if n != int(kv["print_nodes"]):
        raise RuntimeError("ccx printed %d nodes, ours %s" % (n, kv["print_nodes"]))
    diff = sum((x - y) ** 2 for x, y in zip(u_ours, u_ccx)) ** 0.5
    rel = diff / sum(y * y for y in u_ccx) ** 0.5
    return dict(name=name, tets=int(kv["tets"]), dofs=int(kv["dofs"]), ours=u_ours[1], ccx=u_ccx[1], rel=rel,
                t_ours=t_ours, t_ccx=t_ccx, m_ours=m_ours, m_ccx=m_ccx,
                solve_s=float(kv["setup_s"]) + float(kv["solve_s"]))


def ccx_iterations(work, name):
    """Newton iterations of a ccx run: the ITRS column of its .sta file, summed over the increments"""
    total = 0
    for line in open(os.path.join(work, name + ".sta")):
        f = line.split()
        if len(f) >= 4 and all(x.isdigit() for x in f[:4]):
            total += int(f[3])
    return total


def main_job_deck(a, work, env):
    """the main job's CalculiX deck (nuss.inp: TET10, neo-Hookean, NLGEOM, 10 increments), from --deck or a
    fresh run of python/run_main.py through the build's MeshLab (not timed)"""
    if a.deck:
        return os.path.abspath(a.deck)
    out = os.path.join(work, "main_job")
    root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    run_env = dict(env, PECTUS_PREFIX=env.get("PECTUS_PREFIX", os.path.join(root, "build", "prefix")))
    subprocess.run([sys.executable, os.path.join(root, "python", "run_main.py"), out], check=True,
                   capture_output=True, text=True, env=run_env)
    return os.path.join(out, "nuss.inp")


def run_cage_nl_case(a, work, env):
    """both programs on the main job's own deck, whole process against whole process"""
    name = "cage_nl_tet10"
    shutil.copy(main_job_deck(a, work, env), os.path.join(work, name + ".inp"))
    out, t_ours, m_ours = timed([a.solve_tool, name + ".inp", "--vtu", name + "_ours.vtu"], work, env)
    kv = parse_kv(out.strip().splitlines()[-1])
    u_ours = tuple(float(kv[k]) for k in ("mean_ux", "mean_uy", "mean_uz"))
    _, t_ccx, m_ccx = timed([a.ccx, "-i", name], work, env)
    u_ccx, _ = ccx_mean_disp(os.path.join(work, name + ".dat"))
    diff = sum((x - y) ** 2 for x, y in zip(u_ours, u_ccx)) ** 0.5
    rel = diff / sum(y * y for y in u_ccx) ** 0.5
    return dict(name=name, tets=int(kv["tets"]), dofs=int(kv["dofs"]), ours=u_ours[1], ccx=u_ccx[1], rel=rel,
                t_ours=t_ours, t_ccx=t_ccx, m_ours=m_ours, m_ccx=m_ccx,
                solve_s=float(kv["setup_s"]) + float(kv["solve_s"]), it=int(kv["newton_it"]),
                it_ccx=ccx_iterations(work, name))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--tool", required=True)
    ap.add_argument("--ccx", default=shutil.which("ccx") or "ccx")
    ap.add_argument("--cases", default="small", choices=["small", "bench", "cage", "cage-nl", "all"])
    ap.add_argument("--cage-tool", help="pectus_nuss_cli (default: beside --tool, ../pectus_nuss_cli)")
    ap.add_argument("--solve-tool", help="pectus_fe_solve (default: beside --tool)")
    ap.add_argument("--cage-maxvol", type=float, default=2.5, help="TetGen maximum tet volume (mm3) of the cage case")
    ap.add_argument("--deck", help="cage-nl: the main job's nuss.inp (default: made by a run of python/run_main.py)")
    ap.add_argument("--check", action="store_true", help="exit 1 if a tip displacement differs by more than 0.5%%")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--keep", help="keep the decks and results in this folder")
    a = ap.parse_args()
    a.tool = os.path.abspath(a.tool)
    a.cage_tool = os.path.abspath(a.cage_tool or os.path.join(os.path.dirname(a.tool), "..", "pectus_nuss_cli"))
    a.solve_tool = os.path.abspath(a.solve_tool or os.path.join(os.path.dirname(a.tool), "pectus_fe_solve"))
    env = dict(os.environ, OMP_NUM_THREADS=str(a.threads), OPENBLAS_NUM_THREADS=str(a.threads),
               CCX_NPROC_EQUATION_SOLVER=str(a.threads), CCX_NPROC_STIFFNESS=str(a.threads))
    work = a.keep or tempfile.mkdtemp(prefix="fe_vs_ccx_")
    os.makedirs(work, exist_ok=True)
    cases = []
    if a.cases in ("small", "all"):
        for order in (1, 2):
            cases.append(("lin_tet%d" % (4 if order == 1 else 10), (2, 2, 20), order, 20.0, False, 1, False))
            cases.append(("nlgeom_tet%d" % (4 if order == 1 else 10), (2, 2, 20), order, 700.0, True, 10, False))
            # the same with CalculiX's NEO HOOKE (*HYPERELASTIC in the deck; ours: neo-hookean-ccx)
            cases.append(("nlgeom_neo_tet%d" % (4 if order == 1 else 10), (2, 2, 20), order, 700.0, True, 10, False,
                          "neo-hookean-ccx"))
    if a.cases in ("bench", "all"):
        cases.append(("bench_lin_tet4_300k", (20, 20, 125), 1, 20.0, False, 1, True))
        cases.append(("bench_lin_tet10", (10, 10, 50), 2, 20.0, False, 1, True))
    rows, failed = [], False
    for c in cases:
        r = run_case(a, work, *c[:6], env=env, bench=c[6], material=c[7] if len(c) > 7 else "svk")
        rows.append(r)
        failed |= not r["rel"] <= 0.005
        failed |= not r.get("deck_rel", 0.0) <= 1e-6
    if a.cases in ("cage", "all"):
        rows.append(run_cage_case(a, work, env))
        failed |= not rows[-1]["rel"] <= 0.005
    if a.cases in ("cage-nl", "all"):
        rows.append(run_cage_nl_case(a, work, env))
        failed |= not rows[-1]["rel"] <= 0.005
    print("%-22s %8s %8s %12s %12s %9s %9s %9s %9s %9s %8s %8s" % (
        "case", "tets", "dofs", "tip_uy_ours", "tip_uy_ccx", "rel_diff", "ours_s", "ccx_s", "ratio", "solve_s",
        "ours_MB", "ccx_MB"))
    for r in rows:
        print("%-22s %8d %8d %12.6f %12.6f %9.2e %9.2f %9.2f %9.3f %9.2f %8.0f %8.0f" % (
            r["name"], r["tets"], r["dofs"], r["ours"], r["ccx"], r["rel"], r["t_ours"], r["t_ccx"],
            r["t_ours"] / r["t_ccx"], r["solve_s"], r["m_ours"], r["m_ccx"]))
    for r in rows:
        if "it_ccx" in r:
            print("%-22s Newton iterations: ours %d, ccx %d (%.2f x); wall time ours / ccx %.2f"
                  % (r["name"], r["it"], r["it_ccx"], r["it"] / r["it_ccx"], r["t_ours"] / r["t_ccx"]))
    for r in rows:
        if "deck_rel" in r:
            print("%-22s deck read back by pectus_fe_solve: tip uy differs by %.2e (relative) from the model in memory"
                  % (r["name"], r["deck_rel"]))
    print("(tip_uy: the cantilever's tip centre, or for the cage rows the sternal patch's mean uy, rel_diff there "
          "over the mean displacement vector; ours_s/ccx_s: wall time of the whole process incl. meshing/assembly/IO "
          "(the cage row: both read the same deck and write their results); solve_s: our setup + solve; "
          "threads=%d; files in %s)" % (a.threads, work))
    if not a.keep:
        shutil.rmtree(work, ignore_errors=True)
    if a.check and failed:
        print("FAIL: tip displacement differs from CalculiX by more than 0.5%, or the deck read back by more than 1e-6")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
