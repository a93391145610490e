#!/usr/bin/env bash
# Old against new on a shared, loaded machine: runs two raycell binaries on the same
# arguments, alternating, REPS times each, and prints the median CPU time (user + system,
# from /usr/bin/time) and wall time of each, and their ratio. CPU time counts only the time
# the process ran, which the other processes of a loaded machine disturb far less than wall
# time. Outputs go to a scratch folder; the last output of each is compared byte for byte.
# Arguments equal to @OUT are replaced by a per-run output path (for --out).
#
# Usage: tools/bench/cpu_ab.sh OLD_RAYCELL NEW_RAYCELL REPS ARGS...
# e.g.   tools/bench/cpu_ab.sh build-base/build/tools/raycell build/tools/raycell 3 \
#            replay capture.rct --granularity ray --format csv --quiet
set -euo pipefail
old=${1:?usage: cpu_ab.sh OLD NEW REPS ARGS...}
new=${2:?}
reps=${3:?}
shift 3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
declare -A cpu wall
for ((i = 0; i < reps; i++)); do
  for side in old new; do
    bin=$old; [ "$side" = new ] && bin=$new
    out=$work/$side.out
    rm -f "$out" "$out.partial" "$out.checkpoint"
    args=()
    for a in "$@"; do args+=("${a//@OUT/$out}"); done
    /usr/bin/time -f '%U %S %e' -o "$work/time" "$bin" "${args[@]}" > "$work/$side.stdout"
    read -r u s e < "$work/time"
    cpu[$side]+="$(echo "$u + $s" | bc -l) "
    wall[$side]+="$e "
  done
done
median() { printf '%s\n' $1 | sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }
for side in old new; do
  printf '%-4s CPU %8.2f s  wall %8.2f s  (runs: CPU %s)\n' "$side" "$(median "${cpu[$side]}")" \
    "$(median "${wall[$side]}")" "${cpu[$side]}"
done
printf 'old / new CPU: %.2f; load %s\n' \
  "$(echo "$(median "${cpu[old]}") / $(median "${cpu[new]}")" | bc -l)" "$(cut -d' ' -f1-3 /proc/loadavg)"
same=yes
cmp -s "$work/old.stdout" "$work/new.stdout" || same=no
if [ -f "$work/old.out" ] || [ -f "$work/new.out" ]; then
  cmp -s "$work/old.out" "$work/new.out" || same=no
fi
echo "outputs byte-identical: $same"
