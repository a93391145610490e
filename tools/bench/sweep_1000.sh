#!/usr/bin/env bash
# The 1000-configuration sweep of BENCHMARKS.md: scheduler (5) x processors (1, 2, 4, 8) x
# cache capacity (2, 4, 8, 16, 27 cells) x prefetch (off, on) x board bandwidth (5 PCI-era
# rates) over every frame of TRACE, with peak memory from /usr/bin/time -v. A cache of one
# cell is left out: prefetch needs room for two cells, and the sweep refuses combinations it
# cannot replay before doing any work.
#
# Usage: tools/bench/sweep_1000.sh TRACE [OUT_DIR=bench-out/sweep-1000] [JOBS=2] [SHARD=all]
#   RAYCELL=path/to/raycell selects the binary (default build/tools/raycell).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
raycell=${RAYCELL:-$root/build/tools/raycell}
trace=${1:?usage: sweep_1000.sh TRACE [OUT_DIR] [JOBS] [SHARD]}
out=${2:-$root/bench-out/sweep-1000}
jobs=${3:-2}
shard=${4:-}
mkdir -p "$out"
name=$(basename "$raycell")-$(date +%s%N)
csv=$out/$name.csv
rm -f "$csv" "$csv.partial" "$csv.checkpoint"
args=(sweep "$trace" --jobs "$jobs" --out "$csv" --quiet
  --vary scheduler=maxwork,roundrobin,random,peel,celltree
  --vary processors.count=1,2,4,8
  --vary "level.cache.capacity=2 cells,4 cells,8 cells,16 cells,27 cells"
  --vary processors.prefetch=false,true
  --vary level.board.bandwidth=66MB/s,133MB/s,266MB/s,533MB/s,1066MB/s)
[ -n "$shard" ] && args+=(--shard "$shard")
/usr/bin/time -v "$raycell" "${args[@]}" 2> "$out/$name.time"
wall=$(grep 'Elapsed (wall clock)' "$out/$name.time" | awk '{print $NF}')
user=$(grep 'User time' "$out/$name.time" | awk '{print $NF}')
sys=$(grep 'System time' "$out/$name.time" | awk '{print $NF}')
rss=$(grep 'Maximum resident set size' "$out/$name.time" | awk '{print $NF}')
rows=$(($(wc -l < "$csv") - 2))
echo "$raycell: $rows rows, wall $wall, user ${user}s, sys ${sys}s, peak RSS $((rss / 1024)) MiB, load $(cut -d' ' -f1-3 /proc/loadavg) -> $csv"
