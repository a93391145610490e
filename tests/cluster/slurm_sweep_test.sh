#!/usr/bin/env bash
# A sweep run on a real Slurm cluster through tools/slurm/submit_sweep.sh gives the same bytes
# as `raycell sweep` on one machine.
#
#   tests/cluster/slurm_sweep_test.sh RAYCELL SOURCE_DIR      (ctest -R slurm_sweep)
#
# Starts a private single-node cluster on this machine (tests/cluster/cluster.sh: munged,
# slurmctld and slurmd on localhost, everything in a temporary folder, nothing in /etc read or
# changed). Then, on a 3-frame 32x32 capture, a 6-combination sweep (3 schedulers x
# a cache of "1 cell" or "2 cells") in 4 shards:
#  1. with shard 1 interrupted earlier (a .partial with one row) and shard 2 unable to write
#     (its .partial is a directory): tasks 0, 1, 3 succeed, 1 resuming its row; task 2 fails;
#     the merge job is cancelled, not left pending; no sweep.csv;
#  2. the same command again, the blocker removed: only shard 2 is submitted, the merge runs,
#     and OUTDIR/sweep.csv is byte-identical to the unsharded run;
#  3. the same OUTDIR with other arguments, or holding a shard file of another configuration,
#     is refused.
# Every wait is bounded (RAYCELL_SLURM_TIMEOUT seconds, default 120). On exit, success or not,
# every daemon and job process it started is stopped, and the test fails if one survives.
#
# Needs root (slurmd starts jobs as their user) and Debian's slurm-wlm and munge; without
# them it exits 77, which ctest reports as skipped, unless RAYCELL_REQUIRE_SLURM=1 (CI), where
# their absence is a failure.
set -euo pipefail

(($# == 2)) || { echo "usage: $0 RAYCELL SOURCE_DIR" >&2; exit 2; }
raycell=$(realpath "$1") src=$(realpath "$2")
# shellcheck source=tests/cluster/cluster.sh
source "$src/tests/cluster/cluster.sh"

# ---- the sweep, unsharded, as the reference
cd "$tmp"
"$raycell" record --res 32x32 --cells 2x2x2 --orbit 3:30 --no-images --threads 1 \
  --out tiny.rct >/dev/null 2>&1 || fail "raycell record failed"
# A value with a space: the arguments must reach every task intact.
sweep=(--vary "scheduler=maxwork,celltree,peel" --vary "level.cache.capacity=1 cell,2 cells")
"$raycell" sweep tiny.rct --jobs 1 --out reference.csv "${sweep[@]}"
[[ $(grep -vc '^#' reference.csv) == 7 ]] || fail "reference.csv should have a header and 6 rows"

submit=(env "$marker" "$src/tools/slurm/submit_sweep.sh" --raycell "$raycell" --shards 4 --parsable)

# ---- 1. shard 1 interrupted earlier, shard 2 unable to write
mkdir -p out/shards
"$raycell" sweep tiny.rct --jobs 1 --shard 1/4 --out shard1.csv "${sweep[@]}"
head -n 3 shard1.csv >out/shards/shard_1.csv.partial  # comment, header, the first of 2 rows
mkdir out/shards/shard_2.csv.partial
read -r array merge < <("${submit[@]}" tiny.rct out -- "${sweep[@]}")
echo "$(elapsed): round 1: array job $array, merge job $merge"
wait_until "jobs $array and $merge" jobs_done "$array,$merge"
got=$(state "$array")
[[ $got == "0=COMPLETED 1=COMPLETED 2=FAILED 3=COMPLETED" ]] ||
  fail "round 1 array tasks: expected 0,1,3 COMPLETED and 2 FAILED, got '$got'"
got=$(state "$merge")
[[ $got == "-=CANCELLED" ]] || fail "round 1: the merge job should be cancelled after a failed task, got '$got'"
[[ ! -e out/sweep.csv ]] || fail "round 1 wrote out/sweep.csv from an incomplete sweep"
grep -q "resumed 1 rows" out/logs/shard_1.log || fail "shard 1 did not resume from its .partial"
cmp -s shard1.csv out/shards/shard_1.csv || fail "resumed shard 1 differs from shard 1 run alone"

# ---- 2. the same command again: only shard 2 runs, then the merge
rmdir out/shards/shard_2.csv.partial
read -r array merge < <("${submit[@]}" tiny.rct out -- "${sweep[@]}")
echo "$(elapsed): round 2: array job $array, merge job $merge"
wait_until "jobs $array and $merge" jobs_done "$array,$merge"
got=$(state "$array")
[[ $got == "2=COMPLETED" ]] || fail "round 2 should run only shard 2, got '$got'"
got=$(state "$merge")
[[ $got == "-=COMPLETED" ]] || fail "round 2 merge job: got '$got'"
cmp reference.csv out/sweep.csv ||
  fail "out/sweep.csv (4 shards on Slurm) differs from the unsharded reference.csv"

# ---- 3. another sweep into the same OUTDIR is refused before anything is queued
if msg=$("${submit[@]}" tiny.rct out -- --vary scheduler=maxwork 2>&1); then
  fail "submitting another sweep into out/ was accepted"
fi
grep -q "holds another sweep" <<<"$msg" || fail "unexpected refusal message: $msg"
# ... and so is a shard file of another configuration (as if the config had been edited)
sed -i '1s/config_hash=[0-9a-f]*/config_hash=0123456789abcdef/' out/shards/shard_3.csv
if msg=$("${submit[@]}" tiny.rct out -- "${sweep[@]}" 2>&1); then
  fail "a shard file of another configuration was accepted"
fi
grep -q "shard_3.csv is from another sweep" <<<"$msg" || fail "unexpected refusal message: $msg"

echo "$(elapsed): PASS: 6 combinations in 4 shards on Slurm, a failed task rerun and a resumed one," \
  "merged byte-identical to the unsharded sweep"
