#!/usr/bin/env bash
# The Slurm job array of docs/farm.md on a real, single-node Slurm that this test starts on
# localhost (munged with its own key and socket, slurmctld and slurmd in the foreground, a
# generated slurm.conf, every file in a temporary folder) and stops at the end, also on failure.
# tools/slurm-array.sh bakes four different levels sharing one cache folder as a four-task
# array; every output must equal, byte for byte, the same level baked alone outside Slurm.
#   tests/farm/slurm_array_test.sh SNOWBAKE_BINARY
# Exit 0 passed, 1 failed, 77 skipped (Slurm or munge missing, or their daemons cannot start).
set -euo pipefail
snowbake=$(realpath "$1")
source_dir=$(cd "$(dirname "$0")/../.." && pwd)
export SNOWBAKE=$snowbake

skip() { echo "SKIPPED: $*"; exit 77; }
fail() { echo "FAILED: $*"; exit 1; }
for tool in munged munge slurmctld slurmd sbatch squeue scontrol sinfo python3; do
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

# Four levels: different grids and terrains; the last two share their terrain (so their
# precompute keys) and differ in seed, so two tasks read and write the same entries.
write_levels() {
  local common="season.days=20 outputs.frames_days=[] parameters.avalanche_rate_per_km2_per_day=0"
  cat >"$work/levels.txt" <<EOF
# name  scene           overrides
ridge   preset:default  terrain.size=64  terrain.seed=11 $common
valley  preset:default  terrain.size=96  terrain.seed=12 $common
plateau preset:default  terrain.size=128 terrain.seed=13 $common
twin    preset:default  terrain.size=128 terrain.seed=13 run.seed=7 $common
EOF
}

# Submits the array and waits for it; every task must complete with exit status 0.
run_array() {
  local t0=$SECONDS
  job=$(cd "$work" && sbatch --parsable --array=0-3 --cpus-per-task=1 --output="$work/logs/%A_%a.out" \
    "$source_dir/tools/slurm-array.sh" levels.txt farm cache)
  wait_for 300 sh -c "[ -z \"\$(squeue -h -j $job 2>/dev/null)\" ]" || fail "the array $job did not finish within 300 s"
  local states
  states=$(scontrol show job "$job" | grep -o 'JobState=[A-Z]* .*\|ExitCode=[0-9:]*' | tr '\n' ' ')
  [ "$(scontrol show job "$job" | grep -c 'JobState=COMPLETED')" -eq 4 ] || fail "not every task completed: $states"
  [ "$(scontrol show job "$job" | grep -c 'ExitCode=0:0')" -eq 4 ] || fail "a task failed: $states"
  echo "array $job: 4 tasks completed in $((SECONDS - t0)) s"
}

# Each level baked alone, outside Slurm, by the same script with an empty cache: the same
# command line, so every file (manifest included, but for its measured peak) must be the same bytes.
compare_with_levels_alone() {
  mv "$work/farm" "$work/farm.slurm"
  mv "$work/cache" "$work/cache.slurm"
  "$snowbake" cache check --cache-dir "$work/cache.slurm" || fail "a damaged cache entry after the array"
  local entries
  entries=$(find "$work/cache.slurm" -name '*.bin' | wc -l)
  [ "$entries" -eq 6 ] || fail "$entries cache entries, expected 6 (exposure and wind for 3 distinct terrains)"
  for index in 0 1 2 3; do
    rm -rf "$work/cache"
    (cd "$work" && SLURM_ARRAY_TASK_ID=$index SLURM_CPUS_PER_TASK=1 bash "$source_dir/tools/slurm-array.sh" levels.txt farm cache) 2>"$work/alone-$index.log" ||
      fail "level $index alone: $(tail -n 2 "$work/alone-$index.log")"
  done
  # The manifests' "memory" line holds the measured peak, the one line two runs may differ in.
  find "$work/farm.slurm" "$work/farm" -name manifest.json -exec sed -i '/^  "memory": /d' {} +
  diff -r "$work/farm.slurm" "$work/farm" || fail "the array's outputs differ from the levels baked alone"
  local files
  files=$(find "$work/farm" -type f | wc -l)
  cmp -s "$work/farm/plateau/depth.exr" "$work/farm/twin/depth.exr" && fail "plateau and twin baked the same depth: not different levels"
  echo "4 levels, $files files, every one equal to its level baked alone; $entries valid cache entries shared"
}

start_munge
write_slurm_conf
start_slurm
write_levels
run_array
compare_with_levels_alone
