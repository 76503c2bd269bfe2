#!/bin/bash
# Submits a sharded render on a Slurm cluster: an array of N render tasks,
# then the merge, which starts only if every task succeeded (afterok).
#   examples/slurm/submit.sh N
# with RTOW, RTOW_SCENE, RTOW_ARGS, RTOW_SPLIT, RTOW_PARTS, RTOW_OUT in the
# environment (see render-shard.sbatch, merge.sbatch), and
#   RTOW_CPUS   cores per render task (its --threads)             [1]
#   RTOW_TIME   time limit of each render task (sbatch --time)    [30:00]
#   RTOW_MERGE_TIME  time limit of the merge                      [10:00]
# Run it from a folder every node sees (jobs start in the submission folder);
# the binary, a scene file and the parts folder must be on a shared file
# system too (README.md). Prints the two job ids.
set -euo pipefail
n=${1:?usage: $0 N (number of shards)}
here=$(cd "$(dirname "$0")" && pwd)
export RTOW_SHARDS=$n
logs=${RTOW_LOGS:-logs}
mkdir -p "$logs" "${RTOW_PARTS:-parts}"
array=$(sbatch --parsable --array="1-$n" --cpus-per-task="${RTOW_CPUS:-1}" --time="${RTOW_TIME:-30:00}" \
    --output="$logs/shard-%A_%a.out" "$here/render-shard.sbatch")
array=${array%%;*}
merge=$(sbatch --parsable --dependency="afterok:$array" --kill-on-invalid-dep=yes \
    --time="${RTOW_MERGE_TIME:-10:00}" --output="$logs/merge-%j.out" "$here/merge.sbatch")
merge=${merge%%;*}
echo "$array $merge"
