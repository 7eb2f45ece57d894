#!/usr/bin/env bash
# The Slurm job array of docs/farm.md on a real, single-node Slurm that this test starts on
# localhost and stops at the end, also on failure (tests/farm/local_slurm.sh).
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

source "$source_dir/tests/farm/local_slurm.sh"

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
