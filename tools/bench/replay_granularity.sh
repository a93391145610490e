#!/usr/bin/env bash
# Replay speed, and node granularity's speed-up over ray granularity against its error in
# fetches and simulated time, measured alternately in one run (median of REPS).
#
# Usage: tools/bench/replay_granularity.sh TRACE [REPS=3] [--set KEY=VALUE ...]
# e.g.   tools/bench/replay_granularity.sh bench-out/cell-trees/builtin-3x3x3.rct 3
#        tools/bench/replay_granularity.sh T.rct 3 --set processors.count=2
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
raycell=${RAYCELL:-$root/build/tools/raycell}
trace=${1:?usage: replay_granularity.sh TRACE [REPS] [--set KEY=VALUE ...]}
reps=${2:-3}
shift $(( $# >= 2 ? 2 : 1 ))
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
now() { date +%s.%N; }
declare -A times
for ((i = 0; i < reps; i++)); do
  for g in ray node; do
    a=$(now)
    "$raycell" replay "$trace" --granularity "$g" --format csv --quiet "$@" > "$work/$g.csv"
    b=$(now)
    times[$g]+="$(echo "$b - $a" | bc -l) "
  done
done
median() { printf '%s\n' $1 | sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }
t_ray=$(median "${times[ray]}"); t_node=$(median "${times[node]}")
total() { grep '^total' "$work/$1.csv"; }
IFS=, read -r _ f_ray _ time_ray _ <<< "$(total ray)"
IFS=, read -r _ f_node _ time_node _ <<< "$(total node)"
# The segments column, found by its name in the header (columns were added over time).
col=$(grep -v '^#' "$work/ray.csv" | head -1 | tr ',' '\n' | grep -n -x segments | cut -d: -f1)
segments=$(total ray | cut -d, -f"$col")
echo "trace: $trace ($reps runs each, median wall time) $*"
printf 'ray  granularity: %7.3f s  %6.2f M segments/s  fetches %s  simulated %s ps\n' \
  "$t_ray" "$(echo "$segments / $t_ray / 1000000" | bc -l)" "$f_ray" "$time_ray"
printf 'node granularity: %7.3f s  speed-up %.2fx  fetches %s (error %s)  simulated %s ps (error %.4f%%)\n' \
  "$t_node" "$(echo "$t_ray / $t_node" | bc -l)" "$f_node" "$((f_node - f_ray))" "$time_node" \
  "$(echo "($time_node - $time_ray) * 100 / $time_ray" | bc -l)"
