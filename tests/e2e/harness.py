"""End-to-end test helpers: meshlabserver from the private prefix, PLY/OFF read and write, checks.
Tests are plain scripts (run by ctest): call check(...) for each assertion, finish() at the end."""
from __future__ import annotations

import os
import re
import struct
import sys
import tarfile
import tempfile

import numpy as np

import pectus_mlx as mlx
from pectus_meshes import write_off, write_ply  # noqa: F401  (the tests import them from here)
from report import ply_header  # the PLY header, as the run report reads it

SOURCE = os.environ.get("PECTUS_SOURCE", os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..")))
PREFIX = os.environ.get("PECTUS_PREFIX", os.path.join(SOURCE, "build", "prefix"))
DATA = os.path.join(SOURCE, "tests", "data")
_failures: list[str] = []
_passed = 0


SUITES = mlx.userland_suites()  # the Debian suite whose userland runs each newer release


def need_host(release: str):
    """exit 77 (ctest: skipped) when the MeshLab host of that release is not made"""
    if not mlx.host_made(release):
        print(f"skipped: the MeshLab {release} host is not made (scripts/host.sh {release})")
        sys.exit(77)


if mlx.default_host() in SUITES:
    need_host(mlx.default_host())


def workdir(name: str) -> str:
    d = tempfile.mkdtemp(prefix=f"pectus-{name}-")
    return d


CGAL_DATA = "/usr/share/doc/libcgal-dev/data.tar.gz"  # Debian's libcgal-demo


def cgal_meshes(folder: str, *names: str) -> dict:
    """name -> folder/name.off, each of libcgal-demo's data/meshes written there; without libcgal-demo the test
    prints SKIP and ends"""
    if not os.path.exists(CGAL_DATA):
        print("SKIP: libcgal-demo not installed")
        sys.exit(0)
    paths = {}
    with tarfile.open(CGAL_DATA) as tf:
        for name in names:
            paths[name] = os.path.join(folder, name + ".off")
            with open(paths[name], "wb") as fh:
                fh.write(tf.extractfile(f"data/meshes/{name}.off").read())
    return paths


def example_script(example: str, folder: str, name: str, **values) -> str:
    """folder/name.mlx: the example script `example` with some parameter values replaced (each exactly once)"""
    text = open(example).read()
    for k, v in values.items():
        text, n = re.subn(f'(name="{k}" type="\\w+" value=")[^"]*"', f'\\g<1>{v}"', text)
        assert n == 1, k
    path = os.path.join(folder, name + ".mlx")
    open(path, "w").write(text)
    return path


def run(inputs, script, outputs=(), timeout=1800):
    r = mlx.run(inputs, script, outputs, prefix=PREFIX, timeout=timeout)
    return r


def log_figure(log, pattern: str, cast=float):
    """cast(group 1) of the first Log line matching the regular expression, or None: for tests of the Log text
    itself (the figures come back as values: Result.value)"""
    for line in log:
        m = re.search(pattern, line)
        if m:
            return cast(m.group(1))
    return None


def log_figures(log, pattern: str) -> list:
    """float(group 1) of every Log line matching the regular expression (tests of the Log text)"""
    return [float(m.group(1)) for m in (re.search(pattern, l) for l in log) if m]


def as_printed(value, printed, decimals: int) -> bool:
    """a returned value is the Log's figure printed with `decimals` decimals"""
    return value is not None and printed is not None and abs(value - printed) <= 0.5 * 10.0 ** -decimals * (1 + 1e-9)


def check(cond: bool, what: str, detail: str = "") -> bool:
    global _passed
    if cond:
        _passed += 1
        print(f"ok   {what}")
    else:
        _failures.append(what)
        print(f"FAIL {what} {detail}")
    return cond


def check_refused(r, msg: str, what: str) -> bool:
    """A failed filter: meshlabserver exits non-zero and a Log line contains `msg`."""
    ok = check(r.rc != 0, f"{what}: non-zero exit", str(r.rc))
    return check(any(msg in l for l in r.log), f"{what}: message '{msg}' in the Log", "\n".join(r.log)) and ok


def finish():
    print(f"{_passed} passed, {len(_failures)} failed")
    sys.exit(1 if _failures else 0)


# ---------------------------------------------------------------------------------------------
# mesh files

_PLY_TYPES = {"char": "b", "int8": "b", "uchar": "B", "uint8": "B", "short": "h", "int16": "h", "ushort": "H",
              "uint16": "H", "int": "i", "int32": "i", "uint": "I", "uint32": "I", "float": "f", "float32": "f",
              "double": "d", "float64": "d"}


def read_ply(path: str) -> dict:
    """Reads ascii or binary_little_endian PLY. Returns {'vertex': {prop: array}, 'face': {prop: array,
    'vertex_indices': list of lists}} plus 'V' (n,3) and 'F' (list of index lists)."""
    with open(path, "rb") as fh:
        data = fh.read()
    fmt, elements, end = ply_header(data)
    out = {}
    body = data[end:]
    if fmt == "ascii":
        tokens = body.split()
        pos = 0
        for name, count, props in elements:
            cols = {p[0]: [] for p in props}
            for _ in range(count):
                for pname, ptype in props:
                    if isinstance(ptype, tuple):
                        n = int(tokens[pos]); pos += 1
                        cols[pname].append([int(x) for x in tokens[pos:pos + n]]); pos += n
                    else:
                        cols[pname].append(float(tokens[pos])); pos += 1
            out[name] = {k: (v if isinstance(v and v[0], list) else np.array(v)) for k, v in cols.items()}
    else:
        assert fmt == "binary_little_endian", fmt
        pos = 0
        for name, count, props in elements:
            cols = {p[0]: [] for p in props}
            for _ in range(count):
                for pname, ptype in props:
                    if isinstance(ptype, tuple):
                        ct = "<" + _PLY_TYPES[ptype[1]]
                        n = struct.unpack_from(ct, body, pos)[0]; pos += struct.calcsize(ct)
                        it = "<" + str(n) + _PLY_TYPES[ptype[2]]
                        cols[pname].append(list(struct.unpack_from(it, body, pos))); pos += struct.calcsize(it)
                    else:
                        t = "<" + _PLY_TYPES[ptype]
                        cols[pname].append(struct.unpack_from(t, body, pos)[0]); pos += struct.calcsize(t)
            out[name] = {k: (v if (v and isinstance(v[0], list)) else np.array(v)) for k, v in cols.items()}
    v = out.get("vertex", {})
    out["V"] = np.stack([v["x"], v["y"], v["z"]], axis=1) if "x" in v else np.zeros((0, 3))
    out["F"] = out.get("face", {}).get("vertex_indices", [])
    return out






def grid(n: int, quads: bool, jitter: float = 0.0, seed: int = 1, z=None):
    """(n+1)^2 vertices on [0,n]^2, interior vertices jittered; quads or triangles."""
    rng = np.random.default_rng(seed)
    V = []
    for j in range(n + 1):
        for i in range(n + 1):
            x, y = float(i), float(j)
            if 0 < i < n and 0 < j < n and jitter:
                x += rng.uniform(-jitter, jitter)
                y += rng.uniform(-jitter, jitter)
            V.append((x, y, 0.0 if z is None else z(x, y)))
    F = []
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            b, c, d = a + 1, a + n + 2, a + n + 1
            F += [[a, b, c, d]] if quads else [[a, b, c], [a, c, d]]
    return np.array(V), F


def file_digest(path: str) -> str:
    import hashlib
    with open(path, "rb") as fh:
        return hashlib.sha256(fh.read()).hexdigest()
