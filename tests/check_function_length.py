#!/usr/bin/env python3
"""No function of a core is longer than 80 lines (docs/DEVELOPING.md, "Cores read as their steps"): lists every
function in the cores (common/include, common/src, pectus_fe/include, pectus_fe/src and each plugin's core/)
whose definition, from the line of its name to its closing brace, spans more than 80 lines, and fails if there
is one. Universal Ctags finds the functions and their ends; a lambda counts inside the function that holds it.

    tests/check_function_length.py [ROOT]     exit 0: none is longer; 1: they are listed
"""
from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys

LIMIT = 80
SOURCE_EXT = (".h", ".hpp", ".cpp", ".cc", ".inl")


def core_sources(root: str) -> list[str]:
    """the cores' sources, relative to the root"""
    out = []
    for top in sorted(os.listdir(root)):
        if top in ("common", "pectus_fe"):
            dirs = [os.path.join(top, "include"), os.path.join(top, "src")]
        elif top.startswith("filter_"):
            dirs = [os.path.join(top, "core")]
        else:
            continue
        for d in dirs:
            for here, subdirs, names in os.walk(os.path.join(root, d)):
                subdirs.sort()
                out += [os.path.relpath(os.path.join(here, n), root) for n in sorted(names) if n.endswith(SOURCE_EXT)]
    return out


def long_functions(root: str, rel: str, ctags: str) -> list[tuple[int, str, int]]:
    """(first line, name, length) of each function in `rel` longer than LIMIT lines, lambdas left to their holder"""
    tags = subprocess.run([ctags, "--fields=+ne", "--c++-kinds=f", "--language-force=C++", "-o", "-",
                           os.path.join(root, rel)], capture_output=True, text=True, check=True).stdout
    spans = []
    for line in tags.splitlines():
        name = line.split("\t")[0]
        a, b = re.search(r"\tline:(\d+)", line), re.search(r"\tend:(\d+)", line)
        if a and b and not name.startswith("__anon"):
            spans.append((int(a.group(1)), int(b.group(1)), name))
    return [(s, n, e - s + 1) for s, e, n in spans if e - s + 1 > LIMIT]


def main() -> int:
    root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), ".."))
    ctags = shutil.which("ctags-universal") or shutil.which("ctags")
    if not ctags:
        print("Universal Ctags is missing: install the Debian package universal-ctags (scripts/setup.sh)")
        return 1
    sources = core_sources(root)
    found = [(rel, *f) for rel in sources for f in long_functions(root, rel, ctags)]
    for rel, line, name, n in found:
        print(f"{rel}:{line}: {name} is {n} lines long (at most {LIMIT}): make it read as its steps")
    if len(sources) < 50:
        print(f"only {len(sources)} core sources found under {root}")
        return 1
    print(f"{len(sources)} core sources: " + (f"{len(found)} functions over {LIMIT} lines" if found
                                              else f"no function over {LIMIT} lines"))
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
