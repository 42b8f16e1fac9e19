"""Every shell block of the README and of docs/ runs as written: each ```sh block, from the repository root,
under bash -e -o pipefail, within PECTUS_DOCS_LIMIT seconds (default 180: a block must finish within a
minute on an idle 2-core machine; the margin is for ctest's parallel load), with Debian's /usr/bin first on
the PATH, as on the machine the README's setup makes. Blocks fenced ```sh long
(minutes: the main job, the full FE analysis, the test suite) or ```sh install (changes the system) are
listed, not run; every page's example is also given as a quick block that does run."""
from __future__ import annotations

import glob
import os
import subprocess
import time

from docs_pages import SOURCE, shell_blocks
from harness import check, finish

LIMIT = float(os.environ.get("PECTUS_DOCS_LIMIT", "180")) * float(os.environ.get("PECTUS_TIMEOUT_SCALE", "1"))
ENV = dict(os.environ, PATH="/usr/bin:/bin:" + os.environ.get("PATH", ""))
DOCS = [os.path.join(SOURCE, "README.md")] + sorted(glob.glob(os.path.join(SOURCE, "docs", "**", "*.md"),
                                                             recursive=True))


def main():
    ran = skipped = 0
    for path in DOCS:
        rel = os.path.relpath(path, SOURCE)
        for line, info, body in shell_blocks(path):
            words = info.split()
            if len(words) > 1:
                check(words[1] in ("long", "install"), f"{rel}:{line}: fence '{info}' is sh, sh long or sh install")
                skipped += 1
                continue
            t0 = time.time()
            try:
                r = subprocess.run(["bash", "-e", "-o", "pipefail", "-c", body], cwd=SOURCE, capture_output=True,
                                   text=True, timeout=LIMIT, env=ENV)
                rc, out = r.returncode, (r.stdout + r.stderr)[-3000:]
            except subprocess.TimeoutExpired:
                rc, out = "timeout", ""
            dt = time.time() - t0
            ran += 1
            check(rc == 0, f"{rel}:{line}: the block runs ({dt:.1f} s)", f"rc {rc}\n{body}\n{out}")
    check(ran > 0, f"{ran} blocks ran, {skipped} long or install blocks listed")
    finish()


if __name__ == "__main__":
    main()
