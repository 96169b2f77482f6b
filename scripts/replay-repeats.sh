#!/usr/bin/env bash
# Replays a log twice per seed in lockstep and checks that both runs wrote the same
# trajectory bit for bit; scores each seed against the log's relations file when there is one.
#
#   scripts/replay-repeats.sh [LOG] [SEEDS...]
#   scripts/replay-repeats.sh ../shared/data/carmen/aces.clf 1 2 3 4 5
#
# Needs the release binaries (cargo build --release --workspace). Exits non-zero if any
# pair of runs differs.
set -euo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
data=${SLAM_DATA_DIR:-$root/../shared/data}
log=${1:-$data/carmen/aces.clf}
shift || true
seeds=("$@")
[ ${#seeds[@]} -gt 0 ] || seeds=(1 2 3 4 5)
bin=$root/target/release
relations=${log%.*}.relations
out=$(mktemp -d "${TMPDIR:-/tmp}/replay-repeats.XXXXXX")
trap 'rm -rf "$out"' EXIT

[ -x "$bin/slam-launch" ] || { echo "no $bin/slam-launch: run cargo build --release --workspace" >&2; exit 2; }
[ -f "$log" ] || { echo "no log $log" >&2; exit 2; }

format=carmen
case $log in *.csv) format=seed-csv ;; esac

status=0
printf '%-6s %-10s %s\n' seed repeats "score (translation; rotation)"
for seed in "${seeds[@]}"; do
    for run in a b; do
        "$bin/slam-launch" --quiet --replay "$log" --format "$format" --seed "$seed" \
            --out "$out/$seed-$run" > "$out/$seed-$run.console" 2>&1 \
            || { cat "$out/$seed-$run.console" >&2; exit 1; }
    done
    if cmp -s "$out/$seed-a/trajectory.tum" "$out/$seed-b/trajectory.tum"; then
        same=yes
    else
        same=NO
        status=1
    fi
    score=""
    if [ -f "$relations" ]; then
        score=$("$bin/slam-score" --trajectory "$out/$seed-a/trajectory.tum" \
            --relations "$relations" | awk '/^translation/ {t=$3" +- "$5" m"} /^rotation/ {r=$3" +- "$5" deg"} END {print t"; "r}')
    fi
    printf '%-6s %-10s %s\n' "$seed" "$same" "$score"
done
exit $status
