#!/usr/bin/env bash
# A recording and an analysis run on a real Slurm cluster as job arrays of frame ranges, through
# tools/slurm/submit_record.sh and submit_analyze.sh, and a suite run one scene per task
# (submit_suite.sh), give the same bytes as `raycell record`, `raycell analyze` and `raycell
# suite` on one machine.
#
#   tests/cluster/slurm_frames_test.sh RAYCELL SOURCE_DIR      (ctest -R slurm_frames)
#
# On a private single-node cluster (tests/cluster/cluster.sh), with the built-in scene at
# 32x32, 2x2x2 cells, an 8-frame orbit:
#  1. a 4-task recording: OUTDIR/capture.rct equals the one-shot recording;
#  2. a 4-task `analyze --bracket --effort quick --format csv` of that capture: analysis.csv
#     equals the one-shot analysis; the wall times of both arrays and both one-shot runs are
#     printed (BENCHMARKS.md "Frame ranges on Slurm");
#  3. the same analysis in json with task 2 unable to write its part (its .tmp is a folder):
#     tasks 0, 1, 3 succeed, 2 fails, the merge job is cancelled and no analysis.json appears;
#     the same command again runs task 2 alone, then the merge, and analysis.json equals the
#     one-shot run;
#  4. the same OUTDIR with other arguments, an OUTDIR holding another kind of job, and invalid
#     analyze or record arguments are refused before anything is queued;
#  5. `raycell suite` of two scene files, one per task (tools/slurm/submit_suite.sh), then the
#     report job: report.md, suite.csv and the scenes' files equal a one-shot suite's.
# Every wait is bounded; every process of the cluster is stopped on exit. Needs root,
# slurm-wlm and munge (exit 77 without them, unless RAYCELL_REQUIRE_SLURM=1).
set -euo pipefail

(($# == 2)) || { echo "usage: $0 RAYCELL SOURCE_DIR" >&2; exit 2; }
raycell=$(realpath "$1") src=$(realpath "$2")
# shellcheck source=tests/cluster/cluster.sh
source "$src/tests/cluster/cluster.sh"

cd "$tmp"
now() { date +%s.%N; }
seconds() { printf '%.2f' "$(echo "$2 - $1" | bc)"; }
# run_array SUBMIT_SCRIPT ARGS...: submits, waits for the array and its join job, and sets
# `array`, `join` and `took` (seconds from submission to the end of the join).
run_array() {
  local t0 script=$1
  shift
  t0=$(now)
  read -r array join < <(env "$marker" "$src/tools/slurm/$script" --raycell "$raycell" \
    --parsable "$@")
  wait_until "jobs $array and $join" jobs_done "$array,$join"
  took=$(seconds "$t0" "$(now)")
}

record=(--res 32x32 --cells 2x2x2 --orbit 8:90 --no-images)
t0=$(now)
"$raycell" record "${record[@]}" --quiet --out oneshot.rct >/dev/null 2>&1 || fail "raycell record failed"
record_oneshot=$(seconds "$t0" "$(now)")

# ---- 1. the recording
run_array submit_record.sh -n 4 rec -- "${record[@]}"
got=$(state "$array")
[[ $got == "0=COMPLETED 1=COMPLETED 2=COMPLETED 3=COMPLETED" ]] || fail "record array tasks: got '$got'"
[[ $(state "$join") == "-=COMPLETED" ]] || fail "record join job: got '$(state "$join")'"
cmp oneshot.rct rec/capture.rct || fail "rec/capture.rct (4 tasks on Slurm) differs from the one-shot recording"
echo "$(elapsed): record, 8 frames: 4 tasks and the join ${took} s wall; one-shot ${record_oneshot} s"
trace=rec/capture.rct

# ---- 2. the analysis
analyze=(--bracket --effort quick)
t0=$(now)
"$raycell" analyze "$trace" --quiet "${analyze[@]}" --format csv >oneshot.csv || fail "raycell analyze failed"
analyze_oneshot=$(seconds "$t0" "$(now)")
[[ $(wc -l <oneshot.csv) == 9 ]] || fail "oneshot.csv should have a header and 8 rows"
run_array submit_analyze.sh -n 4 "$trace" ana -- "${analyze[@]}" --format csv
got=$(state "$array")
[[ $got == "0=COMPLETED 1=COMPLETED 2=COMPLETED 3=COMPLETED" ]] || fail "analyze array tasks: got '$got'"
[[ $(state "$join") == "-=COMPLETED" ]] || fail "analyze merge job: got '$(state "$join")'"
cmp oneshot.csv ana/analysis.csv || fail "ana/analysis.csv (4 tasks on Slurm) differs from the one-shot analysis"
echo "$(elapsed): analyze --bracket --effort quick, 8 frames: 4 tasks and the merge ${took} s wall; one-shot ${analyze_oneshot} s"

# ---- 3. a failed task reruns alone
"$raycell" analyze "$trace" --quiet "${analyze[@]}" --format json >oneshot.json
mkdir -p json/parts/part_2.part.tmp/blocker  # not empty: the failed write cannot remove it
run_array submit_analyze.sh -n 4 "$trace" json -- "${analyze[@]}" --format json
got=$(state "$array")
[[ $got == "0=COMPLETED 1=COMPLETED 2=FAILED 3=COMPLETED" ]] ||
  fail "round 1: expected tasks 0, 1, 3 COMPLETED and 2 FAILED, got '$got'"
[[ $(state "$join") == "-=CANCELLED" ]] || fail "round 1: the merge job should be cancelled, got '$(state "$join")'"
[[ ! -e json/analysis.json ]] || fail "round 1 wrote json/analysis.json from 3 of 4 parts"
rm -r json/parts/part_2.part.tmp
run_array submit_analyze.sh -n 4 "$trace" json -- "${analyze[@]}" --format json
[[ $(state "$array") == "2=COMPLETED" ]] || fail "round 2 should run task 2 alone, got '$(state "$array")'"
[[ $(state "$join") == "-=COMPLETED" ]] || fail "round 2 merge job: got '$(state "$join")'"
cmp oneshot.json json/analysis.json || fail "json/analysis.json differs from the one-shot analysis"
echo "$(elapsed): a failed analyze task reran alone; merged byte-identical"

# ---- 4. refusals
submit=(env "$marker" "$src/tools/slurm/submit_analyze.sh" --raycell "$raycell" --parsable)
if msg=$("${submit[@]}" -n 4 "$trace" json -- --format json 2>&1); then
  fail "another analysis into json/ was accepted"
fi
grep -q "holds another analyze" <<<"$msg" || fail "unexpected refusal message: $msg"
mkdir -p sweepdir && echo "cwd=/" >sweepdir/sweep.args
if msg=$("${submit[@]}" -n 4 "$trace" sweepdir -- --format json 2>&1); then
  fail "an analysis into a sweep's OUTDIR was accepted"
fi
grep -q "holds a sweep job" <<<"$msg" || fail "unexpected refusal message: $msg"
if msg=$("${submit[@]}" -n 4 "$trace" bad -- --effort fast 2>&1); then
  fail "an invalid analysis was submitted"
fi
grep -q "the analysis is invalid" <<<"$msg" || fail "unexpected refusal message: $msg"
[[ ! -e bad ]] || fail "an invalid analysis left its OUTDIR"
if msg=$(env "$marker" "$src/tools/slurm/submit_record.sh" --raycell "$raycell" --parsable -n 4 \
  badrec -- --orbit 8:90 --res 32x3x 2>&1); then
  fail "an invalid recording was submitted"
fi
grep -q "the record arguments are invalid" <<<"$msg" || fail "unexpected refusal message: $msg"
[[ ! -e badrec ]] || fail "an invalid recording left its OUTDIR"
[[ -z $(squeue -h 2>/dev/null) ]] || fail "a refused submission queued jobs: $(squeue -h)"

# ---- 5. a suite, one scene per task
suite=(--scenes "$src/scenes/dense_fog.toml" --scenes "$src/scenes/animated.toml" --res 16x16
  --frames 2 --fine 6x6x6)
t0=$(now)
"$raycell" suite "${suite[@]}" --quiet --out suite-oneshot >/dev/null || fail "raycell suite failed"
suite_oneshot=$(seconds "$t0" "$(now)")
run_array submit_suite.sh suite -- "${suite[@]}"
got=$(state "$array")
[[ $got == "0=COMPLETED 1=COMPLETED" ]] || fail "suite array tasks: got '$got'"
[[ $(state "$join") == "-=COMPLETED" ]] || fail "suite report job: got '$(state "$join")'"
for f in report.md suite.csv scenes/dense_fog.csv scenes/animated.csv; do
  cmp "suite-oneshot/$f" "suite/$f" || fail "suite/$f (a task per scene on Slurm) differs from the one-shot suite's"
done
[[ -f suite/suite.png ]] || fail "the report job drew no suite/suite.png"
echo "$(elapsed): suite of 2 scenes: 2 tasks and the report ${took} s wall; one-shot ${suite_oneshot} s"

echo "$(elapsed): PASS: record, analyze and a suite as Slurm arrays, joined byte-identical to one run"
