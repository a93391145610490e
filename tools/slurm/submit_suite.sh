#!/usr/bin/env bash
# Runs `raycell suite` on a Slurm cluster: a job array with one task per scene of the suite
# (tools/slurm/suite.sbatch scene: `raycell suite --only NAME`), then a job that starts when
# every task has succeeded and writes the report from the scenes' files (suite.sbatch report:
# `raycell suite --report`), the same bytes as `raycell suite` on one machine. Run
# `submit_suite.sh --help` for the usage.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)

usage() {
  cat <<'USAGE'
Usage: tools/slurm/submit_suite.sh [OPTIONS] OUTDIR -- [SUITE ARGS...]

Submits `raycell suite SUITE ARGS --out OUTDIR` to Slurm as a job array of one task per
scene (`raycell suite --list SUITE ARGS` names them), each recording and replaying its scene
into OUTDIR/scenes/NAME.csv, and a dependent job that writes the report. When it ends:

  OUTDIR/report.md, suite.csv, suite.png   what `raycell suite` writes, report.md and
                                           suite.csv byte for byte
  OUTDIR/scenes/NAME.csv                   one scene's results (task I: the I-th scene)
  OUTDIR/captures/                         the scenes' captures
  OUTDIR/logs/                             scene_I.log per task, report.log
  OUTDIR/suite.args                        the suite this folder holds

Options:
  -c, --cpus-per-task C  CPUs per task (default 1)
USAGE
  common_options_help REPORTJOB
  cat <<'USAGE'

SUITE ARGS are those of `raycell suite` (--scenes, --data, --res, --frames, --cells, --fine,
--processors) except --out, --only, --report and --list, which the jobs set. Paths among them
are read from the directory you submit from, as on one machine: jobs start in it.

Resubmitting: run the same command again. Scenes whose file exists are kept (each is written
through a temporary name, so a file that exists is complete); the others run, then the report.

Example:
  tools/slurm/submit_suite.sh -c 2 runs/suite -- --res 256x256 --frames 16
USAGE
}

prog=submit_suite.sh join_word=report
# shellcheck source=tools/slurm/lib.sh
source "$here/lib.sh"

parse_options --tasks "$@"
suite_args=("${tool_args[@]}")
((${#positional[@]} == 1)) || die "give OUTDIR, then -- and the suite arguments (see --help)"
outdir=${positional[0]}
refuse_args --out --only --report --list
find_raycell

# The scenes, and a check of the arguments, before anything is queued.
names=$("$raycell" suite --list "${suite_args[@]}" 2>&1) ||
  { echo "$names" >&2; die "the suite arguments are invalid (the message above is raycell's); nothing was submitted"; }
mapfile -t scenes < <(cut -f1 <<<"$names")
count=${#scenes[@]}
((count > 0)) || die "the suite has no scene"

record=$(
  printf 'cwd=%q\nscenes=%s\nargs=' "$PWD" "${scenes[*]}"
  printf '%q ' "${suite_args[@]}"
  echo
)
claim_outdir suite "$record" scenes
printf '%s\n' "${scenes[@]}" >"$outdir/scenes.list"

todo=()
for ((i = 0; i < count; i++)); do
  [[ -f $outdir/scenes/${scenes[i]}.csv ]] || todo+=("$i")
done
task_cmd=("$here/suite.sbatch" scene "$raycell" "$outdir" "${suite_args[@]}")
join_cmd=("$here/suite.sbatch" report "$raycell" "$outdir" "${suite_args[@]}")
submit_jobs "scene" "$outdir/report.md" "scene_%a.log" report.log
