#!/usr/bin/env bash
# Runs a fixed set of closed loops, studies and QP solves with two builds of
# `ldcbf-sim` and compares every output file, wall-clock fields left out.
# For refactors that must keep the results bit for bit.
#
#   cargo build --release -p ldcbf-sim && cp target/release/ldcbf-sim /tmp/old-sim
#   ... change the code ...
#   cargo build --release -p ldcbf-sim
#   tools/same-results.sh /tmp/old-sim target/release/ldcbf-sim
#
# Exit 0 when every compared file is identical, 1 otherwise (the differences
# are printed). Run from the repository root (scenarios/ is read from there).
set -euo pipefail

old=${1:?usage: same-results.sh OLD_BIN NEW_BIN [WORKDIR]}
new=${2:?usage: same-results.sh OLD_BIN NEW_BIN [WORKDIR]}
work=${3:-$(mktemp -d)}
qpdir=${QPBENCH:-tests/data/lipmwalk}

run_all() {
    local bin=$1 out=$2
    mkdir -p "$out"
    "$bin" run paper --out "$out/paper" --no-plots >/dev/null
    "$bin" run maze --out "$out/maze" --no-plots >/dev/null
    "$bin" run maze --out "$out/maze-none" --no-plots --set 'planner="none"' >/dev/null
    "$bin" run simple --out "$out/simple" --no-plots >/dev/null
    "$bin" run trap --out "$out/trap" --no-plots --set 'planner="rrt_star"' >/dev/null
    "$bin" run crowded --seed 3 --out "$out/crowded3" --no-plots >/dev/null
    "$bin" run cup-mouth --out "$out/cup-mouth" --no-plots >/dev/null
    "$bin" run random --seed 5 --out "$out/random5" --no-plots \
        --set 'disturbance.push_time=3.0' --set 'disturbance.push_lateral=0.2' >/dev/null
    "$bin" batch --family clutter --seeds 0..6 --perception lidar --jobs 2 --quiet \
        --out "$out/batch-clutter-lidar" >/dev/null
    "$bin" batch --family doorway --seeds 0..4 --planner rrt_star --jobs 2 --quiet \
        --out "$out/batch-doorway-rrt" >/dev/null
    "$bin" batch --family thin --seeds 0..4 --jobs 2 --quiet \
        --out "$out/batch-thin" >/dev/null
    "$bin" robustness paper --random 2 --delta 0.05 --jobs 2 --quiet \
        --out "$out/robustness" >"$out/robustness.stdout"
    if [ -d "$qpdir" ]; then
        # Solver columns only: status, iterations, objective (no times).
        "$bin" qp solve "$qpdir"/*.npz --repeat 1 >"$out/qp.csv"
    fi
}

# Drops CSV columns that hold wall-clock figures (by header name).
strip_csv() {
    python3 - "$1" <<'EOF'
import csv, sys
rows = list(csv.reader(open(sys.argv[1], newline="")))
if not rows:
    sys.exit(0)
timing = ("_ns", "_ms", "wall", "compute", "time_s", "elapsed")
keep = [i for i, h in enumerate(rows[0]) if not any(t in h for t in timing)]
w = csv.writer(sys.stdout, lineterminator="\n")
for r in rows:
    w.writerow([r[i] for i in keep if i < len(r)])
EOF
}

# Drops JSON members that hold wall-clock figures (any depth).
strip_json() {
    python3 - "$1" <<'EOF'
import json, sys
timing = ("_ns", "_ms", "wall", "compute", "time_s", "elapsed", "jobs")
def strip(v):
    if isinstance(v, dict):
        return {k: strip(x) for k, x in v.items() if not any(t in k for t in timing)}
    if isinstance(v, list):
        return [strip(x) for x in v]
    return v
print(json.dumps(strip(json.load(open(sys.argv[1]))), sort_keys=True, indent=1))
EOF
}

strip_text() { grep -v -i -e 'wall' -e 'compute' -e ' µs' -e ' ns' "$1" || true; }

echo "outputs in $work"
run_all "$old" "$work/old"
run_all "$new" "$work/new"

fail=0
count=0
while IFS= read -r f; do
    rel=${f#"$work/old/"}
    g="$work/new/$rel"
    count=$((count + 1))
    if [ ! -f "$g" ]; then
        echo "MISSING in new: $rel"
        fail=1
        continue
    fi
    case $f in
        *.csv) a=$(strip_csv "$f"); b=$(strip_csv "$g") ;;
        *.json) a=$(strip_json "$f"); b=$(strip_json "$g") ;;
        *.png | *.gif) continue ;;
        *) a=$(strip_text "$f"); b=$(strip_text "$g") ;;
    esac
    if [ "$a" != "$b" ]; then
        echo "DIFFERENT: $rel"
        diff <(echo "$a") <(echo "$b") | head -8 || true
        fail=1
    fi
done < <(find "$work/old" -type f | sort)
if [ "$fail" = 0 ]; then
    echo "identical: $count files (wall-clock fields left out)"
fi
exit "$fail"
