#!/usr/bin/env bash
# Output compatibility: runs `raycell replay` (table, json and csv, several configurations)
# and mixed `raycell sweep`s (--jobs 1 and 2, sharded and merged) with two binaries and
# compares every output byte for byte. For checking that a change to the replay or its
# printers leaves every output as it was.
#
# OLD may also be a folder of outputs saved by an earlier run (WORK_DIR/old), which is then
# compared without running anything old.
#
# Usage: tools/bench/compare_replay_outputs.sh OLD_RAYCELL NEW_RAYCELL TRACE [WORK_DIR]
# e.g.   tools/bench/compare_replay_outputs.sh build-base/build/tools/raycell \
#            build/tools/raycell small.rct
set -euo pipefail
old=${1:?usage: compare_replay_outputs.sh OLD NEW TRACE [WORK_DIR]}
new=${2:?usage: compare_replay_outputs.sh OLD NEW TRACE [WORK_DIR]}
trace=${3:?usage: compare_replay_outputs.sh OLD NEW TRACE [WORK_DIR]}
work=${4:-$(mktemp -d)}
mkdir -p "$work/new"
if [ -d "$old" ]; then
  rm -rf "$work/old" && cp -r "$old" "$work/old"
  old=""
else
  mkdir -p "$work/old"
fi

configs=(
  ""
  "--scheduler maxwork"
  "--scheduler peel --granularity ray"
  "--scheduler roundrobin --set processors.count=2 --set 'level.cache.capacity=2 cells'"
  "--scheduler random --set processors.count=3 --set processors.prefetch=true --set 'level.cache.capacity=3 cells'"
  "--scheduler maxwork --set processors.count=4 --set level.cache.replacement=min --set 'level.cache.capacity=2 cells'"
  "--set processors.count=2 --set level.cache.capacity=64KiB --set level.board.replacement=fifo --set level.board.capacity=300KiB"
  "--scheduler peel --set processors.count=8 --set 'level.cache.capacity=4 cells' --set processors.prefetch=true --set level.board.bandwidth=1GB/s"
  "--granularity ray --sample 3 --set processors.count=2 --set 'level.cache.capacity=2 cells'"
  "--frames 2..4 --set processors.queue_record_bytes=48"
  "--scheduler random --granularity node --set processors.count=2 --set seed=5"
  "--scheduler maxwork --set level.cache.replacement=min --set 'level.cache.capacity=3 cells' --set level.board.replacement=min --set level.board.capacity=400KiB"
)
run() {  # BINARY DIR NAME ARGS...; nothing when BINARY is empty (saved outputs)
  local bin=$1 dir=$2 name=$3
  shift 3
  [ -n "$bin" ] || return 0
  "$bin" "$@" --quiet > "$dir/$name" 2> "$dir/$name.err" || echo "exit $?" >> "$dir/$name.err"
}
n=0
for c in "${configs[@]}"; do
  eval "args=($c)"
  for f in table json csv; do
    run "$old" "$work/old" "replay$n.$f" replay "$trace" --format "$f" "${args[@]}"
    run "$new" "$work/new" "replay$n.$f" replay "$trace" --format "$f" "${args[@]}"
  done
  n=$((n + 1))
done

vary=(--vary scheduler=maxwork,roundrobin,random,peel,celltree --vary processors.count=1,2,3
      --vary "level.cache.capacity=2 cells,4 cells" --vary processors.prefetch=false,true
      --vary level.board.bandwidth=133MB/s,1GB/s)
for side in old new; do
  bin=$old; [ "$side" = new ] && bin=$new
  [ -n "$bin" ] || continue
  d=$work/$side
  rm -f "$d"/sweep*.csv "$d"/sweep*.partial
  "$bin" sweep "$trace" "${vary[@]}" --jobs 1 --out "$d/sweep1.csv" --quiet
  "$bin" sweep "$trace" "${vary[@]}" --jobs 2 --out "$d/sweep2.csv" --quiet
  for i in 0 1 2; do
    "$bin" sweep "$trace" "${vary[@]}" --jobs 2 --shard "$i/3" --out "$d/sweep-s$i.csv" --quiet
  done
  "$bin" sweep merge "$d/sweep-merged.csv" "$d/sweep-s2.csv" "$d/sweep-s0.csv" "$d/sweep-s1.csv"
  "$bin" sweep "$trace" "${vary[@]}" --frames 1..3 --jobs 2 --out "$d/sweep-frames.csv" --quiet
done

status=0
for f in "$work"/old/*; do
  name=$(basename "$f")
  if cmp -s "$f" "$work/new/$name"; then
    echo "same      $name ($(wc -c < "$f") bytes)"
  else
    echo "DIFFERENT $name"
    status=1
  fi
done
exit $status
