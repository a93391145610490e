#!/usr/bin/env bash
# Runs every command of the README's tour with a given raycell binary in a fresh folder and
# keeps what each printed (cmdNN.out) beside the files it wrote, so that two builds can be
# compared byte for byte (e.g. before and after a refactoring that must change no output):
#
#   tools/bench/tour_outputs.sh OLD_RAYCELL old/ && tools/bench/tour_outputs.sh build/tools/raycell new/
#   diff -r old new      # only run times (and the files that hold them) may differ
#
# The commands are read from README.md's tour, continuation lines joined, in order, except
# that `study --trace` runs last (it studies the capture a later line records). Needs
# ../shared/data for the real volumes (a symlink to it is made in the folder).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
raycell=$(realpath "${1:?usage: tour_outputs.sh RAYCELL OUTDIR}")
out=${2:?usage: tour_outputs.sh RAYCELL OUTDIR}
mkdir -p "$out/work"
out=$(realpath "$out")
ln -sfn "$(realpath "$root/../shared")" "$out/shared"   # so ../shared/data resolves from work/

# The tour: the first ```sh block after "## A tour of the commands".
mapfile -t commands < <(awk '/^## A tour of the commands/ {t=1} t && /^```sh/ {b=1; next}
  b && /^```/ {exit} b {print}' "$root/README.md" |
  sed -e ':a' -e '/\\$/N; s/\\\n[[:space:]]*/ /; ta' | sed -e 's/[[:space:]]*#[^'"'"']*$//')
last=()
cd "$out/work"
n=0
run() {
  n=$((n + 1))
  local cmd=${1//raycell /$raycell }
  echo "[$n] $1" >&2
  printf '%s\n' "$1" >"$(printf '../cmd%02d.cmd' $n)"
  # --quiet where the command takes it would change nothing printed to a pipe; run as given.
  bash -c "$cmd" >"$(printf '../cmd%02d.out' $n)" 2>&1 || echo "exit $?" >>"$(printf '../cmd%02d.out' $n)"
}
for c in "${commands[@]}"; do
  [ -z "$c" ] && continue
  if [[ $c == *"study --trace"* ]]; then last+=("$c"); continue; fi
  run "$c"
done
for c in "${last[@]}"; do run "$c"; done
