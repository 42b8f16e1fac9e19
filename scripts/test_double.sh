#!/usr/bin/env bash
# The cores, their unit tests and the plugins built with MESHLAB_SCALAR=double (pymeshlab's scalar) against
# bookworm's MeshLab 2020.09 headers, into build-double/, and the unit tests run there (docs/hosts.md).
# The double plugins compile and link but do not load into Debian's float MeshLab, so this build has no
# private prefix, no package and no end-to-end tests.
#   scripts/test_double.sh
# Not a stage of scripts/test.sh: on a 2-core machine shared with other work the build took 45 minutes
# (13 minutes of CPU; load average about 11) and the 218 unit tests 8 minutes (load average about 6).
# Left out of the run: Adapter.FailedFilterRollsBackEveryLayer and Adapter.ExceptionsNeverEscapeAndSuccessCommits.
# They make a MeshDocument, which lives in the libmeshlab-common the build links; Debian's is float, so in a
# double build they crash (they need a libmeshlab-common of the build's scalar, pymeshlab's: -DMESHLAB_COMMON_LIB).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
B="$ROOT/build-double"
start=$(date +%s)
SKIP_BUILD=1 "$ROOT/scripts/setup.sh"  # the packages and MeshLab's headers
cmake -S "$ROOT" -B "$B" -DCMAKE_BUILD_TYPE=Release -DMESHLAB_SCALAR=double >/dev/null
cmake --build "$B" -j"$(nproc)"
echo "[test-double] build took $(( $(date +%s) - start )) s"
ctest --test-dir "$B" -L unit -j"$(nproc)" --output-on-failure --timeout 1500 \
  -E '^Adapter\.(FailedFilterRollsBackEveryLayer|ExceptionsNeverEscapeAndSuccessCommits)$'
echo "[test-double] total $(( $(date +%s) - start )) s"
