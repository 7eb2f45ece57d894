#!/usr/bin/env bash
# The test suite under AddressSanitizer and UndefinedBehaviorSanitizer, then the fuzzer
# (docs/testing.md). Builds build-asan (SNOWBAKE_SANITIZE=ON, CPU only) with only the binaries
# it runs: snowbake (the CLI tests run it), snowbake_tests and snowbake_fuzz.
#   SNOWBAKE_SANITIZE_FILTER  gtest filter of the sanitized suite; the default leaves out the
#                             heaviest tests (each over 20 s unsanitized; they run in the
#                             plain suite) and Blender, which is not ours to sanitize
#   SNOWBAKE_FUZZ_SECONDS     seconds of fuzzing per target (default 20; 0: the corpus only)
set -euo pipefail
cd "$(dirname "$0")/.."
heavy="Bedform.TheThesisBarchanSetGrowsCrescentsOfItsHeight:Stress.TwoHundredRandomTerrainsAndParameters"
heavy+=":HorizonSweep.AgreesWithEmbreeOnRealAndBuiltinTerrain:Season.StressRoughTerrainsStayPhysical:Blender.*"
filter="${SNOWBAKE_SANITIZE_FILTER:--$heavy}"
fuzzSeconds="${SNOWBAKE_FUZZ_SECONDS:-20}"

cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=Release -DSNOWBAKE_SANITIZE=ON -DSNOWBAKE_WITH_CUDA=OFF "$@"
cmake --build build-asan -j"$(nproc)" --target snowbake snowbake_tests snowbake_fuzz

# Every report fails the run. Leaks are not checked: the libraries (TBB's workers, GDAL's and
# OpenVDB's registries) keep allocations to the end on purpose. The fuzzer's allocation budget:
# no single allocation above 1 GiB, no resident set above 3 GiB (shadow memory included).
export ASAN_OPTIONS="detect_leaks=0:abort_on_error=1:allocator_may_return_null=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
start=$(date +%s)
./build-asan/snowbake_tests --gtest_filter="$filter" --gtest_brief=1
echo "sanitized suite: $(( $(date +%s) - start )) s (filter $filter)"

start=$(date +%s)
ASAN_OPTIONS="$ASAN_OPTIONS:max_allocation_size_mb=1024:hard_rss_limit_mb=3072" \
  ./build-asan/snowbake_fuzz all "$fuzzSeconds" --work build-asan/fuzz --corpus tests/fuzz/corpus
echo "fuzzing: $(( $(date +%s) - start )) s"
