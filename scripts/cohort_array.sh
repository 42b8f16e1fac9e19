#!/bin/sh
# The same cohort as a cluster job array (Slurm; other schedulers: set TASK to the 1-based task index).
#   sbatch --array=1-$(($(wc -l < COHORT/patients.csv) - 1)) scripts/cohort_array.sh COHORT OUT [--quick]
#   then: python3 python/cohort.py collect COHORT OUT
#SBATCH --job-name=pectus-cohort
#SBATCH --cpus-per-task=2
#SBATCH --mem=4G
set -eu
here=$(cd "$(dirname "$0")/.." && pwd)
task=${TASK:-${SLURM_ARRAY_TASK_ID:-${PBS_ARRAY_INDEX:-${SGE_TASK_ID:-1}}}}
case=$(tail -n +2 "$1/patients.csv" | sed -n "${task}p" | cut -d, -f1)
export PECTUS_PREFIX=${PECTUS_PREFIX:-$here/build/prefix}
OMP_NUM_THREADS=${SLURM_CPUS_PER_TASK:-2} exec /usr/bin/python3 "$here/python/cohort.py" run "$1" "$case" "$2" ${3:-}
