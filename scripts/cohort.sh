#!/bin/sh
# Run the Nuss analysis over a cohort folder in parallel with GNU parallel, then collect one summary CSV.
#   scripts/cohort.sh COHORT_DIR [OUT_DIR] [--quick]      (scripts/setup.sh first; python/cohort.py demo DIR makes a demo cohort)
# Jobs: PECTUS_JOBS (default: number of cores / 2, each FE solve uses 2 threads).
set -eu
here=$(cd "$(dirname "$0")/.." && pwd)
dir=$(cd "$1" && pwd)
out=${2:-$dir/results}
quick=${3:-}
export PECTUS_PREFIX=${PECTUS_PREFIX:-$here/build/prefix}
jobs=${PECTUS_JOBS:-$(( $(nproc) / 2 > 0 ? $(nproc) / 2 : 1 ))}
mkdir -p "$out"
# every case runs even if another fails; parallel's exit status is the number of failed cases
failed=0
tail -n +2 "$dir/patients.csv" | cut -d, -f1 | \
  OMP_NUM_THREADS=2 parallel --jobs "$jobs" --halt never /usr/bin/python3 "$here/python/cohort.py" run "$dir" {} "$out" $quick \
  || failed=$?
/usr/bin/python3 "$here/python/cohort.py" collect "$dir" "$out"
if [ "$failed" != 0 ]; then echo "cohort: $failed case(s) failed (see $out/CASE/meshlabserver.log)" >&2; exit 1; fi
