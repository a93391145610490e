#!/usr/bin/env bash
# The paper's Cell Tree figures (Frank & Kaufman 2002: volumes in 8 and 27 cells, 256x256,
# reflections, refractions and shadows): records an orbit of the built-in scene and of
# mj_smoke.vdb with 2x2x2 and 3x3x3 cells, analyses every frame's Cell Tree and prints, per
# scene and grid, the means over frames of rays, nodes, rays per node (the paper: about
# 100), the bound, Peel's length and splits, and how often the exact optimum was proved and
# its mean gap to Peel.
#
# Usage: tools/bench/paper_cell_trees.sh [FRAMES=30] [OUT_DIR=bench-out/cell-trees]
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
raycell=${RAYCELL:-$root/build/tools/raycell}
frames=${1:-30}
out=${2:-$root/bench-out/cell-trees}
mkdir -p "$out"
smoke=$root/../shared/data/mj_smoke.vdb

printf '%-8s %-6s %6s %10s %8s %9s %7s %7s %7s %9s %9s\n' scene cells frames rays nodes \
  rays/node bound peel splits "opt/proved" "peel-opt"
for scene in builtin smoke; do
  src=builtin
  if [ "$scene" = smoke ]; then
    [ -f "$smoke" ] || { echo "skipping smoke: no $smoke" >&2; continue; }
    src=$smoke
  fi
  for cells in 2x2x2 3x3x3; do
    trace=$out/$scene-$cells.rct
    "$raycell" record --scene "$src" --cells "$cells" --res 256x256 --orbit "$frames:360" \
      --out "$trace" --no-images --quiet 2>/dev/null
    "$raycell" analyze "$trace" --exact --max-seconds 2 --format csv --quiet > "$out/$scene-$cells.csv"
    awk -F, -v s="$scene" -v c="$cells" 'NR > 1 {
        n++; rays += $2; nodes += $3; rpn += $4; bound += $5; peel += $6; splits += $7
        if ($9 != "") { proved++; gap += $10 }
      } END {
        printf "%-8s %-6s %6d %10.0f %8.1f %9.1f %7.2f %7.2f %7.2f %4d/%-4d %9s\n", s, c, n,
          rays / n, nodes / n, rpn / n, bound / n, peel / n, splits / n, proved, n,
          proved ? sprintf("%.2f", gap / proved) : "-"
      }' "$out/$scene-$cells.csv"
  done
done
echo "per-frame rows: $out/*.csv"
