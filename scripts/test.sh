#!/usr/bin/env bash
# Sets everything up on a fresh Debian bookworm machine (as root), builds, and runs every test:
# GoogleTest unit tests of the cores and end-to-end tests through the real meshlabserver (xvfb-run).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
start=$(date +%s)
"$ROOT/scripts/setup.sh"
echo "[test] setup + build took $(( $(date +%s) - start )) s"
cd "$ROOT/build"
ctest --output-on-failure -j"$(nproc)" --timeout 1500
# the cores under AddressSanitizer + UBSan (the suites that build no rib cage; docs/robustness.md);
# PECTUS_SANITIZE=0 skips it
if [ "${PECTUS_SANITIZE:-1}" != 0 ]; then "$ROOT/scripts/sanitize.sh" ci; fi
echo "[test] total $(( $(date +%s) - start )) s"
