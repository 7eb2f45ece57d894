#!/usr/bin/env bash
# The test suite under AddressSanitizer and UndefinedBehaviorSanitizer, and the fuzzer
# (docs/testing.md). Builds build-asan (SNOWBAKE_SANITIZE=ON, CPU only) with only the binaries
# it runs: snowbake (the CLI tests run it), snowbake_tests, bench_tests, snowbake_fuzz and
# distributed_tests (alone and on 3 ranks where mpiexec is).
#   SNOWBAKE_SANITIZE_FILTER  gtest filter of the sanitized suite (default: every test but the
#                             five heaviest, each over 20 s unsanitized, whose code lighter tests
#                             run too, and the Blender and BlenderAddon suites, which check
#                             Blender's reading, not our code)
#   SNOWBAKE_SANITIZE_SHARDS  processes running the suite at once (default: the cores)
#   SNOWBAKE_FUZZ_SECONDS     seconds of fuzzing per target (default 10; 0: the corpus only)
set -euo pipefail
cd "$(dirname "$0")/.."
heavy="Bedform.TheThesisBarchanSetGrowsCrescentsOfItsHeight:Stress.TwoHundredRandomTerrainsAndParameters"
heavy+=":HorizonSweep.AgreesWithEmbreeOnRealAndBuiltinTerrain:Season.StressRoughTerrainsStayPhysical"
heavy+=":Cli.TerrainFlagBakesOrRefusesByLineEveryRealDemOnEveryPreset"
filter="${SNOWBAKE_SANITIZE_FILTER:--$heavy:Blender*}"
shards="${SNOWBAKE_SANITIZE_SHARDS:-$(nproc)}"
fuzzSeconds="${SNOWBAKE_FUZZ_SECONDS:-10}"
launcher=()
if command -v ccache > /dev/null; then launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi

start=$(date +%s)
# The tests in unity batches (CMakeLists.txt, SNOWBAKE_UNITY_TESTS): this tree is built whole each run.
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=Release -DSNOWBAKE_SANITIZE=ON -DSNOWBAKE_WITH_CUDA=OFF -DSNOWBAKE_UNITY_TESTS=ON "${launcher[@]}" "$@"
cmake --build build-asan -j"$(nproc)" --target snowbake snowbake_tests bench_tests snowbake_fuzz distributed_tests
echo "sanitized build: $(( $(date +%s) - start )) s"

# Every report fails the run. Leaks are not checked: the libraries (TBB's workers, GDAL's and
# OpenVDB's registries) keep allocations to the end on purpose. The fuzzer's allocation budget:
# no single allocation above 1 GiB, no resident set above 3 GiB (shadow memory included).
export ASAN_OPTIONS="detect_leaks=0:abort_on_error=1:allocator_may_return_null=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"

# The suite in `shards` processes at once (gtest's sharding), each with its own log; a shard's
# log is printed when it fails. The fuzzer runs once the first shard ends: the shards seldom end
# together, and a core would idle until the last did.
start=$(date +%s)
logs=build-asan/sanitized-logs
rm -rf "$logs" && mkdir -p "$logs"
# Each shard's exit status lands in shardN.rc (a shard killed by a signal, as ASan's abort, too:
# bash's `wait -n` loses a job it has reported as killed, so the ends are polled).
for ((i = 0; i < shards; ++i)); do
  (
    GTEST_TOTAL_SHARDS=$shards GTEST_SHARD_INDEX=$i ./build-asan/snowbake_tests --gtest_filter="$filter" --gtest_brief=1 \
      --gtest_output="xml:$logs/shard$i.xml" > "$logs/shard$i.log" 2>&1
    echo $? > "$logs/shard$i.rc"
  ) &
done
./build-asan/bench_tests --gtest_filter="$filter" --gtest_brief=1 --gtest_output="xml:$logs/bench.xml" > "$logs/bench.log" 2>&1 || { cat "$logs/bench.log"; failed=1; }
# The decomposition alone and on 3 ranks (a 3 x 1 process grid: every halo path but corners, which
# the unsanitized suite's 4 ranks cross).
./build-asan/distributed_tests --gtest_brief=1 > "$logs/distributed.log" 2>&1 || { cat "$logs/distributed.log"; failed=1; }
if command -v mpiexec > /dev/null; then
  OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 mpiexec --oversubscribe -n 3 ./build-asan/distributed_tests --gtest_brief=1 \
    > "$logs/distributed3.log" 2>&1 || { cat "$logs/distributed3.log"; failed=1; }
fi
fuzzed=0 ended=0
declare -A seen
while [ "$ended" -lt "$shards" ]; do
  sleep 1
  for ((i = 0; i < shards; ++i)); do
    [ -f "$logs/shard$i.rc" ] && [ -z "${seen[$i]:-}" ] || continue
    seen[$i]=1 ended=$((ended + 1))
    [ "$(cat "$logs/shard$i.rc")" = 0 ] || { cat "$logs/shard$i.log"; failed=1; }
  done
  if [ "$fuzzed" = 0 ] && [ "$ended" -gt 0 ]; then
    fuzzStart=$(date +%s)
    ASAN_OPTIONS="$ASAN_OPTIONS:max_allocation_size_mb=1024:hard_rss_limit_mb=3072" \
      ./build-asan/snowbake_fuzz all "$fuzzSeconds" --work build-asan/fuzz --corpus tests/fuzz/corpus || { echo "fuzzing: FAILED"; failed=1; }
    echo "fuzzing: $(( $(date +%s) - fuzzStart )) s"
    fuzzed=1
  fi
done
wait
grep -h "tests ran\|PASSED\|SKIPPED\|FAILED" "$logs"/*.log | grep -v "^\[ *RUN" || true
echo "slowest sanitized tests (s):"
python3 - "$logs" <<'PY' || true
import glob, sys, xml.etree.ElementTree as ET
cases = [(float(c.get("time", 0)), c.get("classname") + "." + c.get("name"))
         for f in glob.glob(sys.argv[1] + "/*.xml") for c in ET.parse(f).iter("testcase")]
for t, name in sorted(cases, reverse=True)[:12]: print(f"  {t:7.1f}  {name}")
PY
echo "sanitized suite and fuzzing: $(( $(date +%s) - start )) s (filter $filter, $shards shards)"
if [ "${failed:-0}" != 0 ]; then echo "sanitized suite: FAILED"; exit 1; fi
