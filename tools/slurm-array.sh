#!/usr/bin/env bash
# One level of a scene list per task of a Slurm job array (docs/farm.md). Submit it with one task
# per level, numbered from 0 like the list's levels:
#   sbatch --array=0-3 tools/slurm-array.sh levels.txt OUT CACHE [more bake options...]
# Task N bakes level N of levels.txt into OUT/NAME, sharing the precompute cache folder CACHE with
# the other tasks. $SNOWBAKE names the program (default: snowbake on the PATH).
#SBATCH --job-name=snowbake
#SBATCH --cpus-per-task=2
#SBATCH --output=snowbake-%A_%a.log
set -euo pipefail
if [ $# -lt 3 ] || [ -z "${SLURM_ARRAY_TASK_ID:-}" ]; then
  echo "usage: sbatch --array=0-N $0 LEVELS OUT CACHE [bake options]  (SLURM_ARRAY_TASK_ID picks the level)" >&2
  exit 2
fi
levels=$1 out=$2 cache=$3
shift 3
# Bytes do not depend on the thread count, so each task uses the CPUs Slurm gave it.
exec "${SNOWBAKE:-snowbake}" bake --scene-list "$levels" --index "$SLURM_ARRAY_TASK_ID" --out "$out" --cache-dir "$cache" \
  --threads "${SLURM_CPUS_PER_TASK:-0}" --quiet "$@"
