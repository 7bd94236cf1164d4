#!/usr/bin/env bash
# A single-node Slurm cluster on localhost, for the farm tests and for trying `render farm`.
#
#   scripts/slurm-local.sh up     start munged, slurmctld and slurmd; print the `export` lines
#                                 that point a shell at the cluster (eval "$(… up)")
#   scripts/slurm-local.sh down   stop the daemons by the PIDs `up` recorded, remove the folder
#                                 if `up` made it
#
# Needs Debian's slurm-wlm and munge (apt-get install slurm-wlm munge); nothing of them is
# configured system-wide: everything (munge key and socket, slurm.conf, state, logs, PID
# files) lives in one folder, $SLURM_LOCAL_DIR if set, else a new temporary folder whose path
# `up` records in /tmp/trilux-slurm-local.dir for `down`. No systemd: the daemons are started
# directly. The node is `localhost` with 2 CPUs and this machine's memory; jobs run as the user
# who ran `up` (root in CI). Settings worth knowing:
#   ProctrackType=proctrack/linuxproc, TaskPlugin=task/none: no cgroups needed;
#   MinJobAge=4: a finished job leaves the controller's tables quickly, so `sbatch --wait`
#     notices the end within seconds;
#   CommunicationParameters=NoInAddrAny: the daemons listen on localhost only.
# Ports: 6817 (slurmctld) and 6818 (slurmd), or $SLURM_LOCAL_PORT and the one above it.
set -euo pipefail

record=/tmp/trilux-slurm-local.dir

die() {
  echo "slurm-local: $*" >&2
  exit 1
}

up() {
  for cmd in munged mungekey slurmctld slurmd sinfo; do
    command -v "$cmd" >/dev/null || die "$cmd not found: apt-get install slurm-wlm munge"
  done
  local dir made=0
  if [ -n "${SLURM_LOCAL_DIR:-}" ]; then
    dir=$SLURM_LOCAL_DIR
    mkdir -p "$dir"
  else
    dir=$(mktemp -d /tmp/trilux-slurm.XXXXXX)
    made=1
  fi
  dir=$(cd "$dir" && pwd)
  [ ! -e "$dir/slurmctld.pid" ] || die "$dir already has a cluster: run '$0 down' first"
  echo "$dir $made" >"$record"
  # munged checks that the folders above its files are not writable by others.
  chmod 700 "$dir"
  mkdir -p "$dir/munge" "$dir/state" "$dir/spool"
  chmod 700 "$dir/munge"
  mungekey --create --keyfile="$dir/munge/munge.key" --force >/dev/null 2>&1 ||
    { dd if=/dev/urandom of="$dir/munge/munge.key" bs=1 count=1024 2>/dev/null; }
  chmod 600 "$dir/munge/munge.key"
  munged --force --socket="$dir/munge/munge.socket" --key-file="$dir/munge/munge.key" \
    --pid-file="$dir/munged.pid" --log-file="$dir/munged.log" --seed-file="$dir/munge/seed" \
    || die "munged did not start (see $dir/munged.log)"

  local port=${SLURM_LOCAL_PORT:-6817}
  local user memory
  user=$(id -un)
  memory=$(awk '/^MemTotal:/ { printf "%d", $2 / 1024 * 0.9 }' /proc/meminfo)
  cat >"$dir/slurm.conf" <<EOF
ClusterName=trilux-local
SlurmctldHost=localhost
SlurmUser=$user
SlurmdUser=$user
AuthType=auth/munge
AuthInfo=socket=$dir/munge/munge.socket
CredType=cred/munge
SlurmctldPort=$port
SlurmdPort=$((port + 1))
CommunicationParameters=NoInAddrAny
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MinJobAge=4
ReturnToService=2
SlurmdTimeout=30
NodeName=localhost NodeAddr=127.0.0.1 CPUs=2 RealMemory=$memory State=UNKNOWN
PartitionName=local Nodes=localhost Default=YES MaxTime=INFINITE State=UP
EOF
  export SLURM_CONF=$dir/slurm.conf
  slurmctld -f "$SLURM_CONF" || die "slurmctld did not start (see $dir/slurmctld.log)"
  slurmd -f "$SLURM_CONF" -N localhost || die "slurmd did not start (see $dir/slurmd.log)"
  local state=""
  for _ in $(seq 1 60); do
    state=$(sinfo -h -n localhost -o %T 2>/dev/null || true)
    case "$state" in idle | mixed | allocated) break ;; esac
    sleep 0.5
  done
  case "$state" in
    idle | mixed | allocated) ;;
    *) die "the node did not become idle in 30 s (state '${state:-none}'; logs in $dir)" ;;
  esac
  echo "export SLURM_CONF=$dir/slurm.conf"
  echo "export SLURM_LOCAL_DIR=$dir"
}

down() {
  local dir made=0
  if [ -n "${SLURM_LOCAL_DIR:-}" ]; then
    dir=$SLURM_LOCAL_DIR
    [ -f "$record" ] && [ "$(cut -d' ' -f1 "$record")" = "$dir" ] && made=$(cut -d' ' -f2 "$record")
  elif [ -f "$record" ]; then
    read -r dir made <"$record"
  else
    die "no cluster recorded: set SLURM_LOCAL_DIR to the folder 'up' used"
  fi
  local pidfile pid
  for pidfile in "$dir/slurmd.pid" "$dir/slurmctld.pid" "$dir/munged.pid"; do
    [ -f "$pidfile" ] || continue
    pid=$(cat "$pidfile")
    kill "$pid" 2>/dev/null || true
    for _ in $(seq 1 50); do
      kill -0 "$pid" 2>/dev/null || break
      sleep 0.1
    done
    kill -9 "$pid" 2>/dev/null || true
    rm -f "$pidfile"
  done
  rm -f "$record"
  [ "$made" = 1 ] && rm -rf "$dir"
  return 0
}

case "${1:-}" in
  up) up ;;
  down) down ;;
  *) die "usage: $0 up|down" ;;
esac
