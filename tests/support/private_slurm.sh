#!/usr/bin/env bash
# A private single-node Slurm cluster on 127.0.0.1, for tests and benches,
# everything inside one folder: munged with its own key and socket, slurmctld
# and slurmd with a generated slurm.conf, their state, spool, logs and pid files.
#
#   private_slurm.sh start DIR   prints SLURM_CONF=DIR/slurm.conf once the node is idle;
#                                exit 77 with the reason on stderr where it cannot run
#                                (not root, Slurm or munge not installed: scripts/install-deps)
#   private_slurm.sh stop DIR    cancels every job of the cluster, then stops slurmd,
#                                slurmctld and munged by the pids in DIR/run/ and waits for them
#
# The recipe (Debian 12: Slurm 22.05, munge 0.5.15; starts in about a second,
# no systemd, no cgroups):
#   - munged --socket, --key-file, --pid-file, --log-file, --seed-file all in DIR;
#     the socket's folder must be searchable by all (0755), the key's private (0700);
#     slurm.conf's AuthInfo=socket=... points Slurm at that socket.
#   - ProctrackType=proctrack/linuxproc, TaskPlugin=task/none,
#     JobAcctGatherType=jobacct_gather/none: no cgroups needed.
#   - CommunicationParameters=NoCtldInAddrAny,NoInAddrAny with
#     SlurmctldHost=<short hostname>(127.0.0.1) and NodeAddr=127.0.0.1: loopback only.
#   - free ports (none of /proc/net/tcp*) for SlurmctldPort and SlurmdPort.
#   - SlurmUser=root (jobs run as the submitting user; root here).
#   - NodeName=<short hostname> with CPUs from nproc, RealMemory 90 % of MemTotal,
#     SlurmdParameters=config_overrides (the node's config counts, so a container
#     that shows more hardware than nproc does not drain the node).
#   - SelectType=select/cons_tres with CR_Core: jobs share the node by cores.
# Commands pointed at it with SLURM_CONF=DIR/slurm.conf talk to it alone.
set -euo pipefail

skip() {
  echo "private_slurm: cannot run here: $*" >&2
  exit 77
}

# A TCP port no socket on this machine uses, other than those in $1.
free_port() {
  local used=" $1 " port
  local line
  for table in /proc/net/tcp /proc/net/tcp6; do
    [ -r "$table" ] || continue
    while read -r _ line _; do
      [[ $line == *:* ]] || continue
      used+="$((16#${line##*:})) "
    done < "$table"
  done
  while :; do
    port=$((20000 + RANDOM % 30000))
    [[ $used == *" $port "* ]] || { echo "$port"; return; }
  done
}

# True while process $1 runs (a zombie does not).
runs() {
  local state
  state=$(awk '{print $3}' "/proc/$1/stat" 2>/dev/null) || return 1
  [ -n "$state" ] && [ "$state" != Z ] && [ "$state" != X ]
}

start() {
  local dir=$1
  [ "$(id -u)" -eq 0 ] || skip "not root (slurmd must run as root to start jobs)"
  local program
  for program in munged mungekey slurmctld slurmd sbatch squeue scontrol scancel sinfo; do
    command -v "$program" >/dev/null 2>&1 ||
      skip "$program is not installed (scripts/install-deps installs slurmctld slurmd slurm-client munge)"
  done
  mkdir -p "$dir"
  dir=$(cd "$dir" && pwd)
  mkdir -p "$dir/munge" "$dir/run" "$dir/state" "$dir/spool" "$dir/log"
  chmod 0755 "$dir" "$dir/run"
  chmod 0700 "$dir/munge"
  mungekey --create --keyfile="$dir/munge/munge.key" --force
  munged --socket="$dir/run/munge.sock" --key-file="$dir/munge/munge.key" --pid-file="$dir/run/munged.pid" \
    --log-file="$dir/log/munged.log" --seed-file="$dir/munge/munged.seed"

  local host ctld_port slurmd_port memory_mb
  host=$(hostname -s)
  ctld_port=$(free_port "")
  slurmd_port=$(free_port "$ctld_port")
  memory_mb=$(awk '/^MemTotal:/ {print int($2 / 1024 * 0.9)}' /proc/meminfo)
  cat > "$dir/slurm.conf" <<EOF
ClusterName=hairrigtest
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
CommunicationParameters=NoCtldInAddrAny,NoInAddrAny
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$dir/run/munge.sock
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/run/slurmctld.pid
SlurmdPidFile=$dir/run/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SlurmdParameters=config_overrides
ReturnToService=2
MpiDefault=none
MailProg=/bin/true
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) RealMemory=$memory_mb State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF
  export SLURM_CONF="$dir/slurm.conf"
  slurmctld -f "$SLURM_CONF"
  slurmd -f "$SLURM_CONF" -N "$host"
  local _
  for _ in $(seq 1 100); do
    if [ "$(sinfo --noheader --nodes="$host" --format=%T 2>/dev/null)" = idle ]; then
      echo "SLURM_CONF=$SLURM_CONF"
      return 0
    fi
    sleep 0.2
  done
  echo "private_slurm: the node did not become idle in 20 s; the logs in $dir/log say why:" >&2
  tail -n 20 "$dir"/log/*.log >&2 || true
  stop "$dir"
  return 1
}

stop() {
  local dir=$1
  export SLURM_CONF="$dir/slurm.conf"
  if [ -f "$dir/run/slurmctld.pid" ] && runs "$(cat "$dir/run/slurmctld.pid")"; then
    scancel --user="$(id -un)" 2>/dev/null || true
    local _
    for _ in $(seq 1 50); do
      [ -z "$(squeue --noheader --user="$(id -un)" 2>/dev/null)" ] && break
      sleep 0.2
    done
  fi
  local daemon pid
  for daemon in slurmd slurmctld munged; do
    [ -f "$dir/run/$daemon.pid" ] || continue
    pid=$(cat "$dir/run/$daemon.pid")
    runs "$pid" || continue
    kill -TERM "$pid" 2>/dev/null || true
    for _ in $(seq 1 50); do
      runs "$pid" || break
      sleep 0.2
    done
    if runs "$pid"; then kill -KILL "$pid" 2>/dev/null || true; fi
  done
}

case "${1:-}" in
  start) start "${2:?usage: private_slurm.sh start DIR}" ;;
  stop) stop "${2:?usage: private_slurm.sh stop DIR}" ;;
  *)
    echo "usage: private_slurm.sh start|stop DIR" >&2
    exit 2
    ;;
esac
