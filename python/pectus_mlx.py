"""Build complete MeshLab filter scripts (.mlx) and run them headless on either MeshLab host.

Standard library only. Three hosts run the scripts (`run(..., host=...)`, default $PECTUS_MESHLAB_HOST or
2020.09):
  - "2020.09": Debian bookworm's meshlabserver from the private prefix, under xvfb-run;
  - "2025.07": pectus-mlrun in the Debian forky userland, through scripts/mlrun.sh;
  - "2022.02": pectus-mlrun in the Debian trixie userland, likewise.
meshlabserver aborts when a parameter is missing or mistyped, so every parameter is given a type:

    from pectus_mlx import Filter, Float, Int, Bool, Enum, Script, run
    s = Script([Filter("Pectus: Element Quality (Triangle Alpha / Quad Beta)",
                       elementType=Enum(0, ["Auto", "Triangles (alpha)", "Quads (beta)"]),
                       colorize=Bool(True))])
    res = run(["in.ply"], s, outputs=[("out.ply", "fq fc")])
    print(res.rc, res.value("quality_mean"), res.log)

Each filter's figures (force, elevation, volumes, counts, timings...) come back as values, one dict per filter
applied (Result.results, Result.value): the plugins append them to the file named by $PECTUS_RESULTS_FILE on
2020.09, pectus-mlrun writes the filters' return values there on the newer releases, and run() reads it.
"""
from __future__ import annotations

import json
import os
import re
import shutil
import signal
import subprocess
import tempfile
import threading
from dataclasses import dataclass, field
from typing import Iterable, Sequence
from xml.sax.saxutils import quoteattr


@dataclass
class _P:
    value: object

    def xml(self, name: str) -> str:
        raise NotImplementedError


class Float(_P):
    def xml(self, name):
        return f'<Param name={quoteattr(name)} type="RichFloat" value="{float(self.value)!r}"/>'


@dataclass
class DynamicFloat(_P):
    """A bounded float: the plugins declare a float this way where MeshLab's plain float field would show it
    rounded to 3 significant digits (11500, 12.25)."""
    lo: float = 0.0
    hi: float = 1.0

    def xml(self, name):
        return (f'<Param name={quoteattr(name)} type="RichDynamicFloat" value="{float(self.value)!r}" '
                f'min="{float(self.lo)!r}" max="{float(self.hi)!r}"/>')


class Int(_P):
    def xml(self, name):
        return f'<Param name={quoteattr(name)} type="RichInt" value="{int(self.value)}"/>'


class Bool(_P):
    def xml(self, name):
        return f'<Param name={quoteattr(name)} type="RichBool" value="{"true" if self.value else "false"}"/>'


class String(_P):
    def xml(self, name):
        return f'<Param name={quoteattr(name)} type="RichString" value={quoteattr(str(self.value))}/>'


class AbsPerc(_P):
    def xml(self, name):
        return f'<Param name={quoteattr(name)} type="RichAbsPerc" value="{float(self.value)!r}" min="0" max="1e9"/>'


class Mesh(_P):
    """A layer, by its index in the document (0 = first loaded)."""

    def xml(self, name):
        return f'<Param name={quoteattr(name)} type="RichMesh" value="{int(self.value)}"/>'


@dataclass
class Enum(_P):
    values: Sequence[str] = ()

    def xml(self, name):
        vals = "".join(f" enum_val{i}={quoteattr(v)}" for i, v in enumerate(self.values))
        return (f'<Param name={quoteattr(name)} type="RichEnum" value="{int(self.value)}" '
                f'enum_cardinality="{len(self.values)}"{vals}/>')


@dataclass
class SaveFile(_P):
    ext: str = ".csv"

    def xml(self, name):
        return (f'<Param name={quoteattr(name)} type="RichSaveFile" value={quoteattr(str(self.value))} '
                f'ext={quoteattr(self.ext)} exts_cardinality="0"/>')


@dataclass
class OpenFile(_P):
    exts: Sequence[str] = ()

    def xml(self, name):
        e = "".join(f" exts{i}={quoteattr(v)}" for i, v in enumerate(self.exts))
        return (f'<Param name={quoteattr(name)} type="RichOpenFile" value={quoteattr(str(self.value))} '
                f'exts_cardinality="{len(self.exts)}"{e}/>')


class Point3(_P):
    def xml(self, name):
        x, y, z = (float(c) for c in self.value)
        return f'<Param name={quoteattr(name)} type="RichPoint3f" x="{x!r}" y="{y!r}" z="{z!r}"/>'


@dataclass
class Filter:
    name: str
    params: dict = field(default_factory=dict)

    def __init__(self, name: str, **params: _P):
        self.name = name
        self.params = params
        for k, v in params.items():
            if not isinstance(v, _P):
                raise TypeError(f"parameter {k} of {name!r} needs a type (Float, Int, Bool, Enum, ...), got {v!r}")

    def set(self, **values) -> "Filter":
        """Override parameter values keeping their types (Enum by index, Point3 by a 3-tuple)."""
        for k, v in values.items():
            if k not in self.params:
                raise KeyError(f"{self.name!r} has no parameter {k!r} (it has {sorted(self.params)})")
            p = self.params[k]
            self.params[k] = v if isinstance(v, _P) else (Enum(v, p.values) if isinstance(p, Enum) else type(p)(v))
            if isinstance(p, SaveFile) and not isinstance(v, _P):
                self.params[k].ext = p.ext
            if isinstance(p, DynamicFloat) and not isinstance(v, _P):
                self.params[k].lo, self.params[k].hi = p.lo, p.hi
        return self

    def xml(self) -> str:
        body = "".join(f"  {p.xml(k)}\n" for k, p in self.params.items())
        return f" <filter name={quoteattr(self.name)}>\n{body} </filter>\n"


@dataclass
class Script:
    filters: list

    def xml(self) -> str:
        return "<!DOCTYPE FilterScript>\n<FilterScript>\n" + "".join(f.xml() for f in self.filters) + "</FilterScript>\n"

    def write(self, path: str) -> str:
        with open(path, "w", encoding="utf-8") as fh:
            fh.write(self.xml())
        return path


def load_script(path: str) -> list:
    """The filters of an .mlx file as Filter objects with typed parameters (e.g. a filter's example
    script, to reuse its complete parameter list and override a few with Filter.set)."""
    import xml.etree.ElementTree as ET
    kinds = {"RichFloat": Float, "RichInt": Int, "RichBool": Bool, "RichString": String, "RichMesh": Mesh,
             "RichAbsPerc": AbsPerc}
    out = []
    for f in ET.parse(path).getroot().iter("filter"):
        params = {}
        for p in f.iter("Param"):
            t, name, v = p.get("type"), p.get("name"), p.get("value")
            if t == "RichEnum":
                n = int(p.get("enum_cardinality"))
                params[name] = Enum(int(v), [p.get(f"enum_val{i}") for i in range(n)])
            elif t == "RichBool":
                params[name] = Bool(v.lower() == "true")
            elif t == "RichPoint3f":
                params[name] = Point3((float(p.get("x")), float(p.get("y")), float(p.get("z"))))
            elif t == "RichSaveFile":
                sf = SaveFile(v)
                sf.ext = p.get("ext", ".csv")
                params[name] = sf
            elif t == "RichDynamicFloat":
                params[name] = DynamicFloat(float(v), float(p.get("min")), float(p.get("max")))
            elif t == "RichOpenFile":
                params[name] = OpenFile(v)
            elif t in ("RichFloat", "RichAbsPerc"):
                params[name] = kinds[t](float(v))
            elif t in ("RichInt", "RichMesh"):
                params[name] = kinds[t](int(v))
            elif t in kinds:
                params[name] = kinds[t](v)
            else:
                raise ValueError(f"{path}: parameter {name} has an unsupported type {t}")
        out.append(Filter(f.get("name"), **params))
    return out


@dataclass
class Result:
    rc: int
    stdout: str
    #: one entry per filter applied, in order: {"filter": <filter name>, "results": {key: value}}
    results: list = field(default_factory=list)

    @property
    def log(self) -> list[str]:
        """The filters' Log() lines (meshlabserver prints them as 'LOG: <level> <text>')."""
        out = []
        for line in self.stdout.splitlines():
            i = line.find("LOG: ")  # other output without a newline can precede it on the line
            if i >= 0:
                line = line[i:]
                parts = line[5:].split(" ", 1)
                out.append(parts[1] if len(parts) == 2 and parts[0].isdigit() else line[5:])
        return out

    def values(self, key: str, filter: str | None = None) -> list:
        """Every value of `key` the filters returned, in the order they ran (only those of the filter named
        `filter`, if given); [] if none."""
        return [r["results"][key] for r in self.results
                if key in r["results"] and (filter is None or r["filter"] == filter)]

    def get(self, key: str, filter: str | None = None, default=None):
        """The last value of `key` (of the filter named `filter`, if given), or `default` when none returned it
        (e.g. after a filter failed: a failed filter returns nothing)."""
        found = self.values(key, filter)
        return found[-1] if found else default

    def value(self, key: str, filter: str | None = None):
        """The last value of `key` the filters returned (of the filter named `filter`, if given); KeyError
        naming the key and the filters that ran when none returned it."""
        found = self.values(key, filter)
        if not found:
            ran = ", ".join(repr(r["filter"]) for r in self.results) or "none"
            where = f" by {filter!r}" if filter else ""
            raise KeyError(f"no result {key!r} returned{where} (filters that returned results: {ran}; exit code {self.rc})")
        return found[-1]


def read_results(path: str) -> list:
    """The JSON lines of a results file ($PECTUS_RESULTS_FILE), in order; [] if it is missing or empty."""
    if not os.path.exists(path):
        return []
    with open(path, encoding="utf-8") as fh:
        return [json.loads(line) for line in fh if line.strip()]


def find_meshlabserver(prefix: str | None = None) -> str:
    """meshlabserver of the given prefix, else of $PECTUS_PREFIX, else of this checkout's build/prefix (where
    the plugins are), else the system one (which sees the plugins only if the .deb is installed)."""
    here = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "build", "prefix")
    for p in (prefix, os.environ.get("PECTUS_PREFIX"), here):
        if p and os.path.exists(os.path.join(p, "bin", "meshlabserver")):
            return os.path.join(p, "bin", "meshlabserver")
    exe = shutil.which("meshlabserver")
    if not exe:
        raise FileNotFoundError("meshlabserver not found: set PECTUS_PREFIX or install meshlab")
    return exe


XVFB_CLEANUP_ERROR = "xvfb-run: error: problem while cleaning up temporary directory"


def userland_suites() -> dict:
    """{MeshLab release: the Debian suite whose userland runs it} (scripts/meshlab_hosts.txt): the releases
    without meshlabserver, run by pectus-mlrun"""
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scripts", "meshlab_hosts.txt")
    with open(path) as fh:
        rows = [line.split() for line in fh if line.strip() and not line.startswith("#")]
    return {r[0]: r[1] for r in rows}


MLRUN_HOSTS = tuple(userland_suites())
HOSTS = ("2020.09",) + MLRUN_HOSTS


def host_made(release: str) -> bool:
    """the release can run here: 2020.09 always (bookworm's meshlabserver), a newer one when scripts/host.sh
    made its userland and its build in this checkout"""
    if release not in MLRUN_HOSTS:
        return release == "2020.09"
    root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    return (os.path.exists(os.path.join(root, ".hosts", userland_suites()[release], ".complete-pkgs"))
            and os.path.exists(os.path.join(root, f"build-{release}", "bin", "pectus-mlrun")))


def default_host() -> str:
    """$PECTUS_MESHLAB_HOST, else 2020.09"""
    h = os.environ.get("PECTUS_MESHLAB_HOST", "2020.09")
    if h not in HOSTS:
        raise ValueError(f"PECTUS_MESHLAB_HOST={h}: one of {', '.join(HOSTS)}")
    return h


def mlrun_script() -> str:
    """scripts/mlrun.sh of this checkout"""
    return os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scripts", "mlrun.sh")


# The progress messages of the project's filters (their ctx.progress / progress callbacks), as regular expressions.
# meshlabserver 2020.09 prints each one with printf("%s") and no newline, so a filter's messages and the first line
# of the Log it prints after the filter arrive run together ("calibrating funnel depthextracting the surface...");
# _tidy_stdout cuts them apart by these. Longer messages first where one begins another.
_NUM = r"-?\d+(?:\.\d+)?"
_FE_PROGRESS = [r"TetGen \(after checking the surface\)", r"Factorising \(CHOLMOD\)", rf"Driving the sternum to {_NUM} mm",
                rf"Calibrating the force: Fe = {_NUM} N", "Solving", "Stress and strain", "Done"]
PROGRESS_MESSAGES = [
    # Pectus: Create Rib Cage (one layer per tissue: the tissue's name)
    "calibrating funnel depth", "extracting the surface", "labelling", "bone", "cartilage", "sternum",
    # element quality, MGA smoothing, C1 surface, quad conversion
    "measuring elements", "writing quality", "building the C1 surface", rf"sweep \d+, mean quality {_NUM}",
    "refining", "writing the mesh", "projecting", "pairing triangles", "writing quads", "structure operators",
    # thoracic volumes and pectus index
    "cutting the planes", "slice regions", "rasterising", "envelope samples", "envelope convergence", "pectus index",
    # Nuss FE analysis, and the bar planner (its options' FE messages after the option's name)
    *_FE_PROGRESS, "Volumes and pectus index before", r"TetGen \(once for every option\)",
    r"(?:1 bar, space \d+|2 bars, spaces \d+ \+ \d+): (?:" + "|".join(_FE_PROGRESS + ["volumes and pectus index after"]) + ")",
    # CT import (each file's name) and patient preparation
    r"[^/\s]+?\.(?:nii\.gz|nii|stl|ply|obj|off|vtk)",
    "classifying the layers", "the structures' solids on one grid", "separating the structures", "numbering the ribs",
    "joining the tissues and the vertebral column", "joining the tissues", "decimating", "landmarks",
    # every filter's last
    "done",
]
PROGRESS = re.compile("|".join(f"(?:{m})" for m in PROGRESS_MESSAGES))


def split_progress(text: str, log_lines: set) -> list[str]:
    """A line of meshlabserver's stdout printed during a filter: the progress messages run together, maybe followed
    by a line of the Log (one of `log_lines`, which meshlabserver prints after the filter): one item per message,
    then the Log's line. A message PROGRESS does not know ends the cutting: it and the rest stay one item."""
    cut = next((i for i in range(len(text)) if text[i:] in log_lines), len(text))
    head, parts = text[:cut], []
    while head:
        m = PROGRESS.match(head)
        if not m or not m.group(0):
            parts.append(head)
            break
        parts.append(m.group(0))
        head = head[m.end():]
    return parts + ([text[cut:]] if cut < len(text) else [])


def _tidy_stdout(line: str, after_filter: bool, log_lines: set) -> list[str]:
    """meshlabserver 2020.09's stdout line as lines: 'Starting Script of N actions' apart from the first
    'filter: NAME', and a line printed during a filter (`after_filter`) cut by split_progress"""
    m = re.match(r"(Starting Script of \d+ actions)(filter: .*)", line)
    if m:
        return [m.group(1), m.group(2)]
    return split_progress(line, log_lines) if after_filter and line else [line]


def _output(p: subprocess.Popen, timeout: float) -> str:
    """Everything `p` prints, stdout and stderr read apart and merged by whole lines in the order they came (the
    filters' 'LOG: ' lines on stderr never cut a line of stdout), each progress message on a line of its own
    (_tidy_stdout). On a timeout the process group is killed and subprocess.TimeoutExpired raised."""
    lines, lock = [], threading.Lock()

    def pump(stream, name):
        for line in iter(stream.readline, ""):
            with lock:
                lines.append((name, line.rstrip("\n")))

    readers = [threading.Thread(target=pump, args=(s, n), daemon=True) for s, n in ((p.stdout, "out"), (p.stderr, "err"))]
    for t in readers:
        t.start()
    try:
        p.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        p.wait()
        raise
    finally:
        for t in readers:
            t.join()
    log_lines = {re.sub(r"^LOG: \d+ ", "", l) for n, l in lines if n == "err" and l.startswith("LOG: ")}
    out, after_filter = [], False
    for name, line in lines:
        if name == "err":
            out.append(line)
            continue
        for piece in _tidy_stdout(line, after_filter, log_lines):
            out.append(piece)
            after_filter = piece.startswith("filter: ")
    return "\n".join(out) + "\n" if out else ""


def run(inputs: Iterable[str], script: Script | str | None, outputs: Sequence[tuple] = (),
        prefix: str | None = None, timeout: float = 3600, cwd: str | None = None, env: dict | None = None,
        host: str | None = None) -> Result:
    """Run a script headless: meshlabserver under xvfb-run (host 2020.09) or pectus-mlrun in the trixie or
    forky userland (host 2022.02 or 2025.07; see default_host). outputs: (path, "vc fq ...", layer_index or None); env:
    variables to set on top of the current environment (e.g. OMP_NUM_THREADS).
    Returns the exit code, everything printed (stdout + stderr) and each filter's results (read from the
    temporary file $PECTUS_RESULTS_FILE names during the run); subprocess.TimeoutExpired on a timeout."""
    host = host or default_host()
    if host in MLRUN_HOSTS:
        cmd = [mlrun_script(), "--host", host]
    elif host == "2020.09":
        exe = find_meshlabserver(prefix)
        # e.g. libasan.so for plugins built with AddressSanitizer (scripts/sanitize.sh e2e): meshlabserver only
        preload = os.environ.get("PECTUS_MESHLAB_PRELOAD")
        launcher = ["env", "LD_PRELOAD=" + preload] if preload else []
        cmd = ["xvfb-run", "-a", "-s", "-screen 0 1024x768x24", *launcher, exe]
    else:
        raise ValueError(f"unknown MeshLab host {host!r}: one of {', '.join(HOSTS)}")
    for i in inputs:
        cmd += ["-i", i]
    tmp = None
    if isinstance(script, Script):
        fd, tmp = tempfile.mkstemp(suffix=".mlx")
        os.close(fd)
        script.write(tmp)
        script = tmp
    for out in outputs:
        path, mask = out[0], out[1] if len(out) > 1 else ""
        cmd += ["-o", path]
        if len(out) > 2 and out[2] is not None:
            cmd += ["-l", str(out[2])]
        if mask:
            cmd += ["-m"] + mask.split()
    if script:
        cmd += ["-s", script]
    # under /tmp: scripts/mlrun.sh shows it inside the userland at the same path
    fd, results_file = tempfile.mkstemp(prefix="pectus-results-", suffix=".jsonl", dir="/tmp")
    os.close(fd)
    run_env = dict(os.environ, **(env or {}), PECTUS_RESULTS_FILE=results_file)
    try:
        for attempt in range(3):
            open(results_file, "w").close()  # a repeated run starts from an empty file
            # own process group: on a timeout meshlabserver (a grandchild under xvfb-run) is killed too
            with subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=cwd, text=True,
                                  errors="replace", env=run_env,
                                  start_new_session=True) as p:
                out = _output(p, timeout)
            # xvfb-run exits 5 when it cannot remove its own temporary folder (seen under parallel load);
            # meshlabserver's exit code is then lost, so run again (the filters are deterministic)
            if not (p.returncode == 5 and XVFB_CLEANUP_ERROR in out):
                break
        return Result(p.returncode, out, read_results(results_file))
    finally:
        os.unlink(results_file)
        if tmp:
            os.unlink(tmp)
