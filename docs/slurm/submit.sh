#!/usr/bin/env bash
# Submit an ldcbf-sim `batch` or `robustness` study to Slurm: an array job of
# SHARDS tasks (docs/slurm/batch-array.sbatch, one shard each) and a merge job
# that runs after all of them succeeded (docs/slurm/merge.sbatch). Prints the
# two job ids. Run it from the repository root on a login node, after
# `cargo build --release -p ldcbf-sim`:
#
#   docs/slurm/submit.sh out/study 16 batch --family random --seeds 0..100000 --planner rrt_star
#   docs/slurm/submit.sh out/rob 8 robustness --random 200
#
# Extra sbatch options (partition, account, time, cpus) go in $SBATCH_ARGS,
# e.g. SBATCH_ARGS="--partition=short --cpus-per-task=4". Results:
# STUDY/shard1..N (one per task), STUDY/merged (the whole study), STUDY/logs.
set -euo pipefail

if [ $# -lt 3 ]; then
    echo "usage: $0 STUDY_DIR SHARDS batch|robustness ARGS..." >&2
    exit 2
fi
study=$1
shards=$2
shift 2
here=$(cd "$(dirname "$0")" && pwd)
sim=${LDCBF_SIM:-$PWD/target/release/ldcbf-sim}
if [ ! -x "$sim" ]; then
    echo "error: $sim not found: build it once with cargo build --release -p ldcbf-sim (or set LDCBF_SIM)" >&2
    exit 1
fi
if [ ! -d scenarios ]; then
    echo "error: run from the repository root (the jobs read ./scenarios)" >&2
    exit 1
fi
mkdir -p "$study/logs"
study=$(cd "$study" && pwd)
export LDCBF_SIM=$sim STUDY=$study
unset SHARDS
# shellcheck disable=SC2086 # SBATCH_ARGS is a list of options
array=$(sbatch --parsable ${SBATCH_ARGS:-} --array="1-$shards" --chdir="$PWD" \
    --output="$study/logs/%x-%A_%a.out" "$here/batch-array.sbatch" "$@")
array=${array%%;*}
# shellcheck disable=SC2086
merge=$(sbatch --parsable ${SBATCH_ARGS:-} --dependency="afterok:$array" --kill-on-invalid-dep=yes \
    --chdir="$PWD" --output="$study/logs/%x-%j.out" "$here/merge.sbatch")
merge=${merge%%;*}
echo "array job $array ($shards shards), merge job $merge; results in $study/merged"
