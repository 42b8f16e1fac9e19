#!/bin/sh
# Thoracic volume benchmark: slice method, Ferguson envelope and CGAL alpha_wrap_3 (peer) on a
# ~300k-face analytic cage, one table. Usage: bench/thoracic_volume.sh [build-dir]
set -e
here=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$here/build}
cmake --build "$build" -j2 --target bench_thoracic_volume
"$build/bench/bench_thoracic_volume"
