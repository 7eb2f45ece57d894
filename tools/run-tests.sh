#!/usr/bin/env bash
# README command 2: install what is missing, build, and run the whole test suite with ctest,
# and with SNOWBAKE_SANITIZED_SUITE=1 the suite under AddressSanitizer and UndefinedBehaviorSanitizer
# and the fuzzer (tools/run-sanitized-tests.sh; not yet run by default: see docs/testing.md, "Sanitizers"). GPU tests skip with a
# message where no CUDA device works; tests on ../shared/data skip when that folder is absent.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup-debian.sh --with-blender
bash tools/build.sh -DSNOWBAKE_PYTHON=ON  # the Python module too (python/), so ctest runs its pytest
(cd build && ctest --output-on-failure -j"$(nproc)" --timeout 900)
if [ "${SNOWBAKE_SANITIZED_SUITE:-0}" != 0 ]; then bash tools/run-sanitized-tests.sh; fi
