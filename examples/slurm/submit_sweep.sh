#!/bin/bash
# Submits a sweep as an N-task Slurm job array and its merge as a job that starts only when
# every task succeeded. Usage: examples/slurm/submit_sweep.sh [N] (default 4), from the
# project folder; SWEEP, PARTS, OUT, CHART (extra chart options for the merge) and CGNODES are passed on to the jobs.
set -euo pipefail
N=${1:-4}
here=$(dirname "$0")
export SWEEP=${SWEEP:-bench/sweeps/arap_iterations.json}
export PARTS=${PARTS:-cluster/parts} OUT=${OUT:-cluster/sweep}
rm -f "$PARTS"/part-*.csv
array=$(sbatch --parsable --export=ALL --array=0-$((N - 1)) "$here/sweep.sbatch")
merge=$(sbatch --parsable --export=ALL --dependency=afterok:"$array" "$here/merge.sbatch")
echo "sweep array $array ($N tasks), merge $merge"
