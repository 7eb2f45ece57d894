#!/usr/bin/env bash
# README command 1: install what is missing, build, and run the main job on the embedded default
# terrain. Outputs go to ./snowbake-demo (or the folder given as $1).
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/build.sh
./build/snowbake demo --out "${1:-snowbake-demo}"
