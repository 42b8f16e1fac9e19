"""The product speaks of itself only: no development history (work sessions, issue numbers) in the README,
the docs, the sources, build files, scripts or tests. The history of a change belongs in its commit message."""
from __future__ import annotations

import os
import re

from docs_pages import SOURCE
from harness import check, finish

PATTERN = re.compile(r"session [0-9]|sessions? [0-9]|issue #?[0-9]", re.I)
SKIP_DIRS = {".git", ".hosts", "third_party", "corpus", "out", "__pycache__"}
TEXT = (".md", ".cpp", ".h", ".hpp", ".py", ".sh", ".txt", ".cmake", ".json", ".mlx", ".in")


def files():
    for top, dirs, names in os.walk(SOURCE):
        dirs[:] = [d for d in dirs if d not in SKIP_DIRS and not d.startswith("build")]
        for n in names:
            if n.endswith(TEXT) or n in ("run", "CMakeLists.txt", ".gitignore"):
                yield os.path.join(top, n)


def main():
    hits, count = [], 0
    for path in files():
        count += 1
        with open(path, encoding="utf-8", errors="replace") as fh:
            for k, line in enumerate(fh, 1):
                if PATTERN.search(line):
                    hits.append(f"{os.path.relpath(path, SOURCE)}:{k}: {line.strip()[:160]}")
    check(count > 100, f"{count} files read")
    check(not hits, "no session or issue numbers in the product", "\n" + "\n".join(hits))
    finish()


if __name__ == "__main__":
    main()
