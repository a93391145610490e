#!/usr/bin/env bash
# Runs one fuzz target of a RAYCELL_FUZZ build over a scratch copy of its seed corpus, with
# the sanitizer options CI uses; keeps whatever it finds (crash, leak, timeout, out of
# memory) and exits non-zero then.
#
# Usage: fuzz/run.sh NAME [libFuzzer options...]     (build folder: $RAYCELL_FUZZ_BUILD or
#                                                     build-asan)
#   fuzz/run.sh trace_reader -max_total_time=60      # as CI does
#   nice fuzz/run.sh trace_reader -runs=10000000     # a campaign (BENCHMARKS.md)
# A finding is saved as $WORK/crash-* (or leak-*, timeout-*, oom-*): reproduce it with
# `BUILD/fuzz/fuzz_NAME FILE`, fix it, and add the file to fuzz/corpus/NAME/.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
name=$1
shift
build=${RAYCELL_FUZZ_BUILD:-$root/build-asan}
work=$(mktemp -d "/tmp/raycell_fuzz_${name}.XXXXXX")
mkdir -p "$work/corpus"
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1}
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1:suppressions=$root/.ci/ubsan.supp
status=0
"$build/fuzz/fuzz_$name" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
  -artifact_prefix="$work/" "$@" "$work/corpus" "$root/fuzz/corpus/$name" \
  > "$work/log.txt" 2>&1 || status=$?
grep -E '^stat::(number_of_executed_units|average_exec_per_sec|new_units_added|peak_rss_mb)' \
  "$work/log.txt" | sed "s/^/fuzz_$name: /"
if [ "$status" -ne 0 ] || ls "$work" | grep -qE '^(crash|leak|timeout|oom|slow-unit)-'; then
  tail -60 "$work/log.txt"
  echo "fuzz_$name: FOUND a problem (exit $status); inputs and log kept in $work"
  exit 1
fi
rm -rf "$work"
