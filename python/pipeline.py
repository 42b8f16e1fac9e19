#!/usr/bin/env python3
"""The thesis pipeline in one MeshLab script, run by the real meshlabserver:

  create the pectus rib cage (thesis patient 1: boy of 8, pectus index 5.3) -> element quality ->
  MGA smoothing -> Nuss FE analysis with the force calibrated to the measured elevation (44.7 mm) ->
  thoracic volume by the slice and the Ferguson envelope methods, before and after -> pectus index
  before and after.

The script is assembled from the filters' example scripts (every parameter, typed) with a few values
overridden, written next to the results as pipeline.mlx (it runs unchanged in the GUI, also in a
project that holds other layers: with a layer loaded, Filters > Show current filter script > Open Script >
pipeline.mlx, Apply Script). Results: the layers as PLY, the FE model (.vtu, .inp),
the force-displacement CSV/PNG, the rib strain CSV, quality histograms, summary.csv, and a table
shaped like the thesis' Table 6-1 on stdout.

    python3 python/pipeline.py [OUTDIR] [--age 8] [--haller 5.3] [--elevation 44.7] [--quick] [--case NAME]
"""
from __future__ import annotations

import argparse
import csv
import datetime
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
import pectus_mlx as mlx  # noqa: E402

EX = {
    "ribcage": os.path.join(ROOT, "filter_ribcage", "examples", "create_ribcage.mlx"),
    "nuss": os.path.join(ROOT, "filter_nuss_fea", "examples", "nuss_fea.mlx"),
    "quality": os.path.join(ROOT, "filter_mga_smooth", "examples", "element_quality.mlx"),
    "mga": os.path.join(ROOT, "filter_mga_smooth", "examples", "mga_smooth.mlx"),
    "slice": os.path.join(ROOT, "filter_thoracic_volume", "examples", "thoracic_volume_slice.mlx"),
    "envelope": os.path.join(ROOT, "filter_thoracic_volume", "examples", "thoracic_volume_envelope.mlx"),
    "index": os.path.join(ROOT, "filter_thoracic_volume", "examples", "pectus_index.mlx"),
    "planner": os.path.join(ROOT, "filter_nuss_fea", "examples", "nuss_bar_planner.mlx"),
}

# layers of the document while the script runs (no input files: the generator creates them)
CAGE, LANDMARKS, RESULT, LANDMARKS_AFTER = 0, 1, 2, 3


def example(key: str, name: str) -> mlx.Filter:
    for f in mlx.load_script(EX[key]):
        if f.name == name:
            return f
    raise KeyError(f"{name!r} not in {EX[key]}")


def fe_settings(quick: bool) -> dict:
    """The FE settings of the main job: small strain TET4 on TetGen's unrefined mesh (seconds, for the end-to-end
    test), or large displacement TET10 on the FE filter's default mesh (tet quality 2.0, no volume bound), whose
    elevation lies within about 2 % of the converged mesh's (docs/validation.md, FE mesh convergence)."""
    return dict(analysis=1, order=1, tetQuality=0.0) if quick else dict(analysis=0, order=0, tetQuality=2.0)


def planner_filters(outdir: str, elevation: float, quick: bool, cage: int, landmarks: int, levels: str, bars: int) -> list:
    """'Pectus: Nuss Bar Planner' on `cage` (made current first) with the main job's FE settings; table in planner.csv."""
    current = mlx.Filter("Change the current layer", layer=mlx.Mesh(cage))  # MeshLab's filter_layer
    plan = example("planner", "Pectus: Nuss Bar Planner").set(
        landmarkLayer=landmarks, levels=levels, bars=bars, targetElevation=elevation,
        csvFile=mlx.SaveFile(os.path.join(outdir, "planner.csv"), ".csv"), **fe_settings(quick))
    return [current, plan]


def analysis_filters(outdir: str, elevation: float, quick: bool, cage: int, landmarks: int) -> list:
    """Nuss FE (calibrated) on the current layer, then both volumes and the pectus index, before = `cage`."""
    nuss = example("nuss", "Pectus: Nuss Procedure FE Analysis").set(
        landmarkLayer=landmarks, mode=0, targetElevation=elevation,
        resultBase=mlx.SaveFile(os.path.join(outdir, "nuss") + ".vtu", ".vtu"), **fe_settings(quick))
    return [nuss] + measure_filters(cage, landmarks)


MEASURES = {"slice": "Pectus: Thoracic Volume (Slice Method)", "envelope": "Pectus: Thoracic Volume (Ferguson Envelope)", "index": "Pectus: Pectus Index"}


def measure_filter(key: str, cage: int, landmarks: int, **params) -> mlx.Filter:
    """One of MEASURES (its example's settings, then `params`) on the current layer (after) against `cage` (before)."""
    return example(key, MEASURES[key]).set(compare=True, beforeLayer=cage, landmarkLayer=landmarks, **params)


def measure_filters(cage: int, landmarks: int) -> list:
    """Both thoracic volumes and the pectus index of the current layer (after) against `cage` (before)."""
    return [measure_filter(k, cage, landmarks) for k in MEASURES]


def build_script(outdir: str, age: float, haller: float, elevation: float, quick: bool, planner: dict | None = None) -> mlx.Script:
    """planner: None, or dict(levels="3,4,5", bars=0 (one and two) / 1 (one) / 2 (two)) to add the bar planner at the end."""
    gen = example("ribcage", "Pectus: Create Rib Cage").set(age=age, hallerIndex=haller, edgeLength=5.0)
    quality = example("quality", "Pectus: Element Quality (Triangle Alpha / Quad Beta)")
    # the generated cage's features by the feature and singular angles: its coarse tubes are bent by 11 degrees
    # from edge to edge (median), as much as a CT surface, and crease chains find no crease on it. Its guard is
    # 0.35, not the filter's 0.7: nearly every node of the cage has a worst element below 0.7, where the guard
    # only keeps it from getting worse; 0.35 leaves the same worst alpha (0.0178) and a higher mean (0.7346
    # against 0.7307)
    mga = example("mga", "Pectus: MGA Surface Mesh Smoothing").set(maxSweeps=2 if quick else 4, featureDetection=1, worstGuard=0.35)
    quality_after = example("quality", "Pectus: Element Quality (Triangle Alpha / Quad Beta)")
    extra = planner_filters(outdir, elevation, quick, CAGE, LANDMARKS, **planner) if planner else []
    return mlx.Script([gen, quality, mga, quality_after] + analysis_filters(outdir, elevation, quick, CAGE, LANDMARKS) + extra)


RIBCAGE = "Pectus: Create Rib Cage"
QUALITY = "Pectus: Element Quality (Triangle Alpha / Quad Beta)"
MGA = "Pectus: MGA Surface Mesh Smoothing"
FE = "Pectus: Nuss Procedure FE Analysis"


def parse(res: mlx.Result) -> dict:
    """The pipeline's figures from the values its filters returned (None where a filter did not run or failed;
    a filter's first run where it ran more than once); the MGA and planner lines are the Log's own text."""
    log = res.log

    def get(key: str, filter: str):
        """the value of the filter's first run (a script may measure again later, e.g. bench/table_6_1.py)"""
        return (res.values(key, filter) + [None])[0]

    def pair(key: str, filter: str) -> list:
        """[before, after] of a measure run in compare mode ([] when it did not run)"""
        return [v for v in (get("before_" + key, filter), get(key, filter)) if v is not None]

    quality = res.values("quality_mean", QUALITY), res.values("quality_min", QUALITY)
    tets = get("tets", FE)
    r = {
        "haller_generator": get("haller_index_measured", RIBCAGE),
        "faces": get("faces", RIBCAGE),
        "quality_mean_before": (quality[0] + [None])[0],
        "quality_min_before": (quality[1] + [None])[0],
        "quality_mean_after": (quality[0][1:] + [None])[0],
        "quality_min_after": (quality[1][1:] + [None])[0],
        "histograms": [[q["results"][f"histogram_{i}"] for i in range(10)]
                       for q in res.results if q["filter"] == QUALITY and "histogram_0" in q["results"]],
        "mga": next((l for l in log if l.startswith("MGA smoothing")), ""),
        "mga_sweeps": get("sweeps", MGA),
        "mga_nodes_moved": get("nodes_moved", MGA),
        "tets": tets,
        "nodes": get("nodes", FE),
        "element": get("element", FE),
        "analysis": get("analysis", FE),
        "force": get("force_N", FE),
        "elevation": get("elevation_mm", FE),
        "solves": get("solves", FE),
        "nonlinear_solves": get("nonlinear_solves", FE),
        "newton_iterations": get("newton_iterations", FE),
        # the FE filter returns its figures only from an equilibrium state: every Newton solve it ends on met its
        # residual and displacement tolerances (it fails when Newton does not converge); the small-strain solve is direct
        "fe_converged": 0 if get("force_N", FE) is None else 1,
        "max_stress": get("max_stress_MPa", FE),
        "max_stress_where": get("max_stress_where", FE),
        "max_stress_body": get("max_stress_body_MPa", FE),
        "max_stress_body_where": get("max_stress_body_where", FE),
        "max_strain": get("max_strain", FE),
        "max_strain_where": get("max_strain_where", FE),
        "slice_change_cm3": get("volume_change_cm3", MEASURES["slice"]),
        "slice_change_pct": get("volume_change_pct", MEASURES["slice"]),
        "envelope_change_cm3": get("volume_change_cm3", MEASURES["envelope"]),
        "envelope_change_pct": get("volume_change_pct", MEASURES["envelope"]),
        "slice_volumes": pair("volume_cm3", MEASURES["slice"]),
        "envelope_volumes": pair("volume_cm3", MEASURES["envelope"]),
        "haller": pair("haller_index", MEASURES["index"]),
        "fe_seconds": get("seconds", FE),
        # 1 when the FE mesh is the converged one's (TET10, quality refinement, a 5 mm cage or finer), else 0
        "reportable": get("reportable", FE),
        "not_reportable_because": get("not_reportable_because", FE),
        "planner_table": [l.split("|", 1)[1][1:] for l in log if l.startswith("Planner |")],
        "planner_header": next((l for l in log if l.startswith("Nuss bar planner:")), ""),
        "planner_best": next((l for l in log if l.startswith("Planner best")), ""),
    }
    before, after = get("quality_mean_before", MGA), get("quality_mean_after", MGA)
    r["mga_mean"] = (before, after) if before is not None and after is not None else None
    return r


def table(r: dict, age: float, sex: str, target: float) -> str:
    def f(v, fmt="{:.2f}"):
        return "n/a" if v is None else fmt.format(v)
    hb, ha = (r["haller"] + [None, None])[:2]
    rows = [
        ("Sex/Age", f"{sex}/{age:g}"),
        ("Pectus (Haller) index before -> after", f"{f(hb)} -> {f(ha)}"),
        ("Elevation of the end of sternum, target (cm)", f(target / 10, "{:.2f}")),
        ("1. simulated displacement of the end of sternum (cm)", f(None if r["elevation"] is None else r["elevation"] / 10)),
        ("2. loading force at sternum end (N)", f(r["force"], "{:.1f}")),
        ("3. max. stress (MPa)", f"{f(r['max_stress'])}  at the {r['max_stress_where'] or 'n/a'}"),
        ("   away from the tissue junctions", f"{f(r['max_stress_body'])}  at the {r['max_stress_body_where'] or 'n/a'}"),
        ("4. max. strain", f"{f(r['max_strain'], '{:.3f}')}  at the {r['max_strain_where'] or 'n/a'}"),
        ("5. increasing volume, slice method (cm3)", f(r["slice_change_cm3"])),
        ("6. increasing volume, slice method (%)", f(r["slice_change_pct"])),
        ("7. increasing volume, Ferguson envelope (cm3)", f(r["envelope_change_cm3"])),
        ("8. increasing volume, Ferguson envelope (%)", f(r["envelope_change_pct"])),
    ]
    w = max(len(a) for a, _ in rows)
    thesis = "the thesis' patient 1: M/8, index 5.3, 4.47 cm, 4.49 cm, 140 N, 43.5 MPa, 0.93, 89.98 cm3, 6.09 %"
    if r.get("reportable") == 1:
        lines = [f"Table 6-1 (this run; {thesis})"]
    else:
        lines = [f"NOT A RESULT TO REPORT: {r.get('not_reportable_because') or 'the FE analysis gave no result'}",
                 "(quick settings, for tests; the main job without --quick runs the converged mesh)",
                 f"Table 6-1 (this quick run; {thesis})"]
    lines += ["-" * (w + 50)] + [f"{a:<{w}}  {b}" for a, b in rows]
    return "\n".join(lines)


def run_settings(script: mlx.Script, quick: bool) -> dict:
    """The analysis settings of `script` that summary.csv records: the run mode, the generated cage's surface edge
    (empty when the cage is read from a file) and the FE filter's analysis, material, load model and tet mesh."""
    by_name = {f.name: f for f in script.filters}
    edge = by_name[RIBCAGE].params["edgeLength"].value if RIBCAGE in by_name else None
    s = {"run_mode": "quick" if quick else "full", "surface_edge": edge}
    fe = by_name.get(FE)
    if fe is None:
        return s
    p = {k: v.value for k, v in fe.params.items()}
    label = {k: v.values[v.value] for k, v in fe.params.items() if isinstance(v, mlx.Enum)}
    small_strain = label["analysis"].startswith("Small strain")
    s.update({
        "analysis": "small strain" if small_strain else "large displacement",
        "material": "linear elastic" if small_strain else label["material"],
        "element": label["order"].split()[1],  # "Quadratic TET10 (no locking)" -> TET10
        "load": label["mode"], "calibration": label["calibration"], "bar_space": p["intercostalSpace"],
        "sternum_load_radius": p["sternumLoadRadius"], "rib_support_radius": p["ribSupportRadius"],
        "joint_radius": p["jointRadius"], "bone_E": p["boneModulus"], "bone_nu": p["nuBone"],
        "cartilage_E": p["cartilageModulus"], "cartilage_nu": p["nuCartilage"],
        "tet_quality": p["tetQuality"], "max_tet_volume": p["maxTetVolume"]})
    return s


# summary.csv, one column per entry: (header with the unit, where the value comes from, format). Sources: "r:KEY"
# parse()'s figure, "s:KEY" run_settings(), "run:KEY" the case itself. Formats: "int" a count, "text", or the
# number of decimals (times to 0.1 s, the other figures as the filters' Log prints them).
SUMMARY_COLUMNS = [
    ("case", "run:case", "text"), ("sex", "run:sex", "text"), ("age_years", "run:age", "g"),
    ("target_elevation_mm", "run:elevation", "g"),
    # what the figures are worth: quick mode, the FE filter's verdict on its mesh, its solve
    ("run_mode", "s:run_mode", "text"), ("reportable", "r:reportable", "int"),
    ("not_reportable_because", "r:not_reportable_because", "text"), ("fe_converged", "r:fe_converged", "int"),
    # the analysis settings
    ("fe_analysis", "s:analysis", "text"), ("fe_material", "s:material", "text"), ("fe_element", "s:element", "text"),
    ("fe_load", "s:load", "text"), ("fe_calibration", "s:calibration", "text"), ("bar_intercostal_space", "s:bar_space", "int"),
    ("sternum_load_radius_mm", "s:sternum_load_radius", "g"), ("rib_support_radius_mm", "s:rib_support_radius", "g"),
    ("joint_radius_mm", "s:joint_radius", "g"), ("bone_E_MPa", "s:bone_E", "g"), ("bone_nu", "s:bone_nu", "g"),
    ("cartilage_E_MPa", "s:cartilage_E", "g"), ("cartilage_nu", "s:cartilage_nu", "g"),
    # mesh density
    ("surface_edge_mm", "s:surface_edge", "g"), ("tet_quality_radius_edge", "s:tet_quality", "g"),
    ("max_tet_volume_mm3", "s:max_tet_volume", "g"), ("cage_faces", "r:faces", "int"), ("fe_tets", "r:tets", "int"),
    ("fe_nodes", "r:nodes", "int"),
    # the solve
    ("fe_solves", "r:solves", "int"), ("fe_nonlinear_solves", "r:nonlinear_solves", "int"),
    ("fe_newton_iterations", "r:newton_iterations", "int"),
    # Table 6-1
    ("force_N", "r:force", 2), ("elevation_mm", "r:elevation", 2), ("max_stress_MPa", "r:max_stress", 2),
    ("max_stress_where", "r:max_stress_where", "text"), ("max_stress_body_MPa", "r:max_stress_body", 2),
    ("max_stress_body_where", "r:max_stress_body_where", "text"), ("max_strain", "r:max_strain", 4),
    ("max_strain_where", "r:max_strain_where", "text"), ("slice_change_cm3", "r:slice_change_cm3", 2),
    ("slice_change_pct", "r:slice_change_pct", 2), ("envelope_change_cm3", "r:envelope_change_cm3", 2),
    ("envelope_change_pct", "r:envelope_change_pct", 2), ("haller_index_before", "r:haller_before", 3),
    ("haller_index_after", "r:haller_after", 3),
    # the generated cage and its smoothing
    ("haller_index_generated", "r:haller_generator", 3), ("quality_alpha_mean_before", "r:quality_mean_before", 4),
    ("quality_alpha_min_before", "r:quality_min_before", 4), ("quality_alpha_mean_after", "r:quality_mean_after", 4),
    ("quality_alpha_min_after", "r:quality_min_after", 4), ("mga_sweeps", "r:mga_sweeps", "int"),
    ("mga_nodes_moved", "r:mga_nodes_moved", "int"),
    ("fe_time_s", "r:fe_seconds", 1), ("pipeline_time_s", "r:seconds", 1),
]
SUMMARY_FORMAT = {name: fmt for name, _, fmt in SUMMARY_COLUMNS}
# the column names of summary.csv files written before the columns carried their units: read_summary renames them
OLD_SUMMARY_NAMES = {
    "age": "age_years", "haller_generator": "haller_index_generated", "faces": "cage_faces",
    "quality_mean_before": "quality_alpha_mean_before", "quality_min_before": "quality_alpha_min_before",
    "quality_mean_after": "quality_alpha_mean_after", "quality_min_after": "quality_alpha_min_after",
    "tets": "fe_tets", "element": "fe_element", "force": "force_N", "elevation": "elevation_mm", "solves": "fe_solves",
    "max_stress": "max_stress_MPa", "max_stress_body": "max_stress_body_MPa", "fe_seconds": "fe_time_s",
    "seconds": "pipeline_time_s", "haller_before": "haller_index_before", "haller_after": "haller_index_after",
}


def summary_cell(value, fmt) -> str:
    """One value as summary.csv writes it: '' for none, a count as an integer, a figure rounded (fmt decimals)."""
    if value is None or value == "":
        return ""
    if fmt == "text":
        return str(value)
    if fmt == "int":
        return str(int(round(float(value))))
    if fmt == "g":
        return f"{float(value):g}"
    return f"{float(value):.{fmt}f}"


def summary_row(r: dict, settings: dict, sex: str, age: float, elevation: float, case: str) -> dict:
    """{column: text} of summary.csv for one run"""
    hb, ha = (r["haller"] + [None, None])[:2]
    src = {"r": dict(r, haller_before=hb, haller_after=ha), "s": settings,
           "run": {"case": case, "sex": sex, "age": age, "elevation": elevation}}
    return {name: summary_cell(src[where.split(":")[0]].get(where.split(":")[1]), fmt) for name, where, fmt in SUMMARY_COLUMNS}


def write_summary(path: str, r: dict, sex: str, age: float, elevation: float, case: str, settings: dict):
    row = summary_row(r, settings, sex, age, elevation, case)
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(list(row))
        w.writerow(list(row.values()))


def read_summary(path: str) -> dict:
    """The row of a summary.csv as {column: text} in SUMMARY_COLUMNS' names and formats, from a file with these
    columns or with the older names (OLD_SUMMARY_NAMES, counts as '14372.0', unrounded figures); a column the
    file lacks is ''."""
    with open(path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    if not rows:
        return {}
    row = {OLD_SUMMARY_NAMES.get(k, k): v for k, v in rows[0].items()}
    out = {}
    for name, fmt in SUMMARY_FORMAT.items():
        v = row.get(name, "")
        try:
            out[name] = v if fmt == "text" else summary_cell(v, fmt)
        except ValueError:  # not a number where one is due: kept as written
            out[name] = v
    return out


def run_pipeline(outdir: str, age=8.0, haller=5.3, elevation=44.7, sex="M", quick=False, prefix=None,
                 planner: dict | None = None, case: str | None = None) -> tuple[int, dict, mlx.Result]:
    """case: summary.csv's case column (default SEX+AGE-indexHALLER, e.g. M8-index5.3)"""
    os.makedirs(outdir, exist_ok=True)
    script = build_script(outdir, age, haller, elevation, quick, planner)
    script_path = script.write(os.path.join(outdir, "pipeline.mlx"))
    outputs = [(os.path.join(outdir, "ribcage_smoothed.ply"), "fc fq", CAGE),
               (os.path.join(outdir, "ribcage_landmarks.ply"), "vq", LANDMARKS),
               (os.path.join(outdir, "nuss_result.ply"), "vq vc fc fq", RESULT),
               (os.path.join(outdir, "nuss_landmarks_after.ply"), "vq", LANDMARKS_AFTER),
               (os.path.join(outdir, "envelope_before.ply"), "", 4),
               (os.path.join(outdir, "envelope_after.ply"), "", 5)]
    t0 = time.time()
    # the planner repeats the calibrated FE per option (full mode: ~4 min each on an idle machine): a longer limit
    res = mlx.run([], script_path, outputs, prefix=prefix, timeout=4 * 3600 if planner else 3600)
    r = parse(res)
    r["seconds"] = time.time() - t0
    with open(os.path.join(outdir, "meshlabserver.log"), "w") as fh:
        fh.write(res.stdout)
    write_summary(os.path.join(outdir, "summary.csv"), r, sex, age, elevation, case or f"{sex}{age:g}-index{haller:g}",
                  run_settings(script, quick))
    return res.rc, r, res


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("outdir", nargs="?")
    ap.add_argument("--age", type=float, default=8.0)
    ap.add_argument("--sex", default="M")
    ap.add_argument("--haller", type=float, default=5.3)
    ap.add_argument("--elevation", type=float, default=44.7, help="measured sternal elevation (mm)")
    ap.add_argument("--quick", action="store_true", help="small-strain TET4 FE (seconds), for tests")
    ap.add_argument("--case", help="summary.csv's case column (default SEX+AGE-indexHALLER, e.g. M8-index5.3)")
    a = ap.parse_args(argv)
    out = os.path.abspath(a.outdir or os.path.join(ROOT, "out", "pipeline-" + datetime.datetime.now().strftime("%Y%m%d-%H%M%S")))
    rc, r, res = run_pipeline(out, a.age, a.haller, a.elevation, a.sex, a.quick, case=a.case)
    if rc != 0:
        print(res.stdout[-4000:], file=sys.stderr)
        print(f"pipeline failed (MeshLab {mlx.default_host()} exit {rc}); log in {out}/meshlabserver.log", file=sys.stderr)
        return 1
    print(table(r, a.age, a.sex, a.elevation))
    print(f"\nMGA smoothing: {r['mga']}")
    print(f"FE: {r['tets']} {r['element']} elements, calibrated in {r['solves']} solves, {round(r['fe_seconds'], 1)} s; "
          f"whole pipeline {r['seconds']:.0f} s")
    print(f"Output folder: {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
