#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/errors.h"
#include "scene/scene.h"
#include "temp_dir.h"

using namespace snow;
namespace fs = std::filesystem;

namespace {

struct SceneTempDir {
  fs::path path;
  SceneTempDir() {
    path = snow::test::uniqueTestDir("scene_test");
  }
  ~SceneTempDir() { fs::remove_all(path); }
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(path / name) << text;
    return (path / name).string();
  }
};

const char* kValid = R"(name = "test"
[terrain]
builtin = "ridged"
size = 64
cell_size_m = 20.0
[site]
latitude_deg = 46.0
[season]
start_date = 2025-12-01
days = 90
[[weather.keyframe]]
day = 0
sea_level_temperature_c = 4.0
wind_speed_mps = 5
[[weather.keyframe]]
day = 50
sea_level_temperature_c = 10.0
[[weather.snowfall]]
start_day = 3
end_day = 6
[[events]]
type = "snowfall"
day = 8
duration_days = 2
[parameters]
rain_snow_limit_m = 1300
melt_rate_m_per_day_per_c = 0.02
[outputs]
layers = ["powder", "depth"]
format = "tiff"
frames_days = [30, 60]
[run]
seed = 77
backend = "cpu"
)";

// Loads `text` expecting an InputError; returns its message.
std::string errorOf(const SceneTempDir& dir, const std::string& text, const std::vector<std::string>& sets = {}) {
  const std::string path = dir.write("scene.toml", text);
  try {
    loadSceneFile(path, sets);
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error for:\n" << text;
  return "";
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

}  // namespace

TEST(SceneFile, ValidSceneIsUnderstood) {
  SceneTempDir dir;
  const Scene s = loadSceneFile(dir.write("scene.toml", kValid));
  EXPECT_EQ(s.name, "test");
  EXPECT_TRUE(s.terrain.builtin);
  EXPECT_EQ(s.terrain.builtinOptions.size, 64);
  EXPECT_DOUBLE_EQ(s.terrain.builtinOptions.cellSizeM, 20.0);
  EXPECT_DOUBLE_EQ(*s.latitudeDeg, 46.0);
  EXPECT_EQ(s.startMonth, 12);
  EXPECT_EQ(s.startDayOfYear(), 335);
  EXPECT_DOUBLE_EQ(s.days, 90.0);
  ASSERT_EQ(s.weather.keyframes.size(), 2u);
  EXPECT_DOUBLE_EQ(s.weather.keyframes[1].state.seaLevelTemperatureC, 10.0);
  EXPECT_DOUBLE_EQ(s.weather.keyframes[1].state.windSpeedMps, 5.0);  // carried from the previous keyframe
  ASSERT_EQ(s.weather.snowfallPeriods.size(), 1u);
  EXPECT_DOUBLE_EQ(s.weather.snowfallPeriods[0].endDay, 6.0);
  ASSERT_EQ(s.userSnowfalls.size(), 1u);
  EXPECT_DOUBLE_EQ(s.userSnowfalls[0].endDay, 10.0);
  EXPECT_DOUBLE_EQ(s.params.rainSnowLimitM, 1300.0);
  EXPECT_DOUBLE_EQ(s.params.meltRateMPerDayPerC, 0.02);
  EXPECT_DOUBLE_EQ(s.params.snowfallRatePerDay, 1e-4);  // untouched default
  EXPECT_EQ(s.outputs.layers, (std::vector<std::string>{"powder", "depth"}));
  EXPECT_EQ(s.outputs.format, ImageFormat::Tiff);
  EXPECT_EQ(s.outputs.frameDays, (std::vector<double>{30, 60}));
  EXPECT_EQ(s.seed, 77u);
  EXPECT_EQ(s.backend, BackendChoice::Cpu);
}

TEST(SceneFile, UnknownKeyNamesFileLineAndKeyWithASuggestion) {
  SceneTempDir dir;
  const std::string msg = errorOf(dir, replaced(kValid, "days = 90", "dayz = 90"));
  EXPECT_NE(msg.find("scene.toml:10"), std::string::npos) << msg;
  EXPECT_NE(msg.find("season.dayz"), std::string::npos) << msg;
  EXPECT_NE(msg.find("unknown key"), std::string::npos) << msg;
  EXPECT_NE(msg.find("did you mean 'season.days'"), std::string::npos) << msg;
}

TEST(SceneFile, UnknownParameterIsAnError) {
  SceneTempDir dir;
  const std::string msg = errorOf(dir, replaced(kValid, "rain_snow_limit_m", "rain_snow_limt_m"));
  EXPECT_NE(msg.find("scene.toml:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("parameters.rain_snow_limt_m"), std::string::npos) << msg;
}

TEST(SceneFile, WrongTypeNamesFileAndKey) {
  SceneTempDir dir;
  const std::string msg = errorOf(dir, replaced(kValid, "days = 90", "days = \"ninety\""));
  EXPECT_NE(msg.find("scene.toml:10"), std::string::npos) << msg;
  EXPECT_NE(msg.find("season.days"), std::string::npos) << msg;
  EXPECT_NE(msg.find("must be a number, not a string"), std::string::npos) << msg;
}

TEST(SceneFile, OutOfRangeNamesFileKeyAndRange) {
  SceneTempDir dir;
  const std::string msg = errorOf(dir, replaced(kValid, "latitude_deg = 46.0", "latitude_deg = 123.0"));
  EXPECT_NE(msg.find("scene.toml:7"), std::string::npos) << msg;
  EXPECT_NE(msg.find("site.latitude_deg"), std::string::npos) << msg;
  EXPECT_NE(msg.find("out of range [-90, 90]"), std::string::npos) << msg;
  const std::string p = errorOf(dir, replaced(kValid, "melt_rate_m_per_day_per_c = 0.02", "melt_rate_m_per_day_per_c = -1"));
  EXPECT_NE(p.find("parameters.melt_rate_m_per_day_per_c"), std::string::npos) << p;
  EXPECT_NE(p.find("out of range"), std::string::npos) << p;
}

TEST(SceneFile, BadChoiceListsTheChoices) {
  SceneTempDir dir;
  const std::string msg = errorOf(dir, replaced(kValid, "format = \"tiff\"", "format = \"jpeg\""));
  EXPECT_NE(msg.find("outputs.format"), std::string::npos) << msg;
  EXPECT_NE(msg.find("exr, tiff"), std::string::npos) << msg;
}

TEST(SceneFile, MissingTerrainFileNamesSceneKeyAndPath) {
  SceneTempDir dir;
  std::string text = replaced(kValid, "builtin = \"ridged\"\nsize = 64\ncell_size_m = 20.0", "file = \"dems/nowhere.asc\"");
  const std::string msg = errorOf(dir, text);
  EXPECT_NE(msg.find("scene.toml:3"), std::string::npos) << msg;
  EXPECT_NE(msg.find("terrain.file"), std::string::npos) << msg;
  EXPECT_NE(msg.find("nowhere.asc"), std::string::npos) << msg;
  EXPECT_NE(msg.find("does not exist"), std::string::npos) << msg;
}

TEST(SceneFile, TerrainNeedsExactlyOneSource) {
  SceneTempDir dir;
  const std::string msg = errorOf(dir, replaced(kValid, "builtin = \"ridged\"", "builtin = \"ridged\"\nfile = \"x.asc\""));
  EXPECT_NE(msg.find("terrain"), std::string::npos) << msg;
  EXPECT_NE(msg.find("exactly one"), std::string::npos) << msg;
}

TEST(SceneFile, SyntaxErrorNamesFileAndLine) {
  SceneTempDir dir;
  const std::string msg = errorOf(dir, replaced(kValid, "days = 90", "days = = 90"));
  EXPECT_NE(msg.find("scene.toml:10"), std::string::npos) << msg;
  EXPECT_NE(msg.find("syntax"), std::string::npos) << msg;
}

TEST(SceneFile, SetOverridesWithTheSameValidation) {
  SceneTempDir dir;
  const std::string path = dir.write("scene.toml", kValid);
  const Scene s = loadSceneFile(path, {"season.days=30", "run.backend=auto", "parameters.snowfall_rate_per_day=2e-4",
                                       "outputs.frames_days=[10]"});
  EXPECT_DOUBLE_EQ(s.days, 30.0);
  EXPECT_EQ(s.backend, BackendChoice::Auto);  // a bare word is read as a string
  EXPECT_DOUBLE_EQ(s.params.snowfallRatePerDay, 2e-4);
  EXPECT_EQ(s.outputs.frameDays, (std::vector<double>{10}));

  const std::string range = errorOf(dir, kValid, {"season.days=0"});
  EXPECT_NE(range.find("--set season.days=0"), std::string::npos) << range;
  EXPECT_NE(range.find("season.days"), std::string::npos) << range;
  EXPECT_NE(range.find("out of range"), std::string::npos) << range;
  const std::string unknown = errorOf(dir, kValid, {"season.lenght=3"});
  EXPECT_NE(unknown.find("--set season.lenght=3"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("unknown key"), std::string::npos) << unknown;
  const std::string malformed = errorOf(dir, kValid, {"season.days"});
  EXPECT_NE(malformed.find("KEY=VALUE"), std::string::npos) << malformed;
}

TEST(SceneFile, FramesAfterTheSeasonAreRefused) {
  SceneTempDir dir;
  const std::string msg = errorOf(dir, kValid, {"season.days=20"});
  EXPECT_NE(msg.find("outputs.frames_days"), std::string::npos) << msg;
}

TEST(SceneFile, MissingSceneFileIsAnInputError) {
  EXPECT_THROW(loadSceneFile("/nonexistent/scene.toml"), InputError);
}

TEST(SceneFile, EmbeddedDefaultPresetLoads) {
  const Scene s = loadScene("preset:default");
  EXPECT_TRUE(s.terrain.builtin);
  EXPECT_EQ(s.terrain.builtinOptions.size, 512);
  EXPECT_DOUBLE_EQ(s.days, 120.0);
  EXPECT_THROW(loadScene("preset:nope"), InputError);
}

TEST(SceneFile, PresetFileOnDiskMatchesTheEmbeddedOne) {
  const Scene fromDisk = loadSceneFile(std::string(SNOWBAKE_SOURCE_DIR) + "/presets/default.toml");
  const Scene embedded = loadScene("preset:default");
  EXPECT_EQ(fromDisk.canonicalToml, embedded.canonicalToml);
}

// season.avalanche_flow: the pipes unless the scene asks for the shallow water; any other name is
// refused with the key and the choices.
TEST(SceneFile, AvalancheFlowIsThePipesUnlessTheSceneAsksForTheShallowWater) {
  SceneTempDir dir;
  EXPECT_EQ(loadSceneFile(dir.write("scene.toml", kValid)).params.avalancheFlow, AvalancheFlow::Pipes);
  const Scene water = loadSceneFile(dir.write("water.toml", replaced(kValid, "days = 90", "days = 90\navalanche_flow = \"shallow_water\"")));
  EXPECT_EQ(water.params.avalancheFlow, AvalancheFlow::ShallowWater);
  const std::string msg = errorOf(dir, replaced(kValid, "days = 90", "days = 90\navalanche_flow = \"particles\""));
  EXPECT_NE(msg.find("season.avalanche_flow"), std::string::npos) << msg;
  EXPECT_NE(msg.find("pipes, shallow_water"), std::string::npos) << msg;
}
