#!/usr/bin/env bash
# Capture time of `raycell record` against OpenVDB's `vdb_render` on the same volume, camera,
# image size, step sizes, light, cutoff and thread count, measured alternately in one run
# (the machines are shared: only the ratio taken in the same run means something).
# Also prints the trace's bytes per visit, the read speed of `raycell trace verify`, and
# how far raycell's image is from vdb_render's (linear RMSE, largest channel difference and
# mean radiance ratio, tools/bench/png_diff.py; a raycell without --image-encoding writes
# sRGB PNGs, which png_diff.py decodes by their sRGB chunk).
#
# Usage: tools/bench/capture_vs_vdb_render.sh [VDB] [THREADS] [REPS]
# Default: ../shared/data/mj_smoke.vdb, 2 threads, 5 repetitions each.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
raycell=${RAYCELL:-$root/build/tools/raycell}
vdb=${1:-$root/../shared/data/mj_smoke.vdb}
threads=${2:-2}
reps=${3:-5}
command -v vdb_render >/dev/null || { echo "needs vdb_render (Debian package libopenvdb-tools)" >&2; exit 2; }
[ -x "$raycell" ] || { echo "needs $raycell: run tools/setup.sh" >&2; exit 2; }
[ -f "$vdb" ] || { echo "no $vdb" >&2; exit 2; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# raycell's own framing of the scene, so that both render the same view.
"$raycell" record --scene "$vdb" --out "$work/probe.rct" --no-images --quiet --res 8x8 2>/dev/null
read -r eye target fov < <("$raycell" trace info "$work/probe.rct" --cameras | awk '/^camera / {print $4, $6, $8; exit}')

common_vr=(-res 256x256 -step 1 -shadowstep 3 -cutoff 0.005 -light 0.3,0.3,0,0.7,0.7,0.7
           -absorb 0.1,0.1,0.1 -scatter 1.5,1.5,1.5 -gain 0.2 -fov "$fov" -translate "$eye"
           -lookat "$target" -cpus "$threads")
common_rc=(--scene "$vdb" --res 256x256 --step 1 --shadow-step 3 --cutoff 0.005
           --light dir:0.3,0.3,0:0.7,0.7,0.7 --fov "$fov" --eye "$eye" --target "$target"
           --threads "$threads" --quiet)
if "$raycell" record --help | grep -q -- --image-encoding; then
  common_rc+=(--image-encoding linear)
fi

now() { date +%s.%N; }
t_vr=(); t_rc=()
for ((i = 0; i < reps; i++)); do
  a=$(now); vdb_render "$vdb" "$work/vr.png" "${common_vr[@]}" >/dev/null 2>&1; b=$(now)
  t_vr+=("$(echo "$b - $a" | bc -l)")
  a=$(now); "$raycell" record "${common_rc[@]}" --out "$work/rc.rct" --images "$work/img" 2>/dev/null; b=$(now)
  t_rc+=("$(echo "$b - $a" | bc -l)")
done
median() { printf '%s\n' "$@" | sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }
m_vr=$(median "${t_vr[@]}"); m_rc=$(median "${t_rc[@]}")
echo "volume: $vdb, 256x256, step 1/3, $threads thread(s), $reps runs each, median wall time"
printf 'vdb_render:      %.3f s\n' "$m_vr"
printf 'raycell record:  %.3f s (renders, records every ray, writes trace and PNG)\n' "$m_rc"
printf 'ratio raycell/vdb_render: %.2f\n' "$(echo "$m_rc / $m_vr" | bc -l)"
"$raycell" trace info "$work/rc.rct" | grep -E "^ +total|^ +frame"
"$raycell" trace verify "$work/rc.rct" | tail -1
printf 'image against vdb_render (linear, 0..1): '
python3 "$root/tools/bench/png_diff.py" "$work/img/frame_0000.png" "$work/vr.png"
