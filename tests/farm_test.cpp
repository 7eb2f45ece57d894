// Farm runs (docs/farm.md): one level of a scene list per task, and a precompute cache that many
// processes share. The Slurm job array itself is tests/farm/slurm_array_test.sh.
#include <gtest/gtest.h>
#include <unistd.h>  // getpid

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>
#include <atomic>

#include "bake/scene_list.h"
#include "cli_support.h"
#include "core/errors.h"
#include "precompute/cache.h"
#include "precompute/cache_folder.h"

using namespace std::string_literals;
namespace fs = std::filesystem;

namespace {

using snow::test::slurp;

fs::path farmWorkDir() {
  const fs::path p = fs::temp_directory_path() /
                     ("snowbake_farm_" + std::to_string(::getpid()) + "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

// Runs a shell command line; its exit status.
int shell(const std::string& command) {
  const int raw = std::system(command.c_str());
  return WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
}

std::string snowbake(const std::string& args) { return "'"s + SNOWBAKE_BINARY + "' " + args; }

// Every output's bytes; the manifest's without command_line, which names each bake's folders.
std::map<std::string, std::string> outputsIn(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    std::string bytes = slurp(e.path());
    if (e.path().filename() == "manifest.json") {
      nlohmann::ordered_json m = nlohmann::ordered_json::parse(bytes);
      m.erase("command_line");
      m.erase("memory");  // the measured peak differs between two runs
      bytes = m.dump(2);
    }
    files[fs::relative(e.path(), dir).string()] = bytes;
  }
  return files;
}

void expectSameOutputs(const fs::path& a, const fs::path& b) {
  const auto fa = outputsIn(a), fb = outputsIn(b);
  ASSERT_GE(fa.size(), 10u) << a;
  ASSERT_EQ(fa.size(), fb.size()) << a << " " << b;
  for (const auto& [name, bytes] : fa) {
    ASSERT_TRUE(fb.count(name)) << name << " missing in " << b;
    EXPECT_TRUE(bytes == fb.at(name)) << name << " differs between " << a << " and " << b;
  }
}

// A level whose precompute (a 256² exposure, 0.6 s of its 1.2 s) is long beside a process start,
// so eight bakes started together compute and store the same keys together; its layers include
// the two the cache feeds directly (sun exposure, wind shadow).
const std::string kLevel = "bake preset:default --backend cpu --threads 1 --quiet --set terrain.size=256 --set season.days=4 "
                           "--set outputs.frames_days=[] --set parameters.avalanche_rate_per_km2_per_day=0 "
                           "--set 'outputs.layers=[\"depth\",\"sun_exposure\",\"wind_shadow_depth\"]' ";

void expectEveryEntryValid(const fs::path& cache, size_t expectedEntries) {
  const auto entries = snow::checkCacheFolder(cache.string());
  EXPECT_EQ(entries.size(), expectedEntries);
  for (const auto& e : entries) EXPECT_EQ(e.problem, "") << e.path;
  for (const auto& e : fs::directory_iterator(cache))
    EXPECT_TRUE(snow::isCacheEntryName(e.path().filename().string())) << "left behind: " << e.path();
}

void setAgeDays(const fs::path& p, double days) {
  const auto now = std::chrono::system_clock::now() - std::chrono::duration<double>(days * 86400.0);
  const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(now.time_since_epoch()).count();
  const struct timespec t[2] = {{ns / 1000000000, ns % 1000000000}, {ns / 1000000000, ns % 1000000000}};
  ASSERT_EQ(::utimensat(AT_FDCWD, p.c_str(), t, 0), 0) << p;
}

void writeBytes(const fs::path& p, size_t n) { std::ofstream(p, std::ios::binary) << std::string(n, 'x'); }

}  // namespace

TEST(SceneList, LevelsAreReadWithTheirScenesBesideTheListAndTheirOverrides) {
  const fs::path dir = farmWorkDir();
  std::ofstream(dir / "levels.txt") << "# nightly levels\n\nnorth  preset:default terrain.size=64 season.days=10\r\n"
                                       "  south levels/south.toml\n";
  const auto levels = snow::readSceneList((dir / "levels.txt").string());
  ASSERT_EQ(levels.size(), 2u);
  EXPECT_EQ(levels[0].name, "north");
  EXPECT_EQ(levels[0].scene, "preset:default");
  EXPECT_EQ(levels[0].sets, (std::vector<std::string>{"terrain.size=64", "season.days=10"}));
  EXPECT_EQ(levels[0].line, 3);
  EXPECT_EQ(levels[1].scene, (dir / "levels/south.toml").string());
  EXPECT_EQ(snow::sceneListEntry((dir / "levels.txt").string(), 1).name, "south");
  fs::remove_all(dir);
}

TEST(SceneList, BadLinesAndOutOfRangeIndicesNameTheFileAndLine) {
  const fs::path dir = farmWorkDir();
  const std::string list = (dir / "levels.txt").string();
  auto refusal = [&](const std::string& text, long long index) -> std::string {
    std::ofstream(list) << text;
    try {
      snow::sceneListEntry(list, index);
    } catch (const snow::InputError& e) {
      return e.what();
    }
    return "accepted";
  };
  EXPECT_EQ(refusal("a preset:default\nb\n", 0), list + ":2: expected NAME SCENE [KEY=VALUE ...], found 'b'");
  EXPECT_EQ(refusal("a preset:default\n../up preset:default\n", 0),
            list + ":2: level name '../up' is not a plain folder name (letters, digits, . _ -)");
  EXPECT_EQ(refusal("a preset:default\n# c\na preset:default\n", 0),
            list + ":3: level name 'a' is already used on line 1 (each level needs its own output folder)");
  EXPECT_EQ(refusal("a preset:default season.days\n", 0), list + ":1: 'season.days' is not KEY=VALUE");
  EXPECT_EQ(refusal("# nothing\n", 0), list + ": the scene list has no levels (one `NAME SCENE [KEY=VALUE ...]` a line)");
  EXPECT_EQ(refusal("a preset:default\nb preset:default\n", 2),
            list + ": --index 2 is out of range: the list has 2 levels, numbered from 0 to 1");
  EXPECT_EQ(refusal("a preset:default\n", -1), list + ": --index -1 is out of range: the list has 1 levels, numbered from 0 to 0");
  fs::remove_all(dir);
}

TEST(SceneList, BakeOfAnIndexWritesThatLevelIntoItsFolderAndABadIndexExits2WritingNothing) {
  const fs::path dir = farmWorkDir();
  std::ofstream(dir / "levels.txt") << "small preset:default terrain.size=48 season.days=3 outputs.frames_days=[]\n"
                                       "other preset:default terrain.size=40 season.days=3 outputs.frames_days=[]\n";
  const std::string args = "bake --scene-list '" + (dir / "levels.txt").string() + "' --quiet --no-cache --out '" + (dir / "out").string() + "'";
  EXPECT_EQ(shell(snowbake(args + " --index 2 2>'" + (dir / "err.txt").string() + "'")), 2);
  EXPECT_NE(slurp(dir / "err.txt").find("levels.txt: --index 2 is out of range"), std::string::npos) << slurp(dir / "err.txt");
  EXPECT_FALSE(fs::exists(dir / "out"));
  // A farm manager reading --progress json gets the refusal as the done line.
  EXPECT_EQ(shell(snowbake(args + " --index 2 --progress json --log-file '" + (dir / "bake.log").string() + "' 2>'" +
                           (dir / "err.json").string() + "'")), 2);
  const std::string json = slurp(dir / "err.json");
  EXPECT_NE(json.find("{\"type\":\"done\",\"outcome\":\"input_error\",\"exit_status\":2"), std::string::npos) << json;
  EXPECT_FALSE(fs::exists(dir / "out"));
  EXPECT_FALSE(fs::exists(dir / "bake.log"));
  ASSERT_EQ(shell(snowbake(args + " --index 1 2>/dev/null")), 0);
  EXPECT_TRUE(fs::exists(dir / "out/other/manifest.json"));
  EXPECT_FALSE(fs::exists(dir / "out/small"));
  // The level is the scene with its line's overrides: the same bytes as that bake by hand.
  ASSERT_EQ(shell(snowbake("bake preset:default --set terrain.size=40 --set season.days=3 --set outputs.frames_days=[] --quiet "
                           "--no-cache --out '" + (dir / "alone").string() + "' 2>/dev/null")), 0);
  expectSameOutputs(dir / "out/other", dir / "alone");
  fs::remove_all(dir);
}

// Eight real processes of the program bake one scene into one cache folder at once: each writes
// the same keys while the others read them. Every bake equals the uncached one, and the folder
// holds exactly the valid entries, no torn or left-over file.
TEST(FarmCache, EightProcessesBakingOneKeyAtOnceAllEqualTheUncachedBakeAndLeaveValidEntries) {
  const fs::path dir = farmWorkDir();
  ASSERT_EQ(shell(snowbake(kLevel + "--no-cache --out '" + (dir / "uncached").string() + "' 2>/dev/null")), 0);
  std::string script = "pids=''\n";
  for (int i = 0; i < 8; ++i)
    script += snowbake(kLevel + "--cache-dir '" + (dir / "cache").string() + "' --out '" + (dir / ("p" + std::to_string(i))).string() +
                       "' 2>'" + (dir / ("p" + std::to_string(i) + ".log")).string() + "' & pids=\"$pids $!\"\n");
  script += "s=0; for p in $pids; do wait $p || s=1; done; exit $s\n";
  std::ofstream(dir / "hammer.sh") << script;
  ASSERT_EQ(shell("sh '" + (dir / "hammer.sh").string() + "'"), 0);
  int computedExposure = 0;
  for (int i = 0; i < 8; ++i) {
    const std::string log = slurp(dir / ("p" + std::to_string(i) + ".log"));
    EXPECT_EQ(log.find("is damaged"), std::string::npos) << log;
    computedExposure += log.find("sun exposure: from the cache") == std::string::npos;
    expectSameOutputs(dir / "uncached", dir / ("p" + std::to_string(i)));
  }
  std::cout << "[ hammer   ] " << computedExposure << " of 8 processes computed and stored the exposure entry\n";
  // Else no two writers met on the key and the test would not have tested them (8 of 8 in our runs).
  EXPECT_GE(computedExposure, 2);
  expectEveryEntryValid(dir / "cache", 2);  // the exposure and the one wind state
  // A ninth bake reads both entries and bakes the same bytes.
  ASSERT_EQ(shell(snowbake(kLevel + "--cache-dir '" + (dir / "cache").string() + "' --out '" + (dir / "again").string() + "' 2>'" +
                           (dir / "again.log").string() + "'")), 0);
  const std::string again = slurp(dir / "again.log");
  EXPECT_NE(again.find("sun exposure: from the cache"), std::string::npos) << again;
  EXPECT_NE(again.find("m/s: from the cache"), std::string::npos) << again;
  expectSameOutputs(dir / "uncached", dir / "again");
  fs::remove_all(dir);
}

// Within one process too: eight threads store one key while a reader loads it over and over;
// every load either misses (before the first rename) or returns the whole, right grids.
TEST(FarmCache, ConcurrentStoresOfOneKeyNeverShowAReaderATornEntry) {
  const fs::path dir = farmWorkDir();
  std::ostringstream log;  // hears of any damaged entry a load finds, or a store that failed
  const snow::PrecomputeCache cache(dir.string(), true, &log);
  snow::Grid<float> a(300, 200), b(300, 200);
  for (size_t i = 0; i < a.size(); ++i) a.data()[i] = static_cast<float>(i) * 0.5f, b.data()[i] = -static_cast<float>(i);
  std::atomic<int> writing{8};
  std::vector<std::thread> writers;
  for (int t = 0; t < 8; ++t)
    writers.emplace_back([&] {
      for (int k = 0; k < 10; ++k) cache.store("wind", "0123456789abcdef", {&a, &b});
      --writing;
    });
  int loads = 0, hits = 0, torn = 0;
  auto readOnce = [&] {
    snow::Grid<float> ra, rb;
    ++loads;
    if (!cache.load("wind", "0123456789abcdef", 300, 200, {&ra, &rb})) return false;
    ++hits;
    torn += ra.values() != a.values() || rb.values() != b.values();
    return true;
  };
  while (writing > 0) readOnce();
  for (auto& w : writers) w.join();
  EXPECT_TRUE(readOnce());
  EXPECT_EQ(torn, 0);
  EXPECT_EQ(log.str(), "");
  std::cout << "[ threads  ] " << hits << " of " << loads << " loads hit during 80 stores, none torn\n";
  expectEveryEntryValid(dir, 1);
  fs::remove_all(dir);
}

// A truncated entry and one with a flipped bit are both found by the reader, said so in the log,
// recomputed and stored again; the bake's bytes do not change.
TEST(FarmCache, TruncatedAndBitFlippedEntriesAreDetectedRecomputedAndRewritten) {
  const fs::path dir = farmWorkDir();
  const std::string cacheArg = "--cache-dir '" + (dir / "cache").string() + "' ";
  ASSERT_EQ(shell(snowbake(kLevel + cacheArg + "--out '" + (dir / "first").string() + "' 2>/dev/null")), 0);
  fs::path exposure, wind;
  for (const auto& e : fs::directory_iterator(dir / "cache"))
    (e.path().filename().string().rfind("exposure-", 0) == 0 ? exposure : wind) = e.path();
  ASSERT_FALSE(exposure.empty());
  ASSERT_FALSE(wind.empty());
  const uintmax_t windBytes = fs::file_size(wind);
  fs::resize_file(wind, windBytes / 2);
  std::string bytes = slurp(exposure);
  bytes[bytes.size() / 2] ^= 0x10;  // one bit of one float in the payload
  std::ofstream(exposure, std::ios::binary | std::ios::trunc) << bytes;
  EXPECT_EQ(snow::PrecomputeCache::checkEntry(exposure.string()).problem, "checksum mismatch");
  EXPECT_EQ(snow::PrecomputeCache::checkEntry(wind.string()).problem,
            "truncated: " + std::to_string(windBytes / 2) + " of " + std::to_string(windBytes) + " bytes");

  ASSERT_EQ(shell(snowbake(kLevel + cacheArg + "--out '" + (dir / "second").string() + "' 2>'" + (dir / "second.log").string() + "'")), 0);
  const std::string log = slurp(dir / "second.log");
  EXPECT_NE(log.find("cache: " + exposure.string() + " is damaged (checksum mismatch): recomputing"), std::string::npos) << log;
  EXPECT_NE(log.find("cache: " + wind.string() + " is damaged (truncated: "), std::string::npos) << log;
  EXPECT_EQ(log.find("sun exposure: from the cache"), std::string::npos) << log;
  EXPECT_EQ(log.find("m/s: from the cache"), std::string::npos) << log;
  expectSameOutputs(dir / "first", dir / "second");
  expectEveryEntryValid(dir / "cache", 2);
  EXPECT_EQ(fs::file_size(wind), windBytes);
  fs::remove_all(dir);
}

TEST(CachePrune, RemovesEntriesUnusedForLongerThanTheAgeThenTheLeastRecentlyUsedBeyondTheSize) {
  const fs::path dir = farmWorkDir();
  const std::map<std::string, std::pair<size_t, double>> files = {  // name -> bytes, days since last use
      {"exposure-00000000000000a1.bin", {1000, 40.0}}, {"wind-00000000000000a2.bin", {2000, 10.0}},
      {"wind-00000000000000a3.bin", {3000, 5.0}},      {"exposure-00000000000000a4.bin", {4000, 1.0}},
      {"notes.txt", {500, 100.0}},                     // not an entry: never touched
      {".wind-00000000000000a5.tmp-vm-12-4242-00000000000000ff.bin", {600, 2.0}},  // a killed writer's: stale, removed
      {".wind-00000000000000a6.tmp-vm-13-4343-00000000000000ff.bin", {700, 0.01}},   // a live writer's: kept
      {".wind-00000000000000a7.bin.tmp-vm-14-4444-00000000000000ff", {800, 3.0}}};  // an older snowbake's killed writer's: removed
  for (const auto& [name, f] : files) {
    writeBytes(dir / name, f.first);
    setAgeDays(dir / name, f.second);
  }
  const auto now = std::chrono::system_clock::now();
  snow::CachePruneOptions o{dir.string(), 30.0, 7000e-9, true};  // 30 days, 7000 bytes, dry run
  snow::CachePruneReport r = snow::pruneCache(o, now);
  const std::vector<std::string> expected = {(dir / ".wind-00000000000000a5.tmp-vm-12-4242-00000000000000ff.bin").string(),
                                             (dir / ".wind-00000000000000a7.bin.tmp-vm-14-4444-00000000000000ff").string(),
                                             (dir / "exposure-00000000000000a1.bin").string(), (dir / "wind-00000000000000a2.bin").string()};
  EXPECT_EQ(r.removed, expected);
  EXPECT_EQ(r.removedBytes, 600u + 800u + 1000u + 2000u);
  EXPECT_EQ(r.keptEntries, 2u);
  EXPECT_EQ(r.keptBytes, 7000u);
  EXPECT_TRUE(fs::exists(dir / "exposure-00000000000000a1.bin"));  // a dry run removes nothing
  o.dryRun = false;
  r = snow::pruneCache(o, now);
  EXPECT_EQ(r.removed, expected);
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(dir)) left.push_back(e.path().filename().string());
  std::sort(left.begin(), left.end());
  EXPECT_EQ(left, (std::vector<std::string>{".wind-00000000000000a6.tmp-vm-13-4343-00000000000000ff.bin", "exposure-00000000000000a4.bin", "notes.txt",
                                            "wind-00000000000000a3.bin"}));
  // Size alone: the least recently used go first.
  r = snow::pruneCache({dir.string(), std::nullopt, 4000e-9, false}, now);
  EXPECT_EQ(r.removed, (std::vector<std::string>{(dir / "wind-00000000000000a3.bin").string()}));
  EXPECT_THROW(snow::pruneCache({dir.string(), std::nullopt, std::nullopt, false}, now), snow::InputError);
  EXPECT_THROW(snow::pruneCache({dir.string(), -1.0, std::nullopt, false}, now), snow::InputError);
  fs::remove_all(dir);
}

TEST(CachePrune, CommandLineRefusesMissingOptionsWithExit2AndPrunesByDaysAndGb) {
  const fs::path dir = farmWorkDir();
  writeBytes(dir / "wind-00000000000000b1.bin", 100);
  setAgeDays(dir / "wind-00000000000000b1.bin", 3.0);
  writeBytes(dir / "wind-00000000000000b2.bin", 100);
  const std::string cache = "--cache-dir '" + dir.string() + "'";
  EXPECT_EQ(shell(snowbake("cache prune " + cache + " 2>/dev/null")), 2);
  EXPECT_EQ(shell(snowbake("cache prune " + cache + " --older-than-days 2 --max-size-gb 1 >'" + (dir / "out.txt").string() + "'")), 0);
  EXPECT_NE(slurp(dir / "out.txt").find("removed 1 files (100 bytes), kept 1 entries (100 bytes)"), std::string::npos) << slurp(dir / "out.txt");
  EXPECT_FALSE(fs::exists(dir / "wind-00000000000000b1.bin"));
  EXPECT_TRUE(fs::exists(dir / "wind-00000000000000b2.bin"));
  // `cache check` reads the entry written above as foreign (it is no entry's format): exit 1.
  EXPECT_EQ(shell(snowbake("cache check " + cache + " >/dev/null")), 1);
  fs::remove_all(dir);
}
