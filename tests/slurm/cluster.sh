#!/usr/bin/env bash
# A throwaway single-node Slurm cluster for the slurm tests, from Debian's slurm-wlm and munge:
# its own munge key and socket, config, state and spool directories and ports, all under DIR.
#   source tests/slurm/cluster.sh; cluster_start DIR; ...; cluster_stop
# cluster_start exports SLURM_CONF so sbatch, squeue, scontrol and scancel talk to it. The node
# offers 8 CPUs whatever the machine has (the test's jobs are small; the machine's cores are shared).
cluster_start() {
  local dir=$1 host port
  host=$(hostname -s)
  mkdir -p "$dir/state" "$dir/spool"
  head -c 1024 /dev/urandom > "$dir/munge.key"
  chmod 400 "$dir/munge.key"
  munged --force --key-file="$dir/munge.key" --socket="$dir/munge.sock" --pid-file="$dir/munged.pid" \
    --log-file="$dir/munged.log" --seed-file="$dir/munge.seed"
  port=$(( 20000 + RANDOM % 20000 ))
  cat > "$dir/slurm.conf" <<CONF
ClusterName=qte-test
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=$(id -un)
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$dir/munge.sock
CredType=cred/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SwitchType=switch/none
MpiDefault=none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
ReturnToService=2
SlurmdParameters=config_overrides
SchedulerParameters=defer_batch
MinJobAge=600
NodeName=$host NodeAddr=127.0.0.1 CPUs=8 RealMemory=16000 State=UNKNOWN
PartitionName=test Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
  export SLURM_CONF=$dir/slurm.conf CLUSTER_DIR=$dir
  slurmctld -f "$SLURM_CONF"
  slurmd -f "$SLURM_CONF"
  for _ in $(seq 1 60); do
    sinfo -h -o %T 2>/dev/null | grep -q '^idle' && return 0
    sleep 1
  done
  echo "the test cluster did not come up: $(tail -3 "$dir/slurmctld.log" "$dir/slurmd.log")" >&2
  return 1
}

cluster_stop() {
  local f
  scancel --user "$(id -un)" 2>/dev/null || true
  for f in slurmd slurmctld munged; do
    [ -f "$CLUSTER_DIR/$f.pid" ] && kill "$(cat "$CLUSTER_DIR/$f.pid")" 2>/dev/null || true
  done
  sleep 1
}
