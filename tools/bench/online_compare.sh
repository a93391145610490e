#!/usr/bin/env bash
# Online scheduling against Max Work (issue 9): fetches summed over a capture's frames
# under maxwork, celltree (frame i+1 follows frame i's Peel schedule), celltree-best (frame
# i+1 follows frame i's best schedule), celltree-union (the best schedule of the union of
# frames i-1 and i), and the two oracles peel and best (each frame its own schedule), with
# the replay's defaults (one block processor with a one-cell cache: the paper's setup)
# unless --set says otherwise. Prints a Markdown table: fetches, against Max Work, the
# simulated time, and each replay's wall time (on a loaded machine too noisy to derive the
# planning time from: `bench_best_schedules TRACE --plan-effort` measures that per frame).
#
# Usage: tools/bench/online_compare.sh TRACE [--set KEY=VALUE ...]
# e.g.   tools/bench/online_compare.sh /work/captures/study/capture_3x3x3.rct
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
raycell=${RAYCELL:-$root/build/tools/raycell}
trace=${1:?usage: online_compare.sh TRACE [--set KEY=VALUE ...]}
shift
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
now() { date +%s.%N; }
schedulers=(maxwork celltree celltree-best celltree-union peel best)
declare -A wall
for s in "${schedulers[@]}"; do
  a=$(now)
  "$raycell" replay "$trace" --scheduler "$s" --format json --quiet "$@" > "$work/$s.json"
  b=$(now)
  wall[$s]=$(echo "$b - $a" | bc -l)
done
frames=$(jq '.frames | length' "$work/maxwork.json")
bound=$(jq '.total.bound' "$work/maxwork.json")
mw=$(jq '.total.fetches' "$work/maxwork.json")
echo "trace: $trace ($frames frames) $*"
echo
echo "| scheduler | fetches | against Max Work | simulated ms | replay wall s |"
echo "|---|---:|---:|---:|---:|"
for s in "${schedulers[@]}"; do
  f=$(jq '.total.fetches' "$work/$s.json")
  t=$(jq '.total.time_ps' "$work/$s.json")
  printf '| %s | %s | %+.1f%% | %.1f | %.2f |\n' "$s" "$f" \
    "$(echo "($f - $mw) * 100 / $mw" | bc -l)" "$(echo "$t / 1000000000" | bc -l)" "${wall[$s]}"
done
echo "| maxGen bound (one-cell cache) | $bound | | | |"
echo
echo "per frame fetches (frame: maxwork celltree celltree-best celltree-union peel best bound):"
paste -d' ' <(jq -r '.frames[] | "\(.frame): \(.fetches)"' "$work/maxwork.json") \
  <(for s in celltree celltree-best celltree-union peel best; do
      jq -r '.frames[].fetches' "$work/$s.json" > "$work/$s.col"; done
    paste -d' ' "$work/celltree.col" "$work/celltree-best.col" "$work/celltree-union.col" \
      "$work/peel.col" "$work/best.col") \
  <(jq -r '.frames[].bound' "$work/maxwork.json")
