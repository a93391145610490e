#!/usr/bin/env bash
# Every scheduler's replay against Max Work's, in the same run (issue 43, "Plans at the cost of
# the replay"; docs/design.md §5 "The cost of deciding"): on each TRACE, at each processor
# count, Max Work first and then every scheduler `raycell replay --help` lists (auto included),
# one replay after another (never two at once), each timed with /usr/bin/time. Prints a table:
# scheduler, processors, cells (of the trace's grid), wall s, the ratio to Max Work's wall time
# of the same (trace, processors), CPU s (user + system) and its ratio to Max Work's (on a
# shared machine the wall time also measures the other processes), and peak RSS in MB. The replay's own results go to a scratch
# file and are dropped (their fetches are not what this measures).
#
# Usage: tools/bench/scheduler_cost.sh [TRACE ...]
#        (default: out/scale/b512.rct out/scale/b4096.rct, the built-in scene at 1920x1080,
#        an orbit of 4 frames over 20 degrees, 8x8x8 and 16x16x16 cells:
#        `raycell record --res 1920x1080 --orbit 4:20 --cells 8x8x8 --no-images`)
# Env:   RAYCELL (default build/tools/raycell), PROCESSORS (default "1 8"), SCHEDULERS (a
#        comma-separated subset, default every registered one; Max Work always runs first),
#        NICE (default 1: run the replays under nice).
# At 1920x1080 and 4096 cells each replay takes tens of seconds: the whole table takes tens of
# minutes on a loaded 2-core machine.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
raycell=${RAYCELL:-$root/build/tools/raycell}
processors=${PROCESSORS:-1 8}
[ $# -gt 0 ] || set -- out/scale/b512.rct out/scale/b4096.rct
prefix=()
[ "${NICE:-1}" = 1 ] && prefix=(nice)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# The registry's names, from the "Schedulers:" section of the help (two spaces, then the name).
if [ -n "${SCHEDULERS:-}" ]; then
  IFS=, read -r -a schedulers <<< "$SCHEDULERS"
else
  mapfile -t schedulers < <("$raycell" replay --help |
    awk '/^Schedulers:/ {on = 1; next} on && /^$/ {exit} on && /^  [a-z]/ {print $1}')
fi
[ ${#schedulers[@]} -gt 0 ] || { echo "scheduler_cost.sh: no scheduler listed" >&2; exit 1; }

# The trace's cells, from the header `raycell trace info` prints first ("cell grid: 8x8x8 = 512
# cells"); awk stops reading there, so the frames' trees are not built.
cells_of() {
  local n
  n=$("$raycell" trace info "$1" 2> /dev/null |
    awk '/^cell grid:/ {for (i = 1; i <= NF; i++) if ($i == "=") print $(i + 1); exit}') || true
  echo "${n:-?}"
}

# Runs one replay; prints "wall_s cpu_s peak_mb".
run() {
  local trace=$1 scheduler=$2 p=$3
  "${prefix[@]}" /usr/bin/time -f '%e %U %S %M' -o "$work/time" "$raycell" replay "$trace" \
    --scheduler "$scheduler" --set "processors.count=$p" --format csv --quiet \
    --out "$work/out.csv" || { echo "replay failed: $scheduler, $p processors, $trace" >&2; exit 1; }
  awk '{printf "%s %.2f %.0f\n", $1, $2 + $3, $4 / 1024}' "$work/time"
}

row='%-22s %10s %6s %8.1f %8.2f %8.1f %8.2f %8s   %s\n'
printf '%-22s %10s %6s %8s %8s %8s %8s %8s   %s\n' scheduler processors cells wall_s ratio \
  cpu_s ratio peak_MB trace
for trace in "$@"; do
  cells=$(cells_of "$trace")
  for p in $processors; do
    read -r base base_cpu base_mb < <(run "$trace" maxwork "$p")
    printf "$row" maxwork "$p" "$cells" "$base" 1 "$base_cpu" 1 "$base_mb" "$(basename "$trace")"
    for s in "${schedulers[@]}"; do
      [ "$s" = maxwork ] && continue
      read -r wall cpu mb < <(run "$trace" "$s" "$p")
      printf "$row" "$s" "$p" "$cells" "$wall" "$(echo "$wall / $base" | bc -l)" "$cpu" \
        "$(echo "$cpu / $base_cpu" | bc -l)" "$mb" "$(basename "$trace")"
    done
  done
done
