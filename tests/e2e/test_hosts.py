"""End to end on a newer MeshLab ($PECTUS_OTHER_HOST: 2025.07, the default, or 2022.02): shipped example
scripts through pectus-mlrun in that release's Debian userland (scripts/mlrun.sh --host 2025.07), each next
to the same script through bookworm's meshlabserver 2020.09.

Both MeshLab builds are float. The layers each host saves must agree to float rounding: the same vertex and
face counts, the same face quality, positions within a few float ulps of the model size; the Log figures
the same to their printed digits (g++ 12 + Eigen 3.4 against g++ 16 + Eigen 5.0 give bit-identical results
here). The rib cage too, vertex by vertex, and then the FE example's tet mesh and force and the main job's
figures (within 2 %).
Then the failure paths on the newer release: a refused input is a message and exit 255 with the layers unchanged,
a parameter of the wrong type is a message and exit 2 (meshlabserver aborts there), a missing script too.
"""
import csv
import os
import re
import subprocess

import numpy as np

from harness import PREFIX, SOURCE, as_printed, check, finish, grid, log_figure, need_host, read_ply, workdir, write_ply
import pectus_mlx as mlx

OTHER = os.environ.get("PECTUS_OTHER_HOST", "2025.07")
HOSTS = ("2020.09", OTHER)
need_host(OTHER)
d = workdir("host" + OTHER)
EX = lambda *p: os.path.join(SOURCE, *p)  # noqa: E731


def out(name, host):
    return os.path.join(d, f"{name}-{host}.ply")


def figures(log, pattern):
    """every number in the Log lines matching the pattern, as printed"""
    return [re.findall(r"-?\d+\.\d+|-?\d+", l) for l in log if re.search(pattern, l)]


def compare_layers(name, tol_rel=1e-5, quality_tol=1e-5):
    a, b = (read_ply(out(name, h)) for h in HOSTS)
    check(len(a["V"]) == len(b["V"]) and len(a["F"]) == len(b["F"]),
          f"{name}: same vertex and face counts on both hosts", f"{len(a['V'])}/{len(a['F'])} vs {len(b['V'])}/{len(b['F'])}")
    if len(a["V"]) != len(b["V"]) or len(a["F"]) != len(b["F"]):
        return
    size = float(np.max(np.ptp(a["V"], axis=0))) if len(a["V"]) else 1.0
    dv = float(np.max(np.abs(a["V"] - b["V"]))) if len(a["V"]) else 0.0
    check(dv <= tol_rel * size, f"{name}: positions agree to {tol_rel:g} of the model size ({size:.1f})",
          f"max difference {dv:g}")
    print(f"     {name}: {len(a['V'])} vertices, {len(a['F'])} faces; max position difference {dv:.3g} (model size {size:.1f}; "
          f"float ulp there {np.spacing(np.float32(size)):.3g})")
    check(a["F"] == b["F"], f"{name}: the same faces, in the same order")
    if "quality" in a.get("face", {}):
        dq = float(np.max(np.abs(a["face"]["quality"] - b["face"]["quality"])))
        check(dq <= quality_tol, f"{name}: face quality agrees to {quality_tol:g}", f"max difference {dq:g}")


# 1. element quality of a jittered grid: the example script as shipped
V, F = grid(8, quads=False, jitter=0.3, seed=5)
grid_ply = write_ply(os.path.join(d, "grid.ply"), V, F)
res = {h: mlx.run([grid_ply], EX("filter_mga_smooth", "examples", "element_quality.mlx"),
                  [(out("quality", h), "fq fc sa", 0)], host=h) for h in HOSTS}
for h, r in res.items():
    check(r.rc == 0, f"element quality on {h}: exit 0", r.stdout[-1500:])
check(figures(res["2020.09"].log, "alpha") == figures(res[OTHER].log, "alpha") and figures(res[OTHER].log, "alpha"),
      "element quality: the same Log figures on both hosts", "\n".join(res["2020.09"].log + res[OTHER].log))
compare_layers("quality", tol_rel=0, quality_tol=0)
# the figures come back as values on both hosts (2020.09: the plugin writes them; the newer: pectus-mlrun from the
# filter's return values), the same
vals = {h: {k: r.get(k) for k in ("elements", "quality_min", "quality_mean", "quality_max", "element_kind")}
        for h, r in res.items()}
check(vals["2020.09"]["elements"] is not None and vals["2020.09"]["element_kind"] == vals[OTHER]["element_kind"]
      and vals["2020.09"]["elements"] == vals[OTHER]["elements"]
      and all(abs(vals["2020.09"][k] - vals[OTHER][k]) <= 1e-9 for k in ("quality_min", "quality_mean", "quality_max")),
      "element quality: the same values returned on both hosts", str(vals))

# 2. MGA smoothing (the fast example) of the same grid: node moves by a seeded micro-genetic search
res = {h: mlx.run([grid_ply], EX("filter_mga_smooth", "examples", "mga_smooth_fast.mlx"),
                  [(out("mga", h), "fq sa", 0)], host=h) for h in HOSTS}
for h, r in res.items():
    check(r.rc == 0, f"MGA smoothing on {h}: exit 0", r.stdout[-1500:])
worst = {h: figures(r.log, r"worst alpha") for h, r in res.items()}
check(worst["2020.09"] and [w[:6] for w in worst["2020.09"]] == [w[:6] for w in worst[OTHER]],
      "MGA smoothing: the same element count, worst and mean alpha before and after on both hosts", str(worst))
compare_layers("mga", tol_rel=1e-5, quality_tol=1e-4)

# 3. C1 refinement (3x3 per triangle) of a curved grid
Vc, Fc = grid(5, quads=False, jitter=0.2, seed=2, z=lambda x, y: 0.1 * x * x - 0.05 * x * y)
curved = write_ply(os.path.join(d, "curved.ply"), Vc, Fc)
res = {h: mlx.run([curved], EX("filter_c1_surface", "examples", "c1_refine.mlx"), [(out("c1", h), "sa")], host=h)
       for h in HOSTS}
for h, r in res.items():
    check(r.rc == 0, f"C1 refinement on {h}: exit 0", r.stdout[-1500:])
compare_layers("c1", tol_rel=1e-5)

# 4. a coarse rib cage (8 mm edges), its element quality and its pectus index, in one script
cage = [f for f in mlx.load_script(EX("filter_ribcage", "examples", "create_ribcage.mlx"))][0]
quality = mlx.load_script(EX("filter_mga_smooth", "examples", "element_quality.mlx"))[0]
index = [f for f in mlx.load_script(EX("filter_thoracic_volume", "examples", "pectus_index.mlx")) if f.name == "Pectus: Pectus Index"][0]
script = mlx.Script([cage.set(edgeLength=8.0), quality, index.set(compare=False)])
res = {h: mlx.run([], script, [(out("cage", h), "fq fc sa", 0)], host=h, timeout=1200) for h in HOSTS}
for h, r in res.items():
    check(r.rc == 0, f"rib cage + quality + pectus index on {h}: exit 0", r.stdout[-1500:])
# The cage is decimated by the project's own start of vcglib's quadric edge collapse (common/src/mesh_simplify.cpp),
# the same on every release: the two cages are the same, vertex by vertex
compare_layers("cage", tol_rel=1e-6, quality_tol=0)
index = {h: [float(x) for x in re.findall(r"Haller index (\d+\.\d+)", "\n".join(r.log))] for h, r in res.items()}
check(index["2020.09"] and index["2020.09"] == index[OTHER], "Pectus Index of the two cages the same", str(index))
print(f"     cage: Pectus Index {index}")


def within(a, b, rel):
    return a is not None and b is not None and abs(a - b) <= rel * max(abs(a), abs(b))


# The FE example as shipped (the 5 mm cage of the thesis' patient 1, TET10 on the FE filter's default mesh) in
# small strain, one linear solve: every release meshes with bookworm's TetGen 1.5 (scripts/host.sh), so the same
# tets and the same force. Run in a folder of its own: no file may be left there.
fe = mlx.load_script(EX("filter_nuss_fea", "examples", "nuss_fea.mlx"))
script = mlx.Script([fe[0], fe[1].set(analysis=1, resultBase=mlx.SaveFile("", ".vtu"))])
fe_values = {}
for h in HOSTS:
    cwd = workdir(f"fe-{h}")
    r = mlx.run([], script, [], host=h, cwd=cwd, timeout=1800)
    line = next((l for l in r.log if l.startswith("Nuss FE result") or " failed: " in l), "no Log line")
    check(r.rc == 0 and line.startswith("Nuss FE result"), f"FE example on {h}: a result", f"rc {r.rc}: {line}")
    force, printed = r.get("force_N", "Pectus: Nuss Procedure FE Analysis"), log_figure(r.log, r"Fe = ([0-9.]+) N \(Fs")
    check(as_printed(force, printed, 2), f"FE example on {h}: the force returned ({force} N) is the Log's ({printed} N)")
    check(not os.listdir(cwd), f"FE example on {h}: nothing left in the working folder", str(os.listdir(cwd)))
    fe_values[h] = {k: r.get(k, "Pectus: Nuss Procedure FE Analysis") for k in ("tets", "force_N", "max_strain", "reportable")}
    print(f"     FE example on {h}: rc {r.rc}: {line[:150]}")
a_, b_ = fe_values["2020.09"], fe_values[OTHER]
check(a_["tets"] is not None and a_["tets"] == b_["tets"], f"FE example: the same tet mesh on both hosts ({a_['tets']}, {b_['tets']} tets)")
check(within(a_["force_N"], b_["force_N"], 0.02) and within(a_["max_strain"], b_["max_strain"], 0.02),
      f"FE example: force and largest strain within 2 % on both hosts ({a_}, {b_})")
check(a_["reportable"] == 1 and b_["reportable"] == 1, "FE example: a result to report (the converged mesh) on both hosts")

# A patient's cage: the CT phantom's messy export imported and prepared by the example script on both releases
# (the preparation decimates through the same code as the generator): the same cage, vertex by vertex
export = os.path.join(d, "patient")
p = subprocess.run([os.path.join(os.path.dirname(PREFIX), "tools", "pectus_ct_phantom"), export, "--only", "messy"],
                   capture_output=True, text=True, timeout=900)
check(p.returncode == 0, "pectus_ct_phantom writes the messy export", p.stderr[-500:])
prep = mlx.load_script(EX("filter_patient", "examples", "prepare_patient_rib_cage.mlx"))
script = mlx.Script([prep[0].set(path=os.path.join(export, "stl_messy")), prep[1]])
res = {h: mlx.run([], script, [(out("prepared", h), "fq sa", None)], host=h, timeout=1200) for h in HOSTS}
for h, r in res.items():
    check(r.rc == 0, f"import and prepare the export on {h}: exit 0", r.stdout[-1500:])
compare_layers("prepared", tol_rel=1e-6, quality_tol=0)

# The main job (--quick: its small-strain TET4) on both releases: the same figures within 2 %
main = {}
for h in HOSTS:
    out_main = workdir(f"main-{h}")
    p = subprocess.run(["/usr/bin/python3", os.path.join(SOURCE, "python", "run_main.py"), out_main, "--quick"],
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=1800,
                       env=dict(os.environ, PECTUS_MESHLAB_HOST=h))
    rows = list(csv.DictReader(open(os.path.join(out_main, "summary.csv")))) if p.returncode == 0 else []
    check(len(rows) == 1, f"main job on {h}: exit 0 and summary.csv", p.stdout[-2000:])
    main[h] = rows[0] if rows else {}
keys = ("fe_tets", "force_N", "max_strain", "slice_change_cm3", "envelope_change_cm3", "haller_index_after")
for k in keys:
    va, vb = (float(main[h][k]) if main[h].get(k) not in (None, "") else None for h in HOSTS)
    check(within(va, vb, 0.02), f"main job: {k} within 2 % on both hosts ({va}, {vb})")
print("     main job: " + "; ".join(f"{k} " + " / ".join(str(main[h].get(k)) for h in HOSTS) for k in keys))

# 5. failures on the newer release
# a refused input: a mesh without faces; exit 255, the reason in the Log, the layer saved unchanged
pts = write_ply(os.path.join(d, "points.ply"), V, [])
r = mlx.run([pts], EX("filter_mga_smooth", "examples", "element_quality.mlx"), [], host=OTHER)
check(r.rc == 255, f"{OTHER}, a mesh without faces: exit 255", f"rc {r.rc}: {r.stdout[-800:]}")
check(any("unchanged" in l for l in r.log), f"{OTHER}, a mesh without faces: the reason in the Log", "\n".join(r.log))
# a parameter of the wrong type: a message naming it, exit 2, no abort
bad = os.path.join(d, "wrong_type.mlx")
text = open(EX("filter_mga_smooth", "examples", "mga_smooth_fast.mlx")).read()
open(bad, "w").write(text.replace('name="maxSweeps" type="RichInt"', 'name="maxSweeps" type="RichFloat"'))
r = mlx.run([grid_ply], bad, [], host=OTHER)
check(r.rc == 2 and "'maxSweeps' is RichFloat in the script, the filter expects RichInt" in r.stdout,
      f"{OTHER}, a parameter of the wrong type: a message naming it, exit 2", f"rc {r.rc}: {r.stdout[-800:]}")
# 2020.09's "Change the current layer", carried out by the runner: the layer named becomes current (the one
# saved without -l); a layer the document lacks is a message and exit 255
switch = [mlx.Filter("Change the current layer", layer=mlx.Mesh(k)) for k in (0, 2)]
r = mlx.run([grid_ply, pts], mlx.Script(switch[:1]), [(out("current", OTHER), "", None)], host=OTHER)
check(r.rc == 0 and len(read_ply(out("current", OTHER))["F"]) > 0,
      f"{OTHER}, 'Change the current layer' to layer 0: the grid (not the points loaded last) is saved", f"rc {r.rc}: {r.stdout[-800:]}")
r = mlx.run([grid_ply, pts], mlx.Script(switch[1:]), [], host=OTHER)
check(r.rc == 255 and "has no layer 2 (2 layers)" in r.stdout, f"{OTHER}, 'Change the current layer' to a missing layer: exit 255",
      f"rc {r.rc}: {r.stdout[-800:]}")
# a script that does not exist
r = mlx.run([grid_ply], os.path.join(d, "missing.mlx"), [], host=OTHER)
check(r.rc == 2 and "cannot read the filter script" in r.stdout, f"{OTHER}, a missing script: a message, exit 2",
      f"rc {r.rc}: {r.stdout[-800:]}")

finish()
