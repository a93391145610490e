#!/usr/bin/env bash
# First result: the README's first command (`tools/setup.sh && build/tools/raycell study`) on a
# fresh clone of this repository, timed step by step (packages, configure and build, study),
# then a check that the study left `git status --porcelain` empty. For BENCHMARKS.md "First
# result and build time". Run it on an otherwise idle machine; it needs root or sudo when
# packages are missing (a bare machine: the install step is then part of the time).
#
# Usage: tools/bench/first_result.sh [WORK_DIR]
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
work=${1:-$(mktemp -d)}
start=$SECONDS
git clone -q "$root" "$work/raycell"
cd "$work/raycell"
echo "first_result: clone took $((SECONDS - start)) s"
t=$SECONDS
tools/setup.sh
echo "first_result: tools/setup.sh took $((SECONDS - t)) s"
t=$SECONDS
build/tools/raycell study
echo "first_result: raycell study took $((SECONDS - t)) s"
echo "first_result: total $((SECONDS - start)) s"
status=$(git status --porcelain)
if [ -n "$status" ]; then
  echo "first_result: git status is not clean after the study:" >&2
  echo "$status" >&2
  exit 1
fi
echo "first_result: git status --porcelain is empty"
