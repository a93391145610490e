#!/usr/bin/env bash
# `--scheduler auto` on a development set of scenes (issue 42; docs/design.md §5 "The
# recommended scheduler"): records each scene (128x128, an 8-frame orbit of 60 degrees, 3x3x3
# cells) unless its capture exists, replays maxwork, celltree, best, balanced,
# balanced-critical, celltree-adaptive and auto at 1 and 8 processors (one sweep per scene,
# --jobs 1), and prints per scene and as geometric mean / worst scene:
#  - 8 processors: fetches (every frame) and simulated time (frames 1.., and the whole capture)
#    of each scheduler against Max Work;
#  - 1 processor: fetches of each online scheduler over the `best` oracle's.
# The scenes: the built-in one, ../shared/data/mj_smoke.vdb and mj_sphere.vdb when present, and
# four made with OpenVDB's vdb_tool as stand-ins for scenes raycell was not tuned on: mirror and
# glass level sets, a dense fog, a perforated CSG solid, sparse fog clouds.
#
# Usage: tools/bench/auto_scheduler.sh [DIR]   (DIR default /tmp/auto-dev: the vdb files, the
#        captures and the sweeps' CSVs; delete a capture to record it again)
# Env:   RAYCELL (default build/tools/raycell), RES (128x128), ORBIT (8:60), CELLS (3x3x3),
#        SCHEDULERS (the list above), SCENES (a subset of the names below), REUSE=1 (keep the
#        sweeps' CSVs of an earlier run with the same schedulers instead of replaying again)
# Takes about 1-2 minutes on a loaded 2-core machine once recorded (recording: under a minute).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
raycell=${RAYCELL:-$root/build/tools/raycell}
dir=${1:-/tmp/auto-dev}
res=${RES:-128x128}
orbit=${ORBIT:-8:60}
cells=${CELLS:-3x3x3}
schedulers=${SCHEDULERS:-maxwork,celltree,best,balanced,balanced-critical,celltree-adaptive,auto}
data=$root/../shared/data
mkdir -p "$dir"
cd "$dir"

# The stand-ins, made once.
[ -f mirror_glass.vdb ] || vdb_tool -sphere dim=128 radius=0.5 center="(-0.6,0,0)" name=mirror \
  -sphere dim=128 radius=0.45 center="(0.6,0.1,0)" name=glass \
  -platonic faces=6 dim=128 scale=0.5 center="(0,-0.2,0.7)" name=block -write mirror_glass.vdb >/dev/null
[ -f dense_fog.vdb ] || vdb_tool -sphere dim=160 radius=1.0 name=fog -ls2fog name=fog \
  -write dense_fog.vdb >/dev/null
[ -f perforated.vdb ] || vdb_tool -platonic faces=6 dim=160 scale=1.6 name=solid \
  -sphere dim=160 radius=0.35 center="(0.4,0.4,0.4)" -difference \
  -sphere dim=160 radius=0.35 center="(-0.4,-0.4,0.4)" -difference \
  -sphere dim=160 radius=0.35 center="(0.4,-0.4,-0.4)" -difference \
  -sphere dim=160 radius=0.35 center="(-0.4,0.4,-0.4)" -difference \
  -sphere dim=160 radius=0.3 center="(0,0,0)" -difference -write perforated.vdb >/dev/null
[ -f clouds.vdb ] || vdb_tool -sphere dim=128 radius=0.3 center="(-0.7,0.2,0)" \
  -sphere dim=128 radius=0.25 center="(0.6,-0.3,0.4)" -union \
  -sphere dim=128 radius=0.2 center="(0.1,0.6,-0.5)" -union \
  -sphere dim=128 radius=0.3 center="(0.2,-0.5,-0.6)" -union -ls2fog name=cloud \
  -write clouds.vdb >/dev/null

declare -A args=(
  [builtin]=""
  [mj_smoke]="--scene $data/mj_smoke.vdb"
  [mj_sphere]="--scene $data/mj_sphere.vdb"
  [mirror_glass]="--scene mirror_glass.vdb --all-grids --material mirror:reflect=0.9 --material glass:transparency=0.9:ior=1.5 --material block:reflect=0.5"
  [dense_fog]="--scene dense_fog.vdb"
  [perforated]="--scene perforated.vdb --material difference_sphere:reflect=0.5"
  [clouds]="--scene clouds.vdb"
)
scenes=${SCENES:-builtin mj_smoke mj_sphere mirror_glass dense_fog perforated clouds}
for s in $scenes; do
  case $s in mj_*) [ -f "$data/$s.vdb" ] || { echo "skipping $s: no $data/$s.vdb" >&2; continue; } ;; esac
  if [ ! -f "$s.rct" ]; then
    # shellcheck disable=SC2086
    nice "$raycell" record ${args[$s]} --res "$res" --cells "$cells" --orbit "$orbit" \
      --no-images --quiet --threads 1 --out "$s.rct"
  fi
done

# One sweep per scene and frame range: frame 0 (the cold load) and frames 1..N-1 (their replay
# first replays frame 0 to warm the memory, unreported), so the two rows of a combination add
# up to the whole capture.
last=$(( ${orbit%%:*} - 1 ))
done_scenes=()
for s in $scenes; do
  [ -f "$s.rct" ] || continue
  for range in 0..0 1..$last; do
    out="$s.$range.csv"
    [ -n "${REUSE:-}" ] && [ -f "$out" ] && head -1 "$out" | grep -q "scheduler=$schedulers\"" && continue
    rm -f "$out"
    nice "$raycell" sweep "$s.rct" --vary "scheduler=$schedulers" --vary processors.count=1,8 \
      --frames "$range" --jobs 1 --quiet --out "$out"
  done
  done_scenes+=("$s")
done

python3 - "$last" "$schedulers" "${done_scenes[@]}" <<'PY'
import csv, math, sys
last, schedulers, scenes = sys.argv[1], sys.argv[2].split(","), sys.argv[3:]

def rows(path):
    with open(path) as f:
        lines = [l for l in f if not l.startswith("#")]
    return {(r["scheduler"], int(r["processors.count"])): r for r in csv.DictReader(lines)}

def gmean(xs):
    return math.exp(sum(math.log(x) for x in xs) / len(xs))

def pct(x):
    return f"{(x - 1) * 100:+.1f}%"

# per scheduler: lists of ratios over the scenes
f8, t8, w8, o1 = ({s: [] for s in schedulers} for _ in range(4))
print(f"8 processors: fetches (every frame) / time frames 1..{last} / whole time, against Max Work;")
print("1 processor: fetches over the best oracle's (online / oracle)\n")
print("| scene | scheduler | 8P fetches | 8P time 1.. | 8P time whole | 1P online/oracle |")
print("|---|---|---:|---:|---:|---:|")
for scene in scenes:
    a, b = rows(f"{scene}.0..0.csv"), rows(f"{scene}.1..{last}.csv")
    tot = lambda s, p, k: float(a[(s, p)][k]) + float(b[(s, p)][k])
    for s in schedulers:
        rf = tot(s, 8, "fetches") / tot("maxwork", 8, "fetches")
        rt = float(b[(s, 8)]["time_ps"]) / float(b[("maxwork", 8)]["time_ps"])
        rw = tot(s, 8, "time_ps") / tot("maxwork", 8, "time_ps")
        ro = tot(s, 1, "fetches") / tot("best", 1, "fetches")
        f8[s].append(rf), t8[s].append(rt), w8[s].append(rw), o1[s].append(ro)
        mw = f" ({int(tot(s, 8, 'fetches'))}, {float(b[(s, 8)]['time_ps']) / 1e9:.2f} ms)" if s == "maxwork" else ""
        print(f"| {scene} | {s} | {pct(rf)}{mw} | {pct(rt)} | {pct(rw)} | {ro:.3f} |")
print(f"\nOver {len(scenes)} scenes: geometric mean (worst scene)\n")
print("| scheduler | 8P fetches | 8P time 1.. | 8P time whole | 1P online/oracle | 1P against celltree, worst |")
print("|---|---:|---:|---:|---:|---:|")
for s in schedulers:
    vs_ct = max(x / y for x, y in zip(o1[s], o1["celltree"]))
    print(f"| {s} | {pct(gmean(f8[s]))} ({pct(max(f8[s]))}) | {pct(gmean(t8[s]))} ({pct(max(t8[s]))}) "
          f"| {pct(gmean(w8[s]))} ({pct(max(w8[s]))}) | {gmean(o1[s]):.3f} ({max(o1[s]):.3f}) | {pct(vs_ct)} |")
PY
