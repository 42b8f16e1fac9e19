#!/usr/bin/env bash
# Builds the libFuzzer targets (CMake preset `fuzz`: clang, ASan + UBSan) and runs each one.
#   scripts/fuzz.sh [RUNS] [MAX_SECONDS] [TARGET...]   defaults: 1000000 runs, 3600 s cap, all targets
# Each target starts from its regression corpus tests/fuzz/corpus/<target>/ (read only) and writes the new
# inputs it finds to build-fuzz/corpus/<target>/; crashes go to build-fuzz/artifacts/<target>/. Minimise
# a crash (-minimize_crash=1), fix it, and add the minimised input to tests/fuzz/corpus/<target>/: ctest's
# fuzz_replay_<target> then keeps it fixed.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
RUNS="${1:-1000000}"
MAXT="${2:-3600}"
shift $(( $# > 2 ? 2 : $# ))
TARGETS=("$@")
[ ${#TARGETS[@]} -gt 0 ] || TARGETS=(c1 mga quad volume fe_model)
cd "$ROOT"
cmake --preset fuzz >/dev/null
cmake --build --preset fuzz -j"$(nproc)" --target "${TARGETS[@]/#/fuzz_}"
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
export OMP_NUM_THREADS=1
for t in "${TARGETS[@]}"; do
  mkdir -p "build-fuzz/corpus/$t" "build-fuzz/artifacts/$t"
  echo "[fuzz] $t: $RUNS runs, at most $MAXT s"
  nice -n 10 "build-fuzz/tests/fuzz/fuzz_$t" -runs="$RUNS" -max_total_time="$MAXT" -timeout=30 -rss_limit_mb=4096 \
    -print_final_stats=1 -artifact_prefix="build-fuzz/artifacts/$t/" \
    "build-fuzz/corpus/$t" "tests/fuzz/corpus/$t" 2>&1 | tee "build-fuzz/fuzz_$t.log" | grep -E "^(#[0-9]+ +(DONE|pulse)|stat::|==[0-9]+==ERROR|SUMMARY)" || true
done
