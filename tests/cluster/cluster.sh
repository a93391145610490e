# shellcheck shell=bash
# A private single-node Slurm cluster for the cluster tests; sourced, not run, by
# tests/cluster/slurm_*_test.sh after they set `raycell` and `src`.
#
# Starts munged, slurmctld and slurmd on localhost with a generated munge key and slurm.conf,
# their sockets, ports, state, spool and logs in a temporary folder `tmp`; Slurm commands find
# it through SLURM_CONF, so nothing in /etc is read or changed. Skips (exit 77) without root,
# slurm-wlm or munge, unless RAYCELL_REQUIRE_SLURM=1 (CI), where that is a failure. Gives the
# test: skip, fail, elapsed, wait_until DESCRIPTION COMMAND... (bounded by
# RAYCELL_SLURM_TIMEOUT seconds, default 120), jobs_done JOBS, state JOB, `host`, and `marker`
# (the environment variable every process of the cluster carries: submit with `env
# "$marker" ...`). On exit, success or not, every daemon and job process it started is
# stopped, and the test fails if one survives; on failure the daemons' logs and those of
# "$tmp"/*/logs/ are printed.
timeout_s=${RAYCELL_SLURM_TIMEOUT:-120}
start_time=$(date +%s.%N)

skip() {
  if [[ ${RAYCELL_REQUIRE_SLURM:-0} == 1 ]]; then
    echo "FAIL: $* (RAYCELL_REQUIRE_SLURM=1: the cluster test must run)" >&2
    exit 1
  fi
  echo "SKIPPED: $*"
  exit 77
}
fail() {
  echo "FAIL: $*" >&2
  exit 1
}
elapsed() { printf '%.1f s' "$(echo "$(date +%s.%N) - $start_time" | bc)"; }

[[ $(id -u) == 0 ]] || skip "the Slurm cluster test needs root (slurmd runs jobs as their user)"
for b in munged mungekey slurmctld slurmd sbatch squeue scontrol scancel sinfo flock python3; do
  command -v "$b" >/dev/null ||
    skip "'$b' is not installed (apt-get install slurm-wlm munge runs the Slurm cluster test)"
done

tmp=$(mktemp -d /tmp/raycell-slurm.XXXXXX)
# The daemons and submissions get this variable, and so every process they start (slurmstepd,
# job shells): the cleanup finds stragglers by it. (Not exported here: it would mark this
# script's own helpers too.)
marker=RAYCELL_SLURM_TEST=$tmp
export SLURM_CONF=$tmp/slurm.conf
munged_pid="" slurmctld_pid="" slurmd_pid=""

alive() { [[ -n $1 ]] && kill -0 "$1" 2>/dev/null && [[ $(ps -o stat= -p "$1") != Z* ]]; }
# The live (not zombie) processes whose environment holds our marker or whose command line
# names the temporary folder.
ours() {
  local p
  for p in $(pgrep -r D,R,S,T,t,I -f "$tmp"; grep -lsxz "$marker" /proc/[0-9]*/environ |
    cut -d/ -f3); do
    [[ $p != "$$" && $p != "$BASHPID" ]] && alive "$p" && echo "$p"
  done | sort -u
}
stop() {  # stop PID: TERM, up to 10 s, then KILL; reaps it when it is our child
  local pid=$1 i
  alive "$pid" || return 0
  kill -TERM "$pid" 2>/dev/null || true
  for ((i = 0; i < 100; i++)); do
    alive "$pid" || break
    sleep 0.1
  done
  alive "$pid" && kill -KILL "$pid" 2>/dev/null
  wait "$pid" 2>/dev/null || true
}
cleanup() {
  local rc=$? p i left
  trap - EXIT INT TERM
  if alive "$slurmctld_pid"; then timeout 5 scancel --quiet --user=root 2>/dev/null || true; fi
  stop "$slurmd_pid"
  stop "$slurmctld_pid"
  for p in $(ours); do
    [[ $p == "$munged_pid" ]] || kill -KILL "$p" 2>/dev/null || true
  done
  stop "$munged_pid"
  for ((i = 0; i < 50; i++)); do  # killed processes that are not our children go after a while
    left=$(ours)
    [[ -z $left ]] && break
    sleep 0.1
  done
  if [[ -n $left ]]; then
    echo "FAIL: processes of the test cluster survived the cleanup:" >&2
    ps -o pid,stat,args -p "$(paste -sd, <<<"$left")" >&2 || true
    rc=1
  fi
  if ((rc != 0)); then
    for f in "$tmp"/log/*.log "$tmp"/*/logs/*.log; do
      [[ -f $f ]] && { echo "---- $f (last 15 lines)"; tail -n 15 "$f"; }
    done >&2
  fi
  rm -rf "$tmp"
  echo "cluster test: $(elapsed) wall, all daemons stopped"
  exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# ---- the private cluster
mkdir -p "$tmp"/{munge,state,spool,log}
chmod 700 "$tmp"/munge
mungekey --create --keyfile="$tmp/munge/munge.key"
env "$marker" munged -F --force --socket="$tmp/munge/munge.sock" --key-file="$tmp/munge/munge.key" \
  --pid-file="$tmp/munge/munged.pid" --log-file="$tmp/log/munged.log" \
  --seed-file="$tmp/munge/munged.seed" >"$tmp/log/munged.out" 2>&1 &
munged_pid=$!

read -r ctld_port slurmd_port < <(python3 -c '
import socket
a, b = socket.socket(), socket.socket()
a.bind(("127.0.0.1", 0)); b.bind(("127.0.0.1", 0))
print(a.getsockname()[1], b.getsockname()[1])')
node=$(slurmd -C | head -n 1)  # NodeName=HOST CPUs=... RealMemory=...: this machine
[[ $node == NodeName=* ]] || fail "slurmd -C printed '$node', not the node's configuration"
host=${node%% *}
host=${host#NodeName=}
cat >"$SLURM_CONF" <<EOF
ClusterName=raycelltest
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$tmp/munge/munge.sock
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/log/slurmctld.log
SlurmdLogFile=$tmp/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/builtin
SchedulerParameters=batch_sched_delay=0,sched_interval=1
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
MailProg=/bin/true
ReturnToService=2
$node NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName=test Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF

for ((i = 0; i < 50; i++)); do
  [[ -S $tmp/munge/munge.sock ]] && break
  alive "$munged_pid" || fail "munged exited at start"
  sleep 0.1
done
env "$marker" slurmctld -D -f "$SLURM_CONF" >"$tmp/log/slurmctld.out" 2>&1 &
slurmctld_pid=$!
env "$marker" slurmd -D -f "$SLURM_CONF" >"$tmp/log/slurmd.out" 2>&1 &
slurmd_pid=$!

# wait_until DESCRIPTION COMMAND...: polls COMMAND until it succeeds, for at most timeout_s,
# failing early when a daemon has died.
wait_until() {
  local what=$1 deadline
  shift
  deadline=$(($(date +%s) + timeout_s))
  until "$@"; do
    local d
    for d in munged:$munged_pid slurmctld:$slurmctld_pid slurmd:$slurmd_pid; do
      alive "${d#*:}" || fail "${d%%:*} (pid ${d#*:}) is no longer running while waiting for $what"
    done
    (($(date +%s) < deadline)) || fail "timed out after ${timeout_s} s waiting for $what ($(squeue -h -o '%i %T %r' 2>&1 | tr '\n' ';'))"
    sleep 0.2
  done
}
node_idle() { [[ $(sinfo -h -n "$host" -o %t 2>/dev/null) == idle ]]; }
wait_until "node $host to be idle" node_idle
echo "$(elapsed): cluster up: $host ($node), ports $ctld_port/$slurmd_port"

jobs_done() { ! squeue -h -j "$1" 2>/dev/null | grep -q .; }
# state JOB: "TASK=STATE ..." for an array (TASK "-" for a plain job), from scontrol.
state() {
  scontrol -o show job "$1" | while read -r line; do
    t=$(sed -nE 's/.*ArrayTaskId=([0-9]+).*/\1/p' <<<"$line")
    echo "${t:--}=$(sed -nE 's/.*JobState=([A-Z_]+).*/\1/p' <<<"$line")"
  done | sort | tr '\n' ' ' | sed 's/ $//'
}
