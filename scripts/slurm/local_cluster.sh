#!/usr/bin/env bash
# A real single-node SLURM cluster on this machine, for tests: its own munged, slurmctld and
# slurmd (Debian's munge and slurm-wlm), run as root, with every file under one directory.
#
#   scripts/slurm/local_cluster.sh start [DIR]   # installs munge + slurm-wlm if missing, writes
#                                                # DIR/slurm.conf, starts the daemons, waits until
#                                                # the node is idle; prints "export SLURM_CONF=..."
#   scripts/slurm/local_cluster.sh stop [DIR]    # stops the three daemons (by their pid files)
#   scripts/slurm/local_cluster.sh status [DIR]  # sinfo
#
# DIR defaults to /tmp/hypershape-slurm. The cluster is one node (this host, 127.0.0.1) with
# all its CPUs (at least 2), one partition `test`, ports SLURM_PORT and SLURM_PORT + 1 (default 6917/6918,
# away from a system SLURM's 6817/6818), munge on its own socket and key (nothing in /etc is
# used or changed). Process tracking by /proc and no task plugin: no cgroups are needed.
# sbatch/srun/squeue/sacct need SLURM_CONF=DIR/slurm.conf in the environment.
set -euo pipefail

cmd=${1:?usage: local_cluster.sh start|stop|status [DIR]}
DIR=${2:-/tmp/hypershape-slurm}
PORT=${SLURM_PORT:-6917}
PACKAGES=(munge slurm-wlm)

install_missing() {
  local missing=()
  for p in "${PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  ((${#missing[@]} == 0)) && return 0
  [ "$(id -u)" = 0 ] || { echo "local_cluster: run as root, or: apt-get install -y ${missing[*]}" >&2; exit 2; }
  echo "[local_cluster] installing: ${missing[*]}"
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null \
    || { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null; }
}

write_conf() {
  local host cpus mem
  host=$(hostname -s)
  # getconf, not nproc (nproc follows OMP_NUM_THREADS); at least 2, so that a 2-rank job runs
  # on a 1-core machine too (config_overrides lets slurmd accept more CPUs than it counts).
  cpus=$(getconf _NPROCESSORS_ONLN)
  ((cpus >= 2)) || cpus=2
  mem=$(( $(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 / 2 ))
  cat >"$DIR/slurm.conf" <<EOF
ClusterName=hypershape-test
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$PORT
SlurmdPort=$((PORT + 1))
SlurmUser=root
SlurmdUser=root
SlurmdParameters=config_overrides
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$DIR/munge/munge.socket
StateSaveLocation=$DIR/state
SlurmdSpoolDir=$DIR/spool
SlurmctldPidFile=$DIR/slurmctld.pid
SlurmdPidFile=$DIR/slurmd.pid
SlurmctldLogFile=$DIR/slurmctld.log
SlurmdLogFile=$DIR/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
InactiveLimit=0
KillWait=5
MinJobAge=600
SlurmctldTimeout=30
SlurmdTimeout=30
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=test Nodes=$host Default=YES MaxTime=INFINITE State=UP OverSubscribe=NO
EOF
}

start_munge() {
  mkdir -p "$DIR/munge"
  chmod 700 "$DIR/munge"
  [ -f "$DIR/munge/munge.key" ] || mungekey --create --keyfile="$DIR/munge/munge.key" >/dev/null
  munged --force --socket="$DIR/munge/munge.socket" --key-file="$DIR/munge/munge.key" \
    --pid-file="$DIR/munge/munged.pid" --log-file="$DIR/munge/munged.log" --seed-file="$DIR/munge/munged.seed"
}

wait_idle() {
  for _ in $(seq 60); do
    if sinfo -h -o '%t' 2>/dev/null | grep -qE '^(idle|mix|alloc)'; then return 0; fi
    sleep 0.5
  done
  echo "local_cluster: the node did not come up; logs in $DIR/slurmctld.log, $DIR/slurmd.log" >&2
  sinfo >&2 || true
  exit 1
}

stop_pidfile() {
  local f=$1
  [ -f "$f" ] || return 0
  local pid
  pid=$(cat "$f")
  if kill "$pid" 2>/dev/null; then
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.2; done
  fi
  rm -f "$f"
}

export SLURM_CONF=$DIR/slurm.conf
case $cmd in
  start)
    install_missing
    "$0" stop "$DIR"
    mkdir -p "$DIR/state" "$DIR/spool"
    write_conf
    start_munge
    slurmctld -f "$SLURM_CONF" -c   # -c: a clean start, no jobs from an earlier run
    slurmd -f "$SLURM_CONF"
    wait_idle
    echo "[local_cluster] up: $(sinfo -h -o '%P %D node(s) %c CPUs %t')"
    echo "export SLURM_CONF=$SLURM_CONF"
    ;;
  stop)
    stop_pidfile "$DIR/slurmd.pid"
    stop_pidfile "$DIR/slurmctld.pid"
    stop_pidfile "$DIR/munge/munged.pid"
    ;;
  status) sinfo ;;
  *) echo "usage: local_cluster.sh start|stop|status [DIR]" >&2; exit 2 ;;
esac
