#!/usr/bin/env bash
# slurm-cluster.sh start|stop DIR - a one-node Slurm cluster on this machine for the tests, from
# Debian's slurm-wlm and munge: munged with its own key and socket, slurmctld and slurmd as root on
# 127.0.0.1 with free ports, every file (configuration, state, spool, logs, pids) in DIR. No system
# service is touched.
#
#   bash scripts/slurm-cluster.sh start /tmp/vff-slurm   # prints SLURM_CONF=DIR/slurm.conf once the node is idle
#   SLURM_CONF=/tmp/vff-slurm/slurm.conf sbatch ...
#   bash scripts/slurm-cluster.sh stop /tmp/vff-slurm    # cancels the jobs, ends the daemons it started
#
# `stop` ends exactly the processes `start` recorded in DIR/pids (and the jobs of this cluster), so
# it is safe after a failed start and when run twice.
set -euo pipefail

cmd=${1:-}
dir=${2:-}
[[ ($cmd == start || $cmd == stop) && -n $dir ]] || { echo "usage: $0 start|stop DIR" >&2; exit 1; }

stop_cluster() {
  if [[ -f $dir/slurm.conf ]] && command -v scancel >/dev/null; then
    SLURM_CONF=$dir/slurm.conf timeout 10 scancel --user "$(id -un)" >/dev/null 2>&1 || true
    for _ in $(seq 20); do
      [[ -z $(SLURM_CONF=$dir/slurm.conf timeout 5 squeue -h 2>/dev/null) ]] && break
      sleep 0.5
    done
  fi
  if [[ -f $dir/pids ]]; then
    local pid
    # Daemons first (slurmd, slurmctld), munged last: they authenticate through it until the end.
    for pid in $(tac "$dir/pids"); do
      kill "$pid" 2>/dev/null || true
    done
    for _ in $(seq 20); do
      local alive=0
      for pid in $(cat "$dir/pids"); do kill -0 "$pid" 2>/dev/null && alive=1; done
      [[ $alive == 0 ]] && break
      sleep 0.25
    done
    for pid in $(cat "$dir/pids"); do kill -9 "$pid" 2>/dev/null || true; done
    rm -f "$dir/pids"
  fi
}

if [[ $cmd == stop ]]; then
  stop_cluster
  exit 0
fi

for p in munged slurmctld slurmd sbatch; do
  command -v $p >/dev/null || { echo "slurm-cluster: error: $p is not installed (apt-get install slurm-wlm munge)" >&2; exit 5; }
done
mkdir -p "$dir"/{munge,state,spool,log}
dir=$(cd "$dir" && pwd)
trap 'status=$?; [[ $status == 0 ]] || { echo "slurm-cluster: error: start failed; logs in $dir/log" >&2; stop_cluster; }' EXIT

# Two free TCP ports on 127.0.0.1.
read -r ctld_port slurmd_port < <(python3 -c '
import socket
s = [socket.socket() for _ in range(2)]
for x in s: x.bind(("127.0.0.1", 0))
print(*[x.getsockname()[1] for x in s])')

# munge: its own key (1024 random bytes, mode 400) and socket.
head -c 1024 /dev/urandom >"$dir/munge/munge.key"
chmod 400 "$dir/munge/munge.key"
chmod 700 "$dir/munge"
munged --force --key-file="$dir/munge/munge.key" --socket="$dir/munge/munge.socket" \
  --pid-file="$dir/munge/munged.pid" --log-file="$dir/log/munged.log" --seed-file="$dir/munge/munged.seed"
for _ in $(seq 50); do [[ -s $dir/munge/munged.pid ]] && break; sleep 0.1; done
cat "$dir/munge/munged.pid" >>"$dir/pids"

cat >"$dir/slurm.conf" <<EOF
ClusterName=vfftest
SlurmctldHost=localhost(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
AuthType=auth/munge
AuthInfo=socket=$dir/munge/munge.socket
CredType=cred/munge
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/builtin
ReturnToService=2
MinJobAge=2
NodeName=localhost NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=vff Nodes=localhost Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF=$dir/slurm.conf

slurmctld -D -f "$SLURM_CONF" >"$dir/log/slurmctld.out" 2>&1 &
echo $! >>"$dir/pids"
slurmd -D -N localhost -f "$SLURM_CONF" >"$dir/log/slurmd.out" 2>&1 &
echo $! >>"$dir/pids"

for _ in $(seq 120); do
  if sinfo -h -o '%t' 2>/dev/null | grep -q -E '^(idle|mix|alloc)'; then
    trap - EXIT
    echo "SLURM_CONF=$SLURM_CONF"
    exit 0
  fi
  sleep 0.5
done
echo "slurm-cluster: error: the node did not become idle within 60 s" >&2
exit 4
