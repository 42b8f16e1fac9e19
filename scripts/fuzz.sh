#!/usr/bin/env bash
# Builds the libFuzzer targets and runs each one.
#   scripts/fuzz.sh [RUNS] [MAX_SECONDS] [TARGET...]   defaults: 1000000 runs, 3600 s cap, all targets
#   MAX_LEN=512 (default)                              largest input, bytes (a 7 x 7 jittered grid reads ~300)
#   TIMEOUT=30 (default)                               seconds one input may take (raise it to pause a run with SIGSTOP)
#   FORK=N (default 0)                                 libFuzzer's fork mode: N jobs in parallel, one run, one count
#                                                      (fresh job processes: fuzz_fe_model ~2.5x the inputs/s on 2 cores)
# Build: preset `fuzz` (clang + ASan + UBSan), or PRESET=<another preset with PECTUS_BUILD_FUZZERS>.
# Each target starts from its regression corpus tests/fuzz/corpus/<target>/ (read only) and writes the new
# inputs it finds to <build>/corpus/<target>/; crashes go to <build>/artifacts/<target>/, the log to <build>/fuzz_<target>.log. Minimise a crash
# (-minimize_crash=1), fix it, and add the minimised input to tests/fuzz/corpus/<target>/: ctest's
# fuzz_replay_<target> then keeps it fixed. Run one target at a time: each uses one core (FORK=N: N cores).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
RUNS="${1:-1000000}"
MAXT="${2:-3600}"
shift $(( $# > 2 ? 2 : $# ))
TARGETS=("$@")
[ ${#TARGETS[@]} -gt 0 ] || TARGETS=(c1 mga quad volume fe_model inp)
PRESET="${PRESET:-fuzz}"
BUILD="build-$PRESET"
cd "$ROOT"
cmake --preset "$PRESET" >/dev/null
cmake --build --preset "$PRESET" -j"$(nproc)" --target "${TARGETS[@]/#/fuzz_}"
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
export OMP_NUM_THREADS=1
for t in "${TARGETS[@]}"; do
  mkdir -p "$BUILD/corpus/$t" "$BUILD/artifacts/$t"
  echo "[fuzz] $t ($PRESET): $RUNS runs, at most $MAXT s"
  start=$(date +%s)
  fork=()
  [ "${FORK:-0}" -gt 0 ] && fork=(-fork="$FORK")
  nice -n 10 "$BUILD/tests/fuzz/fuzz_$t" "${fork[@]}" -runs="$RUNS" -max_total_time="$MAXT" -timeout="${TIMEOUT:-30}" -rss_limit_mb=4096 \
    -max_len="${MAX_LEN:-512}" -print_final_stats=1 -artifact_prefix="$BUILD/artifacts/$t/" \
    "$BUILD/corpus/$t" "tests/fuzz/corpus/$t" 2>&1 | tee "$BUILD/fuzz_$t.log" |
    grep -E "^#[0-9]+ +(DONE|pulse)|^INFO: (fuzzed|exiting)|stat::|==[0-9]+==ERROR|fuzz check failed|SUMMARY" || true
  cov=$(grep -oE "cov: [0-9]+" "$BUILD/fuzz_$t.log" | tail -1 || true)
  echo "[fuzz] $t: $(( $(date +%s) - start )) s, $cov, corpus $(ls "$BUILD/corpus/$t" | wc -l) inputs"
done
