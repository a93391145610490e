#!/usr/bin/env bash
# Two memory levels of different cells (issue 23), BENCHMARKS.md "Two memory levels": records
# SCENE once on a 12x12x12 grid with --regroupable (an orbit of FRAMES frames, 3.75 degrees a
# frame, as the study's), then replays it with the caches' cells FINE (default 6x6x6) under a
# board of COARSE cells (default 3x3x3; level.board.cells) sized to each FRACTION of the
# volume (the 3x3x3 cells' footprints summed), one processor, the rest the default
# configuration (warm memory, a one-cell cache). Schedulers: Max Work, Cell Tree (Peel of frame
# i), celltree-best, the two-level plans (celltree-2level, celltree-2level-best) and, for
# reference, Cell Tree with
# a board of the caches' own cells. Prints one markdown row per board size and scheduler:
# fetches and bytes over each link (host->board: PCI; board->cache) and the simulated time,
# with the change against Cell Tree on the same board.
#
# Usage: tools/bench/two_levels.sh SCENE [FRAMES=24] [RES=256x256] [FINE=6x6x6] [COARSE=3x3x3]
#        [FRACTIONS="0.25 0.5"] [RAYCELL=build/tools/raycell]
set -euo pipefail
scene=$1
frames=${2:-24}
res=${3:-256x256}
fine=${4:-6x6x6}
coarse=${5:-3x3x3}
fractions=${6:-0.25 0.5}
raycell=${7:-build/tools/raycell}
work=$(mktemp -d /tmp/raycell_two_levels.XXXXXX)
trap 'rm -rf "$work"' EXIT
degrees=$(python3 -c "print($frames * 3.75)")
"$raycell" record --scene "$scene" --res "$res" --cells 12x12x12 --regroupable \
  --orbit "$frames:$degrees" --no-images --quiet --out "$work/fine.rct" >&2
volume=$("$raycell" trace info "$work/fine.rct" --cells "$coarse" |
  sed -n 's/^footprints: *[a-z]*, \([0-9]*\) bytes in all.*/\1/p')
echo "scene $scene, $frames frames at $res, 12x12x12 fine; caches of $fine cells (1 cell), board of $coarse cells; volume $volume bytes"
echo "| board | scheduler | cache fetches | board->cache MB | PCI loads | PCI MB | time ms |"
echo "|---|---|---:|---:|---:|---:|---:|"
for fraction in $fractions; do
  board=$(python3 -c "print(int($volume * $fraction))")
  run() {  # NAME SCHEDULER BOARD_CELLS
    "$raycell" replay "$work/fine.rct" --cells "$fine" --scheduler "$2" \
      --set "level.board.cells=$3" --set "level.board.capacity=${board}B" \
      --format json --quiet > "$work/$1.json"
  }
  run maxwork maxwork "$coarse"
  run celltree celltree "$coarse"
  run best celltree-best "$coarse"
  run two celltree-2level "$coarse"
  run twobest celltree-2level-best "$coarse"
  run own celltree same
  python3 - "$work" "$fraction" "$board" "$coarse" "$fine" <<'PY'
import json, sys
work, fraction, board, coarse, fine = sys.argv[1:]
def row(name):
    t = json.load(open("%s/%s.json" % (work, name)))["total"]
    lv = {l["name"]: l for l in t["levels"]}
    return [lv["cache"]["fetches"], lv["cache"]["bytes"], lv["board"]["fetches"],
            lv["board"]["bytes"], t["time_ps"] / 1e9]
base = row("celltree")
names = [("maxwork", "Max Work"), ("celltree", "Cell Tree"), ("best", "celltree-best"),
         ("two", "two-level (Peel)"), ("twobest", "**two-level, best schedules**"), ("own", "Cell Tree, board of %s cells" % fine)]
for name, label in names:
    r = row(name)
    rel = lambda i: "" if name == "celltree" else " (%+.1f%%)" % (100.0 * (r[i] - base[i]) / base[i])
    print("| %s%% (%.2f MB) | %s | %d%s | %.1f%s | %d%s | %.1f%s | %.0f%s |" % (
        int(float(fraction) * 100), int(board) / 1e6, label, r[0], rel(0), r[1] / 1e6, rel(1),
        r[2], rel(2), r[3] / 1e6, rel(3), r[4], rel(4)))
PY
done
