#!/usr/bin/env bash
# The size of `raycell replay --timeline` and what writing it costs: the same replay with and
# without a timeline, alternated, RUNS times each (median printed), then the file's size and
# its check against the trace-event format (tools/bench/check_timeline.py).
#
#   tools/bench/timeline_size.sh TRACE RUNS [replay options...]
#   tools/bench/timeline_size.sh /work/captures/study/capture_3x3x3.rct 3
#   tools/bench/timeline_size.sh /work/captures/study/capture_3x3x3.rct 3 --granularity ray \
#       --set processors.count=2 --set processors.prefetch=true --set "level.cache.capacity=2 cells"
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
raycell=${RAYCELL:-$root/build/tools/raycell}
trace=${1:?usage: timeline_size.sh TRACE RUNS [replay options...]}
runs=${2:?usage: timeline_size.sh TRACE RUNS [replay options...]}
shift 2
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

seconds() {  # wall seconds of one run of "$@"
  local t0 t1
  t0=$(date +%s.%N)
  "$@" >/dev/null
  t1=$(date +%s.%N)
  awk -v a="$t0" -v b="$t1" 'BEGIN {printf "%.3f\n", b - a}'
}
median() { sort -g | awk '{a[NR]=$1} END {print a[int((NR + 1) / 2)]}'; }

plain=() with=()
for ((i = 0; i < runs; ++i)); do
  plain+=("$(seconds "$raycell" replay "$trace" --quiet "$@")")
  with+=("$(seconds "$raycell" replay "$trace" --quiet "$@" --timeline "$out/t.json")")
done
p=$(printf '%s\n' "${plain[@]}" | median)
w=$(printf '%s\n' "${with[@]}" | median)
size=$(stat -c %s "$out/t.json")
echo "trace: $trace  options: $*"
echo "replay without timeline: ${p} s   with: ${w} s   (median of $runs, alternated)"
echo "timeline: $size bytes ($(awk -v s="$size" 'BEGIN {printf "%.1f", s / 1048576}') MiB); limit 268435456 bytes (256 MiB)"
python3 "$root/tools/bench/check_timeline.py" "$out/t.json"
