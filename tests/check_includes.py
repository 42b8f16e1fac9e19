#!/usr/bin/env python3
"""The include rule of the layers (docs/DEVELOPING.md, "The layers"): reads every #include of common/ and of
the filter_* folders and fails, naming the file, the line and the include, when

- a core (common/include, common/src, or any subfolder of a filter_* folder: core/, fe/, patient/, tools/,
  tests/) includes Qt or MeshLab's headers, or a file outside its own plugin folder and the common cores;
- an adapter (the files directly in a filter_* folder) includes another plugin's folder or anything outside
  its own plugin folder and common/;
- common/ includes a plugin's folder.

A quoted include is resolved as the compiler does: beside the including file first, then in the include
directories the CMakeLists.txt files declare (target_include_directories). An include that names headers in
two of those directories is reported too, since which one the compiler takes depends on the target.

    tests/check_includes.py [ROOT]        exit 0: the tree keeps the rule; 1: the violations are listed
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


def zone(rel: str) -> tuple[str, str]:
    """(owner, role) of a path relative to the root: owner 'common', a plugin folder, or the top folder;
    role 'core', 'adapter' (a plugin's adapter files, common/meshlab), 'common-other' or 'outside'"""
    parts = rel.split("/")
    if parts[0] == "common":
        if len(parts) > 2 and parts[1] in ("include", "src"):
            return "common", "core"
        if len(parts) > 2 and parts[1] == "meshlab":
            return "common", "adapter"
        return "common", "common-other"
    if parts[0].startswith("filter_"):
        return parts[0], "adapter" if len(parts) == 2 else "core"
    return parts[0], "outside"


def violation(includer: str, include: str, target: str | None) -> str | None:
    """why `#include include` in `includer` (resolved to `target` in the tree, or None) breaks the rule"""
    owner, role = zone(includer)
    if target is None:  # outside the tree: the standard library, vcglib, Eigen, CGAL, TetGen, ..., Qt, MeshLab
        if role != "core" or not HOST_HEADER.match(include):
            return None
        if includer == MESH_TYPE_DOOR and include in MESH_TYPE_HEADERS:
            return None
        return "a core includes Qt or MeshLab (the mesh type comes from pectus/cmesh.h)"
    t_owner, t_role = zone(target)
    if role == "core":
        if t_owner == owner and t_role == "core" or (t_owner, t_role) == ("common", "core"):
            return None
        if (t_owner, t_role) == ("common", "adapter"):
            return f"a core includes common's MeshLab adapter contract ({target})"
        if t_owner == owner and t_role == "adapter":
            return f"a core includes its plugin's adapter ({target})"
        return f"a core includes {target}, outside its plugin's core and the common cores"
    if owner == "common":
        if t_owner == "common":
            return None
        return f"common/ includes {target}, outside common/"
    if role == "adapter":
        if t_owner in (owner, "common"):
            return None
        if t_owner.startswith("filter_"):
            return f"an adapter includes another plugin's folder ({target})"
        return f"an adapter includes {target}, outside its plugin and common/"
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
    """(the sources of common/ and the filter_* folders relative to the root, the tree's CMakeLists.txt files)"""
    sources, cmakes = [], []
    for d, subdirs, names in os.walk(root):
        subdirs[:] = sorted(s for s in subdirs if not s.startswith((".", "build")) and s != "third_party")
        top = os.path.relpath(d, root).split(os.sep)[0]
        for n in sorted(names):
            p = os.path.join(d, n)
            if n == "CMakeLists.txt":
                cmakes.append(p)
            elif n.endswith(SOURCE_EXT) and (top == "common" or top.startswith("filter_")):
                sources.append(os.path.relpath(p, root))
    return sources, cmakes


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
        ("filter_nuss_fea/core/bar_planner.h", "mga_smooth.h", "filter_mga_smooth/core/mga_smooth.h", True),
        ("filter_nuss_fea/core/bar_planner.h", "QString", None, True),
        ("filter_nuss_fea/fe/src/io.cpp", "common/globals.h", None, True),
        ("common/src/quality.cpp", "QObject", None, True),
        ("common/src/quality.cpp", "ribcage.h", "filter_nuss_fea/core/ribcage.h", True),
        ("filter_mga_smooth/core/mga.cpp", "filter_plugin.h", "common/meshlab/filter_plugin.h", True),
        ("filter_mga_smooth/core/mga.cpp", "filter_mga_smooth.h", "filter_mga_smooth/filter_mga_smooth.h", True),
        ("common/src/labels.cpp", "plot.h", "common/meshlab/plot.h", True),
        ("filter_thoracic_volume/filter_thoracic_volume.cpp", "ribcage.h", "filter_nuss_fea/core/ribcage.h", True),
        ("filter_nuss_fea/core/bar_planner.h", "pectus/thoracic_volume.h", "common/include/pectus/thoracic_volume.h",
         False),
        ("filter_nuss_fea/filter_nuss_fea.cpp", "plot.h", "common/meshlab/plot.h", False),
        ("filter_nuss_fea/filter_nuss_fea.cpp", "QFileInfo", None, False),
        ("filter_nuss_fea/filter_patient.cpp", "prepare.h", "filter_nuss_fea/patient/prepare.h", False),
        ("common/include/pectus/cmesh.h", "common/ml_mesh_type.h", None, False),
        ("common/include/pectus/labels.h", "common/ml_mesh_type.h", None, True),
    ]
    wrong = []
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
            for k, line in enumerate(fh, 1):
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
          + (f"{len(problems)} violations of the include rule (docs/DEVELOPING.md, 'The layers')" if problems
             else "the include rule holds"))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
