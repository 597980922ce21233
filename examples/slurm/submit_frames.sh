#!/bin/bash
# Submits a frame range as an N-task Slurm job array and a check that runs when every task
# succeeded. Usage: examples/slurm/submit_frames.sh [N] (default 4), from the project folder;
# GRAPH, FRAMES, OUT, CACHE and CGNODES are passed on to the jobs.
set -euo pipefail
N=${1:-4}
here=$(dirname "$0")
export GRAPH=${GRAPH:-graphs/frames_counter.json} FRAMES=${FRAMES:-1..240}
export OUT=${OUT:-cluster/frames}
array=$(sbatch --parsable --export=ALL --array=0-$((N - 1)) "$here/frames.sbatch")
done=$(sbatch --parsable --export=ALL --dependency=afterok:"$array" "$here/frames_done.sbatch")
echo "frames array $array ($N tasks), check $done"
