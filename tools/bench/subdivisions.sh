#!/usr/bin/env bash
# Subdivisions of one fine capture at about 27 cells (issue 23), BENCHMARKS.md "Subdivisions":
# records SCENE once on a fine grid (FINE, 12x12x12 by default) with --regroupable (an orbit
# of FRAMES frames, 3.75 degrees a frame, as the study's), then replays it regrouped into each
# SPEC under Max Work and Cell Tree scheduling, with the on-chip cache sized in bytes to the
# median footprint of the uniform 3x3x3 grid (default configuration otherwise: one processor,
# warm memory). Prints one markdown row per SPEC and scheduler: cells, footprint spread,
# fetches, bytes over the board->cache and host->board links, fetch stall, each against 3x3x3.
# Cells: the non-empty ones. A fine grid with 27 cells along an axis adds the 27 slabs across
# it (grid:27x1x1, grid:1x27x1 or grid:1x1x27).
#
# Usage: tools/bench/subdivisions.sh SCENE [FRAMES=8] [RES=256x256] [RAYCELL=build/tools/raycell]
#                                    [FINE=12x12x12]
set -euo pipefail
scene=$1
frames=${2:-8}
res=${3:-256x256}
raycell=${4:-build/tools/raycell}
fine=${5:-12x12x12}
work=$(mktemp -d /tmp/raycell_subdivisions.XXXXXX)
trap 'rm -rf "$work"' EXIT
degrees=$(python3 -c "print($frames * 3.75)")
"$raycell" record --scene "$scene" --res "$res" --cells "$fine" --regroupable \
  --orbit "$frames:$degrees" --no-images --quiet --out "$work/fine.rct" >&2
spread() {  # SPEC's cells: "COUNT MIN MEDIAN MAX" of the non-empty ones' footprints
  "$raycell" trace info "$work/fine.rct" --cells "$1" |
    sed -n 's/^footprint spread: \([0-9]*\) non-empty cells, min \([0-9]*\), median \([0-9]*\), max \([0-9]*\) .*/\1 \2 \3 \4/p'
}
slabs() {  # the grids of 27 slabs that the fine grid has room for
  IFS=x read -r fx fy fz <<<"$fine"
  if ((fx >= 27)); then echo grid:27x1x1; fi
  if ((fy >= 27)); then echo grid:1x27x1; fi
  if ((fz >= 27)); then echo grid:1x1x27; fi
}
median=$(spread 3x3x3 | cut -d' ' -f3)
echo "scene $scene, $frames frames at $res, $fine fine; cache capacity ${median}B (median of 3x3x3)"
echo "| SPEC | cells | footprint min-max (KiB) | max/min | scheduler | fetches | cache bytes | board bytes | stall ms |"
echo "|---|---:|---:|---:|---|---:|---:|---:|---:|"
for spec in 3x3x3 kd:27:footprint kd:27:work kd:27:sqrt "kd:budget:${median}B" "octree:${median}B" \
  dynamic:27 dynamic:27:sqrt auto:27 grid:1x3x9 grid:1x9x3 grid:3x1x9 grid:9x1x3 grid:3x9x1 grid:9x3x1 \
  grid:27:crossings $(slabs); do
  fp=$(spread "$spec")
  for sched in maxwork celltree; do
    "$raycell" replay "$work/fine.rct" --cells "$spec" --scheduler "$sched" \
      --set "level.cache.capacity=${median}B" --format json > "$work/r.json"
    python3 - "$spec" "$sched" "$fp" "$work/r.json" "$work/base_$sched" <<'PY'
import json, os, sys
spec, sched, fp, path, base = sys.argv[1:]
count, lo, mid, hi = (int(x) for x in fp.split())
t = json.load(open(path))["total"]
lv = {l["name"]: l for l in t["levels"]}
row = [t["fetches"], lv["cache"]["bytes"], lv["board"]["bytes"], t["stall_ps"] / 1e9]
if spec == "3x3x3":
    json.dump(row, open(base, "w"))
b = json.load(open(base))
rel = lambda i: "" if spec == "3x3x3" else " (%+.1f%%)" % (100.0 * (row[i] - b[i]) / b[i])
print("| %s | %d | %.0f-%.0f | %.1f | %s | %d%s | %.1f M%s | %.2f M%s | %.1f%s |" % (
    spec, count, lo / 1024, hi / 1024, hi / lo, sched,
    row[0], rel(0), row[1] / 1e6, rel(1), row[2] / 1e6, rel(2), row[3], rel(3)))
PY
  done
done
