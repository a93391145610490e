#!/usr/bin/env bash
# How far today's schedulers can go at several processors on the suite (issue 42): every
# scheduler but random and celltree-2level-best (the oracles best and peel included) replayed
# on each capture of a `raycell suite` run at P processors, fetches over every frame and
# simulated time over the frames after the first, then per scene the scheduler chosen with
# hindsight: the fewest fetches among those with neither more fetches nor more time than Max
# Work. Prints each scheduler's geometric means against Max Work and the hindsight choice's.
#
# Usage: tools/bench/suite_hindsight.sh [SUITE_OUT] [PROCESSORS]   (default out/suite 8)
# SUITE_OUT is a folder `raycell suite --out` wrote (its captures/ are read, never changed).
# SCHEDULERS=a,b,... replaces the list (Max Work first).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
raycell=${RAYCELL:-$root/build/tools/raycell}
suite=${1:-out/suite}
procs=${2:-8}
[ -x "$raycell" ] || { echo "needs $raycell: run tools/setup.sh" >&2; exit 2; }
[ -d "$suite/captures" ] || { echo "no $suite/captures: run raycell suite --out $suite" >&2; exit 2; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
schedulers=maxwork,roundrobin,peel,celltree,best,celltree-best,celltree-union,affinity,partition
schedulers+=,steal,partition-steal,share,balanced,celltree-2level,balanced-critical
schedulers+=,balanced-adaptive,celltree-adaptive,auto
schedulers=${SCHEDULERS:-$schedulers}
for f in "$suite"/captures/*.rct; do
  name=$(basename "$f" .rct)
  cells=()
  case $f in *.fine.rct) name=${name%.fine}; cells=(--cells 3x3x3) ;; esac
  # The capture's frames A..B, from "cameras: N (frames A..B)".
  range=$("$raycell" trace info "$f" --no-character | sed -n 's/^cameras:.*(frames \(.*\))$/\1/p')
  first=${range%..*} last=${range#*..}
  for part in "all:$range" "after:$((first + 1))..$last"; do
    nice "$raycell" sweep "$f" "${cells[@]}" --vary scheduler=$schedulers \
      --vary processors.count="$procs" --jobs 1 --frames "${part#*:}" --quiet \
      --out "$work/${name}_${part%%:*}.csv"
  done
  echo "done: $name" >&2
done
python3 - "$work" <<'PY'
import csv, glob, math, os, sys
work = sys.argv[1]
def rows(path):
    return {r["scheduler"]: r for r in csv.DictReader(l for l in open(path) if not l.startswith("#"))}
scenes = sorted(os.path.basename(p)[:-len("_all.csv")] for p in glob.glob(f"{work}/*_all.csv"))
fetches, time = {}, {}
for s in scenes:
    fetches[s] = {k: int(r["fetches"]) for k, r in rows(f"{work}/{s}_all.csv").items()}
    time[s] = {k: int(r["time_ps"]) for k, r in rows(f"{work}/{s}_after.csv").items()}
names = list(fetches[scenes[0]])
gm = lambda xs: math.exp(sum(math.log(x) for x in xs) / len(xs)) - 1
print("| scheduler | fetches | time after frame 0 |\n|---|---:|---:|")
for k in names:
    f = gm([fetches[s][k] / fetches[s]["maxwork"] for s in scenes])
    t = gm([time[s][k] / time[s]["maxwork"] for s in scenes])
    print(f"| {k} | {f:+.1%} | {t:+.1%} |")
pick = {}
for s in scenes:
    ok = [k for k in names if fetches[s][k] <= fetches[s]["maxwork"] and time[s][k] <= time[s]["maxwork"]]
    pick[s] = min(ok, key=lambda k: (fetches[s][k], time[s][k]))
f = gm([fetches[s][pick[s]] / fetches[s]["maxwork"] for s in scenes])
t = gm([time[s][pick[s]] / time[s]["maxwork"] for s in scenes])
print(f"| **hindsight, per scene** | **{f:+.1%}** | **{t:+.1%}** |")
print("\n" + ", ".join(f"{s}: {pick[s]}" for s in scenes))
PY
