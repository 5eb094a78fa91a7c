#!/usr/bin/env bash
# A single-node Slurm cluster on this machine, for tests and trials: Debian's slurm-wlm and
# munge, configured under a state folder of its own (nothing in /etc/slurm is touched).
#
#   scripts/slurm/cluster.sh install          # apt-get install slurm-wlm munge (root)
#   scripts/slurm/cluster.sh start [STATE]    # munged, slurmctld, slurmd; waits for the node
#   scripts/slurm/cluster.sh stop [STATE]     # stops what start started
#
# STATE defaults to /tmp/ppm-slurm. After start, `source STATE/env` points sbatch, squeue
# and sinfo at the cluster (SLURM_CONF). Needs root: slurmd runs jobs as their users.
set -euo pipefail

cmd=${1:-}
state=${2:-/tmp/ppm-slurm}

die() { echo "cluster.sh: $*" >&2; exit 1; }

install() {
  command -v slurmctld >/dev/null && command -v munged >/dev/null && return
  apt-get update
  DEBIAN_FRONTEND=noninteractive apt-get install -y slurm-wlm munge
}

start() {
  [[ $(id -u) == 0 ]] || die "start needs root (slurmd runs the jobs as their users)"
  command -v slurmctld >/dev/null || die "Slurm is not installed: run '$0 install' first"
  local host cpus memory
  host=$(hostname -s)
  cpus=$(nproc)
  memory=$(( $(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 / 2 ))
  mkdir -p "$state"/{ctld,spool,log,munge,munge-run,run}
  chmod 755 "$state"

  # munge: a key of this cluster's own, the daemon on a socket under STATE.
  if [[ ! -s $state/munge/munge.key ]]; then
    dd if=/dev/urandom of="$state/munge/munge.key" bs=1 count=1024 status=none
  fi
  # The key stays private to munge; the socket's folder is open to every user's jobs.
  chown -R munge:munge "$state/munge" "$state/munge-run"
  chmod 700 "$state/munge"
  chmod 755 "$state/munge-run"
  chmod 400 "$state/munge/munge.key"
  local socket=$state/munge-run/munge.socket
  runuser -u munge -- munged --key-file="$state/munge/munge.key" --socket="$socket" \
    --pid-file="$state/munge-run/munged.pid" --log-file="$state/munge/munged.log" \
    --seed-file="$state/munge/munge.seed"

  cat > "$state/slurm.conf" <<CONF
ClusterName=ppm
SlurmctldHost=$host
SlurmUser=root
AuthType=auth/munge
AuthInfo=socket=$socket
CredType=cred/munge
MpiDefault=none
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
StateSaveLocation=$state/ctld
SlurmdSpoolDir=$state/spool
SlurmctldPidFile=$state/run/slurmctld.pid
SlurmdPidFile=$state/run/slurmd.pid
SlurmctldLogFile=$state/log/slurmctld.log
SlurmdLogFile=$state/log/slurmd.log
NodeName=$host CPUs=$cpus RealMemory=$memory State=UNKNOWN
PartitionName=local Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
  echo "export SLURM_CONF=$state/slurm.conf" > "$state/env"
  export SLURM_CONF=$state/slurm.conf
  slurmctld -f "$SLURM_CONF"
  slurmd -f "$SLURM_CONF"
  for _ in $(seq 100); do
    if sinfo -h -o '%T' 2>/dev/null | grep -qE '^(idle|mixed|allocated)'; then
      echo "cluster.sh: node $host up with $cpus CPUs; source $state/env"
      return
    fi
    sleep 0.2
  done
  tail -n 20 "$state"/log/*.log >&2 || true
  die "the node did not come up (logs above, in $state/log)"
}

stop() {
  local pids=()
  for file in "$state/run/slurmd.pid" "$state/run/slurmctld.pid" "$state/munge-run/munged.pid"; do
    [[ -s $file ]] && pids+=("$(cat "$file")")
  done
  ((${#pids[@]})) || return 0
  kill "${pids[@]}" 2>/dev/null || true
  for _ in $(seq 50); do
    kill -0 "${pids[@]}" 2>/dev/null || return 0
    sleep 0.1
  done
  kill -9 "${pids[@]}" 2>/dev/null || true
}

case $cmd in
  install) install ;;
  start) start ;;
  stop) stop ;;
  *) die "usage: $0 install | start [STATE] | stop [STATE]" ;;
esac
