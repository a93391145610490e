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
  --max-running K        at most K tasks at once (sbatch --array=...%K)
  --raycell PATH         the raycell binary, on a filesystem every node sees (default:
                         $RAYCELL, else build/tools/raycell of this checkout, else PATH)
  --sbatch OPTION        an extra sbatch option for both jobs, e.g. --sbatch --partition=cpu
                         --sbatch --time=2:00:00 (repeatable; SBATCH_* variables work too)
  --parsable             print only "ARRAYJOB MERGEJOB" (ARRAYJOB is "-" when no task ran)
  -h, --help             this text

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

die() {
  echo "submit_sweep.sh: error: $*" >&2
  exit 2
}

# "0 1 2 5 7 8" -> "0-2,5,7-8": the --array list of the shards to run (at least one).
ranges() {
  local out="" start=$1 prev=$1 i
  shift
  for i in "$@" ""; do
    if [[ -n $i && $i -eq $((prev + 1)) ]]; then
      prev=$i
      continue
    fi
    out+="${out:+,}$start"
    if ((prev != start)); then out+="-$prev"; fi
    start=$i prev=$i
  done
  echo "$out"
}

shards=4 cpus=1 max_running="" raycell=${RAYCELL:-} parsable=0
sbatch_opts=() positional=()
while (($#)); do
  case $1 in
    -h | --help) usage; exit 0 ;;
    -n | --shards) (($# >= 2)) || die "$1 needs a value"; shards=$2; shift 2 ;;
    -c | --cpus-per-task) (($# >= 2)) || die "$1 needs a value"; cpus=$2; shift 2 ;;
    --max-running) (($# >= 2)) || die "$1 needs a value"; max_running=$2; shift 2 ;;
    --raycell) (($# >= 2)) || die "$1 needs a value"; raycell=$2; shift 2 ;;
    --sbatch) (($# >= 2)) || die "$1 needs a value"; sbatch_opts+=("$2"); shift 2 ;;
    --parsable) parsable=1; shift ;;
    --) shift; break ;;
    -*) die "unknown option '$1' (sweep arguments go after --; see --help)" ;;
    *) positional+=("$1"); shift ;;
  esac
done
sweep_args=("$@")

((${#positional[@]} == 2)) || die "give TRACE and OUTDIR, then -- and the sweep arguments (see --help)"
trace=${positional[0]} outdir=${positional[1]}
[[ $shards =~ ^[1-9][0-9]*$ ]] || die "--shards must be a positive integer, got '$shards'"
[[ $cpus =~ ^[1-9][0-9]*$ ]] || die "--cpus-per-task must be a positive integer, got '$cpus'"
[[ -z $max_running || $max_running =~ ^[1-9][0-9]*$ ]] ||
  die "--max-running must be a positive integer, got '$max_running'"
[[ -f $trace ]] || die "TRACE '$trace' is not a file"
for a in "${sweep_args[@]}"; do
  case $a in
    --shard | --shard=* | --out | --out=*) die "'$a' is set by the tasks; leave it out of the sweep arguments" ;;
    merge) die "'merge' is not a sweep argument: the merge job runs it" ;;
  esac
done

if [[ -z $raycell ]]; then
  if [[ -x $here/../../build/tools/raycell ]]; then
    raycell=$here/../../build/tools/raycell
  else
    raycell=$(command -v raycell) || die "no raycell binary: build it, or give --raycell PATH"
  fi
fi
[[ -x $raycell ]] || die "--raycell '$raycell' is not an executable"
raycell=$(realpath "$raycell")
command -v sbatch >/dev/null || die "sbatch not found: run this on a Slurm login node"

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

mkdir -p "$outdir/shards" "$outdir/logs"
outdir=$(cd "$outdir" && pwd)
record=$(
  printf 'cwd=%q\nshards=%s\ntrace=%q\nargs=' "$PWD" "$shards" "$trace"
  printf '%q ' "${sweep_args[@]}"
  echo
)
if [[ -f $outdir/sweep.args ]]; then
  [[ $(cat "$outdir/sweep.args") == "$record" ]] ||
    die "$outdir holds another sweep ($outdir/sweep.args differs from this one); use another OUTDIR or delete it"
else
  echo "$record" >"$outdir/sweep.args"
fi

# The first line of a sweep file names the sweep exactly (replay/sweep.h): trace, config and
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

array_job="-" dependency=()
if ((${#todo[@]})); then
  spec=$(ranges "${todo[@]}")${max_running:+%$max_running}
  out=$(sbatch --parsable --array="$spec" --cpus-per-task="$cpus" \
    --output="$outdir/logs/shard_%a.log" --open-mode=append "${sbatch_opts[@]}" \
    "$here/sweep.sbatch" "$raycell" "$shards" "$outdir" "$trace" "${sweep_args[@]}") ||
    die "sbatch refused the array job (its message is above)"
  array_job=${out%%;*}
  dependency=(--dependency="afterok:$array_job" --kill-on-invalid-dep=yes)
fi
out=$(sbatch --parsable "${dependency[@]}" --output="$outdir/logs/merge.log" --open-mode=append \
  "${sbatch_opts[@]}" "$here/merge.sbatch" "$raycell" "$shards" "$outdir") ||
  die "sbatch refused the merge job (its message is above); the array job $array_job is queued: scancel it or rerun this command"
merge_job=${out%%;*}

if ((parsable)); then
  echo "$array_job $merge_job"
elif ((${#todo[@]})); then
  echo "Submitted array job $array_job: shard(s) $spec of $shards; $((shards - ${#todo[@]})) already done."
  echo "Submitted merge job $merge_job, after every shard succeeds."
  echo "Result: $outdir/sweep.csv   (logs: $outdir/logs/, status: squeue -j $array_job,$merge_job)"
  echo "If a task fails, the merge job is cancelled: see its log, then run this command again."
else
  echo "All $shards shards are done; submitted merge job $merge_job."
  echo "Result: $outdir/sweep.csv   (log: $outdir/logs/merge.log)"
fi
