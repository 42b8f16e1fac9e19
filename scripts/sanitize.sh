#!/usr/bin/env bash
# The cores' GoogleTests and the fuzz corpus replays under AddressSanitizer + UndefinedBehaviorSanitizer
# (CMake preset `asan`: gcc, no MeshLab plugins, build dir build-asan/). Any report fails the run.
#   scripts/sanitize.sh          # configure, build everything, ctest (every suite; too slow for CI, see README)
#   scripts/sanitize.sh ci       # the CI stage (.ci/run): the suites that build no rib cage, and the corpus
#                                # replays of c1, mga, quad and volume, under ASan + UBSan
#   scripts/sanitize.sh tsan     # the same under ThreadSanitizer (clang + libomp + Archer), not in CI
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
MODE="${1:-asan}"
cd "$ROOT"
start=$(date +%s)
if [ "$MODE" = ci ]; then
  # every GoogleTest suite except the four that generate a rib cage (test_ribcage, test_nuss,
  # test_bar_planner, test_tissue_join: ~6 min in Release, 2-4x that under ASan, and CGAL's corefinement
  # is a long ASan compile); those run with `scripts/sanitize.sh`
  SUITES=(test_quality test_elements test_c1_surface test_mga test_mga_smooth test_quad_convert
          test_thoracic_volume test_fe_io test_fe_mesher test_fe_solver)
  REPLAYS=(c1 mga quad volume)
  cmake --preset asan >/dev/null
  cmake --build --preset asan -j"$(nproc)" --target "${SUITES[@]}" "${REPLAYS[@]/#/replay_}"
  echo "[sanitize:ci] build took $(( $(date +%s) - start )) s"
  export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1"
  export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
  export OMP_NUM_THREADS=2
  run() {  # one suite, its output only on failure
    local log; log=$(mktemp)
    if "$@" >"$log" 2>&1; then echo "[sanitize:ci] ok   $(basename "$1") $(grep -E '^\[  PASSED' "$log" || true)"
    else echo "[sanitize:ci] FAIL $*"; cat "$log"; rm -f "$log"; return 1; fi
    rm -f "$log"
  }
  for s in "${SUITES[@]}"; do
    run "$(find build-asan -name "$s" -type f -executable | head -1)"
  done
  for r in "${REPLAYS[@]}"; do
    run "build-asan/tests/fuzz/replay_$r" "tests/fuzz/corpus/$r"
  done
  echo "[sanitize:ci] total $(( $(date +%s) - start )) s"
  exit 0
fi
cmake --preset "$MODE" >/dev/null
cmake --build --preset "$MODE" -j"$(nproc)"
echo "[sanitize:$MODE] build took $(( $(date +%s) - start )) s"
ctest --preset "$MODE" -j"$(nproc)" --timeout 1500 ${CTEST_ARGS:-}
echo "[sanitize:$MODE] total $(( $(date +%s) - start )) s"
