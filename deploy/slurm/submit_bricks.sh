#!/usr/bin/env bash
# Runs one sheetmesh job over a volume too large for one machine on a Slurm cluster: a plan,
# a job array of bricks (each reads and selects its box of the volume), and a merge that
# waits for every brick and runs the rest of the job. The folders must be seen by every node
# (a shared file system).
#
# Usage: deploy/slurm/submit_bricks.sh VOLUME OUT_DIR [job flags, as for sheetmesh-pipeline run]
# Environment:
#   SHEETMESH_PIPELINE  the program (default: sheetmesh-pipeline on PATH)
#   BRICK_SIZE          the bricks' edge in voxels, N or NXxNYxNZ (default auto: slabs of
#                       whole slices, about 128 M voxels each)
#   PLAN_DIR            where the plan and the bricks go (default OUT_DIR.plan)
#   BRICK_MEM           memory per brick task for sbatch --mem (default 2G)
#   MERGE_MEM           memory of the merge (default 16G)
#   MAX_PARALLEL        bricks at once (default: as many as the cluster gives)
#   SBATCH_ARGS         more sbatch options for all three (a partition, an account)
# Prints the array's and the merge's job ids; the merge's log is OUT_DIR.merge.log.
set -euo pipefail
if [ $# -lt 2 ]; then
  sed -n '2,18p' "$0" | sed 's/^# \{0,1\}//'
  exit 2
fi
volume=$1
out=$2
shift 2
pipeline=${SHEETMESH_PIPELINE:-sheetmesh-pipeline}
# A word for the batch script (sh): in single quotes, each ' as '\''. Paths are data: a
# folder named out'$(touch x)' must run nothing.
quote() { printf "'%s'" "$(printf '%s' "$1" | sed "s/'/'\\\\''/g")"; }
plan=${PLAN_DIR:-$out.plan}
read -r -a extra <<< "${SBATCH_ARGS:-}"

"$pipeline" plan "$volume" -o "$plan" --brick_size="${BRICK_SIZE:-auto}" "$@"
count=$(grep -c '"index":' "$plan/plan.json")
array="0-$((count - 1))"
[ -n "${MAX_PARALLEL:-}" ] && array="$array%$MAX_PARALLEL"
mkdir -p "$plan/logs"
# Each task reads its index from $SLURM_ARRAY_TASK_ID. A task that fails or is killed
# leaves no brick file; the merge, which needs every brick, then does not run (afterok):
# resubmit the failed indices with --array=I,J.
bricks=$(sbatch --parsable "${extra[@]}" --job-name=sheetmesh-bricks --array="$array" \
  --cpus-per-task=1 --mem="${BRICK_MEM:-2G}" --output="$plan/logs/brick_%a.log" \
  --wrap="exec $(quote "$pipeline") brick $(quote "$plan")")
bricks=${bricks%%;*}
merge=$(sbatch --parsable "${extra[@]}" --job-name=sheetmesh-merge --dependency=afterok:"$bricks" \
  --mem="${MERGE_MEM:-16G}" --output="$out.merge.log" \
  --wrap="exec $(quote "$pipeline") merge $(quote "$plan") -o $(quote "$out")")
merge=${merge%%;*}
echo "bricks $bricks ($count tasks), merge $merge"
