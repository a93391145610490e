#!/usr/bin/env bash
# --cells auto:N against the uniform grid over a set of fine captures (issue 42, "One
# recommendation per question"; docs/design.md §1 "Subdivisions"). Each CAPTURE is a
# `--regroupable` fine capture (e.g. `raycell record --cells 12x12x12 --regroupable --res
# 128x128 --orbit 8:60`); each is replayed regrouped into every SPEC under every scheduler of
# $SCHEDULERS with the on-chip cache sized in bytes to the median footprint of the uniform grid
# BASE's non-empty cells (as tools/bench/subdivisions.sh). Prints per capture and SPEC the
# change of cache bytes (board->cache) against BASE, then per SPEC and scheduler the geometric
# mean of the ratios and the worst capture. Schedulers that the raycell binary does not know
# (`auto` until it exists) are skipped, saying so.
#
# Usage: tools/bench/auto_cells.sh [CAPTURE...]
# With no CAPTURE, records the built-in scene and ../shared/data/mj_smoke.vdb (when present) at
# 128x128, 12x12x12 fine, 8 frames of an orbit of 3.75 degrees a frame (as subdivisions.sh), and
# measures those (about 2 minutes on one core).
# Environment: RAYCELL (build/tools/raycell), BASE (3x3x3), SPECS ("auto:27 kd:27:footprint
#   kd:27:sqrt dynamic:27:sqrt grid:27:crossings"), SCHEDULERS ("maxwork celltree-best auto").
set -euo pipefail
raycell=${RAYCELL:-build/tools/raycell}
base=${BASE:-3x3x3}
specs=${SPECS:-auto:27 kd:27:footprint kd:27:sqrt dynamic:27:sqrt grid:27:crossings}
schedulers=${SCHEDULERS:-maxwork celltree-best auto}
work=$(mktemp -d /tmp/raycell_auto_cells.XXXXXX)
trap 'rm -rf "$work"' EXIT
known=()
for s in $schedulers; do
  if "$raycell" replay --help | sed -n 's/^ *--scheduler TEXT *//p' | sed 's/ *(.*//' |
    tr ',' '\n' | tr -d ' ' | grep -qx -- "$s"; then known+=("$s"); else
    echo "scheduler '$s' unknown to $raycell: skipped" >&2; fi
done
captures=("$@")
if ((${#captures[@]} == 0)); then
  data=$(dirname "$0")/../../../shared/data
  for scene in builtin "$data/mj_smoke.vdb"; do
    [[ $scene == builtin || -f $scene ]] || continue
    name=$(basename "$scene" .vdb)
    "$raycell" record --scene "$scene" --res 128x128 --cells 12x12x12 --regroupable \
      --orbit 8:30 --no-images --quiet --out "$work/$name.rct" >&2
    captures+=("$work/$name.rct")
  done
fi
for capture in "${captures[@]}"; do
  median=$("$raycell" trace info "$capture" --cells "$base" |
    sed -n 's/^footprint spread: [0-9]* non-empty cells, min [0-9]*, median \([0-9]*\), .*/\1/p')
  for spec in "$base" $specs; do
    for sched in "${known[@]}"; do
      bytes=$("$raycell" replay "$capture" --cells "$spec" --scheduler "$sched" \
        --set "level.cache.capacity=${median}B" --format json |
        python3 -c 'import json,sys; t=json.load(sys.stdin)["total"]; print([l["bytes"] for l in t["levels"] if l["name"]=="cache"][0])')
      echo "$(basename "$capture") $spec $sched $bytes" >> "$work/rows"
    done
  done
done
python3 - "$work/rows" "$base" <<'PY'
import math, sys
rows = [l.split() for l in open(sys.argv[1])]
base = sys.argv[2]
b = {(c, s): int(v) for c, sp, s, v in rows if sp == base}
caps = list(dict.fromkeys(c for c, *_ in rows))
specs = list(dict.fromkeys(sp for _, sp, _, _ in rows if sp != base))
scheds = list(dict.fromkeys(s for _, _, s, _ in rows))
v = {(c, sp, s): int(x) for c, sp, s, x in rows}
print("cache bytes against %s (cache: its median footprint); per capture, then geometric mean and worst" % base)
print("| capture | scheduler | %s bytes (MB) | %s |" % (base, " | ".join(specs)))
print("|---|---|---:|" + "---:|" * len(specs))
for c in caps:
    for s in scheds:
        print("| %s | %s | %.1f | %s |" % (c, s, b[c, s] / 1e6, " | ".join(
            "%+.1f%%" % (100.0 * (v[c, sp, s] / b[c, s] - 1)) for sp in specs)))
for s in scheds:
    cells = []
    for sp in specs:
        r = [v[c, sp, s] / b[c, s] for c in caps]
        g = math.exp(sum(map(math.log, r)) / len(r))
        w = max(range(len(r)), key=lambda i: r[i])
        cells.append("%+.1f%% / %+.1f%% (%s)" % (100 * (g - 1), 100 * (r[w] - 1), caps[w]))
    print("| **geomean / worst** | %s | | %s |" % (s, " | ".join(cells)))
PY
