#!/usr/bin/env bash
# A private single-node Slurm cluster on this machine, for trying and testing `fdem-tools ... --scheduler slurm`.
#
#   tools/slurm/local-cluster.sh start [DIR]   start munged, slurmctld and slurmd; prints `export SLURM_CONF=...`
#   tools/slurm/local-cluster.sh env [DIR]     print the same export line again (eval "$(... env)")
#   tools/slurm/local-cluster.sh status [DIR]  sinfo of the cluster
#   tools/slurm/local-cluster.sh stop [DIR]    cancel the jobs left in its queue, then stop the three daemons (by
#                                              the process ids saved at start)
#
# DIR (default $FDEM_SLURM_DIR, else /tmp/fdem-slurm-<uid>) holds everything: the munge key and socket,
# slurm.conf, the controller's state, the spool and the logs (DIR/log/*.log). Nothing outside DIR is written and no
# systemd is needed: the daemons run in their foreground modes (munged -F, slurmctld -D, slurmd -D) as children of
# this script's background jobs. The Slurm commands find the cluster through SLURM_CONF=DIR/slurm.conf, so they
# never talk to another Slurm on the same machine; the ports are free ones picked at start.
#
# Packages: Debian's slurm-wlm and munge (tools/setup.sh installs them). Made for a machine or container where we
# are root: SlurmUser = SlurmdUser = the calling user, no cgroups (proctrack/linuxproc, task/none), no accounting
# database (sacct is then unavailable: fdem-tools reads the states from squeue and from its own exit files).
# One node named after this host with the CPUs and memory `slurmd -C` reports, one partition `debug`.
# FDEM_SLURM_NICE (default 0): the daemons, and so every job they start, run at this nice value (the tests use 10,
# so that they yield the CPU on a shared machine).
set -euo pipefail

cmd=${1:-}
DIR=${2:-${FDEM_SLURM_DIR:-/tmp/fdem-slurm-$(id -u)}}
# Unix socket paths are limited to 107 bytes: keep DIR short.
if [ "${#DIR}" -gt 70 ]; then
  echo "local-cluster: DIR '$DIR' is too long for the munge socket path (at most 70 characters)" >&2
  exit 1
fi

say() { echo "local-cluster: $*" >&2; }

export_line() { echo "export SLURM_CONF=$DIR/slurm.conf"; }

free_port() {
  /usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}

alive() { [ -f "$DIR/$1.pid" ] && kill -0 "$(cat "$DIR/$1.pid")" 2>/dev/null; }

show_logs() {
  local f
  for f in "$DIR"/log/*.log "$DIR"/log/*.out; do
    [ -s "$f" ] || continue
    echo "----- $f (last 40 lines)" >&2
    tail -n 40 "$f" >&2
  done
}

stop_daemon() {  # stop_daemon NAME: SIGTERM to the process id saved at start, SIGKILL after 10 s
  local name=$1 pid i
  [ -f "$DIR/$name.pid" ] || return 0
  pid=$(cat "$DIR/$name.pid")
  if kill -0 "$pid" 2>/dev/null; then
    kill -TERM "$pid" 2>/dev/null || true
    for i in $(seq 100); do
      kill -0 "$pid" 2>/dev/null || break
      sleep 0.1
    done
    if kill -0 "$pid" 2>/dev/null; then
      say "$name ($pid) still running after 10 s: SIGKILL"
      kill -KILL "$pid" 2>/dev/null || true
    fi
  fi
  rm -f "$DIR/$name.pid"
}

cancel_jobs() {  # cancel what is left in this cluster's queue and wait (15 s at most) until it has ended
  alive slurmctld || return 0
  export SLURM_CONF="$DIR/slurm.conf"
  scancel --user="$(id -un)" 2>/dev/null || true
  local i
  for i in $(seq 150); do
    [ -z "$(squeue -h -o %i 2>/dev/null)" ] && return 0
    sleep 0.1
  done
  say "jobs still in the queue after 15 s: $(squeue -h -o %i 2>/dev/null | tr '\n' ' ')"
}

stop_all() {
  stop_daemon slurmd
  stop_daemon slurmctld
  stop_daemon munged
}

start() {
  local b
  for b in munged mungekey slurmctld slurmd sinfo sbatch; do
    if ! command -v "$b" >/dev/null && [ ! -x "/usr/sbin/$b" ]; then
      say "'$b' not found: install Debian's slurm-wlm and munge (apt-get install slurm-wlm munge; tools/setup.sh does)"
      exit 1
    fi
  done
  export PATH="$PATH:/usr/sbin"
  if alive slurmctld || alive slurmd || alive munged; then
    say "a cluster is already running in $DIR (stop it first)"
    exit 1
  fi
  mkdir -p "$DIR"
  chmod 700 "$DIR"
  rm -rf "$DIR/munge" "$DIR/state" "$DIR/spool" "$DIR/log"
  mkdir -p "$DIR/munge" "$DIR/state" "$DIR/spool" "$DIR/log"
  chmod 700 "$DIR/munge"

  # munge: a fresh key, the daemon on a private socket
  mungekey --create --keyfile="$DIR/munge/munge.key" --force 2>/dev/null ||
    dd if=/dev/urandom of="$DIR/munge/munge.key" bs=1024 count=1 status=none
  chmod 600 "$DIR/munge/munge.key"
  munged -F --force --socket="$DIR/munge/socket" --key-file="$DIR/munge/munge.key" \
    --pid-file="$DIR/munge/munged.pid" --log-file="$DIR/log/munged.log" --seed-file="$DIR/munge/seed" \
    >"$DIR/log/munged.out" 2>&1 &
  echo $! >"$DIR/munged.pid"
  local i
  for i in $(seq 50); do
    [ -S "$DIR/munge/socket" ] && break
    alive munged || break
    sleep 0.1
  done
  if [ ! -S "$DIR/munge/socket" ]; then
    say "munged did not start"
    show_logs
    stop_all
    exit 1
  fi

  # slurm.conf for this host
  local host user node ctl_port d_port
  host=$(hostname -s)
  user=$(id -un)
  node=$(slurmd -C 2>/dev/null | head -n 1 | sed -e 's/^NodeName=[^ ]* //')
  if [ -z "$node" ]; then
    say "slurmd -C printed nothing"
    stop_all
    exit 1
  fi
  ctl_port=${FDEM_SLURMCTLD_PORT:-$(free_port)}
  d_port=${FDEM_SLURMD_PORT:-$(free_port)}
  : >"$DIR/plugstack.conf"
  cat >"$DIR/slurm.conf" <<EOF
# written by tools/slurm/local-cluster.sh: a private single-node cluster, everything under $DIR
ClusterName=fdemlocal
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctl_port
SlurmdPort=$d_port
SlurmUser=$user
SlurmdUser=$user
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$DIR/munge/socket
StateSaveLocation=$DIR/state
SlurmdSpoolDir=$DIR/spool/slurmd
SlurmctldPidFile=$DIR/state/slurmctld.pid
SlurmdPidFile=$DIR/spool/slurmd.pid
SlurmctldLogFile=$DIR/log/slurmctld.log
SlurmdLogFile=$DIR/log/slurmd.log
PlugStackConfig=$DIR/plugstack.conf
MailProg=/bin/true
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
SwitchType=switch/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
ReturnToService=2
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
# finished jobs stay visible to squeue -t all / scontrol for an hour (there is no accounting database)
MinJobAge=3600
KillWait=5
InactiveLimit=0
SlurmctldTimeout=30
SlurmdTimeout=60
NodeName=$host NodeAddr=127.0.0.1 $node State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
  export SLURM_CONF="$DIR/slurm.conf"

  local nice=${FDEM_SLURM_NICE:-0}
  nice -n "$nice" slurmctld -D -c -f "$SLURM_CONF" >"$DIR/log/slurmctld.out" 2>&1 &
  echo $! >"$DIR/slurmctld.pid"
  nice -n "$nice" slurmd -D -f "$SLURM_CONF" >"$DIR/log/slurmd.out" 2>&1 &
  echo $! >"$DIR/slurmd.pid"

  # ready when the node is idle (30 s at most)
  local state=""
  for i in $(seq 300); do
    if ! alive slurmctld || ! alive slurmd; then
      break
    fi
    state=$(sinfo -h -N -o %t 2>/dev/null | head -n 1 || true)
    case "$state" in idle | mix | alloc) break ;; esac
    sleep 0.1
  done
  case "$state" in
    idle | mix | alloc) ;;
    *)
      say "the cluster did not come up (node state '${state:-none}'; slurmctld $(alive slurmctld && echo running || echo stopped), slurmd $(alive slurmd && echo running || echo stopped))"
      show_logs
      stop_all
      exit 1
      ;;
  esac
  say "running in $DIR: node $host ($node), partition debug, slurmctld port $ctl_port, slurmd port $d_port"
  export_line
}

case "$cmd" in
  start) start ;;
  stop)
    cancel_jobs
    stop_all
    say "stopped ($DIR kept: logs in $DIR/log)"
    ;;
  env) export_line ;;
  status)
    export SLURM_CONF="$DIR/slurm.conf"
    sinfo
    ;;
  logs) show_logs 2>&1 ;;
  *)
    echo "usage: $0 start|stop|env|status|logs [DIR]" >&2
    exit 1
    ;;
esac
