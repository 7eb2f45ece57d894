// End-to-end: the `snowbake` program as pipelines run it.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>

#include "bakers/grid_writer.h"
#include "bake/bake.h"
#include "cli_support.h"
#include "temp_dir.h"

using namespace std::string_literals;
namespace fs = std::filesystem;

namespace {

using snow::test::ProcessResult;
using snow::test::snowbake;

fs::path cliWorkDir() {
  return snow::test::uniqueTestDir("cli");
}

// Every file's bytes; a manifest's without its command_line, which names each run's --out.
std::map<std::string, std::string> filesIn(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    std::ifstream in(e.path(), std::ios::binary);
    std::stringstream s;
    s << in.rdbuf();
    std::string bytes = s.str();
    if (e.path().filename() == "manifest.json" && nlohmann::ordered_json::accept(bytes)) {
      nlohmann::ordered_json m = nlohmann::ordered_json::parse(bytes);
      m.erase("command_line");
      m.erase("memory");  // the measured peak: the one member that differs between two runs
      bytes = m.dump(2);
    }
    files[fs::relative(e.path(), dir).string()] = bytes;
  }
  return files;
}

// A small, quick version of the default bake.
const std::string kSmall = "--set terrain.size=96 --set terrain.cell_size_m=20 --set season.days=40 --set outputs.frames_days=[20] "
                           "--quiet --no-cache ";

}  // namespace

TEST(Cli, SameSeedSameBytesAndThreadCountDoesNotMatter) {
  const fs::path dir = cliWorkDir();
  ASSERT_EQ(snowbake(dir, "bake preset:default --backend cpu --threads 1 --seed 5 --out " + (dir / "a").string() + " " + kSmall).status, 0);
  ASSERT_EQ(snowbake(dir, "bake preset:default --backend cpu --threads 2 --seed 5 --out " + (dir / "b").string() + " " + kSmall).status, 0);
  ASSERT_EQ(snowbake(dir, "bake preset:default --backend cpu --threads 2 --seed 6 --out " + (dir / "c").string() + " " + kSmall).status, 0);
  const auto a = filesIn(dir / "a"), b = filesIn(dir / "b"), c = filesIn(dir / "c");
  EXPECT_GE(a.size(), 11u);  // 5 layers final + 5 at day 20 + manifest
  EXPECT_TRUE(a.count("manifest.json"));
  EXPECT_TRUE(a.count("frames/powder.0020.exr"));
  ASSERT_EQ(a.size(), b.size());
  for (const auto& [name, bytes] : a) {
    ASSERT_TRUE(b.count(name)) << name;
    EXPECT_TRUE(bytes == b.at(name)) << name << " differs between 1 and 2 threads";
  }
  EXPECT_FALSE(a.at("powder.exr") == c.at("powder.exr")) << "another seed should give another season";
  if (!HasFailure()) fs::remove_all(dir);  // kept for inspection when it fails
}

// Frame days are written on their own thread from a copy of the state (and of the ski-track
// texture, which the season goes on stamping) while the season continues, after the season from
// copies held through it, or while the season waits with its fields lent to the writers: the same
// files and manifest as writing them in place, with three frames (one in flight at a time) and skiers.
TEST(Cli, FramesWrittenBesideAfterOrPausingTheSeasonEqualFramesWrittenInPlace) {
  const fs::path dir = cliWorkDir();
  std::map<std::string, std::string> files[4];
  const snow::FrameTiming timings[4] = {snow::FrameTiming::InPlace, snow::FrameTiming::Beside, snow::FrameTiming::AfterSeason,
                                        snow::FrameTiming::Paused};
  for (int beside = 0; beside < 4; ++beside) {
    snow::BakeOptions o;
    o.scene = "preset:default";
    o.outDir = (dir / ("timing" + std::to_string(beside))).string();
    o.backend = "cpu";
    o.useCache = false;
    o.progress = false;
    o.frames = timings[beside];
    o.sets = {"terrain.size=96", "terrain.cell_size_m=20", "season.days=40", "outputs.frames_days=[10,20,30]", "parameters.skiers_per_hour=5",
              "outputs.layers=[\"powder\",\"depth\",\"ski_tracks\",\"preview\"]", "outputs.meshes=[\"glb\"]"};
    std::ostringstream log;
    snow::runBake(o, log);
    files[beside] = filesIn(o.outDir);
  }
  EXPECT_TRUE(files[1].count("frames/ski_tracks.0020.exr"));
  EXPECT_TRUE(files[1].count("frames/snow_surface.0030.glb"));
  EXPECT_TRUE(files[1].count("contact_sheet.png"));
  EXPECT_FALSE(files[1].at("frames/ski_tracks.0010.exr") == files[1].at("ski_tracks.exr")) << "no skiing after day 10?";
  for (int other = 1; other < 4; ++other) {
    ASSERT_EQ(files[0].size(), files[other].size());
    for (const auto& [name, bytes] : files[0]) {
      ASSERT_TRUE(files[other].count(name)) << name;
      EXPECT_TRUE(bytes == files[other].at(name)) << name << " differs when frames are written " << (other == 1 ? "beside" : other == 2 ? "after" : "pausing")
                                                  << " the season";
    }
  }
  if (!HasFailure()) fs::remove_all(dir);
}

TEST(Cli, ManifestListsEveryFileWritten) {
  const fs::path dir = cliWorkDir();
  const ProcessResult r = snowbake(dir, "bake preset:default --backend cpu --out " + (dir / "o").string() + " " + kSmall);
  ASSERT_EQ(r.status, 0) << r.err;
  const auto files = filesIn(dir / "o");
  const std::string manifest = files.at("manifest.json");
  for (const auto& [name, bytes] : files)
    if (name != "manifest.json") {
      EXPECT_NE(manifest.find("\"" + name + "\""), std::string::npos) << name;
    }
  EXPECT_NE(manifest.find("\"unit\": \"m\""), std::string::npos);
  EXPECT_NE(r.err.find("season:"), std::string::npos) << "stage timings are reported";
  fs::remove_all(dir);
}

TEST(Cli, BadSceneExitsTwoWithOneLineNamingFileAndKey) {
  const fs::path dir = cliWorkDir();
  const std::string scene = (dir / "bad.toml").string();
  std::ofstream(scene) << "[terrain]\nbuiltin = \"ridged\"\n[season]\ndays = -4\n";
  fs::create_directories(dir / "out");
  std::ofstream(dir / "out" / "keep.txt") << "earlier bake";
  const ProcessResult r = snowbake(dir, "bake " + scene + " --out " + (dir / "out").string());
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find(scene + ":4"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("season.days"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  // Nothing was written or touched.
  const auto files = filesIn(dir / "out");
  EXPECT_EQ(files.size(), 1u);
  EXPECT_EQ(files.at("keep.txt"), "earlier bake");
  fs::remove_all(dir);
}

TEST(Cli, UsageErrorsExitTwoAndHelpExitsZero) {
  const fs::path dir = cliWorkDir();
  EXPECT_EQ(snowbake(dir, "bake").status, 2);
  EXPECT_EQ(snowbake(dir, "frobnicate").status, 2);
  EXPECT_EQ(snowbake(dir, "bake preset:default --backend gpu").status, 2);
  const ProcessResult help = snowbake(dir, "bake --help");
  EXPECT_EQ(help.status, 0);
  EXPECT_NE(help.out.find("--terrain"), std::string::npos);
  EXPECT_EQ(snowbake(dir, "--help").status, 0);
  EXPECT_EQ(snowbake(dir, "demo --help").status, 0);
  EXPECT_EQ(snowbake(dir, "info --help").status, 0);
  const ProcessResult missing = snowbake(dir, "bake preset:default --terrain /nonexistent/dem.tif");
  EXPECT_EQ(missing.status, 2);
  EXPECT_NE(missing.err.find("/nonexistent/dem.tif"), std::string::npos) << missing.err;
  fs::remove_all(dir);
}

// mpirun -np 2 (or srun -n 2): a scene the bake across ranks cannot run yet (here, the CUDA backend) is
// refused by each process with exit 2 before any work, naming the key, and so is every command
// but bake, info and help (each would run N times over). The bakes it runs: distributed tests.
TEST(Cli, LaunchOfSeveralProcessesRefusesWhatCannotRunAcrossRanksBeforeWritingAnything) {
  const fs::path dir = cliWorkDir();
  setenv("OMPI_COMM_WORLD_SIZE", "2", 1);
  const ProcessResult r = snowbake(dir, "bake preset:default --set terrain.size=64 --set 'run.backend=\"cuda\"' --out " + (dir / "out").string());
  const ProcessResult info = snowbake(dir, "help scene");
  const ProcessResult plan = snowbake(dir, "plan preset:default");
  unsetenv("OMPI_COMM_WORLD_SIZE");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("started as 2 processes"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("run.backend=\"cuda\":1: run.backend = \"cuda\": a bake across ranks does not run it yet"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(fs::exists(dir / "out"));
  EXPECT_EQ(info.status, 0);  // reading commands still run
  EXPECT_EQ(plan.status, 2);
  EXPECT_NE(plan.err.find("only `snowbake bake` runs across ranks"), std::string::npos) << plan.err;
  setenv("SLURM_STEP_ID", "0", 1);  // srun -n 3, whatever its MPI plugin
  setenv("SLURM_STEP_NUM_TASKS", "3", 1);
  const ProcessResult srun = snowbake(dir, "bake preset:default --set terrain.size=64 --set 'run.backend=\"cuda\"' --out " + (dir / "out").string());
  setenv("SLURM_STEP_ID", "batch", 1);  // a batch script of a job with 3 tasks: one process
  const ProcessResult batch = snowbake(dir, "help scene");
  unsetenv("SLURM_STEP_ID");
  unsetenv("SLURM_STEP_NUM_TASKS");
  EXPECT_EQ(srun.status, 2);
  EXPECT_NE(srun.err.find("started as 3 processes"), std::string::npos) << srun.err;
  EXPECT_EQ(batch.status, 0);
  setenv("OMPI_COMM_WORLD_SIZE", "1", 1);  // mpirun -np 1: the bake as ever
  const ProcessResult one = snowbake(dir, "bake preset:default --set terrain.size=64 --set season.days=2 --set 'outputs.frames_days=[]' --no-cache --out " + (dir / "one").string());
  unsetenv("OMPI_COMM_WORLD_SIZE");
  EXPECT_EQ(one.status, 0) << one.err;
  fs::remove_all(dir);
}

TEST(Cli, InfoReportsTheTerrainAsJson) {
  const fs::path dir = cliWorkDir();
  const ProcessResult r = snowbake(dir, "info builtin:ridged --json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("\"width\": 512"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"cell_size_x_m\": 10.0"), std::string::npos) << r.out;
  const ProcessResult bad = snowbake(dir, "info /nonexistent/x.asc");
  EXPECT_EQ(bad.status, 2);
  fs::remove_all(dir);
}

TEST(Cli, AutoBackendSaysWhichItPicked) {
  const fs::path dir = cliWorkDir();
  const ProcessResult r = snowbake(dir, "bake preset:default --backend auto --out " + (dir / "o").string() + " " + kSmall);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("backend: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("(auto: "), std::string::npos) << r.err;
  fs::remove_all(dir);
}

namespace {

// Bakes `scene` into an output folder that already holds an earlier bake's file; expects exit 2,
// a one-line message containing every `expected` string, and the folder untouched.
void expectRefused(const fs::path& dir, const std::string& scene, const std::vector<std::string>& expected) {
  const fs::path out = dir / "out";
  fs::remove_all(out);
  fs::create_directories(out);
  std::ofstream(out / "manifest.json") << "earlier bake";
  const ProcessResult r = snowbake(dir, "bake " + scene + " --quiet --no-cache --out " + out.string());
  EXPECT_EQ(r.status, 2) << r.err;
  // The log may have begun; the error is its last line, and one line.
  const auto at = r.err.find("snowbake: error: ");
  ASSERT_NE(at, std::string::npos) << r.err;
  const std::string line = r.err.substr(at);
  EXPECT_EQ(std::count(line.begin(), line.end(), '\n'), 1) << line;
  for (const auto& e : expected) EXPECT_NE(line.find(e), std::string::npos) << "missing '" << e << "' in: " << line;
  const auto files = filesIn(out);
  EXPECT_EQ(files.size(), 1u);
  EXPECT_EQ(files.at("manifest.json"), "earlier bake");
}

std::string sceneFor(const fs::path& dir, const std::string& terrainTable) {
  const std::string path = (dir / "scene.toml").string();
  std::ofstream(path) << "[terrain]\n" << terrainTable << "\n[season]\ndays = 5\n";
  return path;
}

}  // namespace

TEST(Cli, BadTerrainInputIsRefusedBeforeAnythingIsWritten) {
  const fs::path dir = cliWorkDir();
  const std::string garbage = (dir / "garbage.tif").string();
  std::ofstream(garbage) << "not a GeoTIFF at all";
  expectRefused(dir, sceneFor(dir, "file = \"garbage.tif\""), {garbage, "cannot read"});

  const std::string empty = (dir / "empty.asc").string();
  std::ofstream(empty).close();
  expectRefused(dir, sceneFor(dir, "file = \"empty.asc\""), {empty, "empty"});

  // A truncated ESRI grid: the header promises 10 rows, the file has 3.
  const std::string truncated = (dir / "truncated.asc").string();
  std::ofstream(truncated) << "ncols 10\nnrows 10\nxllcorner 0\nyllcorner 0\ncellsize 5\n"
                           << "1.5 1 1 1 1 1 1 1 1 1\n1 1 1 1 1 1 1 1 1 1\n1 1 1 1 1 1 1 1 1 1\n";
  expectRefused(dir, sceneFor(dir, "file = \"truncated.asc\""), {truncated});

  const std::string raw = (dir / "short.r16").string();
  std::ofstream(raw, std::ios::binary) << std::string(100, '\0');
  expectRefused(dir, sceneFor(dir, "file = \"short.r16\"\nraw_width = 16\nraw_height = 16\ncell_size_m = 2\nheight_range_m = [0, 100]"),
                {raw, "has 100 bytes", "need 512"});

  const std::string nan = (dir / "nan.asc").string();
  std::ofstream(nan) << "ncols 4\nnrows 4\nxllcorner 0\nyllcorner 0\ncellsize 5\n"
                     << "1.5 1 1 1\n1 nan 1 1\n1 1 1 1\n1 1 1 1\n";
  expectRefused(dir, sceneFor(dir, "file = \"nan.asc\""), {nan, "not finite"});

  const std::string tiny = (dir / "tiny.asc").string();
  std::ofstream(tiny) << "ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 5\n1.5 1\n1 1\n";
  expectRefused(dir, sceneFor(dir, "file = \"tiny.asc\""), {tiny, "too small"});

  const std::string huge = (dir / "huge.r32").string();
  std::ofstream(huge, std::ios::binary) << std::string(16, '\0');
  expectRefused(dir, sceneFor(dir, "file = \"huge.r32\"\nraw_width = 900000\nraw_height = 900000\ncell_size_m = 1"),
                {huge, "GiB"});
  fs::remove_all(dir);
}

TEST(Cli, InfoJsonReportsWhatTheSimulationWillUse) {
  const fs::path dir = cliWorkDir();
  // A 12 x 10 float heightmap at 2.5 m, resampled to 5 m.
  const std::string r32 = (dir / "hm.r32").string();
  {
    std::ofstream out(r32, std::ios::binary);
    for (int i = 0; i < 120; ++i) {
      const float v = 500.f + static_cast<float>(i);
      out.write(reinterpret_cast<const char*>(&v), 4);
    }
  }
  const std::string scene = sceneFor(dir, "file = \"hm.r32\"\nraw_width = 12\nraw_height = 10\ncell_size_m = 2.5\nresample_cell_size_m = 5");
  const ProcessResult r = snowbake(dir, "info " + scene + " --json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("\"format\": \"raw\""), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"width\": 6"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"height\": 5"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"cell_size_x_m\": 5.0"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"native_width\": 12"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"min_elevation_m\": 506.5"), std::string::npos) << r.out;  // mean of the first 2 x 2 block
  EXPECT_NE(r.out.find("box filter"), std::string::npos) << r.out;
  // A heightmap given directly has no cell size: info says to use a scene.
  const ProcessResult direct = snowbake(dir, "info " + r32);
  EXPECT_EQ(direct.status, 2);
  EXPECT_NE(direct.err.find("scene"), std::string::npos) << direct.err;
  fs::remove_all(dir);
}

// --terrain replaces the preset's [terrain] table: its builtin size and cell_size_m do not reach
// the DEM (they made every DEM fail), --set terrain.KEY still applies to the file.
TEST(Cli, TerrainFlagBakesARealDemOnThePresetReplacingItsTerrainTable) {
  const std::string dem = std::string(SNOWBAKE_SHARED_DATA_DIR) + "/dem/tyrol_avaKot_5m.asc";
  if (!fs::exists(dem)) GTEST_SKIP() << "shared data not found: " << dem;
  const fs::path dir = cliWorkDir();
  const ProcessResult r = snowbake(dir, "bake preset:default --terrain " + dem + " --set season.days=10 --set outputs.frames_days=[5] --no-cache --out " + (dir / "o").string());
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("439 x 517 cells of 5.00 x 5.00 m"), std::string::npos) << r.err;
  EXPECT_EQ(snow::readFloatImage((dir / "o" / "depth.exr").string()).width(), 439);
  const ProcessResult resampled =
      snowbake(dir, "bake preset:default --terrain " + dem + " --set terrain.resample_cell_size_m=10 --set season.days=2 --set outputs.frames_days=[1] --no-cache --out " +
                        (dir / "o2").string());
  ASSERT_EQ(resampled.status, 0) << resampled.err;
  EXPECT_EQ(snow::readFloatImage((dir / "o2" / "depth.exr").string()).width(), 219);  // 439 cells of 5 m: 2195 m at 10 m
  fs::remove_all(dir);
}

// --terrain on every real DEM of ../shared/data with every preset: each bake either runs (its
// outputs and manifest written) or is refused with exit 2 naming the preset's file, the line and
// the key of what does not fit the DEM, with nothing written; and each preset bakes the DEMs it suits.
// Short seasons where a preset allows it; art direction keeps its 90-day timeline, so its one
// square DEM (Front Range, 758 x 758 cells) is cropped to 150 x 150 cells.
TEST(Cli, TerrainFlagBakesOrRefusesByLineEveryRealDemOnEveryPreset) {
  const std::string data = SNOWBAKE_SHARED_DATA_DIR;
  if (!fs::exists(data + "/dem")) GTEST_SKIP() << "shared data not found: " << data;
  std::vector<std::string> dems;
  for (const char* name : {"front_range_small_srtm3.asc", "front_range_srtm3.asc", "tyrol_avaKot_5m.asc", "tyrol_avaWog_5m.asc"})
    dems.push_back(data + "/dem/" + name);
  for (const char* c : {"avaAlr", "avaHelix", "avaKot", "avaWog"}) dems.push_back(data + "/avaframe/" + c + "/dem.tif");
  for (const auto& d : dems) ASSERT_TRUE(fs::exists(d)) << d;
  struct Preset {
    std::string scene, name, args;
    int bakes;  // how many of the eight DEMs it suits (docs/command-line.md)
  };
  const std::string presets = std::string(SNOWBAKE_SOURCE_DIR) + "/presets/";
  const std::vector<Preset> all = {
      {"preset:default", "preset:default", "--set season.days=2 --set 'outputs.frames_days=[1]'", 8},
      // a periodic window: the two Front Range DEMs have even grids, the six others odd ones
      {presets + "bedforms.toml", "bedforms.toml", "--set season.days=1 --set 'outputs.frames_days=[]'", 2},
      // masks painted square without a georeference: only the square Front Range grid
      {presets + "art_direction.toml", "art_direction.toml", "", 1}};
  const fs::path dir = cliWorkDir();
  int run = 0;
  for (const Preset& p : all) {
    int baked = 0;
    for (const std::string& dem : dems) {
      std::string args = p.args;
      if (p.name == "art_direction.toml" && dem.find("/front_range_srtm3.asc") != std::string::npos)
        args += " --set 'terrain.crop_m=[0,0,10650,13890]'";
      const fs::path out = dir / ("o" + std::to_string(run++));
      const ProcessResult r = snowbake(dir, "bake '" + p.scene + "' --terrain '" + dem + "' " + args + " --quiet --no-cache --out '" + out.string() + "'");
      const std::string what = p.name + " on " + dem;
      if (r.status == 0) {
        ++baked;
        EXPECT_TRUE(fs::exists(out / "manifest.json")) << what;
        EXPECT_TRUE(fs::exists(out / "depth.exr") || fs::exists(out / "depth.16.png")) << what;
      } else {
        EXPECT_EQ(r.status, 2) << what << "\n" << r.err;
        const std::regex named(std::regex_replace(p.name, std::regex("\\."), "\\.") + ":[0-9]+: [a-z_]+\\.[a-z_.]+");
        EXPECT_TRUE(std::regex_search(r.err, named)) << what << ": the refusal names no file, line and key\n" << r.err;
        EXPECT_TRUE(!fs::exists(out) || fs::is_empty(out)) << what << ": refused but wrote";
      }
      fs::remove_all(out);
    }
    EXPECT_EQ(baked, p.bakes) << p.name << " baked " << baked << " of the " << dems.size() << " real DEMs";
  }
  fs::remove_all(dir);
}

TEST(Cli, RealDemWithNodataBakesWithAMaskAndNoSnowInTheHoles) {
  const std::string dem = std::string(SNOWBAKE_SHARED_DATA_DIR) + "/dem/tyrol_avaWog_5m.asc";
  if (!fs::exists(dem)) GTEST_SKIP() << "shared data not found: " << dem;
  const fs::path dir = cliWorkDir();
  const std::string scene = (dir / "tyrol.toml").string();
  std::ofstream(scene) << "[terrain]\nfile = \"" << dem << "\"\n[site]\nlatitude_deg = 47.2\n[season]\ndays = 60\n"
                       << "[[weather.keyframe]]\nday = 0\nsea_level_temperature_c = 2.0\n"
                       // (no spontaneous avalanches: at the paper's rate they take this DEM's season past 10 minutes)
                       << "[parameters]\nrain_snow_limit_m = 1000\navalanche_rate_per_km2_per_day = 0\n[outputs]\nlayers = [\"depth\", \"bedrock\"]\n";
  const ProcessResult r = snowbake(dir, "bake " + scene + " --quiet --no-cache --backend cpu --out " + (dir / "o").string());
  ASSERT_EQ(r.status, 0) << r.err;
  const snow::Grid<float> mask = snow::readFloatImage((dir / "o" / "valid_mask.exr").string());
  const snow::Grid<float> depth = snow::readFloatImage((dir / "o" / "depth.exr").string());
  ASSERT_EQ(mask.width(), 490);
  size_t holes = 0, snowy = 0;
  for (size_t i = 0; i < mask.size(); ++i) {
    if (mask.values()[i] == 0.f) {
      ++holes;
      ASSERT_EQ(depth.values()[i], 0.f);
    } else if (depth.values()[i] > 0.f) {
      ++snowy;
    }
  }
  EXPECT_EQ(holes, 94079u);
  EXPECT_GT(snowy, (mask.size() - holes) / 2);
  fs::remove_all(dir);
}

TEST(Cli, PrecomputeCacheIsReusedAndGivesTheSameBytes) {
  const fs::path dir = cliWorkDir();
  const std::string cache = (dir / "cache").string();
  const std::string common = "bake preset:default --backend cpu --quiet --set terrain.size=64 --set season.days=20 "
                             "--set outputs.frames_days=[] --set 'outputs.layers=[\"depth\",\"sun_exposure\",\"wind_shadow_depth\"]' "
                             "--cache-dir " + cache;
  const ProcessResult first = snowbake(dir, common + " --out " + (dir / "a").string());
  ASSERT_EQ(first.status, 0) << first.err;
  EXPECT_EQ(first.err.find("sun exposure: from the cache"), std::string::npos) << first.err;
  EXPECT_EQ(first.err.find("m/s: from the cache"), std::string::npos) << first.err;
  const ProcessResult second = snowbake(dir, common + " --out " + (dir / "b").string());
  ASSERT_EQ(second.status, 0) << second.err;
  EXPECT_NE(second.err.find("sun exposure: from the cache"), std::string::npos) << second.err;
  EXPECT_NE(second.err.find("m/s: from the cache"), std::string::npos) << second.err;
  const auto a = filesIn(dir / "a"), b = filesIn(dir / "b");
  for (const auto& [name, bytes] : a) EXPECT_TRUE(bytes == b.at(name)) << name;
  // A changed input is recomputed, and --no-cache reads nothing.
  const ProcessResult changed = snowbake(dir, common + " --set site.latitude_deg=30 --out " + (dir / "c").string());
  EXPECT_EQ(changed.err.find("sun exposure: from the cache"), std::string::npos) << changed.err;
  const ProcessResult off = snowbake(dir, common + " --no-cache --out " + (dir / "d").string());
  EXPECT_EQ(off.err.find("sun exposure: from the cache"), std::string::npos) << off.err;
  EXPECT_EQ(off.err.find("m/s: from the cache"), std::string::npos) << off.err;
  fs::remove_all(dir);
}

TEST(Cli, SunOffSkipsTheExposure) {
  const fs::path dir = cliWorkDir();
  const ProcessResult r = snowbake(dir, "bake preset:default --backend cpu --no-cache --set precompute.sun=false " + kSmall +
                                            " --out " + (dir / "o").string());
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("sun exposure off"), std::string::npos) << r.err;
  fs::remove_all(dir);
}

// Avalanche events that cannot be honoured are refused with the scene file, its line and why;
// the earlier bake's files stay.
TEST(Cli, BadAvalancheEventsAreRefusedWithFileLineAndReason) {
  const fs::path dir = cliWorkDir();
  const std::string scene = (dir / "scene.toml").string();
  auto write = [&](const std::string& event) {
    std::ofstream(scene) << "[terrain]\nbuiltin = \"ridged\"\nsize = 64\n[season]\ndays = 5\n[[events]]\ntype = \"avalanche\"\nday = 2\n"
                         << event << "\n";
    return scene;
  };
  expectRefused(dir, write(""), {scene, "position_m"});
  expectRefused(dir, write("position_m = [5000, 10]"), {scene + ":6", "outside the terrain", "640.0 x 640.0 m"});
  expectRefused(dir, write("position_m = [10]"), {scene, "position_m", "two numbers"});
  expectRefused(dir, write("position_m = [10, 10]\nmap_position = [1, 2]"), {scene, "one of them"});
  fs::remove_all(dir);
}
