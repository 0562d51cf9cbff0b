#!/usr/bin/env bash
# Test of the Slurm recipe (docs/slurm.md) on a one-node Slurm cluster made on
# this machine from Debian's packages. NOT part of .ci/run: it needs root,
# installs packages and starts daemons (munged, slurmctld, slurmd), which it
# stops at the end (only those it started).
#
#   sudo bash tools/slurm-test.sh            # from anywhere in the repository
#
# What it does, timing each phase:
#  1. apt-get install slurm-wlm munge jq (skipped if already there);
#  2. writes a one-node slurm.conf in a temporary directory (the node is this
#     host as `slurmd -C` sees it; no cgroups, no accounting, no systemd) and
#     starts munged (if not running), slurmctld and slurmd in the foreground
#     mode (-D) in the background;
#  3. submits with docs/slurm/submit.sh a 4-shard array job of
#     `batch --family random --seeds 0..40` and its dependent merge job, and a
#     3-shard `robustness simple --random 3 --delta 0,0.1` study;
#  4. waits for the merge jobs (at most $SLURM_TEST_TIMEOUT s, default 600);
#  5. runs the same two studies in one process and compares: batch runs.csv
#     without the timing columns (compute_*_ns, plan_time_ms, wall_ms) and the
#     summary without the timings must be identical; robustness runs.csv must
#     be identical byte for byte, table.md but for its last line.
# Exit status 0 if everything matched. The daemons' logs and the studies are
# kept in the printed directory.
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$PWD
timeout=${SLURM_TEST_TIMEOUT:-600}
t_start=$(date +%s)
phase_t=$t_start
phase() {
    local now
    now=$(date +%s)
    printf '[%4ds, +%3ds] %s\n' "$((now - t_start))" "$((now - phase_t))" "$*"
    phase_t=$now
}

if [ "$(id -u)" != 0 ]; then
    echo "error: run as root (installs packages, starts slurmd)" >&2
    exit 1
fi

# ---- 1. packages -------------------------------------------------------------
if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null || ! command -v jq >/dev/null; then
    phase "installing slurm-wlm munge jq (apt-get)"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq slurm-wlm munge jq >/dev/null
fi
phase "packages: $(slurmctld -V), $(munged --version 2>&1 | head -1)"

sim=$repo/target/release/ldcbf-sim
if [ ! -x "$sim" ]; then
    phase "building ldcbf-sim (release)"
    cargo build --release -p ldcbf-sim
fi

# ---- 2. a one-node cluster ------------------------------------------------------
work=$(mktemp -d /tmp/ldcbf-slurm.XXXXXX)
chmod 755 "$work"
started=()
# shellcheck disable=SC2317 # called by the EXIT trap
cleanup() {
    local status=$?
    for pid in "${started[@]}"; do
        kill "$pid" 2>/dev/null || true
    done
    for pid in "${started[@]}"; do
        for _ in $(seq 50); do
            kill -0 "$pid" 2>/dev/null || break
            sleep 0.1
        done
    done
    echo "daemons stopped; logs and studies in $work"
    exit "$status"
}
trap cleanup EXIT

# munge: a key, and the daemon unless one answers already.
if [ ! -s /etc/munge/munge.key ]; then
    mungekey --create --keyfile /etc/munge/munge.key
    chown munge:munge /etc/munge/munge.key
    chmod 400 /etc/munge/munge.key
fi
if ! munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
    mkdir -p /run/munge /var/log/munge /var/lib/munge
    chown munge:munge /run/munge /var/log/munge /var/lib/munge
    runuser -u munge -- munged --foreground >"$work/munged.log" 2>&1 &
    started+=($!)
    for _ in $(seq 50); do
        munge -n 2>/dev/null | unmunge >/dev/null 2>&1 && break
        sleep 0.1
    done
    munge -n | unmunge >/dev/null
    phase "munged started (pid ${started[-1]})"
else
    phase "munged already running"
fi

node=$(slurmd -C | head -1)     # NodeName=<host> CPUs=... RealMemory=...
host=$(echo "$node" | sed -n 's/^NodeName=\([^ ]*\).*/\1/p')
mkdir -p "$work/state" "$work/spool"
export SLURM_CONF=$work/slurm.conf
cat >"$SLURM_CONF" <<EOF
# One-node test cluster (tools/slurm-test.sh).
ClusterName=ldcbftest
SlurmctldHost=$host
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
SlurmctldPort=6817
SlurmdPort=6818
# No cgroups, no accounting: processes are tracked through /proc.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MpiDefault=none
ReturnToService=2
MinJobAge=3600
$node State=UNKNOWN
PartitionName=test Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
slurmctld -D -f "$SLURM_CONF" >"$work/slurmctld.out" 2>&1 &
started+=($!)
slurmd -D -f "$SLURM_CONF" >"$work/slurmd.out" 2>&1 &
started+=($!)
state=""
for _ in $(seq 120); do
    state=$(sinfo -h -N -o %T 2>/dev/null | head -1 || true)
    [ "$state" = idle ] && break
    sleep 0.5
done
if [ "$state" != idle ]; then
    echo "error: the node is not idle after 60 s (state '${state}')" >&2
    tail -n 20 "$work"/slurmctld.log "$work"/slurmd.log "$work"/*.out >&2 || true
    exit 1
fi
phase "slurmctld and slurmd up: $(sinfo -h -N -o '%N %T %c cpus %m MB')"

# ---- 3. the studies, through the documented recipe -------------------------
batch_args=(batch --family random --seeds 0..40)
rob_args=(robustness simple --random 3 --delta "0,0.1")
export LDCBF_SIM=$sim
export SBATCH_ARGS="--cpus-per-task=1 --time=00:20:00"
out_b=$(docs/slurm/submit.sh "$work/batch" 4 "${batch_args[@]}")
echo "$out_b"
out_r=$(docs/slurm/submit.sh "$work/rob" 3 "${rob_args[@]}")
echo "$out_r"
merge_b=$(echo "$out_b" | sed -n 's/.*merge job \([0-9]*\).*/\1/p')
merge_r=$(echo "$out_r" | sed -n 's/.*merge job \([0-9]*\).*/\1/p')
phase "submitted (merge jobs $merge_b and $merge_r)"

# ---- 4. wait ------------------------------------------------------------------
job_state() { scontrol show job "$1" 2>/dev/null | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p' | head -1; }
deadline=$(($(date +%s) + timeout))
while :; do
    sb=$(job_state "$merge_b")
    sr=$(job_state "$merge_r")
    case "$sb$sr" in COMPLETEDCOMPLETED) break ;; esac
    for s in "$sb" "$sr"; do
        case "$s" in FAILED | CANCELLED | TIMEOUT | NODE_FAIL | OUT_OF_MEMORY | BOOT_FAIL | DEADLINE)
            echo "error: a merge job ended $s" >&2
            squeue -a || true
            tail -n 30 "$work"/batch/logs/* "$work"/rob/logs/* >&2 || true
            exit 1
            ;;
        esac
    done
    if [ "$(date +%s)" -ge "$deadline" ]; then
        echo "error: the jobs did not finish within ${timeout} s (merge jobs: $sb, $sr)" >&2
        squeue -a || true
        exit 1
    fi
    sleep 1
done
phase "all jobs completed"
sacct_like() {
    for j in "$@"; do
        scontrol -o show job "$j" | tr ' ' '\n' |
            grep -E '^(JobId|ArrayJobId|ArrayTaskId|JobName|JobState|RunTime|NodeList)=' | tr '\n' ' '
        echo
    done
}
array_b=$(echo "$out_b" | sed -n 's/^array job \([0-9]*\).*/\1/p')
sacct_like "$array_b" "$merge_b" | sed 's/^/  /'

# ---- 5. the same studies in one process, and the comparison ----------------
"$sim" "${batch_args[@]}" --jobs 2 --quiet --out "$work/single-batch" >/dev/null
"$sim" "${rob_args[@]}" --jobs 2 --quiet --out "$work/single-rob" >/dev/null
phase "single-process runs done"

fail=0
# batch runs.csv without the timing columns 13-15 (compute_*_ns), 18
# (plan_time_ms) and 20 (wall_ms).
det() { cut -d, -f1-12,16,17,19,21,22 "$1"; }
if cmp -s <(det "$work/batch/merged/runs.csv") <(det "$work/single-batch/runs.csv"); then
    echo "batch runs.csv: identical to the single process without the timing columns ($(($(wc -l <"$work/single-batch/runs.csv") - 1)) runs)"
else
    echo "batch runs.csv: DIFFERENT"
    diff <(det "$work/batch/merged/runs.csv") <(det "$work/single-batch/runs.csv") | head -20
    fail=1
fi
agg='.aggregate | with_entries(select(.key | startswith("compute") | not))'
meta='.meta | del(.shard, .merged_shards, .jobs, .wall_time_s)'
if cmp -s <(jq -S "$agg, $meta" "$work/batch/merged/summary.json") \
    <(jq -S "$agg, $meta" "$work/single-batch/summary.json"); then
    echo "batch summary.json: aggregate and study identical but for the timings"
else
    echo "batch summary.json: DIFFERENT"
    diff <(jq -S "$agg, $meta" "$work/batch/merged/summary.json") \
        <(jq -S "$agg, $meta" "$work/single-batch/summary.json") | head -20
    fail=1
fi
notime() { grep -v -e 'wall time' -e compute "$1"; }
if cmp -s <(notime "$work/batch/merged/summary.md") <(notime "$work/single-batch/summary.md"); then
    echo "batch summary.md: identical but for the wall time and compute lines"
else
    echo "batch summary.md: DIFFERENT"
    diff <(notime "$work/batch/merged/summary.md") <(notime "$work/single-batch/summary.md") | head
    fail=1
fi
if cmp "$work/rob/merged/runs.csv" "$work/single-rob/runs.csv"; then
    echo "robustness runs.csv: identical byte for byte ($(($(wc -l <"$work/single-rob/runs.csv") - 1)) runs)"
else
    fail=1
fi
if cmp -s <(sed '$d' "$work/rob/merged/table.md") <(sed '$d' "$work/single-rob/table.md"); then
    echo "robustness table.md: identical but for the last line:"
    echo "  merged: $(tail -1 "$work/rob/merged/table.md")"
    echo "  single: $(tail -1 "$work/single-rob/table.md")"
else
    echo "robustness table.md: DIFFERENT"
    diff "$work/rob/merged/table.md" "$work/single-rob/table.md" | head
    fail=1
fi
phase "compared"
if [ "$fail" = 0 ]; then
    echo "PASS: the Slurm array + merge results equal the single-process runs ($(($(date +%s) - t_start)) s in all)"
else
    echo "FAIL"
fi
exit "$fail"
