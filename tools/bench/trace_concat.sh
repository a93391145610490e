#!/usr/bin/env bash
# `raycell trace concat` against `cat` of the same files: records the built-in scene's orbit
# FRAMES:360 at RES in PARTS consecutive ranges (--frames A..B), then REPS times, alternating,
# joins them with `trace concat` (which checks each frame against the hash of its bytes in the
# index and fsyncs its output), `cat`s them into one file, `cat`s them then fsyncs (coreutils
# `sync FILE`), checks them with `zstd -t` (decompression and content checksums: what
# concat's check cost before the index kept that hash, and still costs for older captures), and
# joins two 1-frame 8x8 captures (what the raycell process costs whatever the input: loading
# its libraries, the header), all reading from the page cache. Prints the median wall time
# and MB/s (input bytes / time) of each, the ratios, and the load; checks the join verifies
# (`trace verify`).
#
# Usage: tools/bench/trace_concat.sh [FRAMES=48] [PARTS=3] [REPS=11] [RES=256x256]
#                                    [RAYCELL=build/tools/raycell]
set -euo pipefail
frames=${1:-48}
parts=${2:-3}
reps=${3:-11}
res=${4:-256x256}
raycell=${5:-build/tools/raycell}
dir=$(mktemp -d /tmp/raycell_concat_bench.XXXXXX)
trap 'rm -rf "$dir"' EXIT

inputs=()
for ((p = 0; p < parts; p++)); do
  a=$((p * frames / parts))
  b=$(((p + 1) * frames / parts - 1))
  "$raycell" record --orbit "$frames:360" --frames "$a..$b" --res "$res" --no-images --quiet \
    --out "$dir/part$p.rct" 2> /dev/null
  inputs+=("$dir/part$p.rct")
done
bytes=$(cat "${inputs[@]}" | wc -c)
for f in 0 1; do
  "$raycell" record --orbit 2:90 --frames "$f..$f" --res 8x8 --no-images --quiet \
    --out "$dir/tiny$f.rct" 2> /dev/null
done

ns() { date +%s%N; }
declare -A times
for ((i = 0; i < reps; i++)); do
  rm -f "$dir/joined.rct" "$dir/cat.rct" "$dir/catsync.rct"
  t0=$(ns)
  "$raycell" trace concat "${inputs[@]}" --out "$dir/joined.rct" 2> /dev/null
  t1=$(ns)
  cat "${inputs[@]}" > "$dir/cat.rct"
  t2=$(ns)
  cat "${inputs[@]}" > "$dir/catsync.rct" && sync "$dir/catsync.rct"
  t3=$(ns)
  zstd -qt "${inputs[@]}"
  t4=$(ns)
  "$raycell" trace concat "$dir/tiny0.rct" "$dir/tiny1.rct" --out "$dir/tiny.rct" 2> /dev/null
  t5=$(ns)
  times[concat]+="$((t1 - t0)) "
  times[cat]+="$((t2 - t1)) "
  times[catsync]+="$((t3 - t2)) "
  times[zstd_t]+="$((t4 - t3)) "
  times[tiny]+="$((t5 - t4)) "
done
"$raycell" trace verify "$dir/joined.rct" > /dev/null

median() { printf '%s\n' $1 | sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }
echo "inputs: $parts parts of the orbit $frames:360 at $res, $bytes bytes; $reps runs each"
for what in concat cat catsync zstd_t; do
  m=$(median "${times[$what]}")
  printf '%-8s median %8.2f ms  %8.0f MB/s\n' "$what" "$(echo "$m / 1000000" | bc -l)" \
    "$(echo "$bytes * 1000 / $m" | bc -l)"
done
printf '%-8s median %8.2f ms  (two 1-frame 8x8 captures)\n' tiny \
  "$(echo "$(median "${times[tiny]}") / 1000000" | bc -l)"
c=$(median "${times[concat]}")
fixed=$(median "${times[tiny]}")
printf 'concat time / cat: %.2f; / cat+fsync: %.2f; / zstd -t: %.2f; load %s\n' \
  "$(echo "$c / $(median "${times[cat]}")" | bc -l)" \
  "$(echo "$c / $(median "${times[catsync]}")" | bc -l)" \
  "$(echo "$c / $(median "${times[zstd_t]}")" | bc -l)" "$(cut -d' ' -f1-3 /proc/loadavg)"
printf 'concat less the 2-frame join (per-byte cost): %.2f ms, %.0f MB/s\n' \
  "$(echo "($c - $fixed) / 1000000" | bc -l)" "$(echo "$bytes * 1000 / ($c - $fixed)" | bc -l)"
