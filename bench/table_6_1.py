#!/usr/bin/python3
"""The thesis' five patients (Table 6-1) built by the generator and calibrated with the FE filter's defaults,
in one run, beside the thesis' columns: force, Newton iterations, solves and time, max stress and strain and
where (the stress also away from the tissue junctions, where it is singular), the intrathoracic volume gain (slice method and Ferguson envelope) and the pectus index after.

Each patient: 'Pectus: Create Rib Cage' (sex/age and pectus index of Table 6-1, --edge mm) ->
'Pectus: Nuss Procedure FE Analysis' with its defaults, calibrated to the patient's measured elevation of the
lower sternum end -> both thoracic volume filters and the pectus index, before and after; one
meshlabserver per patient and method. --methods adds other large-displacement settings, on the same TET10 mesh:

  default  the filter's defaults: neo-Hookean, displacement control, line search, adaptive load steps
  search   the same with the force search instead of displacement control
  svk      St Venant-Kirchhoff, force search, plain Newton

--cartilage-e runs each method at each costal cartilage modulus of a list (MPa; the thesis' 12.25 by default):
the sensitivity of the force to the one soft tissue. A row at another modulus than the thesis' names it in
its method column ("default, E 24.5"). With --input exports, --spine keep (or cut,keep) has 'Prepare Patient
Rib Cage' keep the vertebral column as the fixed support instead of cutting the ribs at the costovertebral
joints ("default, spine kept").

With --input exports, each patient's cage is first written as a messy CT segmentation export by
pectus_ct_phantom (the generator's cage of that age and index on a 1 mm CT grid, TotalSegmentator-named STL
files with the defects of real exports), then imported and prepared by 'Pectus: Import CT Segmentation' and
'Pectus: Prepare Patient Rib Cage' (their defaults: 4 mm edges) in the same script before the analysis.

--funnel-z builds every cage with that funnel centre (the generator's funnelCenterZ; default its own, 1.1).
--cartilage-section runs each at each costal cartilage section of a list: rib (the generator's default, the
rib's own section) and ct (circular, twice the rib's area; "default, CT cartilage").
--slice-from sternum measures the slice method a second time over the envelope's range, from the lower end of
the sternum up instead of from the dome of the diaphragm (its lowerLimit), in the same script, and adds that
gain as a column: how much of the slice method's gain its range decides.

--thesis-modelling builds the force from the FE filter's defaults to the thesis' own modelling, one choice at a
time on each case (THESIS_STEPS: the CT-based cartilage section, linear TET4, about 320,000 tets, each rib held
at its head and its tubercle), and prints each step's force and its factor: the decomposition of the gap to the thesis.

    bench/table_6_1.py --thesis-modelling [--cases 1,2,3,4,5]
    bench/table_6_1.py [--edge 5] [--cases 1,2,3,4,5] [--methods default] [--input generated|exports] [--funnel-z F]
                       [--cartilage-e 12.25[,24.5,...]] [--cartilage-section rib[,ct]] [--spine cut[,keep]]
                       [--slice-from dome|sternum] [--out /tmp/pectus-table61]

Needs the plugins and meshlabserver of build/prefix (scripts/setup.sh).
"""
import argparse
import itertools
import os
import platform
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, os.path.join(ROOT, "python"))
import pectus_filters as pf  # noqa: E402
import pectus_mlx as mlx  # noqa: E402
import pipeline  # noqa: E402
from cohort import THESIS  # noqa: E402  (case, sex, age, index, elevation mm)

# Table 6-1's simulation rows: force N, max stress MPa, max strain, volume gain %
THESIS_RESULTS = {"case1": (140, 43.5, 0.93, 6.09), "case2": (120, 90.6, 1.20, 5.05), "case3": (190, 33.25, 1.04, 2.72),
                  "case4": (80, 37.7, 0.65, 4.43), "case5": (70, 54.5, 0.59, 8.88)}
METHODS = {"default": {},
           "search": dict(calibration=0),
           "svk": dict(material=0, calibration=0, newton=1)}
THESIS_CARTILAGE_E = pf.NUSS_MODEL["cartilageModulus"][1]  # MPa
SECTIONS = ("rib", "ct")  # the generator's cartilageSection
SLICE_FROM = ("dome", "sternum")  # the slice method's lowerLimit: 700 the dome of the diaphragm, 500 the lower sternum end
SPINE = ("cut", "keep")  # 'Pectus: Prepare Patient Rib Cage': the vertebral column cut at the joints or kept, fixed
CAGE, LANDMARKS = 0, 1
PHANTOM = os.path.join(ROOT, "build", "tools", "pectus_ct_phantom")


def cage_filters(case, age, index, edge, source, out, spine, generator):
    """the filters that make the patient's cage (current) and landmarks, and their layer numbers; generator:
    the generator's parameters beyond age, index and edge (funnelCenterZ, cartilageSection)"""
    if source == "generated":
        return [pf.create_ribcage(age=age, hallerIndex=index, edgeLength=edge, **generator)], CAGE, LANDMARKS
    folder = os.path.join(out, f"{case}_export")
    flags = {"funnelCenterZ": lambda v: ["--funnel-z", str(v)], "cartilageSection": lambda v: ["--cartilage", SECTIONS[v]]}
    subprocess.run([PHANTOM, folder, "--age", str(age), "--haller", str(index), "--only", "messy"]
                   + [x for k, v in generator.items() for x in flags[k](v)], check=True, capture_output=True)
    imp = pf.import_ct_segmentation(path=os.path.join(folder, "stl_messy"))
    n = mlx.run([], mlx.Script([imp])).get("structures")
    return [imp, pf.prepare_patient_rib_cage(spine=SPINE.index(spine))], n, n + 1  # the prepared cage and its landmarks follow the imports


def run_case(case, sex, age, index, elevation, method, edge, out, source, cartilage_e, spine, generator, slice_from,
             fe_extra=None):
    """one script: the cage, the FE analysis (METHODS[method], then fe_extra's parameters) and the measures"""
    make, cage, landmarks = cage_filters(case, age, index, edge, source, out, spine, generator)
    section = SECTIONS[generator.get("cartilageSection", 0)]
    extra = "".join(f"_{k}{v:g}" for k, v in sorted((fe_extra or {}).items()))
    base = os.path.join(out, f"{case}_{source}_{method}_E{cartilage_e:g}_{spine}_{section}{extra}")
    fe = pf.nuss_fea(landmarkLayer=landmarks, targetElevation=elevation, resultBase=mlx.SaveFile(base + ".vtu", ".vtu"),
                     cartilageModulus=cartilage_e, **{**METHODS[method], **(fe_extra or {})})
    volumes = pipeline.measure_filters(cage, landmarks)
    if slice_from == "sternum":  # the slice method once more, over the envelope's range; its Log line comes second
        volumes.append(pipeline.measure_filter("slice", cage, landmarks, lowerLimit=SLICE_FROM.index("sternum")))
    t0 = time.time()
    res = mlx.run([], mlx.Script(make + [fe] + volumes), timeout=4 * 3600)
    wall = time.time() - t0
    with open(base + ".log", "w") as fh:
        fh.write(res.stdout)
    r = pipeline.parse(res)
    sternum = res.values("volume_change_pct", pipeline.MEASURES["slice"])[1:]
    r["slice_sternum_pct"] = sternum[0] if sternum else None
    r["newton"] = res.get("newton_iterations", pipeline.FE)
    r["rc"], r["wall"] = res.rc, wall
    r["error"] = next((l for l in res.log if "failed" in l.lower() or "no converged" in l.lower()), "")
    return r


# --thesis-modelling: from the FE filter's defaults to the thesis' own modelling (6.1-6.2: linear SOLID185
# tets, about 320,000 of them after its Table 6-2 convergence test, ANSYS' large-displacement static solver,
# the moduli 11.5 GPa and 12.25 MPa, each rib held at its head and tubercle, the cage segmented from CT), one
# choice at a time, each step on the cage and settings of the one before. The tissues stay neo-Hookean: at
# these strains St Venant-Kirchhoff, the closest law to ANSYS' linear elasticity in large displacement, moves
# the main job's force by 1.6 % (README), and on case 1's 345,000 linear tets its calibration had not finished
# after 10 minutes, where the neo-Hookean one takes 1.
THESIS_TETS = 320000
# mm: the thesis holds each rib rigid at its head and its tubercle (6.2); the FE filter's default holds the nodes
# within 6 mm of the head. The rib's neck, from the head to the tubercle, is about 2.5 cm long in an adult
# (Gray's Anatomy); scaled by the chest's width (the generated chests of ages 5-8: 165-189 mm, against about
# 270 mm in an adult) about 16 mm, so the nodes within 16 mm of the head hold both.
THESIS_JOINT_RADIUS = 16.0
THESIS_STEPS = [  # (column, the generator's cartilageSection, FE parameters; maxTetVolume None: chosen per case)
    ("the FE filter's defaults", 0, {}),
    ("+ the CT-based cartilage section", 1, {}),
    ("+ linear TET4, the same mesh", 1, dict(order=1)),
    ("+ about 320,000 tets", 1, dict(order=1, maxTetVolume=None)),
    ("+ head and tubercle held = the thesis' modelling", 1, dict(order=1, maxTetVolume=None,
                                                                  jointRadius=THESIS_JOINT_RADIUS)),
]


def thesis_volume(case, sex, age, index, elevation, edge, out, trial=3.0):
    """the max tet volume (mm3) that gives about THESIS_TETS TET4 on the case's CT-section cage: one small-strain
    trial at `trial` mm3, then the bound scaled by the tets it gave (the count goes about as 1/bound there)"""
    r = run_case(case, sex, age, index, elevation, "default", edge, out, "generated", THESIS_CARTILAGE_E, "cut",
                 dict(cartilageSection=1), "dome", fe_extra=dict(order=1, maxTetVolume=trial, analysis=1))
    if r["rc"] != 0 or not r["tets"]:
        raise SystemExit(f"{case}: the mesh trial failed: {r['error']}")
    return round(trial * r["tets"] / THESIS_TETS, 3)


def thesis_modelling(cases, edge, out):
    """runs THESIS_STEPS on each case and prints the decomposition of the force gap; returns the exit status"""
    rows = []
    for case, sex, age, index, elevation in cases:
        vol = thesis_volume(case, sex, age, index, elevation, edge, out)
        steps = []
        for name, section, fe in THESIS_STEPS:
            fe = {k: (vol if k == "maxTetVolume" else v) for k, v in fe.items()}
            r = run_case(case, sex, age, index, elevation, "default", edge, out, "generated", THESIS_CARTILAGE_E, "cut",
                         dict(cartilageSection=section) if section else {}, "dome", fe_extra=fe)
            steps.append(r)
            print(f"{case} {name}: rc {r['rc']}, {f(r['tets'] and int(r['tets']), '{:,}')} {r['element']}, Fe "
                  f"{f(r['force'], '{:.2f}')} N, {r['newton']} Newton iterations, {r['wall']:.0f} s"
                  + (f"; {r['error']}" if r["rc"] else ""), flush=True)
        rows.append((case, sex, age, elevation, vol, steps))
    print(f"\nTable 6-1's force, from the FE filter's defaults to the thesis' modelling, one choice at a time (generated "
          f"cages, {edge:g} mm edges; each step's factor on the step before); {platform.node()}, {os.cpu_count()} cores, "
          f"{time.strftime('%Y-%m-%d')}")
    print("| case | sex/age | target mm | " + " | ".join(f"Fe N, {n}" for n, _, _ in THESIS_STEPS) +
          " | tets, thesis' modelling (max tet volume mm³) | thesis Fe N | thesis / thesis' modelling |")
    print("|---|---|---:|" + "---:|" * len(THESIS_STEPS) + "---:|---:|---:|")
    failed = 0
    for case, sex, age, elevation, vol, steps in rows:
        cells, prev = [], None
        for r in steps:
            ok = r["rc"] == 0 and r["force"]
            failed += not ok
            cells.append(f(r["force"] if ok else None, "{:.2f}") + (f" (× {r['force'] / prev:.2f})" if ok and prev else ""))
            prev = r["force"] if ok else None
        last = steps[-1]
        tf = THESIS_RESULTS[case][0]
        print(f"| {case[-1]} | {sex}/{age} | {elevation} | " + " | ".join(cells) +
              f" | {f(last['tets'] and int(last['tets']), '{:,}')} ({vol:g}) | {tf} | "
              f"{f(tf / last['force'] if last['rc'] == 0 and last['force'] else None, '× {:.2f}')} |")
    return 1 if failed else 0


def f(v, spec="{:.1f}"):
    return "—" if v is None else spec.format(v)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--edge", type=float, default=5.0)
    ap.add_argument("--cases", default="1,2,3,4,5")
    ap.add_argument("--methods", default="default")
    ap.add_argument("--input", choices=("generated", "exports"), default="generated")
    ap.add_argument("--cartilage-e", default=f"{THESIS_CARTILAGE_E:g}", help="costal cartilage moduli, MPa")
    ap.add_argument("--cartilage-section", default="rib", help="costal cartilage sections: rib, ct or rib,ct")
    ap.add_argument("--spine", default="cut", help="with --input exports: cut, keep or cut,keep")
    ap.add_argument("--funnel-z", type=float, default=None,
                    help="the generator's funnelCenterZ for every cage (default: the generator's own)")
    ap.add_argument("--slice-from", choices=SLICE_FROM, default="dome",
                    help="sternum: also the slice method's gain from the lower sternum end up")
    ap.add_argument("--thesis-modelling", action="store_true",
                    help="the force from the FE filter's defaults to the thesis' own modelling, one choice at a time")
    ap.add_argument("--out", default="/tmp/pectus-table61")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    cases = [THESIS[int(k) - 1] for k in a.cases.split(",")]
    if a.thesis_modelling:
        return thesis_modelling(cases, a.edge, a.out)
    methods = a.methods.split(",")
    rows = []
    moduli = [float(e) for e in a.cartilage_e.split(",")]
    spines = a.spine.split(",")
    if any(sp not in SPINE for sp in spines) or (a.input == "generated" and spines != ["cut"]):
        ap.error("--spine takes cut and keep, with --input exports (the generated cage has no vertebral column)")
    sections = a.cartilage_section.split(",")
    if any(sec not in SECTIONS for sec in sections):
        ap.error("--cartilage-section takes rib and ct")
    for (case, sex, age, index, elevation), method, e, spine, sec in itertools.product(cases, methods, moduli, spines, sections):
        generator = {} if a.funnel_z is None else dict(funnelCenterZ=a.funnel_z)
        if sec != "rib":
            generator["cartilageSection"] = SECTIONS.index(sec)
        r = run_case(case, sex, age, index, elevation, method, a.edge, a.out, a.input, e, spine, generator, a.slice_from)
        m = (method + ("" if e == THESIS_CARTILAGE_E else f", E {e:g}") + (", spine kept" if spine == "keep" else "")
             + (", CT cartilage" if sec == "ct" else ""))
        rows.append((case, sex, age, index, elevation, m, r))
        print(f"{case} {m}: rc {r['rc']}, Fe {r['force'] if r['force'] is None else round(r['force'], 2)} N, {r['newton']} Newton iterations, {r['wall']:.0f} s"
              + (f"; {r['error']}" if r["rc"] else ""), flush=True)

    what = f"generated cages ({a.edge:g} mm edges)" if a.input == "generated" else "their CT-like exports, prepared (4 mm edges)"
    what += "" if a.funnel_z is None else f", funnel centre {a.funnel_z:g}"
    print(f"\nTable 6-1, {what}, TET10 as the FE filter meshes them by default; "
          f"{platform.node()}, {os.cpu_count()} cores, {time.strftime('%Y-%m-%d')}")
    sternum = a.slice_from == "sternum"
    print("| case | sex/age | index | target mm | method | tets | result | Fe N (thesis) | Newton it. | solves | wall s |"
          " max stress MPa (thesis), where | away from the tissue junctions MPa, where | max strain (thesis), where | volume gain % slice / envelope (thesis) |"
          + (" slice from the sternum end % |" if sternum else "") + " index after |")
    print("|---|---|---:|---:|---|---:|---|---:|---:|---:|---:|---|---|---|---|" + ("---:|" if sternum else "") + "---:|")
    for case, sex, age, index, elevation, m, r in rows:
        tf, ts, te, tv = THESIS_RESULTS[case]
        ok = r["rc"] == 0
        hb, ha = (r["haller"] + [None, None])[:2]
        print(f"| {case[-1]} | {sex}/{age} | {index} | {elevation} | {m} | {f(r['tets'] and int(r['tets']), '{:,}')} | "
              f"{'calibrated' if ok else 'stopped'} | {f(r['force'] if ok else None, '{:.2f}')} ({tf}) | {f(r['newton'], '{}')} | "
              f"{f(r['solves'], '{}')} | {r['wall']:.0f} | "
              f"{f(r['max_stress'] if ok else None)} ({ts}), {r['max_stress_where'] or '—'} | "
              f"{f(r['max_stress_body'] if ok else None)}, {r['max_stress_body_where'] or '—'} | "
              f"{f(r['max_strain'] if ok else None, '{:.3f}')} ({te}), {r['max_strain_where'] or '—'} | "
              f"{f(r['slice_change_pct'] if ok else None, '{:.2f}')} / {f(r['envelope_change_pct'] if ok else None, '{:.2f}')} ({tv}) | "
              + (f"{f(r['slice_sternum_pct'] if ok else None, '{:.2f}')} | " if sternum else "") +
              f"{f(ha if ok else None, '{:.2f}')} |")
    print("Published forces: 68 N (Fonkalsrud, 4 children under 11) to 250 N (instrumented bar); "
          "Weber et al.: 181 ± 48 N, boys aged 5-17; the thesis: 70-190 N.")
    failed = [r for *_, m, r in rows if m.startswith("default") and r["rc"] != 0]
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
