#!/usr/bin/env bash
# A bake across ranks launched by Slurm (docs/distributed.md): `srun --mpi=pmix -n N snowbake
# bake`, N = 2 and 4 (4 overcommitted on this node's cores), on a single-node Slurm the test starts
# on localhost and stops at the end (tests/farm/local_slurm.sh). Every file must equal the bake
# of one process outside Slurm, byte for byte (the manifest but for its measured memory); srun
# without an MPI plugin fails, writing nothing (OpenMPI refuses to start; an MPI that made each
# task a world of one would meet snowbake's own refusal).
#   tests/distributed/srun_bake_test.sh SNOWBAKE_BINARY
# Exit 0 passed, 1 failed, 77 skipped (Slurm, munge or Slurm's PMIx plugin missing, or their
# daemons cannot start).
set -euo pipefail
snowbake=$(realpath "$1")
source_dir=$(cd "$(dirname "$0")/../.." && pwd)

skip() { echo "SKIPPED: $*"; exit 77; }
fail() { echo "FAILED: $*"; exit 1; }

source "$source_dir/tests/farm/local_slurm.sh"

args=(bake preset:default --set terrain.size=96 --set season.days=30 --set 'outputs.frames_days=[15]'
      --no-cache --quiet --threads 1 --out out)

# same DIR: every file of alone/out in DIR/out with the same bytes, and no other.
same() {
  local dir="$1"
  find "$work/alone/out" "$dir/out" -name manifest.json -exec sed -i '/^  "memory": /d' {} +
  diff -r "$work/alone/out" "$dir/out" || fail "$dir: the files differ from the single process's"
}

start_munge
write_slurm_conf
start_slurm
srun --mpi=list 2>&1 | grep -q pmix || skip "Slurm has no PMIx plugin (srun --mpi=list)"

mkdir -p "$work/alone"
(cd "$work/alone" && "$snowbake" "${args[@]}" > log 2>&1) || fail "the single-process bake: $(tail -n 3 "$work/alone/log")"
for ranks in 2 4; do
  mkdir -p "$work/srun$ranks"
  (cd "$work/srun$ranks" && srun --mpi=pmix --overcommit -n "$ranks" --time=5 "$snowbake" "${args[@]}" > log 2>&1) ||
    fail "srun -n $ranks: $(tail -n 5 "$work/srun$ranks/log")"
  grep -q "season: across $ranks ranks" "$work/srun$ranks/log" || fail "srun -n $ranks: the season did not run across the ranks"
  same "$work/srun$ranks"
  echo "srun --mpi=pmix -n $ranks: $(find "$work/srun$ranks/out" -type f | wc -l) files, each the single process's bytes"
done

# Without --mpi=pmix the tasks cannot join one MPI world: no bake, nothing written.
mkdir -p "$work/nompi"
status=0
(cd "$work/nompi" && srun --mpi=none -n 2 --time=5 "$snowbake" "${args[@]}" > log 2>&1) || status=$?
[ "$status" -ne 0 ] || fail "srun --mpi=none -n 2 baked"
grep -q "MPI joined 1\|MPI_Init" "$work/nompi/log" || fail "srun --mpi=none -n 2: no message about MPI: $(cat "$work/nompi/log")"
[ ! -e "$work/nompi/out" ] || fail "srun --mpi=none -n 2 wrote an output folder"
echo "srun --mpi=none -n 2: refused (exit $status)"
