#!/usr/bin/env bash
# Configures and builds snowbake in ./build (Release). CUDA is built when nvcc is found
# (/usr/local/cuda/bin/nvcc or on PATH); otherwise the CPU backend alone, said at configure time.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup-debian.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release "$@"
cmake --build build -j"$(nproc)"
