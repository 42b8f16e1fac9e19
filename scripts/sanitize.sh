#!/usr/bin/env bash
# The cores' GoogleTests and the fuzz corpus replays under AddressSanitizer + UndefinedBehaviorSanitizer
# (CMake preset `asan`: gcc, no MeshLab plugins, build dir build-asan/). Any report fails the run.
#   scripts/sanitize.sh          # configure, build, ctest (not in CI: too slow for its budget, see README)
#   scripts/sanitize.sh tsan     # the same under ThreadSanitizer (clang + libomp + Archer), not in CI
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
PRESET="${1:-asan}"
cd "$ROOT"
start=$(date +%s)
cmake --preset "$PRESET" >/dev/null
cmake --build --preset "$PRESET" -j"$(nproc)"
echo "[sanitize:$PRESET] build took $(( $(date +%s) - start )) s"
ctest --preset "$PRESET" -j"$(nproc)" --timeout 1500 ${CTEST_ARGS:-}
echo "[sanitize:$PRESET] total $(( $(date +%s) - start )) s"
