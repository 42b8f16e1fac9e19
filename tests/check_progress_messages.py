#!/usr/bin/python3
"""Every progress message the filters give as a plain string literal (progress(N, "..."), prog(N, "..."),
report(opt, N, "...")) is one that python/pectus_mlx.py's PROGRESS_MESSAGES knows: meshlabserver 2020.09 prints
the messages without newlines, and pectus_mlx cuts them apart by that list. Reads the sources, builds nothing.

    tests/check_progress_messages.py [SOURCE_DIR]
"""
import os
import re
import sys

ROOT = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(ROOT, "python"))
import pectus_mlx  # noqa: E402

# a call whose message argument is a whole string literal (messages built at run time have patterns of their own)
CALL = re.compile(r'\b(?:progress|prog|report)\((?:[^;()"]*,)?\s*[^;()"]*,\s*"([^"]+)"\s*\)')
SKIP = {".git", ".hosts", "third_party", "tests", "tools", "mlrun"}


def sources():
    for top, dirs, names in os.walk(ROOT):
        dirs[:] = [d for d in dirs if d not in SKIP and not d.startswith("build")]
        for n in names:
            if n.endswith((".cpp", ".h")):
                yield os.path.join(top, n)


def main() -> int:
    found, unknown = 0, []
    for path in sources():
        with open(path, encoding="utf-8", errors="replace") as fh:
            for k, line in enumerate(fh, 1):
                for m in CALL.finditer(line):
                    found += 1
                    if not pectus_mlx.PROGRESS.fullmatch(m.group(1)):
                        unknown.append(f"{os.path.relpath(path, ROOT)}:{k}: {m.group(1)!r}")
    for u in unknown:
        print(f"not in pectus_mlx.PROGRESS_MESSAGES: {u}")
    print(f"{found} progress messages in the sources, {len(unknown)} unknown to pectus_mlx")
    return 1 if unknown or found < 20 else 0


if __name__ == "__main__":
    sys.exit(main())
