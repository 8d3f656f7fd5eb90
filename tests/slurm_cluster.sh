# A single-node Slurm cluster for tests and benchmarks, sourced (bash):
#   source tests/slurm_cluster.sh
#   slurm_cluster_check || exit 77      # prints why it cannot run (not root, not installed)
#   trap slurm_cluster_stop EXIT
#   slurm_cluster_start "$TMPDIR_OF_YOURS"  # exports SLURM_CONF; waits for an idle node
# munged runs with a private 0600 key and its socket in a 0755 directory; slurmctld and
# slurmd run in the foreground (-D) as root with a temp slurm.conf on two free ports
# (settings measured on Debian 12's slurm-wlm 22.05); every daemon is stopped by its PID.
SLURM_CLUSTER_PIDS=()

slurm_cluster_check() {
  PATH=$PATH:/usr/sbin:/sbin
  if [ "$(id -u)" -ne 0 ]; then
    echo "not root: this single-node cluster runs slurmctld/slurmd as SlurmUser=root and munged with a root-owned key"
    return 1
  fi
  local b
  for b in munged slurmctld slurmd sbatch squeue scontrol sinfo; do
    command -v "$b" >/dev/null || { echo "$b not installed (Debian: slurm-wlm munge; scripts/setup.sh installs them)"; return 1; }
  done
}

slurm_cluster_stop() {
  local p
  for p in "${SLURM_CLUSTER_PIDS[@]}"; do kill "$p" 2>/dev/null || true; done
  for p in "${SLURM_CLUSTER_PIDS[@]}"; do
    for _ in $(seq 50); do kill -0 "$p" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$p" 2>/dev/null || true
  done
  SLURM_CLUSTER_PIDS=()
}

slurm_cluster_start() {
  local T=$1
  chmod 0755 "$T"
  mkdir -p "$T/munge" "$T/state" "$T/spool" && chmod 0755 "$T/munge"
  head -c 1024 /dev/urandom > "$T/munge/munge.key" && chmod 0600 "$T/munge/munge.key"
  munged -F --key-file="$T/munge/munge.key" --socket="$T/munge/munge.socket" --pid-file="$T/munge/munged.pid" \
    --log-file="$T/munge/munged.log" --seed-file="$T/munge/munged.seed" --num-threads=2 >"$T/munged.out" 2>&1 &
  SLURM_CLUSTER_PIDS+=($!)
  local ctld_port slurmd_port host
  read -r ctld_port slurmd_port < <(python3 -c '
import socket
s=[socket.socket() for _ in range(2)]
for x in s: x.bind(("127.0.0.1",0))
print(*[x.getsockname()[1] for x in s])')
  host=$(hostname -s)
  export SLURM_CONF="$T/slurm.conf"
  cat > "$SLURM_CONF" <<CONF
ClusterName=skycaltest
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$T/munge/munge.socket
StateSaveLocation=$T/state
SlurmdSpoolDir=$T/spool
SlurmctldPidFile=$T/slurmctld.pid
SlurmdPidFile=$T/slurmd.pid
SlurmctldLogFile=$T/slurmctld.log
SlurmdLogFile=$T/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/filetxt
JobCompLoc=$T/jobcomp.txt
SchedulerParameters=batch_sched_delay=0
DependencyParameters=kill_invalid_depend
MailProg=/bin/true
ReturnToService=2
MinJobAge=600
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
  slurmctld -D -i >"$T/slurmctld.out" 2>&1 &
  SLURM_CLUSTER_PIDS+=($!)
  slurmd -D >"$T/slurmd.out" 2>&1 &
  SLURM_CLUSTER_PIDS+=($!)
  local i
  for i in $(seq 100); do
    sinfo -h -o %t 2>/dev/null | grep -q idle && return 0
    sleep 0.2
  done
  echo "the Slurm node never became idle:"; sinfo || true
  tail -n 20 "$T/slurmctld.log" "$T/slurmd.log" 2>/dev/null || true
  return 1
}
