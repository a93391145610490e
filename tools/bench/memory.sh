#!/usr/bin/env bash
# Peak memory against the number of frames (issue 43, "Memory that follows the frame"): the
# built-in scene at 1920x1080 in 16x16x16 cells (4096), an orbit of 4 frames (4:20) and of 30
# frames at the same 5 degrees a frame (30:150), recorded once (or reused when the capture
# exists), then on each capture: record, analyze (no bracket), replay under Max Work, celltree,
# celltree-adaptive, celltree-union and auto at 1 and 8 processors, and a small sweep (2
# schedulers x 2 processor counts). Each step runs under nice and /usr/bin/time -f '%e %M'
# (wall seconds, peak resident set size). Prints a table: command, frames, wall s, peak MB, and
# the ratio of the 30-frame peak to the 4-frame one (the goal: at most 1.2, every peak at most
# 1 GiB).
#
# Usage: tools/bench/memory.sh [OUTDIR] [RES] [CELLS] [STEPS]
# Default: out/scale, 1920x1080, 16x16x16, every step. The captures are OUTDIR/b4096.rct and
# OUTDIR/b4096_30.rct (other RES or CELLS: OUTDIR/mem_RES_CELLS_N.rct); STEPS, a space-separated
# subset of: record analyze replay sweep (record only times a capture it makes).
# RAYCELL=path/to/raycell measures another build (e.g. the one before a change);
# SCHEDULERS="maxwork celltree" replays fewer schedulers (default: maxwork celltree
# celltree-adaptive celltree-union auto).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
raycell=${RAYCELL:-$root/build/tools/raycell}
out=${1:-out/scale}
res=${2:-1920x1080}
cells=${3:-16x16x16}
steps=${4:-record analyze replay sweep}
schedulers=${SCHEDULERS:-maxwork celltree celltree-adaptive celltree-union auto}
[ -x "$raycell" ] || { echo "needs $raycell: run tools/setup.sh" >&2; exit 2; }
[ -x /usr/bin/time ] || { echo "needs /usr/bin/time (Debian package time)" >&2; exit 2; }
mkdir -p "$out"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

capture() {  # capture FRAMES: the capture's path
  if [ "$res" = 1920x1080 ] && [ "$cells" = 16x16x16 ]; then
    [ "$1" = 4 ] && echo "$out/b4096.rct" || echo "$out/b4096_$1.rct"
  else
    echo "$out/mem_${res}_${cells}_$1.rct"
  fi
}

declare -A wall peak
# run KEY COMMAND...: runs it under nice and /usr/bin/time, keeps its wall time and peak MB.
run() {
  local key=$1; shift
  /usr/bin/time -f '%e %M' -o "$tmp/time" nice "$@" > "$tmp/stdout" 2> "$tmp/stderr" || {
    echo "$key failed:" >&2; cat "$tmp/stderr" >&2; exit 1; }
  read -r w m < <(tail -1 "$tmp/time")
  wall[$key]=$w
  peak[$key]=$(awk -v k="$m" 'BEGIN { printf "%.0f", k / 1024 }')
  echo "done: ${key%|*}, $n frames: $w s, ${peak[$key]} MB" >&2  # as it goes: runs are long
}

labels=()
for n in 4 30; do
  trace=$(capture $n)
  deg=$((n * 5))
  if [[ " $steps " == *" record "* ]] || [ ! -f "$trace" ]; then
    if [ -f "$trace" ]; then  # reused: time a recording into the scratch folder instead
      run "record|$n" "$raycell" record --res "$res" --orbit "$n:$deg" --cells "$cells" \
        --no-images --quiet --out "$tmp/r.rct"
      rm -f "$tmp/r.rct"
    else
      run "record|$n" "$raycell" record --res "$res" --orbit "$n:$deg" --cells "$cells" \
        --no-images --quiet --out "$trace"
    fi
  fi
  if [[ " $steps " == *" analyze "* ]]; then
    run "analyze|$n" "$raycell" analyze "$trace" --format csv --quiet
  fi
  if [[ " $steps " == *" replay "* ]]; then
    for s in $schedulers; do
      for p in 1 8; do
        run "replay $s, $p processor(s)|$n" "$raycell" replay "$trace" --scheduler "$s" \
          --set processors.count=$p --format csv --quiet
      done
    done
  fi
  if [[ " $steps " == *" sweep "* ]]; then
    run "sweep maxwork,celltree x 1,8 proc., --jobs 1|$n" "$raycell" sweep "$trace" \
      --vary scheduler=maxwork,celltree --vary processors.count=1,8 --jobs 1 --quiet \
      --out "$tmp/sweep.csv"
  fi
done

echo "built-in scene, $res, $cells cells; $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg); $raycell"
printf '| %-46s | %6s | %8s | %7s | %14s |\n' command frames "wall s" "peak MB" "30/4 frames"
printf '|%s|%s|%s|%s|%s|\n' "------------------------------------------------" "--------" \
  "----------" "---------" "----------------"
for key in "${!peak[@]}"; do labels+=("${key%|*}"); done
mapfile -t order < <(printf '%s\n' "${labels[@]}" | awk '!seen[$0]++' | sort)
for label in "${order[@]}"; do
  for n in 4 30; do
    k="$label|$n"
    [ -n "${peak[$k]:-}" ] || continue
    ratio=""
    if [ "$n" = 30 ] && [ -n "${peak[$label|4]:-}" ]; then
      ratio=$(awk -v a="${peak[$k]}" -v b="${peak[$label|4]}" 'BEGIN { printf "%.2f", a / b }')
    fi
    printf '| %-46s | %6s | %8s | %7s | %14s |\n' "$label" "$n" "${wall[$k]}" "${peak[$k]}" "$ratio"
  done
done
