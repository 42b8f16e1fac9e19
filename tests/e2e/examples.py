"""Shared by test_examples.py and test_examples_patient.py: every shipped example script (*/examples/*.mlx)
runs unchanged through meshlabserver, each in exactly one of the two tests (a new example without a case
fails both). The inputs are the ones the example's docs page names; the folders the patient examples read
are fixed paths under /tmp/pectus-docs, which the docs' blocks write too (ctest serialises the three tests)."""
from __future__ import annotations

import glob
import os
import re

import harness as h
import pectus_mlx as mlx
from harness import check

# example file name -> the test that runs it
CASES = {
    "c1_refine.mlx": "examples", "c1_project.mlx": "examples",
    "element_quality.mlx": "examples", "gradient_smooth.mlx": "examples", "mga_smooth.mlx": "examples",
    "mga_smooth_fast.mlx": "examples",
    "tri_to_quad.mlx": "examples", "structure.mlx": "examples", "save_polygonal.mlx": "examples",
    "tri_to_quad_and_save.mlx": "examples",
    "create_ribcage.mlx": "examples", "nuss_fea.mlx": "examples", "nuss_bar_planner.mlx": "examples",
    "thoracic_volume_slice.mlx": "examples", "thoracic_volume_envelope.mlx": "examples", "pectus_index.mlx": "examples",
    "import_ct_segmentation.mlx": "patient", "prepare_patient_rib_cage.mlx": "patient",
    "patient_nuss_analysis.mlx": "patient",
}


def shipped() -> dict:
    """example file name -> path, every */examples/*.mlx of the source tree"""
    return {os.path.basename(p): p for p in sorted(glob.glob(os.path.join(h.SOURCE, "*", "examples", "*.mlx")))}


def check_coverage(group: str) -> list[str]:
    """every shipped example has a case; returns the paths of this group's examples"""
    ex = shipped()
    missing = sorted(set(ex) - set(CASES))
    check(not missing, "every shipped example has a case in tests/e2e/examples.py", f"missing: {missing}")
    check(not (set(CASES) - set(ex)), "every case is a shipped example", str(sorted(set(CASES) - set(ex))))
    return [ex[n] for n in sorted(ex) if CASES.get(n) == group]


def run(name: str, inputs=(), outputs=(), cwd=None):
    """runs the shipped example `name` unchanged; checks it exits 0 and returns the Result"""
    path = shipped()[name]
    r = h.run(list(inputs), path, outputs) if cwd is None else mlx.run(list(inputs), path, outputs, prefix=h.PREFIX,
                                                                         cwd=cwd, timeout=1800)
    check(r.rc == 0, f"{name} runs as shipped", f"rc {r.rc}\n" + "\n".join(r.log[-15:]))
    return r


def number(r, pattern: str, group: int = 1):
    """the number the first Log line matching `pattern` gives (None if none)"""
    for line in r.log:
        m = re.search(pattern, line)
        if m:
            return float(m.group(group))
    return None


def check_range(r, name: str, pattern: str, lo: float, hi: float, what: str):
    v = number(r, pattern)
    check(v is not None and lo <= v <= hi, f"{name}: {what} {v} in [{lo}, {hi}]",
          "\n".join(l for l in r.log if "LOG" in l or l)[-1500:] if v is None else "")
    return v


def check_converged(r, name: str, filter_name: str):
    """a shipped FE example runs on the converged mesh: the filter's own verdict (reportable 1), and no warning in
    the Log"""
    check(r.get("reportable", filter_name) == 1 and not any(l.startswith("Not a result to report") for l in r.log),
          f"{name}: a result to report (TET10 on the converged mesh)",
          str(r.get("not_reportable_because", filter_name)))
