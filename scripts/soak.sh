#!/usr/bin/env bash
# Soak test (issue 14): loops the office world in real time for a while, killing a random
# stage of a run every few minutes (that run fails, the next one starts at once), and checks
# that nothing piles up between runs and that finished runs' results are whole.
#
#   scripts/soak.sh [--duration S] [--kill-period S] [--rate HZ] [--particles N]
#                   [--out DIR] [--bin DIR]
#   nice scripts/soak.sh                    # 30 minutes, 40 Hz, 1000 particles
#
# Per run it writes one line of OUT/soak.csv: the stage killed (if any) and when, the
# launcher's exit status, the peak resident memory (VmHWM, sampled once a second; map-sink's
# as it logs it) of the launcher and of every stage, the files in /dev/shm before and after (all of them, and
# those of the run's own domain, which must be none after), the entries of the iceoryx2
# root directories, /dev/shm's used KiB and MemAvailable before the run, and whether the
# results are whole: a finished run's trajectory.tum (whole lines of 8 numbers),
# metrics.json (parses) and map_corners.csv; a killed run's trajectory files (whole lines).
# A summary follows at the end; the exit status is non-zero if a finished run's results
# were not whole, a run left files of its domain behind, or a run that was not killed
# failed.
#
# Needs the release binaries (cargo build --release --workspace), jq and awk.
set -euo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
duration=1800
kill_period=180
rate=40
particles=1000
out=
bin=$root/target/release
while [ $# -gt 0 ]; do
    case $1 in
        --duration) duration=$2; shift 2 ;;
        --kill-period) kill_period=$2; shift 2 ;;
        --rate) rate=$2; shift 2 ;;
        --particles) particles=$2; shift 2 ;;
        --out) out=$2; shift 2 ;;
        --bin) bin=$2; shift 2 ;;
        -h|--help) sed -n '2,21p' "$0"; exit 0 ;;
        *) echo "soak.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
    esac
done
[ -x "$bin/slam-launch" ] || { echo "soak.sh: no $bin/slam-launch: run cargo build --release --workspace" >&2; exit 2; }
command -v jq > /dev/null || { echo "soak.sh: needs jq" >&2; exit 2; }
[ -n "$out" ] || out=$(mktemp -d "${TMPDIR:-/tmp}/soak.XXXXXX")
mkdir -p "$out"
csv=$out/soak.csv
stages=(lidar-sim feature-proc slam-proc map-sink)
uid=$(id -u)

# Every file in /dev/shm, and those of one domain (any user's prefix holds the domain name
# between underscores).
shm_files() { find /dev/shm -mindepth 1 -maxdepth 1 2> /dev/null | wc -l; }
domain_files() { find /dev/shm -mindepth 1 -maxdepth 1 -name "slam_*$1_*" 2> /dev/null | wc -l; }
# Entries under the iceoryx2 root directories (the shared default and this user's own).
root_entries() { find /tmp/iceoryx2 "/tmp/slam-iceoryx2-$uid" -mindepth 1 2> /dev/null | wc -l; }
shm_used_kib() { df -k --output=used /dev/shm | tail -n 1 | tr -d ' '; }
mem_available_mib() { awk '/^MemAvailable:/ { print int($2 / 1024) }' /proc/meminfo; }
hwm_kib() { awk '/^VmHWM:/ { print $2 }' "/proc/$1/status" 2> /dev/null || true; }

# A file of whole lines: not empty, its last byte a newline.
ends_whole() { [ -s "$1" ] && [ "$(tail -c 1 "$1" | od -An -tx1 | tr -d ' ')" = 0a ]; }
# A TUM file of whole lines, each 8 numbers.
whole_tum() {
    ends_whole "$1" && awk 'NF != 8 { exit 1 } { for (i = 1; i <= 8; i++) if ($i !~ /^-?[0-9]+(\.[0-9]+)?([eE][-+]?[0-9]+)?$/) exit 1 }' "$1"
}
# What the results of a run are: "whole", or the first thing wrong.
check_results() {
    local dir=$1 finished=$2
    if [ "$finished" = yes ]; then
        whole_tum "$dir/trajectory.tum" || { echo "trajectory.tum"; return; }
        jq -e '.frames_processed' "$dir/metrics.json" > /dev/null 2>&1 || { echo "metrics.json"; return; }
        ends_whole "$dir/map_corners.csv" || { echo "map_corners.csv"; return; }
    fi
    local f
    for f in "$dir"/*.tum; do
        [ -e "$f" ] || continue
        # A killed run may have started a file and written nothing yet.
        [ -s "$f" ] || continue
        whole_tum "$f" || { echo "$(basename "$f")"; return; }
    done
    echo whole
}

echo "run,start_s,killed,kill_at_s,exit,wall_s,frames,rss_kib_slam-launch,rss_kib_lidar-sim,rss_kib_feature-proc,rss_kib_slam-proc,rss_kib_map-sink,shm_files_before,shm_files_after,domain_files_after,root_entries_before,root_entries_after,shm_used_kib_before,mem_available_mib_before,results" > "$csv"
echo "soak: $duration s of office at $rate Hz, $particles particles, a stage killed every $kill_period s; runs in $out" >&2

started=$(date +%s)
last_kill=$started
run=0
status=0
while [ $(( $(date +%s) - started )) -lt "$duration" ]; do
    run=$((run + 1))
    dir=$out/run-$run
    domain=soak-$$-$run
    shm_before=$(shm_files)
    root_before=$(root_entries)
    used_before=$(shm_used_kib)
    mem_before=$(mem_available_mib)
    victim=
    kill_at=
    if [ $(( $(date +%s) - last_kill )) -ge "$kill_period" ]; then
        victim=${stages[RANDOM % ${#stages[@]}]}
        # Within the first minute: an office run at 40 Hz takes about 100 s.
        kill_at=$(( 5 + RANDOM % 55 ))
    fi
    run_start=$(date +%s)
    "$bin/slam-launch" --quiet --world office --rate "$rate" --particles "$particles" \
        --seed "$run" --domain "$domain" --out "$dir" > "$dir.console" 2>&1 &
    launcher=$!
    declare -A peak=()
    killed=
    while kill -0 "$launcher" 2> /dev/null; do
        for pid in $launcher $(pgrep -P "$launcher" || true); do
            name=$(cat "/proc/$pid/comm" 2> /dev/null || true)
            kib=$(hwm_kib "$pid")
            [ -n "$name" ] && [ -n "$kib" ] || continue
            [ "${peak[$name]:-0}" -ge "$kib" ] || peak[$name]=$kib
        done
        if [ -n "$victim" ] && [ -z "$killed" ] && [ $(( $(date +%s) - run_start )) -ge "$kill_at" ]; then
            pid=$(pgrep -P "$launcher" -x "$victim" || true)
            if [ -n "$pid" ]; then
                kill -KILL "$pid" 2> /dev/null && killed=$victim
                last_kill=$(date +%s)
            fi
        fi
        sleep 1
    done
    code=0
    wait "$launcher" || code=$?
    wall=$(( $(date +%s) - run_start ))
    finished=no
    [ "$code" -eq 0 ] && finished=yes
    # map-sink's peak comes at its very end (the occupancy grid), between two samples at
    # times: it logs its own VmHWM as it ends, which is exact.
    logged=$(awk '/map-sink: peak memory/ { printf "%d", $(NF - 1) * 1000 }' "$dir/logs/map-sink.log" 2> /dev/null || true)
    if [ -n "$logged" ] && [ "$logged" -gt "${peak[map-sink]:-0}" ]; then peak[map-sink]=$logged; fi
    frames=$(jq -r '.frames_processed // ""' "$dir/metrics.json" 2> /dev/null || true)
    results=$(check_results "$dir" "$finished")
    leftover=$(domain_files "$domain")
    echo "$run,$(( run_start - started )),${killed:-},${killed:+$kill_at},$code,$wall,$frames,${peak[slam-launch]:-},${peak[lidar-sim]:-},${peak[feature-proc]:-},${peak[slam-proc]:-},${peak[map-sink]:-},$shm_before,$(shm_files),$leftover,$root_before,$(root_entries),$used_before,$mem_before,$results" >> "$csv"
    echo "soak: run $run: exit $code in $wall s${killed:+, $killed killed at $kill_at s}; results $results; $leftover files of its domain left" >&2
    if [ "$finished" = yes ] && [ "$results" != whole ]; then status=1; fi
    if [ -z "$killed" ] && [ "$code" -ne 0 ]; then status=1; fi
    if [ "$leftover" -ne 0 ]; then status=1; fi
    unset peak
done

# The summary: counts, and the first and last runs' figures side by side.
awk -F, '
    NR == 1 { for (i = 1; i <= NF; i++) col[$i] = i; next }
    {
        runs++
        if ($col["killed"] != "") killed++
        else if ($col["exit"] == 0) finished++
        else failed++
        if ($col["results"] != "whole") broken++
        left += $col["domain_files_after"]
        # Peaks are compared between finished runs: a killed one stops early.
        if ($col["exit"] == 0) { if (first == "") first = $0; last = $0 }
    }
    END {
        printf "runs %d: %d finished, %d with a stage killed, %d failed otherwise\n", runs, finished, killed, failed
        printf "results not whole: %d; files of a run left in /dev/shm: %d\n", broken, left
        split(first, f, ","); split(last, l, ",")
        n = split("rss_kib_slam-launch rss_kib_lidar-sim rss_kib_feature-proc rss_kib_slam-proc rss_kib_map-sink shm_files_before root_entries_before shm_used_kib_before mem_available_mib_before", keys, " ")
        printf "%-26s %12s %12s\n", "first vs last finished", "first", "last"
        for (k = 1; k <= n; k++) printf "%-26s %12s %12s\n", keys[k], f[col[keys[k]]], l[col[keys[k]]]
    }' "$csv" | tee "$out/summary.txt" >&2
echo "per run: $csv" >&2
exit "$status"
