"""The bad-input matrix: every filter against empty layers, points only, one triangle,
non-manifold edges and vertices, open surfaces where a closed one is needed, self-intersection, NaN/Inf
coordinates, zero-area and duplicate faces, coordinates near 1e8, missing labels/landmarks, and every
numeric parameter at 0, -1 and an absurd value (taken from the filter's example .mlx).

Each cell runs the real meshlabserver with the filter; when it fails, the same filter with the same
parameters runs once more in-process (build/bin/pectus_layer_check: meshlabserver saves nothing after a
failed filter) saving every layer before and after it. A cell is classified as
  - "error: <message>"       the filter failed (rc 255) with its reason in a LOG line, and every layer
                              after it is byte-identical to the layer before it;
  - "valid result (...)"      rc 0, nothing non-finite in the saved layers and written files;
  - "not loaded: ..."         MeshLab itself refused the file before any filter ran;
  - "FAIL: ..."               a crash, a hang, rc 0 with NaN/Inf output, a missing message, or a layer
                              changed by a failed filter. A test fails on any of these.

    python3 tests/e2e/bad_input_matrix.py --write     # run every filter, rewrite docs/bad_input_matrix.md
    python3 tests/e2e/bad_input_matrix.py mga         # run some filters (kept in build/bad_input_results.json)
    python3 tests/e2e/bad_input_matrix.py --write mga # rerun some, rewrite the table with the others' last run
ctest runs one test per group (e2e_bad_input_<group>, registered by tests/CMakeLists.txt from --groups):
it checks its cells and compares them with the committed table. With PECTUS_MESHLAB_HOST=2025.07 (or
2022.02) the cells run through pectus-mlrun on that release (e2e_2025_bad_input_<group>): every cell must
give the committed outcome (error, valid result or not loaded) without a FAIL; the messages may differ where
the host's own vcglib made the input (the generated cage), and the in-process layer comparison is left to
the Adapter unit tests built against that release. Set PECTUS_PREFIX/PECTUS_BUILD when the
build folder is not ./build."""
from __future__ import annotations

import hashlib
import json
import os
import re
import subprocess
import sys
import tempfile

import numpy as np

SOURCE = os.environ.get("PECTUS_SOURCE", os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..")))
sys.path.insert(0, os.path.join(SOURCE, "python"))
import pectus_mlx as mlx  # noqa: E402
from pectus_meshes import closed_ellipsoid, saddle_mesh, write_ply  # noqa: E402

PREFIX = os.environ.get("PECTUS_PREFIX", os.path.join(SOURCE, "build", "prefix"))
TABLE = os.path.join(SOURCE, "docs", "bad_input_matrix.md")
MASK = "vq vc fq fc sa"
TIMEOUT = 60.0 * float(os.environ.get("PECTUS_TIMEOUT_SCALE", "1"))  # scripts/sanitize.sh e2e: x 5 under ASan
BUILD = os.environ.get("PECTUS_BUILD", os.path.join(SOURCE, "build"))
LAYER_CHECK = os.environ.get("PECTUS_LAYER_CHECK", os.path.join(BUILD, "bin", "pectus_layer_check"))
PLUGINS = os.environ.get("PECTUS_PLUGINS", os.path.join(BUILD, "plugins"))
HOST = mlx.default_host()
REFERENCE_HOST = "2020.09"  # the host whose outcomes docs/bad_input_matrix.md holds
TIMING = re.compile(r"(?<![A-Za-z0-9_])[0-9.]+(e[-+]?[0-9]+)? ?(s|ms|seconds?)\b")  # masked in Log lines
_NONFINITE = re.compile(rb"(?<![A-Za-z_])-?(nan|inf|infinity)(?![A-Za-z_])", re.I)

# ---------------------------------------------------------------------------------------------
# inputs: (V, F, face props) transformed from a valid base mesh of the filter's kind

KINDS = [  # key, table heading
    ("valid", "valid input"), ("empty", "empty layer"), ("points", "points only"),
    ("one_triangle", "one triangle"), ("nm_edge", "non-manifold edge"), ("nm_vertex", "non-manifold vertex"),
    ("open", "open surface"), ("self_intersecting", "self-intersecting"), ("nan", "NaN coordinate"),
    ("inf", "Inf coordinate"), ("zero_area", "zero-area face"), ("duplicate", "duplicate face"),
    ("large", "coordinates ~1e8"), ("no_labels", "no tissue labels"), ("no_landmarks", "no landmarks")]
KIND_TITLE = dict(KINDS)


def _faces_with(F, fp, extra_faces, like=0):
    """F plus extra faces; face properties of the new faces copied from face `like`"""
    F2 = list(F) + extra_faces
    fp2 = {n: (t, list(v) + [v[like]] * len(extra_faces)) for n, (t, v) in fp.items()}
    return F2, fp2


def make_kind(kind: str, V, F, fp):
    """(V, F, face props) of input `kind` built from the valid mesh (V, F, fp); None if not applicable"""
    V = np.array(V, float)
    F = [list(f) for f in F]
    k = len(F) // 2
    a, b, c = F[k]
    if kind == "valid":
        return V, F, fp
    if kind == "empty":
        return np.zeros((0, 3)), [], {n: (t, []) for n, (t, _) in fp.items()}
    if kind == "points":
        return V, [], {n: (t, []) for n, (t, _) in fp.items()}
    if kind == "one_triangle":
        return V[[a, b, c]], [[0, 1, 2]], {n: (t, [v[k]]) for n, (t, v) in fp.items()}
    if kind == "nm_edge":  # a fin on the edge a-b: three faces share it
        n = np.cross(V[b] - V[a], V[c] - V[a])
        tip = (V[a] + V[b]) / 2 + n / (np.linalg.norm(n) + 1e-30) * np.linalg.norm(V[b] - V[a])
        F2, fp2 = _faces_with(F, fp, [[a, b, len(V)]], k)
        return np.vstack([V, tip]), F2, fp2
    if kind == "nm_vertex":  # a second triangle fan at vertex a (a bow tie)
        e = np.linalg.norm(V[b] - V[a])
        n = np.cross(V[b] - V[a], V[c] - V[a])
        n = n / (np.linalg.norm(n) + 1e-30) * e
        F2, fp2 = _faces_with(F, fp, [[a, len(V), len(V) + 1]], k)
        return np.vstack([V, V[a] + n, V[a] + n + (V[b] - V[a])]), F2, fp2
    if kind == "open":  # the faces around vertex a removed: a hole (closed bases only)
        keep = [i for i, f in enumerate(F) if a not in f]
        return V, [F[i] for i in keep], {n: (t, [v[i] for i in keep]) for n, (t, v) in fp.items()}
    if kind == "self_intersecting":  # a copy turned 90 degrees about x through the centroid
        m = V.mean(axis=0)
        W = (V - m)[:, [0, 2, 1]] * [1, -1, 1] + m
        F2, fp2 = _faces_with(F, fp, [], k)
        F2 += [[i + len(V) for i in f] for f in F]
        fp2 = {n: (t, list(v) * 2) for n, (t, v) in fp.items()}
        return np.vstack([V, W]), F2, fp2
    if kind in ("nan", "inf"):
        V2 = V.copy()
        V2[a, 0] = float(kind)
        return V2, F, fp
    if kind == "zero_area":  # vertex c moved onto the edge a-b
        V2 = V.copy()
        V2[c] = (V[a] + V[b]) / 2
        return V2, F, fp
    if kind == "duplicate":
        F2, fp2 = _faces_with(F, fp, [list(F[k])], k)
        return V, F2, fp2
    if kind == "large":
        return V * (1e8 / np.abs(V).max()), F, fp
    if kind == "no_labels":
        return V, F, {}
    raise KeyError(kind)


# ---------------------------------------------------------------------------------------------
# filters: example script, base overrides, layout of the layers, which kinds apply


def _ex(path):
    return os.path.join(SOURCE, path)


SURFACE_KINDS = ["valid", "empty", "points", "one_triangle", "nm_edge", "nm_vertex", "self_intersecting", "nan",
                 "inf", "zero_area", "duplicate", "large"]
CLOSED_KINDS = SURFACE_KINDS[:6] + ["open"] + SURFACE_KINDS[6:]

FILTERS = {
    # key: name (as the example), example, base mesh, overrides, layout, kinds, group
    "c1_refine": dict(mlx="filter_c1_surface/examples/c1_refine.mlx", base="open", set=dict(subdivisions=1),
                      kinds=SURFACE_KINDS, group="c1"),
    "c1_project": dict(mlx="filter_c1_surface/examples/c1_project.mlx", base="open", layout="project",
                       kinds=SURFACE_KINDS, group="c1"),
    "quality": dict(mlx="filter_mga_smooth/examples/element_quality.mlx", base="open", kinds=SURFACE_KINDS,
                    group="quality"),
    "mga": dict(mlx="filter_mga_smooth/examples/mga_smooth.mlx", base="open", set=dict(maxSweeps=2),
                kinds=SURFACE_KINDS, group="mga"),
    "gradient": dict(mlx="filter_mga_smooth/examples/gradient_smooth.mlx", base="open", set=dict(maxSweeps=2),
                     kinds=SURFACE_KINDS, group="gradient"),
    # the generator reads no layer: one cell with a layer loaded (left alone), the rest are parameters
    "ribcage": dict(mlx="filter_ribcage/examples/create_ribcage.mlx", base="open", set=dict(edgeLength=8.0),
                    kinds=["valid"], group="ribcage"),
    "nuss": dict(mlx="filter_nuss_fea/examples/nuss_fea.mlx", index=1, base="cage", layout="nuss",
                 set=dict(analysis=1, order=1, tetQuality=0.0, targetElevation=10.0,
                          resultBase=mlx.SaveFile("", ".vtu")),  # no files (the example writes into the cwd)
                 kinds=CLOSED_KINDS + ["no_labels", "no_landmarks"], group="nuss", split=True),
    "planner": dict(mlx="filter_nuss_fea/examples/nuss_bar_planner.mlx", index=1, base="cage", layout="nuss",
                    set=dict(levels="4", bars=1, analysis=1, order=1, tetQuality=0.0, targetElevation=10.0,
                             csvFile=mlx.SaveFile("", ".csv")),
                    kinds=CLOSED_KINDS + ["no_labels", "no_landmarks"], group="planner", split=True),
    "tri_to_quad": dict(mlx="filter_quad_convert/examples/tri_to_quad.mlx", base="open", kinds=SURFACE_KINDS,
                        group="quad"),
    "structure": dict(mlx="filter_quad_convert/examples/structure.mlx", base="open", kinds=SURFACE_KINDS,
                      group="quad"),
    "save_polygonal": dict(mlx="filter_quad_convert/examples/save_polygonal.mlx", base="open", layout="save",
                           kinds=SURFACE_KINDS, group="quad"),
    "slice": dict(mlx="filter_thoracic_volume/examples/thoracic_volume_slice.mlx", base="closed",
                  layout="thoracic", set=dict(compare=False, rangeSource=1, zLow=-50.0, zHigh=50.0, resolution=128,
                                              rays=90), kinds=CLOSED_KINDS + ["no_landmarks"], group="slice"),
    "envelope": dict(mlx="filter_thoracic_volume/examples/thoracic_volume_envelope.mlx", base="closed",
                     layout="thoracic", set=dict(compare=False, rangeSource=1, zLow=-50.0, zHigh=50.0, patchesLong=6,
                                                 patchesAround=8, tessellation=2),
                     kinds=CLOSED_KINDS + ["no_landmarks"], group="envelope"),
    "pectus_index": dict(mlx="filter_thoracic_volume/examples/pectus_index.mlx", base="closed", layout="thoracic",
                         set=dict(compare=False, levelSource=1, zLow=-50.0, zHigh=50.0, rays=90),
                         kinds=CLOSED_KINDS + ["no_landmarks"], group="pectus_index"),
    # the patient filters: the input is the file 'path' names (import), or the only layer (prepare: one blob
    # that neither its name nor its shape makes a rib cage of). Prepare so has no valid cell (refusal=True): the
    # patient e2e tests run it on real exports
    "import_ct": dict(mlx="filter_patient/examples/import_ct_segmentation.mlx", base="closed", layout="import",
                      kinds=CLOSED_KINDS, group="patient"),
    "prepare": dict(mlx="filter_patient/examples/prepare_patient_rib_cage.mlx", index=1, base="closed",
                    kinds=CLOSED_KINDS, group="patient", refusal=True),
}
# one ctest per group; a filter with split=True has its parameter cells in a second group <group>_params
GROUPS = sorted({f["group"] for f in FILTERS.values()} | {f["group"] + "_params" for f in FILTERS.values() if f.get("split")})
ABSURD = {"Float": 1e9, "Int": 1000000000}


def base_filter(key: str) -> mlx.Filter:
    spec = FILTERS[key]
    f = mlx.load_script(_ex(spec["mlx"]))[spec.get("index", 0)]
    return f.set(**spec.get("set", {}))


def filter_title(key: str) -> str:
    return base_filter(key).name


def numeric_params(key: str) -> list:
    """(name, kind) of the filter's numeric parameters, in the example's order"""
    out = []
    for name, p in base_filter(key).params.items():
        if type(p) in (mlx.Float, mlx.DynamicFloat):
            out.append((name, "Float"))
        elif type(p) is mlx.Int:
            out.append((name, "Int"))
    return out


def cells(key: str, part: str = "all") -> list:
    """(row title, kind, filter overrides) of the filter's cells: part "all", "inputs" or "params" """
    out = [(KIND_TITLE[k], k, {}) for k in FILTERS[key]["kinds"]] if part != "params" else []
    for name, kind in (numeric_params(key) if part != "inputs" else []):
        for v in (0, -1, ABSURD[kind]):
            out.append((f"`{name}` = {v:g}", "valid", {name: v}))
    return out


def param_lines(f: mlx.Filter) -> str:
    """the filter's parameters for pectus_layer_check: "<type> <name> <value>" lines"""
    out = []
    for name, p in f.params.items():
        kind = {mlx.Float: "Float", mlx.DynamicFloat: "DynamicFloat", mlx.AbsPerc: "Float", mlx.Int: "Int", mlx.Mesh: "Mesh", mlx.Enum: "Enum",
                mlx.Bool: "Bool", mlx.Point3: "Point3", mlx.SaveFile: "SaveFile", mlx.OpenFile: "String",
                mlx.String: "String"}[type(p)]
        v = " ".join(repr(float(c)) for c in p.value) if kind == "Point3" else (
            int(bool(p.value)) if kind == "Bool" else p.value)
        out.append(f"{kind} {name} {v}\n")
    return "".join(out)


# ---------------------------------------------------------------------------------------------
# running


class Runner:
    def __init__(self, workdir: str | None = None, env: dict | None = None, size: int = 1):
        """size scales the valid open and closed meshes (1: 50 and 288 triangles)"""
        self.dir = workdir or tempfile.mkdtemp(prefix="pectus-badinput-")
        self.env = env
        self.size = size
        self._bases: dict = {}

    def run(self, inputs, script, outputs, timeout=TIMEOUT, env=None):
        return mlx.run(inputs, script, outputs, prefix=PREFIX, timeout=timeout, env=env or self.env)

    # the valid meshes the inputs are made from
    def base(self, name: str):
        if name not in self._bases:
            if name == "open":
                V, F = saddle_mesh(5 * self.size + 1, 0.2)
                self._bases[name] = (V, F, {})
            elif name == "closed":
                V, F = closed_ellipsoid(120.0, 80.0, 100.0, 16 * self.size, 10 * self.size)
                self._bases[name] = (V, F, {})
            elif name == "cage":
                self._make_cage()
            else:
                raise KeyError(name)
        return self._bases[name]

    def _make_cage(self):
        """the coarse rib cage and its landmarks, generated once per build and host (cached: a rib cage takes seconds)"""
        from harness import read_ply
        gen = mlx.load_script(_ex("filter_ribcage/examples/create_ribcage.mlx"))[0].set(edgeLength=8.0)
        cache = os.path.join(BUILD, "bad_input_cache", HOST, hashlib.sha1(gen.xml().encode()).hexdigest()[:12])
        cage, lms = os.path.join(cache, "gen_cage.ply"), os.path.join(cache, "gen_landmarks.ply")
        if not (os.path.exists(cage) and os.path.exists(lms)):
            tmp = tempfile.mkdtemp(prefix="cage-", dir=self.dir)
            r = self.run([], mlx.Script([gen]), [(os.path.join(tmp, "gen_cage.ply"), "fc fq", 0),
                                                 (os.path.join(tmp, "gen_landmarks.ply"), "vq", 1)], timeout=600)
            if r.rc != 0 or not os.path.exists(os.path.join(tmp, "gen_landmarks.ply")):
                raise RuntimeError("the rib cage for the Nuss FE cells could not be generated:\n" + r.stdout[-2000:])
            os.makedirs(os.path.dirname(cache), exist_ok=True)
            try:
                os.rename(tmp, cache)  # atomic: a test running in parallel may have made it meanwhile
            except OSError:
                pass
        C = read_ply(cage)
        fp = {n: ("uchar" if n in ("red", "green", "blue", "alpha") else "float", list(C["face"][n]))
              for n in ("red", "green", "blue", "alpha", "quality") if n in C["face"]}
        self._bases["cage"] = (C["V"], C["F"], fp)
        self.landmarks = lms

    def input_file(self, base: str, kind: str) -> str:
        path = os.path.join(self.dir, f"{base}_{kind}.ply")
        if not os.path.exists(path):
            V, F, fp = make_kind("valid" if kind == "no_landmarks" else kind, *self.base(base))
            write_ply(path, V, F, fprops=fp)
        return path

    def layout(self, key: str, kind: str):
        """(input files, index of the layer under test, filter overrides placing the layers)"""
        spec = FILTERS[key]
        bad = self.input_file(spec["base"], kind)
        lay = spec.get("layout")
        if lay == "project":  # the bad surface is layer 0; the points to project are the current layer
            pts = os.path.join(self.dir, "project_points.ply")
            if not os.path.exists(pts):
                V, _, _ = self.base("open")
                write_ply(pts, V[::3] + [0.05, -0.05, 0.3], [])
            return [bad, pts], 0, dict(surfaceMesh=0)
        if lay == "nuss":
            self.base("cage")
            if kind == "no_landmarks":
                return [bad], 0, dict(landmarkLayer=0)
            return [self.landmarks, bad], 1, dict(landmarkLayer=0)
        if lay == "thoracic":
            over = dict(beforeLayer=0, landmarkLayer=0)
            if kind == "no_landmarks":
                over["levelSource" if key == "pectus_index" else "rangeSource"] = 0
            return [bad], 0, over
        if lay == "import":  # the bad file is read from 'path'; a valid layer is loaded beside it, left alone
            return [self.input_file(spec["base"], "valid")], 0, dict(path=bad)
        if lay == "save":
            return [bad], 0, dict(fileName=mlx.SaveFile(os.path.join(self.dir, "saved_polygonal.obj"), ".obj"))
        return [bad], 0, {}

    def layers_after_failure(self, f: mlx.Filter, inputs, tag: str):
        """indices of the layers the filter changed although it failed, run in-process by pectus_layer_check
        (meshlabserver saves nothing after a failed filter); None when the filter did not fail there"""
        params = os.path.join(self.dir, f"{tag}_params.txt")
        with open(params, "w", encoding="utf-8") as fh:
            fh.write(param_lines(f))
        prefix = os.path.join(self.dir, f"{tag}_")
        p = subprocess.run([LAYER_CHECK, PLUGINS, f.name, params, prefix] + list(inputs), stdout=subprocess.PIPE,
                           stderr=subprocess.STDOUT, text=True, errors="replace", timeout=TIMEOUT, env=self._env())
        if p.returncode != 0 or "applyFilter 0" not in p.stdout:
            return None
        return [i for i in range(len(inputs)) if open(f"{prefix}before_{i}.ply", "rb").read() !=
                open(f"{prefix}after_{i}.ply", "rb").read()]

    def _env(self):
        return dict(os.environ, **self.env) if self.env else None

    def cell(self, key: str, kind: str, over: dict, tag: str = "cell") -> str:
        inputs, layer, place = self.layout(key, kind)
        f = base_filter(key).set(**place).set(**over)
        cur = os.path.join(self.dir, f"{tag}_current.ply")
        written = [p.value for p in f.params.values() if isinstance(p, mlx.SaveFile) and p.value]
        for p in [cur] + written:
            if os.path.exists(p):
                os.unlink(p)
        try:
            r = self.run(inputs, mlx.Script([f]), [(cur, MASK)])
        except subprocess.TimeoutExpired:
            return f"FAIL: hang (no answer in {TIMEOUT:.0f} s)"
        if "It was not possible to import mesh" in r.stdout:
            return f"not loaded: MeshLab refuses the file (rc {r.rc}, 'Failed loading')"
        failed = [l for l in r.log if " failed: " in l]
        if r.rc == 0:
            bad = [p for p in [cur] + written if os.path.exists(p) and _NONFINITE.search(open(p, "rb").read())]
            if bad:
                return "FAIL: rc 0 with NaN/Inf in " + ", ".join(os.path.basename(p) for p in bad)
            if not os.path.exists(cur):
                return "FAIL: rc 0 but the current layer was not saved"
            head = open(cur, "rb").read(400).decode("ascii", "replace")
            nv = re.search(r"element vertex (\d+)", head)
            nf = re.search(r"element face (\d+)", head)
            first = TIMING.sub("<t>", r.log[0]) if r.log else "no Log line"
            first = first if len(first) <= 240 else first[:237] + "..."
            return f"valid result (current layer {nv and nv.group(1)} vertices, {nf and nf.group(1)} faces): {first}"
        if r.rc != 255:
            return f"FAIL: crash (rc {r.rc}): " + " / ".join(r.stdout.strip().splitlines()[-3:])
        if not failed:
            return "FAIL: rc 255 without a LOG message: " + " / ".join(r.stdout.strip().splitlines()[-3:])
        changed = self.layers_after_failure(f, inputs, tag) if HOST == REFERENCE_HOST else []
        if changed is None:
            return "FAIL: meshlabserver failed but the in-process run did not: " + failed[-1]
        if changed:
            return f"FAIL: layer(s) {changed} changed by the failed filter; message: " + failed[-1]
        msg = failed[-1].split(" failed: ", 1)[1]
        return "error: " + msg.replace(" (the layers are unchanged)", "")

    def filter_rows(self, key: str, part: str = "all") -> list:
        rows = []
        for i, (title, kind, over) in enumerate(cells(key, part)):
            outcome = self.cell(key, kind, over, tag=f"{key}_{part}{i}")
            outcome = outcome.replace(self.dir, "<tmp>").replace(BUILD, "<build>")  # the table does not depend on them
            rows.append((title, kind, over, outcome))
            print(f"{filter_title(key)} | {title} | {rows[-1][3]}", flush=True)
        return rows


# ---------------------------------------------------------------------------------------------
# the table


def _short(outcome: str) -> str:
    return {"e": "E", "v": "V", "n": "L", "F": "**FAIL**"}[outcome[0]]


def render_filter(key: str, rows: list) -> str:
    out = [f"### {filter_title(key)}", "", "| input | outcome |", "|---|---|"]
    out += [_row(title, outcome) for title, _, _, outcome in rows]
    return "\n".join(out) + "\n"


def render_summary_row(key: str, rows: list) -> str:
    by_kind = {kind: o for _, kind, over, o in rows if not over}
    params = [o for _, _, over, o in rows if over]
    cells_ = [_short(by_kind[k]) if k in by_kind else "–" for k, _ in KINDS]
    pe = sum(1 for o in params if o.startswith("error"))
    pv = sum(1 for o in params if o.startswith("valid"))
    pf = len(params) - pe - pv
    return f"| {filter_title(key)} | " + " | ".join(cells_) + f" | {pe} E, {pv} V" + (f", {pf} FAIL" if pf else "") + " |"


HEADER = """# Bad-input matrix

Generated by `python3 tests/e2e/bad_input_matrix.py --write` (real meshlabserver, this project's
plugins); the e2e tests `test_bad_input_<group>.py` rerun it and fail when a cell differs from this file,
crashes, hangs, returns NaN/Inf with exit code 0, fails without a LOG message, or changes a layer it
failed on (every layer is saved after the filter and compared byte for byte with the same input saved
without the filter).

Inputs are made from a valid mesh of the filter's kind: a 6x6 saddle (open surface, 50 triangles) for the
surface filters, a closed ellipsoid (288 triangles) for the thoracic volume filters, the generated rib
cage (edge 8 mm, with tissue labels and its landmark layer) for the Nuss FE analysis. The patient filters
take the ellipsoid too: *Pectus: Import CT Segmentation* reads it as the file its `path` names (a valid layer is
loaded beside it and must stay unchanged), *Pectus: Prepare Patient Rib Cage* as its only layer, a blob that neither
its name nor its shape makes a rib cage of. Parameter rows change one numeric parameter of the filter's
example script (`filter_*/examples/*.mlx`) on the valid input.

Legend: **E** error (meshlabserver exit code 255, the message below in the Log and the error), **V** valid
result (exit code 0, finite output; what the filter does with that input is documented by the message-less
result in the detail table), **L** MeshLab refuses to load the file (before any filter runs), – not
applicable.
"""


def render_summary(results: dict) -> str:
    keys = [k for k in FILTERS if k in results]
    out = ["| filter | " + " | ".join(t for _, t in KINDS) + " | numeric parameters at 0, -1, 1e9 |",
           "|---" * (len(KINDS) + 2) + "|"]
    out += [render_summary_row(k, results[k]) for k in keys]
    n = sum(len(results[k]) for k in keys)
    fails = sum(1 for k in keys for r in results[k] if r[3].startswith("FAIL"))
    out += ["", f"{n} cells, {fails} failures (crash, hang, NaN output, missing message or changed layer)."]
    return "\n".join(out) + "\n"


def render(results: dict) -> str:
    keys = [k for k in FILTERS if k in results]
    out = [HEADER, "## Summary", "", render_summary(results), "## Details", ""]
    out += [render_filter(k, results[k]) for k in keys]
    return "\n".join(out)


def _row(title: str, outcome: str) -> str:
    return f"| {title} | {outcome.replace('|', '/')} |"


def committed_rows(key: str) -> tuple:
    """(detail rows, summary row) of the filter in the committed docs/bad_input_matrix.md"""
    text = open(TABLE, encoding="utf-8").read() if os.path.exists(TABLE) else ""
    title = filter_title(key)
    m = re.search(r"^### " + re.escape(title) + r"\n.*?(?=^### |\Z)", text, re.S | re.M)
    rows = [l for l in (m.group(0).splitlines() if m else []) if l.startswith("| ") and not l.startswith("| input |")]
    summary = [l for l in text.splitlines() if l.startswith(f"| {title} |")]
    return rows, (summary[0] if summary else None)


# Outcomes that differ from the reference host for a known reason of the other host, and the reason
HOST_DIFFERENCES = [
    # MeshLab 2021.05 and later drop the vertices with NaN or Inf coordinates (and their faces) while loading
    # a file: the NaN and Inf cells are the filter on a cleaned layer, and the loader's warning says so
    (lambda host, kind, o: kind in ("nan", "inf") and "vertices with NAN coords" in o,
     "valid once the loader dropped the non-finite vertices"),
]


def check_kinds(key: str, part: str, rows: list, committed: list):
    """on another host than the reference: each cell's outcome is of the committed kind (error, valid result,
    not loaded), or differs for one of the HOST_DIFFERENCES; how many messages differ in their text and
    for which known reason is printed"""
    from harness import check
    kinds = {r.split(" | ")[0][2:]: _short(r.split(" | ", 1)[1]) for r in committed}
    known = {t: why for t, kind, _, o in rows for test, why in HOST_DIFFERENCES
             if kinds.get(t) != _short(o) and test(HOST, kind, o)}
    differ = [t for t, _, _, o in rows if kinds.get(t) != _short(o) and t not in known]
    check(not differ, f"{filter_title(key)} ({part}) on {HOST}: every cell of the committed kind (E, V, L)",
          "\n".join(f"{t}: committed {kinds.get(t)}, now {o}" for t, _, _, o in rows if t in differ))
    texts = sum(1 for t, _, _, o in rows if _row(t, o) not in committed)
    reasons = {why: sum(1 for w in known.values() if w == why) for why in set(known.values())}
    print(f"     {filter_title(key)} ({part}) on {HOST}: {len(rows)} cells, {texts} with another message text"
          + "".join(f"; {n} {why}" for why, n in sorted(reasons.items())))


def run_group(group: str):
    """the e2e test of one group: runs its cells, checks them, compares them with the committed table"""
    from harness import check, finish
    params = group.endswith("_params")
    base = group[:-len("_params")] if params else group
    keys = [k for k, f in FILTERS.items() if f["group"] == base]
    if not keys:
        raise SystemExit(f"no filter group {group!r} (groups: {', '.join(GROUPS)})")
    runner = Runner()
    for key in keys:
        split = FILTERS[key].get("split")
        part = "params" if params else ("inputs" if split else "all")
        rows = runner.filter_rows(key, part)
        for title, _, _, outcome in rows:
            check(not outcome.startswith("FAIL"), f"{filter_title(key)} / {title}: {outcome}")
        committed, summary = committed_rows(key)
        if HOST != REFERENCE_HOST:
            check_kinds(key, part, rows, committed)
            continue
        hint = "(rerun python3 tests/e2e/bad_input_matrix.py --write)"
        stale = [_row(t, o) for t, _, _, o in rows if _row(t, o) not in committed]
        check(not stale, f"{filter_title(key)} ({part}): every cell as in docs/bad_input_matrix.md {hint}",
              "\nnow:\n" + "\n".join(stale))
        if not params:
            check(len(committed) == len(cells(key)), f"{filter_title(key)}: the table has one row per cell",
                  f"{len(committed)} rows, {len(cells(key))} cells")
            now = render_summary_row(key, rows)
            if split:  # the parameter column is checked by the _params group's rows
                now, summary = now.rsplit(" | ", 1)[0], summary and summary.rsplit(" | ", 1)[0]
            check(summary == now, f"{filter_title(key)}: summary row up to date {hint}",
                  f"\nnow:       {now}\ncommitted: {summary}")
    finish()


def main(argv):
    if "--groups" in argv:  # for tests/CMakeLists.txt: one ctest per group
        print(";".join(GROUPS))
        return 0
    if "--check" in argv:
        run_group(argv[argv.index("--check") + 1])
    keys = [a for a in argv if a in FILTERS] or list(FILTERS)
    runner = Runner()
    results = {k: runner.filter_rows(k) for k in keys}
    cache = os.path.join(BUILD, "bad_input_results.json")  # the last run of every filter, for --write KEY...
    saved = json.load(open(cache)) if os.path.exists(cache) else {}
    saved.update({k: [list(r) for r in v] for k, v in results.items()})
    with open(cache, "w") as fh:
        json.dump(saved, fh)
    if "--write" in argv:
        if any(k not in saved for k in FILTERS):
            raise SystemExit("--write: run every filter once first (no filter keys)")
        results = {k: [tuple(r) for r in saved[k]] for k in FILTERS}
        with open(TABLE, "w", encoding="utf-8") as fh:
            fh.write(render(results))
        print("wrote", TABLE)
    fails = [(k, r[0], r[3]) for k in results for r in results[k] if r[3].startswith("FAIL")]
    print(f"{sum(len(v) for v in results.values())} cells, {len(fails)} failures")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
