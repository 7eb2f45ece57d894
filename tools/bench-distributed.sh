#!/usr/bin/env bash
# The distributed decomposition's cost table (docs/distributed.md): bench/distributed_bench.cpp on
# 1, 2 and 4 ranks of this machine (oversubscribed where the ranks outnumber the cores).
#   tools/bench-distributed.sh [BUILD=build] [SIZE=2048] [STEPS=4]
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build}" size="${2:-2048}" steps="${3:-4}"
cmake --build "$build" --target distributed_bench > /dev/null
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
echo "distributed_bench: ${size}^2 default range, 10 m cells, half-day steps, ${steps} steps; $(nproc) cores: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'); commit $(git rev-parse --short HEAD)"
"$build/distributed_bench" "$size" "$steps" --header
for ranks in 2 4; do mpiexec --oversubscribe -n "$ranks" "$build/distributed_bench" "$size" "$steps"; done
