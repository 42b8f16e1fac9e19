#!/usr/bin/env bash
# The cores' GoogleTests and the fuzz corpus replays under AddressSanitizer + UndefinedBehaviorSanitizer
# (CMake preset `asan`: gcc, no MeshLab plugins, build dir build-asan/). Any report fails the run.
#   scripts/sanitize.sh          # configure, build everything, ctest (every suite; too slow for CI, see docs/robustness.md)
#   scripts/sanitize.sh ci       # the CI stage (.ci/run): the suites that build no rib cage, and the corpus
#                                # replays of c1, mga, quad and volume, under ASan + UBSan
#   scripts/sanitize.sh tsan     # the same under ThreadSanitizer (clang + libomp + Archer), not in CI
#   scripts/sanitize.sh e2e      # the MeshLab plugins under ASan + UBSan (preset asan-e2e, build-asan-e2e/) and
#                                # every end-to-end test through the real meshlabserver with libasan preloaded;
#                                # any sanitizer report (written to build-asan-e2e/sanitizer-reports/) fails the
#                                # run. Leak checking is off there: MeshLab and Qt are not instrumented and keep
#                                # memory to exit (the cores' leaks are checked by the GoogleTest runs). Not in CI
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
. "$ROOT/scripts/cache.sh"   # ccache outside the clone
MODE="${1:-asan}"
cd "$ROOT"
start=$(date +%s)
if [ "$MODE" = ci ]; then
  # every GoogleTest suite except the six that generate a rib cage (test_ribcage, test_nuss,
  # test_bar_planner, test_tissue_join, test_patient_prepare, test_ct_phantom: ~6 min in Release, 2-4x that
  # under ASan, and CGAL's corefinement is a long ASan compile); those run with `scripts/sanitize.sh`
  SUITES=(test_quality test_elements test_surface test_errors test_c1_surface test_mga test_mga_smooth
          test_quad_convert test_thoracic_volume test_fe_io test_fe_mesher test_fe_solver test_label_volume
          test_ct_import test_ct_import_nifti)
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
    run "$(find build-asan -name "$s" -type f -executable | sed -n 1p)"
  done
  for r in "${REPLAYS[@]}"; do
    run "build-asan/tests/fuzz/replay_$r" "tests/fuzz/corpus/$r"
  done
  echo "[sanitize:ci] total $(( $(date +%s) - start )) s"
  exit 0
fi
if [ "$MODE" = e2e ]; then
  cmake --preset asan-e2e >/dev/null
  cmake --build --preset asan-e2e -j"$(nproc)"
  echo "[sanitize:e2e] build took $(( $(date +%s) - start )) s"
  reports="$ROOT/build-asan-e2e/sanitizer-reports"
  rm -rf "$reports" && mkdir -p "$reports"
  export PECTUS_MESHLAB_PRELOAD="$(gcc -print-file-name=libasan.so)"  # the runtime first, before MeshLab's libraries
  # no strict_string_checks here: libxkbcommon (under Qt's xcb platform) strndup()s a buffer without a terminator
  export ASAN_OPTIONS="detect_leaks=0:abort_on_error=1:log_path=$reports/asan"
  export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:log_path=$reports/ubsan"
  export PECTUS_TIMEOUT_SCALE=5
  rc=0
  ( cd build-asan-e2e && ctest -L e2e --output-on-failure -j"$(nproc)" ${CTEST_ARGS:-} ) || rc=$?
  if [ -n "$(ls -A "$reports")" ]; then
    echo "[sanitize:e2e] sanitizer reports:"; head -n 60 "$reports"/*; rc=1
  fi
  # gcc's UBSan in a plugin writes to meshlabserver's stderr, which the tests print on failure
  if grep -nE "runtime error:|ERROR: (Address|Undefined|Leak)Sanitizer" build-asan-e2e/Testing/Temporary/LastTest.log; then rc=1; fi
  echo "[sanitize:e2e] total $(( $(date +%s) - start )) s, $( [ $rc = 0 ] && echo clean || echo FAILED)"
  exit $rc
fi
cmake --preset "$MODE" >/dev/null
cmake --build --preset "$MODE" -j"$(nproc)"
echo "[sanitize:$MODE] build took $(( $(date +%s) - start )) s"
ctest --preset "$MODE" -j"$(nproc)" --timeout 1500 ${CTEST_ARGS:-}
echo "[sanitize:$MODE] total $(( $(date +%s) - start )) s"
