#!/usr/bin/env bash
# Sets everything up on a fresh Debian bookworm machine (as root), builds, and runs every test:
# GoogleTest unit tests of the cores and end-to-end tests through the real meshlabserver (xvfb-run);
# the same plugins for MeshLab 2025.07 (a Debian forky userland, scripts/host.sh): their unit tests there
# and the end-to-end tests through pectus-mlrun; then the cores under ASan + UBSan.
# PECTUS_HOST_2025=0 skips the 2025.07 host; PECTUS_SANITIZE=0 the sanitizer stage.
# MeshLab 2022.02 (scripts/host.sh 2022.02) is not made here; its end-to-end tests run when it was made.
#
# The compiler cache, the forky userland and MeshLab's headers are kept outside the clone
# (scripts/cache.sh: /var/cache/pectus-meshlab), so a second run on the same machine rebuilds only what
# changed. All tests run in one ctest run, longest first (ctest's cost data, kept in the cache too; on a
# fresh machine tests/ctest_costs.txt), so both cores stay busy to the end. At the end a table gives the
# time of each stage and the 15 slowest tests (docs/DEVELOPING.md: the budget).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
. "$ROOT/scripts/cache.sh"
LOGS="$ROOT/build/test-logs"
start=$(date +%s)
STAGES=()
stage() {  # stage NAME CMD...: runs CMD, records its time
  local name="$1" t rc=0
  shift
  t=$(date +%s)
  "$@" || rc=$?
  STAGES+=("$name|$(( $(date +%s) - t ))|$([ $rc = 0 ] && echo ok || echo "FAILED ($rc)")")
  echo "[test] $name took $(( $(date +%s) - t )) s"
  return $rc
}
report() {
  local rc=$?
  echo
  echo "[test] stages"
  printf '  %-44s %8s  %s\n' stage seconds result
  local s
  for s in "${STAGES[@]}"; do IFS='|' read -r n secs res <<<"$s"; printf '  %-44s %8s  %s\n' "$n" "$secs" "$res"; done
  printf '  %-44s %8s\n' total "$(( $(date +%s) - start ))"
  if [ -f "$LOGS/ctest.log" ]; then
    echo "[test] the 15 slowest tests (s)"
    sed -nE 's/^ *[0-9]+\/[0-9]+ Test +#[0-9]+: ([^ ]+) \.+.* ([0-9.]+) sec$/\2 \1/p' "$LOGS/ctest.log" |
      sort -rn | awk 'NR <= 15 {printf "  %8.1f  %s\n", $1, $2}'  # awk reads it all: no SIGPIPE under pipefail
  fi
  exit $rc
}
trap report EXIT

stage "Debian packages + MeshLab headers" env SKIP_BUILD=1 "$ROOT/scripts/setup.sh"
# the forky userland downloads and unpacks while the bookworm tree compiles (on a machine that has run this
# once, it is there already and this returns at once)
userland=""
if [ "${PECTUS_HOST_2025:-1}" != 0 ]; then
  mkdir -p "$LOGS"
  "$ROOT/scripts/host.sh" 2025.07 userland > "$LOGS/userland-2025.07.log" 2>&1 &
  userland=$!
fi
stage "build" "$ROOT/scripts/setup.sh"
if [ -n "$userland" ]; then
  wait_userland() {
    local rc=0
    wait "$userland" || rc=$?
    cat "$LOGS/userland-2025.07.log"
    return $rc
  }
  stage "MeshLab 2025.07 userland (after the build)" wait_userland
  stage "MeshLab 2025.07 build" "$ROOT/scripts/host.sh" 2025.07
fi

# one ctest run: the bookworm unit and end-to-end tests, the 2025.07 end-to-end tests and the 2025.07 unit
# stage (test unit_2025; tests labelled host2025 or host2022 skip themselves when that host was not made),
# longest first
mkdir -p "$LOGS" "$ROOT/build/Testing/Temporary"
COSTS="$ROOT/build/Testing/Temporary/CTestCostData.txt"
if [ -f "$PECTUS_CACHE/CTestCostData.txt" ]; then cp "$PECTUS_CACHE/CTestCostData.txt" "$COSTS"
elif [ ! -f "$COSTS" ]; then cp "$ROOT/tests/ctest_costs.txt" "$COSTS"; fi
rm -rf "$ROOT/build/test-cache"  # the unit tests' generated cages (tools/include/pectus/fixture/coarse_cage.h): made anew each run
# Two tests share the two cores: an OpenMP thread that waits must sleep, not spin on a core another test needs
# (the results do not depend on it: every filter is byte-identical across thread counts)
ctest_all() {  # (called after ||: errexit is off here)
  (cd "$ROOT/build" && OMP_WAIT_POLICY=passive ctest --output-on-failure -j"$(nproc)" --timeout 1500) 2>&1 | tee "$LOGS/ctest.log"
  local rc=${PIPESTATUS[0]}
  [ "$rc" != 0 ] || cp "$COSTS" "$PECTUS_CACHE/CTestCostData.txt"
  return "$rc"
}
stage "ctest (unit + end-to-end, both hosts)" ctest_all

# the cores under AddressSanitizer + UBSan (the suites that build no rib cage; docs/robustness.md)
if [ "${PECTUS_SANITIZE:-1}" != 0 ]; then stage "sanitizers" "$ROOT/scripts/sanitize.sh" ci; fi
