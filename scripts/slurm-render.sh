#!/usr/bin/env bash
# Renders one animation over a Slurm job array: each array task renders every N-th frame
# (`kdray render --shard I/N`) into OUTDIR, and merges its frames into OUTDIR/stats.json under
# the folder's lock, so that the finished array leaves one folder and one stats.json, as one run
# would. Frame numbers (and so keyframed cameras) do not depend on the sharding. A task that was
# cut short is resumed by submitting the array again with --skip-existing.
#
#   sbatch --array=0-7 scripts/slurm-render.sh 'anim/*.obj' anim/render.json out
#   kdray stats out --json
#
#SBATCH --job-name=kdray-render
#SBATCH --cpus-per-task=4
#SBATCH --output=kdray-render-%A_%a.log
set -euo pipefail
frames=${1:?usage: slurm-render.sh FRAMES_GLOB RENDER_JSON OUTDIR [kdray options]}
render_json=${2:?missing RENDER_JSON}
out=${3:?missing OUTDIR}
shift 3
kdray=${KDRAY:-kdray}
index=${SLURM_ARRAY_TASK_ID:?run this through sbatch --array}
count=${SLURM_ARRAY_TASK_COUNT:?run this through sbatch --array}
# The quoted glob reaches kdray unexpanded; kdray expands and sorts it the same way in every task.
exec "$kdray" render "$frames" --camera "$render_json" -o "$out" --shard "$index/$count" "$@"
