#!/usr/bin/env bash
# GLPK is linked only where the lower bounds are (bounds/ and what stands on it): the link
# lines of programs that use graph/, search/, scheduling/, replay/ or runner/ alone name no
# GLPK, and that of a bounds/ test does (so that this test sees link lines at all). Reads the
# Makefile generator's link.txt files, or Ninja's commands (`ninja -t commands`); skipped
# (exit 77) under another generator.
# Usage: tests/tools/glpk_link_test.sh BUILD_DIR
set -euo pipefail
build=${1:?usage: glpk_link_test.sh BUILD_DIR}
if [ -f "$build/tests/bounds/CMakeFiles/lower_bound_test.dir/link.txt" ]; then
  line() { cat "$build/tests/$1/CMakeFiles/$2.dir/link.txt"; }
elif [ -f "$build/build.ninja" ] && command -v ninja > /dev/null; then
  line() { ninja -C "$build" -t commands "tests/$1/$2" | tail -n 1; }  # the last: its link
else
  echo "glpk_link_test: neither link.txt nor build.ninja (another generator): skipped"
  exit 77
fi
fail=0
line bounds lower_bound_test | grep -q glpk || { echo "FAIL: lower_bound_test links no GLPK"; fail=1; }
for t in graph/cell_tree_test search/best_schedule_test scheduling/schedulers_test \
  replay/replay_core_test runner/runner_sweep_test; do
  if line "${t%/*}" "${t#*/}" | grep -q glpk; then
    echo "FAIL: ${t#*/} links GLPK: $(line "${t%/*}" "${t#*/}" | grep -o '[^ ]*glpk[^ ]*')"
    fail=1
  fi
done
[ $fail -eq 0 ] && echo "glpk_link_test: GLPK only below bounds/"
exit $fail
