#!/usr/bin/env bash
# host_unit.sh RELEASE: the unit tests of a newer MeshLab release's build (scripts/host.sh RELEASE makes it),
# run inside that release's userland: the adapter and the cores built against its vcglib, Eigen and
# libmeshlab-common. ctest runs this as one test (unit_2025), beside the end-to-end tests; it exits 77
# (skipped) when that host is not made.
# Left out there: the suites that build whole rib cages (the bookworm build runs them; about 20 minutes on
# 2 cores).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
REL="$1"
SUITE="$(awk -v r="$REL" '$1 == r {print $2}' "$ROOT/scripts/meshlab_hosts.txt")"
if [ ! -f "$ROOT/.hosts/$SUITE/.complete-pkgs" ] || [ ! -x "$ROOT/build-$REL/bin/pectus-mlrun" ]; then
  echo "skipped: the MeshLab $REL host is not made (scripts/host.sh $REL)"
  exit 77
fi
# function_length reads the sources with Universal Ctags, which the userland does not have; the bookworm build
# runs it on the same sources
exec "$ROOT/scripts/host.sh" "$REL" run ctest --test-dir "build-$REL" -L unit -j1 --output-on-failure --timeout 1500 \
  -E '^(RibCage|RibCageCoarse|NussAnalysis|PatientPrepare|BarPlanner|TissueJoin)\.|^function_length$'
