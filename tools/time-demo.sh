#!/usr/bin/env bash
# The demo's run time (README): `snowbake bake preset:default --no-cache` RUNS times, one after the
# other; each run's wall and CPU seconds (GNU time, which tools/setup-debian.sh installs), the
# season's and the avalanches' seconds, the avalanches and their steps (from the log), then each
# column's range.
#   tools/time-demo.sh [BUILD=build] [RUNS=3] [KEY=VALUE ...]   (extra arguments: scene keys, as --set)
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build}" runs="${2:-3}"
shift $(($# < 2 ? $# : 2))
sets=()
for kv in "$@"; do sets+=(--set "$kv"); done
bin="$(realpath "$build/snowbake")"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
echo "the demo (preset:default${*:+ $*}), --no-cache, $runs runs; $(nproc) cores: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 |
  sed 's/^ //'), load average $(cut -d' ' -f1 /proc/loadavg) at the start; commit $(git rev-parse --short HEAD)"
echo "| run | wall s | CPU s | season s | avalanches s | avalanches | avalanche steps |"
echo "|---|---|---|---|---|---|---|"
for run in $(seq 1 "$runs"); do
  /usr/bin/time -f '%e %U %S' -o "$work/time" "$bin" bake preset:default "${sets[@]}" --no-cache --quiet --out "$work/out" > "$work/log" 2>&1
  read -r wall user sys < "$work/time"
  season="$(sed -n 's/^season: .* (\([0-9.]*\) s)$/\1/p' "$work/log")"
  aval="$(sed -n 's/^  avalanche  *[0-9]* steps  *\([0-9.]*\) s$/\1/p' "$work/log")"
  count="$(grep -c '^  avalanche day' "$work/log" || true)"
  steps="$(sed -n 's/^  avalanche  *\([0-9]*\) steps .*$/\1/p' "$work/log")"
  printf '| %s | %s | %.2f | %s | %s | %s | %s |\n' "$run" "$wall" "$(awk -v u="$user" -v s="$sys" 'BEGIN { print u + s }')" "${season:--}" \
    "${aval:--}" "$count" "${steps:--}" | tee -a "$work/rows"
  rm -rf "$work/out"
done
awk -F'|' '{ for (c = 3; c <= 6; ++c) { v = $c + 0; if (NR == 1 || v < lo[c]) lo[c] = v; if (NR == 1 || v > hi[c]) hi[c] = v } }
  END { printf "ranges: wall %.2f-%.2f s, CPU %.2f-%.2f s, season %.2f-%.2f s, avalanches %.2f-%.2f s\n", lo[3], hi[3], lo[4], hi[4], lo[5], hi[5], lo[6], hi[6] }' "$work/rows"
