# A real, single-node Slurm on localhost for a test, sourced by the tests that need one
# (tests/farm/slurm_array_test.sh, tests/distributed/srun_bake_test.sh): munged with its own key
# and socket, slurmctld and slurmd in the foreground, a generated slurm.conf, every file in a
# temporary folder $work, all stopped and removed at exit, also on failure. The sourcing test
# defines skip and fail, and may set $job (scancelled at exit). Then:
#   start_munge; write_slurm_conf; start_slurm
for tool in munged munge slurmctld slurmd sbatch srun squeue scontrol sinfo python3; do
  command -v "$tool" >/dev/null || skip "$tool is not installed (tools/setup-debian.sh installs slurm-wlm and munge)"
done

work=$(mktemp -d /tmp/snowbake-slurm.XXXXXX)
chmod 755 "$work"  # munged wants its socket's folders open to everyone (x)
pids=()
stop_all() {
  local status=$?
  [ -n "${job:-}" ] && scancel "$job" 2>/dev/null || true
  for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done
  for pid in "${pids[@]}"; do wait "$pid" 2>/dev/null || true; done
  if [ "$status" -ne 0 ]; then
    for log in "$work"/*.log "$work"/logs/*; do [ -f "$log" ] && { echo "--- $log"; tail -n 20 "$log"; }; done
  fi
  rm -rf "$work"
}
trap stop_all EXIT

# Waits up to $1 seconds for the command after it to succeed.
wait_for() {
  local seconds=$1
  shift
  for _ in $(seq $((seconds * 5))); do "$@" >/dev/null 2>&1 && return 0; sleep 0.2; done
  return 1
}

start_munge() {
  mkdir -m 700 "$work/munge"
  dd if=/dev/urandom of="$work/munge/munge.key" bs=1024 count=1 status=none
  chmod 400 "$work/munge/munge.key"
  munged -F -f --key-file="$work/munge/munge.key" --socket="$work/munge/socket" --pid-file="$work/munge/pid" \
    --log-file="$work/munged.log" --seed-file="$work/munge/seed" >>"$work/munged.log" 2>&1 &
  pids+=($!)
  wait_for 10 sh -c "munge -n -S '$work/munge/socket' | unmunge -S '$work/munge/socket'" || skip "munged does not start ($work/munged.log)"
}

write_slurm_conf() {
  local ports user memory_mb
  ports=$(python3 -c 'import socket
s=[socket.socket() for _ in range(2)]
[x.bind(("127.0.0.1",0)) for x in s]
print(*[x.getsockname()[1] for x in s])')
  user=$(id -un)
  memory_mb=$(($(awk '/MemTotal/ {print $2}' /proc/meminfo) * 9 / 10 / 1024))  # under what slurmd finds, or it drains the node
  mkdir -p "$work/state" "$work/spool" "$work/logs"
  cat >"$work/slurm.conf" <<EOF
ClusterName=snowbaketest
SlurmctldHost=localhost(127.0.0.1)
SlurmctldPort=${ports% *}
SlurmdPort=${ports#* }
AuthType=auth/munge
AuthInfo=socket=$work/munge/socket
CredType=cred/munge
SlurmUser=$user
SlurmdUser=$user
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/builtin
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
ReturnToService=2
MinJobAge=600
NodeName=localhost NodeAddr=127.0.0.1 CPUs=$(nproc) RealMemory=$memory_mb State=UNKNOWN
PartitionName=snowbake Nodes=localhost Default=YES MaxTime=INFINITE State=UP
EOF
  export SLURM_CONF=$work/slurm.conf
}

start_slurm() {
  slurmctld -D -i -f "$SLURM_CONF" >>"$work/slurmctld.log" 2>&1 &
  pids+=($!)
  slurmd -D -N localhost -f "$SLURM_CONF" >>"$work/slurmd.log" 2>&1 &
  pids+=($!)
  wait_for 30 sh -c 'sinfo -h -n localhost -o %t | grep -qx idle' || skip "slurmctld and slurmd do not start (logs in $work: $(tail -n 3 "$work/slurmd.log" | tr '\n' ' '))"
}

