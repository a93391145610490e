#!/usr/bin/env bash
# kill -9 at random moments of a capture: RUNS times, starts `raycell record` of a few frames,
# kills it with SIGKILL after a random delay (0 to 1.2 times a whole capture's time), and
# checks what it left:
#   - OUT.tmp does not exist, or it opens (its header is complete) and every complete frame
#     in it verifies (`trace verify` reports no damaged frame; it exits 2 for the missing
#     index) and equals the same frame of an uninterrupted capture (`trace cat`);
#   - OUT, if it exists, is complete (`trace verify` exits 0) and equals the uninterrupted
#     capture byte for byte.
# Prints one line per run and a tally; exits 1 if any check failed.
#
# Usage: tools/bench/kill_capture.sh [RUNS=50] [RAYCELL=build/tools/raycell] [SEED=1]
set -euo pipefail
runs=${1:-50}
raycell=${2:-build/tools/raycell}
RANDOM=${3:-1}
dir=$(mktemp -d /tmp/raycell_kill.XXXXXX)
trap 'rm -rf "$dir"' EXIT
record=(record --res 40x40 --orbit 6:60 --no-images --quiet --threads 2)

ms() { date +%s%3N; }
t0=$(ms)
"$raycell" "${record[@]}" --out "$dir/full.rct" 2> /dev/null
full_ms=$(($(ms) - t0))
frames=$("$raycell" trace info "$dir/full.rct" | awk '/^frames:/ {print $2}')
for ((f = 0; f < frames; f++)); do
  "$raycell" trace cat "$dir/full.rct" --frame "$f" | md5sum > "$dir/full_$f.md5"
done
echo "uninterrupted capture: $frames frames in $full_ms ms"

failures=0 nothing=0 complete=0
declare -A kept=()
for ((run = 1; run <= runs; run++)); do
  rm -f "$dir/out.rct" "$dir/out.rct.tmp"
  delay_ms=$((RANDOM * 32768 + RANDOM))
  delay_ms=$((delay_ms % (full_ms * 12 / 10 + 1)))
  "$raycell" "${record[@]}" --out "$dir/out.rct" 2> /dev/null &
  pid=$!
  sleep "$(printf '%d.%03d' $((delay_ms / 1000)) $((delay_ms % 1000)))"
  kill -9 "$pid" 2>/dev/null || true
  wait "$pid" 2>/dev/null || true
  outcome="" problem=""
  if [ -e "$dir/out.rct" ]; then
    if "$raycell" trace verify "$dir/out.rct" > /dev/null 2>&1 &&
       cmp -s "$dir/out.rct" "$dir/full.rct"; then
      outcome="complete"; complete=$((complete + 1))
    else
      problem="out.rct exists but is incomplete or differs"
    fi
    [ -e "$dir/out.rct.tmp" ] && problem="$problem; out.rct.tmp left beside out.rct"
  elif [ -e "$dir/out.rct.tmp" ]; then
    code=0
    "$raycell" trace verify "$dir/out.rct.tmp" > "$dir/verify.out" 2> "$dir/verify.err" || code=$?
    ok=$(grep -c ': ok,' "$dir/verify.out" || true)
    if grep -q 'DAMAGED' "$dir/verify.out"; then
      problem="a complete frame does not verify: $(cat "$dir/verify.err")"
    elif [ "$code" -ne 0 ] && [ "$code" -ne 2 ]; then
      problem="trace verify exited $code: $(cat "$dir/verify.err")"
    elif grep -q ': header: \|cannot open' "$dir/verify.err"; then
      problem="out.rct.tmp does not open: $(cat "$dir/verify.err")"
    else
      for ((f = 0; f < ok; f++)); do
        if ! "$raycell" trace cat "$dir/out.rct.tmp" --frame "$f" 2> /dev/null | md5sum |
            cmp -s - "$dir/full_$f.md5"; then
          problem="frame $f of out.rct.tmp differs from the uninterrupted capture's"
        fi
      done
      outcome="tmp with $ok complete frame(s)"
      kept[$ok]=$((${kept[$ok]:-0} + 1))
    fi
  else
    outcome="no file yet"; nothing=$((nothing + 1))
  fi
  if [ -n "$problem" ]; then
    failures=$((failures + 1))
    echo "run $run: killed after $delay_ms ms: FAILED: $problem"
  else
    echo "run $run: killed after $delay_ms ms: $outcome"
  fi
done

echo "runs: $runs; no file yet: $nothing; complete OUT: $complete; OUT.tmp by complete frames:" \
  "$(for k in $(printf '%s\n' "${!kept[@]}" | sort -n); do printf '%s:%s ' "$k" "${kept[$k]}"; done)"
echo "failures: $failures"
[ "$failures" -eq 0 ]
