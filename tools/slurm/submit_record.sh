#!/usr/bin/env bash
# Runs `raycell record` on a Slurm cluster: a job array of N tasks, task I recording the I-th of
# N contiguous ranges of an orbit's frames (tools/slurm/frames.sbatch), then a job that starts
# when every task has succeeded and concatenates the parts (tools/slurm/join.sbatch) into the
# file one `raycell record` writes on one machine, byte for byte. Run `submit_record.sh --help`
# for the usage.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)

usage() {
  cat <<'USAGE'
Usage: tools/slurm/submit_record.sh [OPTIONS] OUTDIR -- RECORD ARGS...

Submits `raycell record RECORD ARGS` to Slurm as a job array of N tasks, each recording one
range of the frames of the camera orbit (`--orbit FRAMES:DEGREES`, which RECORD ARGS must
give: frames 0..FRAMES-1), and a dependent job that joins the parts (`raycell trace concat`).
The result appears in OUTDIR when the join job ends:

  OUTDIR/capture.rct        what `raycell record RECORD ARGS --out capture.rct` writes,
                            byte for byte
  OUTDIR/parts/part_I.rct   range I of N: `record --frames A..B` (the ranges are contiguous,
                            their sizes differ by at most one)
  OUTDIR/logs/              part_I.log per task, join.log (appended on resubmission)
  OUTDIR/record.args        the recording this folder holds

Options:
  -n, --tasks N          array tasks, one frame range each (default 4; at most one per frame)
  -c, --cpus-per-task C  CPUs per task, given to record as --threads C (default 1)
USAGE
  common_options_help JOINJOB
  cat <<'USAGE'

RECORD ARGS are those of `raycell record` except --frames and --out, which the tasks set.
Paths among them (--scene, --images, ...) are read from the directory you submit from, as on
one machine: jobs start in it. Images, unless --no-images, go to the --images folder as one
recording writes them (each task writes its own frames' files).

The binary must have `raycell trace concat`. Before queueing anything the record arguments are
checked on this machine as far as they parse (a range past the orbit's end reads every option
and value, then is refused before anything is rendered); the scene itself is first read by
the tasks: a missing file fails every task, and the join job is then cancelled.

Resubmitting: run the same command again. Parts that exist are kept (each is written through
a temporary name, so a part that exists is complete); the others run, then the join. OUTDIR
holds one recording: other arguments are refused.

Example:
  tools/slurm/submit_record.sh -n 10 -c 4 runs/smoke -- --scene smoke.vdb --cells 3x3x3 \
      --orbit 30:360 --no-images
USAGE
}

prog=submit_record.sh
# shellcheck source=tools/slurm/lib.sh
source "$here/lib.sh"

parse_options --tasks "$@"
record_args=("${tool_args[@]}")
((${#positional[@]} == 1)) || die "give OUTDIR, then -- and the record arguments (see --help)"
outdir=${positional[0]}
refuse_args --frames --out
frames=""
for ((i = 0; i < ${#record_args[@]}; i++)); do
  case ${record_args[i]} in
    --orbit) orbit=${record_args[i + 1]:-} ;;
    --orbit=*) orbit=${record_args[i]#--orbit=} ;;
    *) continue ;;
  esac
  [[ $orbit =~ ^([1-9][0-9]*):[^:]+$ ]] ||
    die "--orbit '$orbit': give FRAMES:DEGREES (e.g. 30:360), so that the frames to split are known"
  frames=${BASH_REMATCH[1]}
done
[[ -n $frames ]] || die "the record arguments need --orbit FRAMES:DEGREES (the frames 0..FRAMES-1 to split; see --help)"
((count <= frames)) || die "--tasks $count: the orbit has $frames frames; give at most $frames"
find_raycell
# (`trace concat --help` would print trace's help and succeed: look in the list instead.)
"$raycell" trace --help 2>/dev/null | grep -qE '^ +concat( |$)' ||
  die "$raycell has no \`raycell trace concat\`, which joins the parts; build a raycell that has it"

# The options must parse before N tasks are queued: a range just past the orbit's end reads
# every option and value, then is refused before anything is rendered (and says so).
check=$(mktemp -d)
trap 'rm -rf "$check"' EXIT
probe="$frames..$frames"
if msg=$("$raycell" record --quiet --frames "$probe" --out "$check/probe.rct" "${record_args[@]}" 2>&1 >/dev/null) ||
  [[ $msg != *"--frames $probe: not frames of --orbit"* ]]; then
  echo "$msg" >&2
  die "the record arguments are invalid (the message above is raycell's); nothing was submitted"
fi

record=$(
  printf 'cwd=%q\ntasks=%s\nframes=0..%s\nargs=' "$PWD" "$count" "$((frames - 1))"
  printf '%q ' "${record_args[@]}"
  echo
)
claim_outdir record "$record" parts

todo=()
for ((i = 0; i < count; i++)); do
  [[ -f $outdir/parts/part_$i.rct ]] || todo+=("$i")
done
task_cmd=("$here/frames.sbatch" record "$raycell" "$count" 0 "$((frames - 1))" "$outdir" "${record_args[@]}")
join_cmd=("$here/join.sbatch" record "$raycell" "$count" "$outdir" "$outdir/capture.rct")
submit_jobs "frame range" "$outdir/capture.rct" "part_%a.log" join.log
