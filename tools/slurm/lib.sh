# shellcheck shell=bash
# shellcheck disable=SC2154  # prog, here, todo, task_cmd, join_cmd: set by the sourcing script
# What the submit scripts of tools/slurm share; sourced, not run. Each script sets `here` (its
# folder), `prog` (its name, for messages) and `usage` (a function printing its --help) first,
# and `todo`, `task_cmd` and `join_cmd` before submit_jobs.
#
# A submission is a job array whose task I writes one file, OUTDIR/.../I, and a join job that
# runs once every task has succeeded (--dependency=afterok, cancelled when one fails) and
# joins the files. OUTDIR holds one job: KIND.args records its arguments, and other arguments,
# or another KIND's folder, are refused. Resubmitting the same command submits only the tasks
# whose file is missing, then the join.

die() {
  echo "$prog: error: $*" >&2
  exit 2
}

# "0 1 2 5 7 8" -> "0-2,5,7-8": the --array list of the tasks to run (at least one).
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

# common_options_help JOB: the options every submit script takes after -n and -c, for its
# --help; JOB names the join job in --parsable's output.
common_options_help() {
  cat <<EOF
  --max-running K        at most K tasks at once (sbatch --array=...%K)
  --raycell PATH         the raycell binary, on a filesystem every node sees (default:
                         \$RAYCELL, else build/tools/raycell of this checkout, else PATH)
  --sbatch OPTION        an extra sbatch option for both jobs, e.g. --sbatch --partition=cpu
                         --sbatch --time=2:00:00 (repeatable; SBATCH_* variables work too)
  --parsable             print only "ARRAYJOB $1" (ARRAYJOB is "-" when no task ran)
  -h, --help             this text
EOF
}

# parse_options COUNT_OPTION "$@": the options every submit script takes. COUNT_OPTION is the
# long name of -n (--shards, --tasks). Sets count, cpus, max_running, raycell, sbatch_opts,
# parsable, positional (before --) and tool_args (after --).
parse_options() {
  local count_option=$1
  shift
  count=4 cpus=1 max_running="" raycell=${RAYCELL:-} parsable=0
  sbatch_opts=() positional=() tool_args=()
  while (($#)); do
    case $1 in
      -h | --help) usage; exit 0 ;;
      -n | "$count_option") (($# >= 2)) || die "$1 needs a value"; count=$2; shift 2 ;;
      -c | --cpus-per-task) (($# >= 2)) || die "$1 needs a value"; cpus=$2; shift 2 ;;
      --max-running) (($# >= 2)) || die "$1 needs a value"; max_running=$2; shift 2 ;;
      --raycell) (($# >= 2)) || die "$1 needs a value"; raycell=$2; shift 2 ;;
      --sbatch) (($# >= 2)) || die "$1 needs a value"; sbatch_opts+=("$2"); shift 2 ;;
      --parsable) parsable=1; shift ;;
      --) shift; break ;;
      -*) die "unknown option '$1' (raycell's arguments go after --; see --help)" ;;
      *) positional+=("$1"); shift ;;
    esac
  done
  tool_args=("$@")
  [[ $count =~ ^[1-9][0-9]*$ ]] || die "$count_option must be a positive integer, got '$count'"
  [[ $cpus =~ ^[1-9][0-9]*$ ]] || die "--cpus-per-task must be a positive integer, got '$cpus'"
  [[ -z $max_running || $max_running =~ ^[1-9][0-9]*$ ]] ||
    die "--max-running must be a positive integer, got '$max_running'"
}

# refuse_args OPTION... : tool arguments the tasks set themselves.
refuse_args() {
  local a o
  for a in "${tool_args[@]}"; do
    for o in "$@"; do
      case $a in "$o" | "$o"=*) die "'$a' is set by the tasks; leave it out of raycell's arguments" ;; esac
    done
  done
}

# The raycell binary, absolute: --raycell, $RAYCELL, build/tools/raycell of this checkout, PATH.
find_raycell() {
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
}

# claim_outdir KIND RECORD SUBDIR: makes OUTDIR/SUBDIR and OUTDIR/logs, makes outdir
# absolute, and writes RECORD to OUTDIR/KIND.args, or checks that it equals what is there.
claim_outdir() {
  local kind=$1 record=$2 sub=$3 f
  mkdir -p "$outdir/$sub" "$outdir/logs"
  outdir=$(cd "$outdir" && pwd)
  for f in "$outdir"/*.args; do
    [[ -f $f && $f != "$outdir/$kind.args" ]] &&
      die "$outdir holds a $(basename "$f" .args) job ($f), not a $kind; use another OUTDIR"
  done
  if [[ -f $outdir/$kind.args ]]; then
    [[ $(cat "$outdir/$kind.args") == "$record" ]] ||
      die "$outdir holds another $kind ($outdir/$kind.args differs from this one); use another OUTDIR or delete it"
  else
    echo "$record" >"$outdir/$kind.args"
  fi
}

# submit_jobs NOUN RESULT TASK_LOG JOIN_LOG: submits the array of the task indices in `todo`
# (none: no array) running the command in the array `task_cmd` (a script and its arguments),
# then `join_cmd` after it; prints what was submitted (--parsable: "ARRAYJOB JOINJOB"). The
# join job is called `join_word` in messages (default "join").
submit_jobs() {
  local noun=$1 result=$2 task_log=$3 join_log=$4 out spec="" array_job="-" dependency=()
  if ((${#todo[@]})); then
    spec=$(ranges "${todo[@]}")${max_running:+%$max_running}
    out=$(sbatch --parsable --array="$spec" --cpus-per-task="$cpus" \
      --output="$outdir/logs/$task_log" --open-mode=append "${sbatch_opts[@]}" "${task_cmd[@]}") ||
      die "sbatch refused the array job (its message is above)"
    array_job=${out%%;*}
    dependency=(--dependency="afterok:$array_job" --kill-on-invalid-dep=yes)
  fi
  out=$(sbatch --parsable "${dependency[@]}" --output="$outdir/logs/$join_log" --open-mode=append \
    "${sbatch_opts[@]}" "${join_cmd[@]}") ||
    die "sbatch refused the ${join_word:-join} job (its message is above); the array job $array_job is queued: scancel it or rerun this command"
  local join_job=${out%%;*}
  if ((parsable)); then
    echo "$array_job $join_job"
  elif ((${#todo[@]})); then
    echo "Submitted array job $array_job: $noun(s) $spec of $count; $((count - ${#todo[@]})) already done."
    echo "Submitted ${join_word:-join} job $join_job, after every $noun succeeds."
    echo "Result: $result   (logs: $outdir/logs/, status: squeue -j $array_job,$join_job)"
    echo "If a task fails, the ${join_word:-join} job is cancelled: see its log, then run this command again."
  else
    echo "All $count ${noun}s are done; submitted ${join_word:-join} job $join_job."
    echo "Result: $result   (log: $outdir/logs/$join_log)"
  fi
}
