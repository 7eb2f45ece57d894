#!/usr/bin/env bash
# A bake across ranks against one process (docs/distributed.md): the default preset with its
# avalanches and skiers off (the scenes a bake across ranks runs today), SIZE² cells of 10 m, DAYS
# days, baked alone (2 threads) and by `mpiexec -n N` (N = 2, 4; one thread a rank, oversubscribed
# past the cores), no cache. Prints each run's season and total seconds and its peak resident
# memory per process (the alone bake's manifest; a bake across ranks' log gathers every rank's),
# and checks that every output file has the single process's bytes.
#   tools/bench-distributed-bake.sh [BUILD=build] [SIZE=1024] [DAYS=30]
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build}" size="${2:-1024}" days="${3:-30}"
bin="$(realpath "$build/snowbake")"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
args=(bake preset:default --set "terrain.size=$size" --set "season.days=$days" --set 'outputs.frames_days=[]'
      --set parameters.avalanche_rate_per_km2_per_day=0 --set parameters.skiers_per_hour=0 --no-cache --quiet --out out)
echo "bake across ranks: the default preset without avalanches and skiers, ${size}^2 cells of 10 m, $days days;" \
     "$(nproc) cores: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'); commit $(git rev-parse --short HEAD)"
printf '| %s | %s | %s | %s | %s | %s |\n' ranks "threads/rank" "season s" "total s" "peak MiB per rank" "largest rank / one process"
echo "|---|---|---|---|---|---|"
one=""
for ranks in 1 2 4; do
  mkdir -p "$work/$ranks"
  if [ "$ranks" = 1 ]; then
    (cd "$work/1" && "$bin" "${args[@]}" --threads 2 > log 2>&1)
    peaks="$(grep -o '"measured_peak_mib": [0-9.]*' "$work/1/out/manifest.json" | grep -o '[0-9.]*$')"
    one="$peaks"
  else
    (cd "$work/$ranks" && mpiexec --oversubscribe -n "$ranks" "$bin" "${args[@]}" --threads 1 > log 2>&1)
    peaks="$(sed -n 's/^memory: peak resident per rank \(.*\) MiB$/\1/p' "$work/$ranks/log")"
    for f in $(cd "$work/1/out" && find . -type f ! -name manifest.json); do
      cmp -s "$work/1/out/$f" "$work/$ranks/out/$f" || { echo "bench-distributed-bake: $f differs on $ranks ranks" >&2; exit 1; }
    done
  fi
  season="$(sed -n 's/^season: .* on cpu (\([0-9.]*\) s)$/\1/p' "$work/$ranks/log")"
  total="$(sed -n 's/^total: \([0-9.]*\) s$/\1/p' "$work/$ranks/log")"
  largest="$(echo "$peaks" | tr ',' '\n' | sort -g | tail -1 | tr -d ' ')"
  printf '| %s | %s | %s | %s | %s | %s |\n' "$ranks" "$([ "$ranks" = 1 ] && echo 2 || echo 1)" "$season" "$total" "$peaks" \
    "$(awk -v a="$largest" -v b="$one" 'BEGIN { printf "%.2f", a / b }')"
done
