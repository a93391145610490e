#!/usr/bin/env bash
# Runs a raycell sweep on a Slurm cluster: a job array of N tasks, task I running shard I/N
# (tools/slurm/sweep.sbatch), then a job that starts when every task has succeeded and merges
# the shard files into OUTDIR/sweep.csv (tools/slurm/merge.sbatch), byte-identical to what
# `raycell sweep` writes on one machine. Run `submit_sweep.sh --help` for the usage.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)

usage() {
  cat <<'EOF'
Usage: tools/slurm/submit_sweep.sh [OPTIONS] TRACE OUTDIR -- [SWEEP ARGS...]

Submits `raycell sweep TRACE SWEEP ARGS` to Slurm as a job array of N shards and a
dependent merge job. The result appears in OUTDIR/sweep.csv when the merge job ends.

  OUTDIR/sweep.csv          the merged sweep, as an unsharded run writes it
  OUTDIR/shards/shard_I.csv shard I/N (shard_I.csv.partial while it runs)
  OUTDIR/logs/              shard_I.log per task, merge.log (appended on resubmission)
  OUTDIR/sweep.args         the sweep this folder holds

Options:
  -n, --shards N         array tasks, one shard each (default 4)
  -c, --cpus-per-task C  CPUs per task, given to the shard as --jobs C (default 1)
EOF
  common_options_help MERGEJOB
  cat <<'EOF'

SWEEP ARGS are those of `raycell sweep` except --shard and --out, which the tasks set
(--vary, --config, --frames, --jobs, ...). Paths among them, and TRACE, are read from the
directory you submit from, as on one machine: jobs start in it.

Before queueing anything the sweep is checked on this machine (trace readable, --vary values
valid for the configuration) by a shard that owns no combination.

Resubmitting: run the same command again. Shards whose file exists are kept; the others run,
resuming from their .partial where an earlier task was cancelled, timed out or lost its node;
then the merge. OUTDIR holds one sweep: other arguments, or shard files that name another
sweep (a configuration file edited since), are refused.

Example:
  tools/slurm/submit_sweep.sh -n 16 -c 4 smoke.rct runs/cache -- --config gicube.toml \
      --vary scheduler=maxwork,celltree,peel --vary "level.cache.capacity=1 cell,2 cells"
EOF
}

prog=submit_sweep.sh join_word=merge
# shellcheck source=tools/slurm/lib.sh
source "$here/lib.sh"

parse_options --shards "$@"
shards=$count sweep_args=("${tool_args[@]}")
((${#positional[@]} == 2)) || die "give TRACE and OUTDIR, then -- and the sweep arguments (see --help)"
trace=${positional[0]} outdir=${positional[1]}
[[ -f $trace ]] || die "TRACE '$trace' is not a file"
refuse_args --shard --out
for a in "${sweep_args[@]}"; do
  [[ $a != merge ]] || die "'merge' is not a sweep argument: the merge job runs it"
done
find_raycell

# The sweep must be valid before N tasks are queued: a shard index past the last combination
# (there are at most 10^7) runs nothing but still opens the trace and checks every --vary
# value against the configuration.
check=$(mktemp -d)
trap 'rm -rf "$check"' EXIT
if ! "$raycell" sweep "$trace" --shard 9999999/10000000 --out "$check/check.csv" \
  "${sweep_args[@]}" >"$check/log" 2>&1; then
  cat "$check/log" >&2
  die "the sweep is invalid (the message above is raycell's); nothing was submitted"
fi

record=$(
  printf 'cwd=%q\nshards=%s\ntrace=%q\nargs=' "$PWD" "$shards" "$trace"
  printf '%q ' "${sweep_args[@]}"
  echo
)
claim_outdir sweep "$record" shards

# The first line of a sweep file names the sweep exactly (runner/sweep.h): trace, config and
# its hash, varies, frames, shard. Shard files left by an earlier run must name this sweep, so
# that a configuration file edited since is not merged with old rows.
name=$(head -n 1 "$check/check.csv")
probe=' shard="9999999/10000000"'
[[ $name == *"$probe"* ]] || die "raycell wrote an unexpected first line: $name"
todo=()
for ((i = 0; i < shards; i++)); do
  f=$outdir/shards/shard_$i.csv
  want=${name/"$probe"/ shard=\"$i/$shards\"}
  ((shards > 1)) || want=${name/"$probe"/ shard=\"all\"}
  for g in "$f" "$f.partial"; do
    [[ ! -f $g || $(head -n 1 "$g") == "$want" ]] ||
      die "$g is from another sweep (its first line differs: was the configuration edited?); use another OUTDIR, or delete the file to run that shard again"
  done
  [[ -f $f ]] || todo+=("$i")
done

task_cmd=("$here/sweep.sbatch" "$raycell" "$shards" "$outdir" "$trace" "${sweep_args[@]}")
join_cmd=("$here/merge.sbatch" "$raycell" "$shards" "$outdir")
submit_jobs shard "$outdir/sweep.csv" "shard_%a.log" merge.log
