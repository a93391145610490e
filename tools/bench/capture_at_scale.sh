#!/usr/bin/env bash
# Capture at scale: `raycell record` of the built-in scene at large image sizes in several
# cell grids, then `raycell analyze` and `raycell replay` (default granularity, which is per
# Cell Tree node with one processor, and per ray segment) of each capture. Prints each step's
# wall time and peak memory (maximum resident set size, from /usr/bin/time -v), and the
# capture's rays, visits and bytes. Every step runs under `nice` (shared machines).
#
# Usage: tools/bench/capture_at_scale.sh [OUTDIR] [SIZES] [CELLS] [THREADS]
# Default: a temporary folder, "1024 2048", "3x3x3 8x8x8", 2 threads.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
raycell=${RAYCELL:-$root/build/tools/raycell}
out=${1:-}
sizes=${2:-1024 2048}
grids=${3:-3x3x3 8x8x8}
threads=${4:-2}
[ -x "$raycell" ] || { echo "needs $raycell: run tools/setup.sh" >&2; exit 2; }
[ -x /usr/bin/time ] || { echo "needs /usr/bin/time (Debian package time)" >&2; exit 2; }
if [ -z "$out" ]; then
  out=$(mktemp -d)
  trap 'rm -rf "$out"' EXIT
fi
mkdir -p "$out"

# run LABEL COMMAND...: runs it under nice and /usr/bin/time -v, prints one table row.
run() {
  local label=$1; shift
  /usr/bin/time -v -o "$out/time.txt" nice "$@" > "$out/stdout.txt" 2> "$out/stderr.txt" || {
    echo "$label failed:" >&2; cat "$out/stderr.txt" >&2; exit 1; }
  local wall rss
  wall=$(awk -F': ' '/Elapsed \(wall clock\)/ {print $2}' "$out/time.txt")
  rss=$(awk -F': ' '/Maximum resident set size/ {print $2}' "$out/time.txt")
  printf '| %-36s | %10s | %8.0f |\n' "$label" "$wall" "$(echo "$rss / 1024" | bc -l)"
}

echo "built-in scene, $threads thread(s), nice; $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"
printf '| %-36s | %10s | %8s |\n' "step" "wall m:s" "peak MiB"
printf '|%s|%s|%s|\n' "--------------------------------------" "------------" "----------"
for size in $sizes; do
  for cells in $grids; do
    trace="$out/builtin_${size}_${cells}.rct"
    run "record ${size}x${size} $cells" "$raycell" record --res "${size}x${size}" --cells "$cells" \
      --threads "$threads" --no-images --quiet --out "$trace"
    info=$("$raycell" trace info "$trace" | grep -E "^ +total" || true)
    run "analyze ${size}x${size} $cells" "$raycell" analyze "$trace" --format csv --quiet
    run "replay ${size}x${size} $cells" "$raycell" replay "$trace" --format csv --quiet
    run "replay per ray ${size}x${size} $cells" "$raycell" replay "$trace" --granularity ray \
      --format csv --quiet
    echo "|   capture: ${info# } |"
  done
done
