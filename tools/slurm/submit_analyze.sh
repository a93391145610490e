#!/usr/bin/env bash
# Runs `raycell analyze` on a Slurm cluster: a job array of N tasks, task I analysing the I-th
# of N contiguous frame ranges into a part (tools/slurm/frames.sbatch), then a job that starts
# when every task has succeeded and merges the parts (tools/slurm/join.sbatch), byte-identical
# to what `raycell analyze` prints on one machine. Run `submit_analyze.sh --help` for the usage.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)

usage() {
  cat <<'USAGE'
Usage: tools/slurm/submit_analyze.sh [OPTIONS] TRACE OUTDIR -- [ANALYZE ARGS...]

Submits `raycell analyze TRACE ANALYZE ARGS` to Slurm as a job array of N tasks, each
analysing one range of the trace's frames, and a dependent job that merges them
(`raycell analyze merge`). The result appears in OUTDIR when the merge job ends:

  OUTDIR/analysis.csv       what `raycell analyze TRACE ANALYZE ARGS` prints, byte for byte
                            (analysis.json with --format json, analysis.txt for the table)
  OUTDIR/parts/part_I.part  range I of N: `analyze --frames A..B --part` (the ranges are
                            contiguous, their sizes differ by at most one)
  OUTDIR/logs/              part_I.log per task, join.log (appended on resubmission)
  OUTDIR/analyze.args       the analysis this folder holds

Options:
  -n, --tasks N          array tasks, one frame range each (default 4; at most one per frame)
  -c, --cpus-per-task C  CPUs per task, given to analyze as --jobs C (default 1)
USAGE
  common_options_help MERGEJOB
  cat <<'USAGE'

ANALYZE ARGS are those of `raycell analyze` (--bracket, --effort, --exact, --format, ...)
except --frames, --frame, --all, --part, --paths and --dot, which the tasks set or which
have no meaning here. TRACE and paths among them are read from the directory you submit from,
as on one machine: jobs start in it.

Before queueing anything the analysis is checked on this machine (the trace readable, the
options valid) by a run over a range with no frame, which analyses nothing.

Resubmitting: run the same command again. Parts that exist are kept (each is written
through a temporary name, so a part that exists is complete); the others run, then the
merge. OUTDIR holds one analysis: other arguments are refused. The merge checks that every
part names the same trace (by content) and options: parts of a trace rewritten since fail
the merge job with raycell's message; delete OUTDIR/parts then.

Example:
  tools/slurm/submit_analyze.sh -n 16 -c 2 capture.rct runs/bracket -- \
      --bracket --effort quick --format csv
USAGE
}

prog=submit_analyze.sh join_word=merge
# shellcheck source=tools/slurm/lib.sh
source "$here/lib.sh"

parse_options --tasks "$@"
analyze_args=("${tool_args[@]}")
((${#positional[@]} == 2)) || die "give TRACE and OUTDIR, then -- and the analyze arguments (see --help)"
trace=${positional[0]} outdir=${positional[1]}
[[ -f $trace ]] || die "TRACE '$trace' is not a file"
refuse_args --frames --frame --all --part
for a in "${analyze_args[@]}"; do
  case $a in
    --paths | --paths=*) die "'$a': the array analyses TRACE; analyse a paths file on one machine" ;;
    --dot | --dot=*) die "'$a' writes one frame's tree: run it on one machine (raycell analyze TRACE --frame N --dot FILE)" ;;
  esac
done
format=table
for ((i = 0; i < ${#analyze_args[@]}; i++)); do
  case ${analyze_args[i]} in
    merge) die "'merge' is not an analyze argument: the merge job runs it" ;;
    --format) format=${analyze_args[i + 1]:-} ;;
    --format=*) format=${analyze_args[i]#--format=} ;;
  esac
done
case $format in
  csv | json) result=analysis.$format ;;
  table) result=analysis.txt ;;
  *) die "--format '$format': expected table, json or csv" ;;
esac
find_raycell

# The trace's frame numbers, first and last, from the frames table of `raycell trace info`.
info=$("$raycell" trace info "$trace" 2>&1) || { echo "$info" >&2; die "cannot read TRACE '$trace' (the message above is raycell's)"; }
read -r first last < <(awk '/^ *frame +primary / {t = 1; next} t && $1 ~ /^-?[0-9]+$/ {if (n++ == 0) f = $1; l = $1} t && $1 !~ /^-?[0-9]+$/ {t = 0} END {if (n) print f, l}' <<<"$info")
[[ -n ${first:-} ]] || die "TRACE '$trace' has no frames (raycell trace info lists none)"
frames=$((last - first + 1))
((count <= frames)) || die "--tasks $count: the trace has $frames frames ($first..$last); give at most $frames"

# The analysis must be valid before N tasks are queued: a range after the last frame opens the
# trace and checks every option, then finds no frame to analyse (and says so).
probe="$((last + 1))..$((last + 1))"
if msg=$("$raycell" analyze "$trace" --quiet --frames "$probe" "${analyze_args[@]}" 2>&1 >/dev/null) ||
  [[ $msg != *"no frame in --frames $probe"* ]]; then
  echo "$msg" >&2
  die "the analysis is invalid (the message above is raycell's); nothing was submitted"
fi

record=$(
  printf 'cwd=%q\ntasks=%s\ntrace=%q\nframes=%s..%s\nargs=' "$PWD" "$count" "$trace" "$first" "$last"
  printf '%q ' "${analyze_args[@]}"
  echo
)
claim_outdir analyze "$record" parts

todo=()
for ((i = 0; i < count; i++)); do
  [[ -f $outdir/parts/part_$i.part ]] || todo+=("$i")
done
task_cmd=("$here/frames.sbatch" analyze "$raycell" "$count" "$first" "$last" "$outdir" "$trace" "${analyze_args[@]}")
join_cmd=("$here/join.sbatch" analyze "$raycell" "$count" "$outdir" "$outdir/$result")
submit_jobs "frame range" "$outdir/$result" "part_%a.log" join.log
