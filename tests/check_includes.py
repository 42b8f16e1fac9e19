#!/usr/bin/env python3
"""The include rule of the layers (docs/DEVELOPING.md, "The layers"): reads every #include of common/,
pectus_fe/, tools/ and the filter_* folders and fails, naming the file, the line and the include, when

- a core (common/include, common/src, pectus_fe/include, pectus_fe/src, a plugin's core/) includes Qt or MeshLab's
  headers, or a file outside its own core and the libraries: the common cores, and pectus_fe for a plugin's core
  (common's cores include only common's; pectus_fe's only its own and common's);
- an adapter (the files directly in a filter_* folder) includes another plugin's folder or anything outside its
  own plugin folder and the libraries (common/, including its MeshLab adapter contract, and pectus_fe);
- a test (a tests/ folder) includes an adapter other than its own folder's, or another folder's tests;
- a tool (tools/) includes Qt, MeshLab, an adapter or a test;

and, for the header layout, when a core's or a tool's public header is not under an `include/pectus/` folder, or
a header in `include/pectus/<area>/` does not declare `namespace pectus::<area>` (one in `include/pectus/` itself:
`namespace pectus`). A core's private headers sit beside its sources in `src/`; test-only headers in `tests/`.

A quoted include is resolved as the compiler does: beside the including file first, then in the include
directories the CMakeLists.txt files declare (target_include_directories). An include that names headers in
two of those directories is reported too, since which one the compiler takes depends on the target.

    tests/check_includes.py [ROOT]        exit 0: the tree keeps the rules; 1: the violations are listed
"""
from __future__ import annotations

import os
import re
import sys

SOURCE_EXT = (".h", ".hpp", ".cpp", ".cc", ".cxx", ".inl")
INCLUDE = re.compile(r'^\s*#\s*include\s*([<"])([^>"]+)[>"]')
# Qt (<QString>, <QtCore/...>) and MeshLab (its src/ include root: <common/...>, <meshlab/...>; vcglib's Qt and
# GUI wrappers)
HOST_HEADER = re.compile(r"^(Q[A-Za-z]*|Qt[A-Za-z]*/.*|common/.*|meshlab/.*|wrap/(qt|gui)/.*)$")
# MeshLab's vcglib mesh type (CMeshO, no Qt): the one door is common/include/pectus/cmesh.h
MESH_TYPE_DOOR = "common/include/pectus/cmesh.h"
MESH_TYPE_HEADERS = {"common/ml_mesh_type.h", "common/ml_document/cmesh.h"}


# the libraries every core may build on: the common cores and the FE library
LIBRARIES = ("common", "pectus_fe")


def zone(rel: str) -> tuple[str, str]:
    """(owner, role) of a path relative to the root. owner: 'common', 'pectus_fe', a plugin folder, 'tools' or the
    top folder. role: 'core' (common/include, common/src, pectus_fe/include, pectus_fe/src, a plugin's core/),
    'adapter' (the files directly in a plugin folder, common/meshlab), 'test' (a tests/ folder of any of them),
    'tool' (tools/: the command-line drivers, the phantom and the test fixtures) or 'outside'"""
    parts = rel.split("/")
    top = parts[0]
    if top in LIBRARIES:
        if len(parts) > 2 and parts[1] in ("include", "src"):
            return top, "core"
        if len(parts) > 2 and parts[1] == "meshlab":
            return top, "adapter"
        if len(parts) > 2 and parts[1] == "tests":
            return top, "test"
        return top, "outside"
    if top.startswith("filter_"):
        if len(parts) == 2:
            return top, "adapter"
        if parts[1] == "tests":
            return top, "test"
        if parts[1] == "core":
            return top, "core"
        return top, "outside"
    if top == "tools":
        return top, "tool"
    return top, "outside"


def violation(includer: str, include: str, target: str | None) -> str | None:
    """why `#include include` in `includer` (resolved to `target` in the tree, or None) breaks the rule"""
    owner, role = zone(includer)
    if target is None:  # outside the tree: the standard library, vcglib, Eigen, CGAL, TetGen, ..., Qt, MeshLab
        if role not in ("core", "tool") or not HOST_HEADER.match(include):
            return None
        if includer == MESH_TYPE_DOOR and include in MESH_TYPE_HEADERS:
            return None
        return f"a {role} includes Qt or MeshLab (the mesh type comes from pectus/cmesh.h)"
    t_owner, t_role = zone(target)
    if role == "core":
        if t_role == "core" and (t_owner == owner or t_owner == "common"
                                 or (t_owner == "pectus_fe" and owner != "common")):
            return None
        if t_role == "adapter" and t_owner == "common":
            return f"a core includes common's MeshLab adapter contract ({target})"
        if t_owner == owner and t_role == "adapter":
            return f"a core includes its plugin's adapter ({target})"
        return f"a core includes {target}, outside its own core and the libraries ({', '.join(LIBRARIES)})"
    if role == "adapter":
        if t_owner == owner or (t_owner in LIBRARIES and t_role in ("core", "adapter")):
            return None
        if t_owner.startswith("filter_"):
            return f"an adapter includes another plugin's folder ({target})"
        return f"an adapter includes {target}, outside its plugin and the libraries ({', '.join(LIBRARIES)})"
    if role == "test":
        if t_role in ("core", "tool", "test") and (t_role != "test" or t_owner == owner):
            return None
        if t_role == "adapter" and t_owner == owner:
            return None  # an adapter's own tests (common/tests: the adapter contract)
        return f"a test includes {target}: tests use the cores, the tools' fixtures and their own folder"
    if role == "tool":
        if t_role in ("core", "tool"):
            return None
        return f"a tool includes {target}: tools use the cores and tools/ only"
    return None


def include_dirs(root: str, cmake_files: list[str]) -> list[str]:
    """the folders in the tree that target_include_directories names, relative to the root"""
    dirs = []
    for cm in cmake_files:
        here = os.path.dirname(cm)
        with open(cm, encoding="utf-8") as fh:
            text = re.sub(r"(?m)#[^\"\n]*$", "", fh.read())
        for call in re.findall(r"target_include_directories\s*\((.*?)\)", text, re.S):
            for arg in re.findall(r'"([^"]*)"|(\S+)', call):
                a = arg[0] or arg[1]
                a = a.replace("${CMAKE_CURRENT_SOURCE_DIR}", here).replace("${CMAKE_SOURCE_DIR}", root)
                if "${" in a or not os.path.isabs(a):
                    continue
                a = os.path.normpath(a)
                if os.path.isdir(a) and a.startswith(root + os.sep):
                    rel = os.path.relpath(a, root)
                    if rel not in dirs:
                        dirs.append(rel)
    return dirs


def scanned_files(root: str) -> tuple[list[str], list[str]]:
    """(the sources of common/, pectus_fe/, tools/ and the filter_* folders relative to the root, the tree's
    CMakeLists.txt files)"""
    sources, cmakes = [], []
    for d, subdirs, names in os.walk(root):
        subdirs[:] = sorted(s for s in subdirs if not s.startswith((".", "build")) and s != "third_party")
        top = os.path.relpath(d, root).split(os.sep)[0]
        for n in sorted(names):
            p = os.path.join(d, n)
            if n == "CMakeLists.txt":
                cmakes.append(p)
            elif n.endswith(SOURCE_EXT) and (top in LIBRARIES or top == "tools" or top.startswith("filter_")):
                sources.append(os.path.relpath(p, root))
    return sources, cmakes


NAMESPACE = re.compile(r"^\s*namespace\s+([A-Za-z_][\w:]*)\s*\{", re.M)


def layout_violation(rel: str, text: str) -> str | None:
    """why the header `rel` (relative to the root) with source `text` breaks the header layout, or None"""
    owner, role = zone(rel)
    if role not in ("core", "tool") or not rel.endswith((".h", ".hpp")):
        return None
    parts = rel.split("/")
    if "src" in parts:
        return None  # a core's private header beside its sources
    if "include" not in parts or parts[parts.index("include") + 1:parts.index("include") + 2] != ["pectus"]:
        return "a core's public header outside an include/pectus/ folder (move it to include/pectus/<area>/)"
    below = parts[parts.index("include") + 2:]
    want = "pectus" if len(below) == 1 else "pectus::" + "::".join(below[:-1])
    declared = [n for n in NAMESPACE.findall(text) if n.startswith("pectus")]
    if not declared:
        return f"declares no namespace; its folder says {want}"
    wrong = sorted({n for n in declared if n != want and not n.startswith(want + "::detail")})
    if wrong:
        return f"declares namespace {', '.join(wrong)}; its folder says {want}"
    return None


def resolve(root: str, dirs: list[str], includer: str, delim: str, include: str) -> list[str]:
    """the files in the tree the include can name, relative to the root"""
    if delim == '"':
        beside = os.path.normpath(os.path.join(os.path.dirname(includer), include))
        if os.path.isfile(os.path.join(root, beside)):
            return [beside]
    found = []
    for d in dirs:
        rel = os.path.normpath(os.path.join(d, include))
        if os.path.isfile(os.path.join(root, rel)) and rel not in found:
            found.append(rel)
    return found


def self_check() -> list[str]:
    """the rule on known cases, so that a rule that lets everything through fails too"""
    cases = [
        ("filter_nuss_fea/core/include/pectus/nuss/bar_planner.h", "pectus/smooth/mga_smooth.h",
         "filter_mga_smooth/core/include/pectus/smooth/mga_smooth.h", True),
        ("filter_nuss_fea/core/include/pectus/nuss/bar_planner.h", "QString", None, True),
        ("pectus_fe/src/io.cpp", "common/globals.h", None, True),
        ("pectus_fe/src/io.cpp", "pectus/nuss/nuss_analysis.h",
         "filter_nuss_fea/core/include/pectus/nuss/nuss_analysis.h", True),
        ("common/src/quality.cpp", "QObject", None, True),
        ("common/src/quality.cpp", "pectus/ribcage/ribcage.h", "filter_ribcage/core/include/pectus/ribcage/ribcage.h",
         True),
        ("common/src/quality.cpp", "pectus/fe/solver.h", "pectus_fe/include/pectus/fe/solver.h", True),
        ("filter_patient/core/src/prepare.cpp", "pectus/ribcage/ribcage.h",
         "filter_ribcage/core/include/pectus/ribcage/ribcage.h", True),
        ("filter_patient/core/src/prepare.cpp", "pectus/mesh_simplify.h", "common/include/pectus/mesh_simplify.h",
         False),
        ("filter_nuss_fea/core/src/nuss_analysis.cpp", "pectus/fe/solver.h", "pectus_fe/include/pectus/fe/solver.h",
         False),
        ("filter_mga_smooth/core/src/mga.cpp", "filter_plugin.h", "common/meshlab/filter_plugin.h", True),
        ("filter_mga_smooth/core/src/mga.cpp", "filter_mga_smooth.h", "filter_mga_smooth/filter_mga_smooth.h", True),
        ("common/src/labels.cpp", "plot.h", "common/meshlab/plot.h", True),
        ("filter_thoracic_volume/filter_thoracic_volume.cpp", "pectus/ribcage/ribcage.h",
         "filter_ribcage/core/include/pectus/ribcage/ribcage.h", True),
        ("filter_nuss_fea/core/include/pectus/nuss/bar_planner.h", "pectus/vol/thoracic_volume.h",
         "common/include/pectus/vol/thoracic_volume.h", False),
        ("filter_nuss_fea/filter_nuss_fea.cpp", "plot.h", "common/meshlab/plot.h", False),
        ("filter_nuss_fea/filter_nuss_fea.cpp", "QFileInfo", None, False),
        ("filter_nuss_fea/filter_nuss_fea.cpp", "pectus/patient/prepare.h",
         "filter_patient/core/include/pectus/patient/prepare.h", True),
        ("filter_patient/filter_patient.cpp", "pectus/patient/prepare.h",
         "filter_patient/core/include/pectus/patient/prepare.h", False),
        ("filter_patient/tests/test_patient_spine.cpp", "pectus/phantom/ct_phantom_core.h",
         "tools/include/pectus/phantom/ct_phantom_core.h", False),
        ("filter_patient/tests/test_patient_spine.cpp", "filter_nuss_fea.h", "filter_nuss_fea/filter_nuss_fea.h", True),
        ("tools/ct_phantom.cpp", "QString", None, True),
        ("tools/ct_phantom.cpp", "filter_plugin.h", "common/meshlab/filter_plugin.h", True),
        ("common/include/pectus/cmesh.h", "common/ml_mesh_type.h", None, False),
        ("common/include/pectus/labels.h", "common/ml_mesh_type.h", None, True),
    ]
    layouts = [
        ("filter_nuss_fea/core/include/pectus/nuss/bar_planner.h", "namespace pectus::nuss {", False),
        ("filter_nuss_fea/core/include/pectus/nuss/bar_planner.h", "namespace pectus::ribcage {", True),
        ("filter_nuss_fea/core/bar_planner.h", "namespace pectus::nuss {", True),
        ("common/include/pectus/errors.h", "namespace pectus {", False),
        ("common/include/pectus/c1/surface.h", "namespace pectus {", True),
        ("filter_mga_smooth/core/src/private.h", "namespace pectus::smooth {", False),
        ("tools/include/pectus/fixture/coarse_cage.h", "namespace pectus::fixture {", False),
        ("tools/include/pectus/fixture/coarse_cage.h", "namespace pectus {", True),
        ("pectus_fe/include/pectus/fe/solver.h", "namespace pectus::fe {", False),
        ("filter_nuss_fea/filter_nuss_fea.h", "namespace pectus::ml {", False),
    ]
    wrong = []
    for rel, text, bad in layouts:
        if (layout_violation(rel, text) is not None) != bad:
            wrong.append(f"self-check: {rel} with '{text}' should {'fail' if bad else 'pass'} the header layout")
    for includer, include, target, bad in cases:
        if (violation(includer, include, target) is not None) != bad:
            wrong.append(f"self-check: {includer}: #include {include} should {'fail' if bad else 'pass'}")
    return wrong


def main() -> int:
    root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), ".."))
    problems = self_check()
    sources, cmakes = scanned_files(root)
    dirs = include_dirs(root, cmakes)
    count = 0
    for rel in sources:
        with open(os.path.join(root, rel), encoding="utf-8", errors="replace") as fh:
            text = fh.read()
        why = layout_violation(rel, text)
        if why:
            problems.append(f"{rel}: {why}")
        for k, line in enumerate(text.splitlines(), 1):
            m = INCLUDE.match(line)
            if not m:
                continue
            count += 1
            delim, include = m.groups()
            shown = f'"{include}"' if delim == '"' else f"<{include}>"
            targets = resolve(root, dirs, rel, delim, include)
            if len(targets) > 1:
                problems.append(f"{rel}:{k}: #include {shown} names {len(targets)} headers ({', '.join(targets)}); "
                                "give it a unique path")
                continue
            why = violation(rel, include, targets[0] if targets else None)
            if why:
                problems.append(f"{rel}:{k}: #include {shown}: {why}")
    if len(sources) < 50 or len(dirs) < 5:
        problems.append(f"only {len(sources)} sources and {len(dirs)} include directories found under {root}")
    for p in problems:
        print(p)
    print(f"{count} includes in {len(sources)} files checked ({len(dirs)} include directories): "
          + (f"{len(problems)} violations of the include rule or the header layout (docs/DEVELOPING.md, "
                "'The layers')" if problems else "the include rule and the header layout hold"))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
