#!/usr/bin/env bash
# README command 2: install what is missing, build, and run the whole test suite with ctest, then
# the suite again under AddressSanitizer and UndefinedBehaviorSanitizer and the fuzzer
# (tools/run-sanitized-tests.sh, docs/testing.md "Sanitizers"; SNOWBAKE_SANITIZED_SUITE=0 leaves
# them out). GPU tests skip with a message where no CUDA device works; tests on ../shared/data skip
# when that folder is absent.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup-debian.sh --with-blender
# The Python module too (python/), so ctest runs its pytest: built for Debian's python3, which has
# pytest and numpy from setup-debian.sh (a pyenv python first on PATH may have neither).
bash tools/build.sh -DSNOWBAKE_PYTHON=ON -DPython3_EXECUTABLE=/usr/bin/python3
(cd build && ctest --output-on-failure -j"$(nproc)" --timeout 900)
if [ "${SNOWBAKE_SANITIZED_SUITE:-1}" != 0 ]; then bash tools/run-sanitized-tests.sh; fi
