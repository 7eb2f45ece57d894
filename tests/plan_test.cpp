// snowbake plan: on scenes of every mode (season, occlusion, mesh), with frames, tiles (layers.exr
// and the contact sheet among them), encodings, GeoTIFF, resize (also a tile set's own) and meshes,
// the files the plan lists are exactly the files the bake then writes, the sizes it calls exact
// are, and the plan itself writes nothing.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "bake/plan.h"
#include "core/errors.h"

namespace snow {
namespace {

namespace fs = std::filesystem;

fs::path workDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("snowbake_plan_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::set<std::string> filesUnder(const fs::path& dir) {
  std::set<std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) files.insert(fs::relative(e.path(), dir).string());
  return files;
}

const std::string kSeason =
    "[season]\ndays = 6\n[precompute]\nsun = false\n[[weather.snowfall]]\nstart_day = 0\nend_day = 4\n[run]\nseed = 5\nthreads = 2\n";
const std::string kBuiltin = "[terrain]\nbuiltin = \"ridged\"\nsize = 64\ncell_size_m = 20.0\n";

struct PlanCase {
  std::string name, scene;
};

std::vector<PlanCase> planCases(const fs::path& dir) {
  std::ofstream(dir / "block.obj") << "v 0 0 0\nv 2 0 0\nv 2 2 0\nv 0 2 0\nv 0.7 0.7 0.5\nv 1.3 0.7 0.5\nv 1.3 1.3 0.5\nv 0.7 1.3 0.5\n"
                                      "v 0.7 0.7 0\nv 1.3 0.7 0\nv 1.3 1.3 0\nv 0.7 1.3 0\nf 1 2 3\nf 1 3 4\nf 5 6 7\nf 5 7 8\n"
                                      "f 9 10 6\nf 9 6 5\nf 10 11 7\nf 10 7 6\nf 11 12 8\nf 11 8 7\nf 12 9 5\nf 12 5 8\n";
  return {
      {"encodings", kBuiltin + kSeason +
                        "[outputs]\nlayers = [\"depth\", \"surface\", \"snow_coverage\", \"preview\"]\nencodings = [\"png16\", \"png8\", \"r16\", \"r32\"]\n"
                        "multichannel_exr = true\ndisplacement_size = [50, 40]\nvdb = true\n"},
      {"frames", kBuiltin + kSeason + "[outputs]\nlayers = [\"depth\", \"preview\"]\nencodings = [\"png16\"]\nframes_days = [0, 2, 5]\n"
                                      "[outputs.ranges]\ndepth = \"season\"\n"},
      {"tiles", kBuiltin + kSeason +
                    "[outputs]\nlayers = [\"depth\", \"preview\", \"splat_map\", \"snow_normal\"]\nencodings = [\"png8\", \"r16\", \"r32\"]\n"
                    "meshes = [\"glb\", \"obj\"]\nmesh_tile_size_m = 400.0\nmultichannel_exr = true\nframes_days = [2]\n[outputs.tiles]\nconvention = \"grid\"\nsize_px = 24\n"},
      {"tiff_resize", kBuiltin + kSeason +
                          "[outputs]\nlayers = [\"depth\", \"weight_snow\", \"splat_map\"]\nformat = \"tiff\"\nencodings = [\"png16\"]\n"
                          "resize = [40, 30]\nmeshes = [\"ply\"]\nframes_days = [3]\n[outputs.tiles]\nconvention = \"unity\"\nsize_px = 33\nresize = [65, 65]\n"},
      {"occlusion", "mode = \"occlusion\"\n" + kBuiltin + "[outputs]\nlayers = [\"depth\", \"preview\"]\nencodings = [\"png8\"]\nvdb = true\n"},
      {"mesh", "mode = \"mesh\"\n[terrain]\nfile = \"" + (dir / "block.obj").string() +
                   "\"\n[mesh_snow]\ndepth_m = 0.3\nsite_spacing_m = 0.05\n[outputs]\nmeshes = [\"glb\", \"ply\"]\nvdb = true\n"},
  };
}

TEST(Plan, ListsExactlyTheFilesTheBakeWritesOnSixScenesOfEveryModeAndWritesNothing) {
  const fs::path dir = workDir("six");
  for (const PlanCase& c : planCases(dir)) {
    SCOPED_TRACE(c.name);
    const fs::path scene = dir / (c.name + ".toml"), out = dir / c.name;
    std::ofstream(scene) << c.scene;
    BakeOptions o;
    o.scene = scene.string();
    o.outDir = out.string();
    o.backend = "cpu";
    o.useCache = false;
    o.progress = false;
    const BakePlan plan = planBake(o);
    EXPECT_FALSE(fs::exists(out)) << "the plan wrote into its output folder";
    std::set<std::string> planned;
    for (const PlannedFile& f : plan.files) {
      EXPECT_EQ(f.condition, "") << f.path << ": these scenes have no file that depends on the snow";
      EXPECT_TRUE(planned.insert(fs::relative(f.path, out).string()).second) << f.path << " listed twice";
    }
    std::ostringstream log;
    runBake(o, log);
    const std::set<std::string> written = filesUnder(out);
    EXPECT_EQ(planned, written);
    std::printf("[ measure ] %s: %zu files planned, %zu written\n", c.name.c_str(), planned.size(), written.size());
    size_t exact = 0;
    for (const PlannedFile& f : plan.files)
      if (f.exactBytes && fs::exists(f.path)) {
        ++exact;
        EXPECT_EQ(static_cast<double>(fs::file_size(f.path)), f.dataBytes) << f.path;
      }
    if (c.name == "encodings" || c.name == "tiles") {
      EXPECT_GT(exact, 0u);
    }
    EXPECT_GT(plan.memory.peakBytes(), 0.0);
    EXPECT_FALSE(plan.timeClass.empty());
  }
  fs::remove_all(dir);
}

TEST(Plan, SaysWhichStagesRunAndWhyOthersAreSkippedAndListsPathsRelativeToARelativeOut) {
  const fs::path dir = workDir("stages");
  std::ofstream(dir / "s.toml") << kBuiltin + kSeason + "[outputs]\nlayers = [\"depth\"]\n";
  BakeOptions o;
  o.scene = (dir / "s.toml").string();
  o.outDir = "snowbake_plan_relative_out";  // relative to the working folder, as on a command line
  o.useCache = false;
  const BakePlan plan = planBake(o);
  EXPECT_FALSE(fs::exists(o.outDir));
  std::map<std::string, PlannedStage> byName;
  for (const auto& s : plan.stages) byName[s.name] = s;
  EXPECT_FALSE(byName["sun exposure"].runs);
  EXPECT_EQ(byName["sun exposure"].why, "precompute.sun = false");
  EXPECT_FALSE(byName["wind"].runs);
  EXPECT_EQ(byName["wind"].why, "no wind in the season");
  EXPECT_TRUE(byName["season"].runs);
  EXPECT_FALSE(byName["frames"].runs);
  const std::string json = planToJson(plan);
  EXPECT_NE(json.find("\"path\": \"depth.exr\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"peak_bytes\""), std::string::npos);
  fs::remove_all(dir);
}

TEST(Plan, ListsTheSunTermsOfZeroWeightAsSkippedInTheExposureStage) {
  const fs::path dir = workDir("terms");
  std::ofstream(dir / "s.toml") << "[terrain]\nbuiltin = \"ridged\"\nsize = 32\ncell_size_m = 20.0\n"
                                   "[season]\ndays = 2\n[precompute]\nsun = true\n"
                                   "[parameters]\nsky_ambient_weight_hours = 0.0\n[outputs]\nlayers = [\"depth\"]\n";
  BakeOptions o;
  o.scene = (dir / "s.toml").string();
  o.outDir = (dir / "o").string();
  o.useCache = false;
  std::map<std::string, PlannedStage> byName;
  for (const auto& s : planBake(o).stages) byName[s.name] = s;
  EXPECT_TRUE(byName["sun exposure"].runs);
  const std::string& why = byName["sun exposure"].why;
  EXPECT_NE(why.find("skipped sky: sky_ambient_weight_hours = 0"), std::string::npos) << why;
  EXPECT_EQ(why.find("direct sun"), std::string::npos) << why;
  fs::remove_all(dir);
}

TEST(Plan, ABadKeyIsTheBakesInputError) {
  const fs::path dir = workDir("bad");
  std::ofstream(dir / "s.toml") << kBuiltin + "[season]\ndays = -3\n";
  BakeOptions o;
  o.scene = (dir / "s.toml").string();
  o.outDir = (dir / "out").string();
  try {
    planBake(o);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("s.toml:6"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("season.days"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir / "out"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace snow
