#!/usr/bin/env bash
# Scale (issue 43): wall time and peak memory of `raycell record`, `analyze` (no bracket),
# `replay` (Max Work, 1 processor) and `sweep` (Max Work, 4 times per sample, 2
# threads) of the built-in scene against its visits (256x256 to
# 2048x2048 in 8x8x8 cells) and against its cells (1920x1080 in 2x2x2 to 16x16x16 cells),
# FRAMES frames of an orbit each, with each command's log-log slope (least squares of log
# time, log memory on log visits, log cells): the study's scale section (study/scale.h) at
# full size. Peak memory from /usr/bin/time (a fork of a small process, so the child's own).
#
# Usage: tools/bench/scale.sh [OUTDIR] [FRAMES]     default: a temporary folder, 2 frames
# SCALE_RES, SCALE_CELLS and SCALE_AT (the cells series' image) replace the points;
# SCALE_SCENE=scenes/NAME.toml measures that scene instead of the built-in one.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
raycell=${RAYCELL:-$root/build/tools/raycell}
out=${1:-}
frames=${2:-2}
[ -x "$raycell" ] || { echo "needs $raycell: run tools/setup.sh" >&2; exit 2; }
[ -x /usr/bin/time ] || { echo "needs /usr/bin/time (Debian package time)" >&2; exit 2; }
if [ -z "$out" ]; then
  out=$(mktemp -d)
  trap 'rm -rf "$out"' EXIT
fi
mkdir -p "$out"
rows=$out/scale.csv
echo "res,cells,series,visits,command,seconds,peak_mb" > "$rows"

# run RES CELLS SERIES: records (unless recorded), analyses and replays one point.
run() {
  local res=$1 cells=$2 series=$3 trace=$out/$1_$2.rct
  local -a cmds=(
    "record ${SCALE_SCENE:+--scene $SCALE_SCENE }--res $res --cells $cells --orbit $frames:$((2 * frames)) --no-images --quiet --out $trace"
    "analyze $trace --quiet --format csv"
    "replay $trace --scheduler maxwork --quiet"
    "sweep $trace --vary scheduler=maxwork --vary processors.time_per_sample=5ns,10ns,20ns,40ns --jobs 2 --out $out/sweep.csv --quiet")
  local names=(record analyze replay sweep) i visits=""
  for i in 0 1 2 3; do
    # shellcheck disable=SC2086
    /usr/bin/time -f '%e %M' -o "$out/time.txt" nice "$raycell" ${cmds[$i]} > /dev/null 2> "$out/err.txt" ||
      { echo "raycell ${cmds[$i]} failed:" >&2; cat "$out/err.txt" >&2; exit 1; }
    [ -n "$visits" ] || visits=$("$raycell" trace info "$trace" --no-character |
      awk '$1 == "total" {print $7}')
    read -r secs kb < "$out/time.txt"
    echo "$res,$cells,$series,$visits,${names[$i]},$secs,$(echo "$kb / 1024" | bc -l | xargs printf '%.0f')" >> "$rows"
  done
}

echo "${SCALE_SCENE:-built-in scene}, $frames frames, nice; $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"
for res in ${SCALE_RES:-256x256 512x512 1024x1024 2048x2048}; do run "$res" 8x8x8 visits; done
for cells in ${SCALE_CELLS:-2x2x2 4x4x4 8x8x8 16x16x16}; do run ${SCALE_AT:-1920x1080} "$cells" cells; done
python3 - "$rows" <<'PY'
import csv, math, sys
rows = list(csv.DictReader(open(sys.argv[1])))
def slope(pts):
    lx = [math.log(x) for x, _ in pts]; ly = [math.log(y) for _, y in pts]
    mx, my = sum(lx) / len(lx), sum(ly) / len(ly)
    sxx = sum((a - mx) ** 2 for a in lx)
    return sum((a - mx) * (b - my) for a, b in zip(lx, ly)) / sxx if sxx else 0.0
print("| image | cells | visits | record s (MB) | analyze s (MB) | replay s (MB) | sweep s (MB) |")
print("|---|---|---:|---:|---:|---:|---:|")
points = []
for r in rows:
    if (r["res"], r["cells"]) not in points: points.append((r["res"], r["cells"]))
for res, cells in points:
    rs = {r["command"]: r for r in rows if (r["res"], r["cells"]) == (res, cells)}
    print(f"| {res} | {cells} | {rs['record']['visits']} | " + " | ".join(
        f"{float(rs[c]['seconds']):.1f} ({rs[c]['peak_mb']})" for c in ("record", "analyze", "replay", "sweep")) + " |")
print("\n| command | time on visits | memory on visits | time on cells | memory on cells |")
print("|---|---:|---:|---:|---:|")
cell_count = lambda c: math.prod(int(v) for v in c.split("x"))
for c in ("record", "analyze", "replay", "sweep"):
    out = []
    for series, x in (("visits", lambda r: float(r["visits"])), ("cells", lambda r: cell_count(r["cells"]))):
        sel = [r for r in rows if r["command"] == c and r["series"] == series]
        out += [slope([(x(r), float(r["seconds"])) for r in sel]),
                slope([(x(r), float(r["peak_mb"])) for r in sel])]
    print(f"| {c} | " + " | ".join(f"{v:.2f}" for v in out) + " |")
PY
