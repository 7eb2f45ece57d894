// The Blender add-on (python/blender/snowbake_import.py, docs/blender.md) in Blender 3.4 headless
// (tools/blender_addon_check.py): it registers with its File > Import entry; a bake imports
// through the operator with its snow material (masks as Non-Color textures, the coverage wired to
// the snow/rock mix, the normal map to the BSDF) and the VDB as a volume with a density material;
// a 32 x 32 Cycles render from above is bright where the bake has snow and dark where it has none,
// and changes without the normal map; a mesh tile set imports with its neighbours' border vertices
// coinciding; frames come in as an image sequence on the timeline. Skips without blender (fails in CI).
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "bake_support.h"

namespace snow {
namespace {

namespace fs = std::filesystem;

TEST(BlenderAddon, RegistersImportsABakeAndItsRenderIsBrightWhereTheBakeHasSnowAndTilesMeet) {
  if (std::system("command -v blender >/dev/null 2>&1") != 0) {
    if (std::getenv("CI")) FAIL() << "blender is not installed (tools/setup-debian.sh --with-blender installs it)";
    GTEST_SKIP() << "blender not found: run tools/setup-debian.sh --with-blender";
  }
  const std::string terrain = "[terrain]\nbuiltin = \"ridged\"\nsize = 64\ncell_size_m = 20\n";
  // Occlusion mode: snow on the flats, none on the steep flanks. A coarse mesh (5 m), so the
  // normal map has detail the mesh lacks.
  const test::Bake render = test::bakeSceneText(
      "addon_render", "mode = \"occlusion\"\n" + terrain +
                          "[outputs]\nlayers = [\"depth\", \"snow_coverage\", \"weight_snow\", \"snow_normal\"]\nmeshes = [\"glb\"]\n"
                          "mesh_max_error_m = 5\nvdb = true\nvdb_voxel_size_m = 10\n");
  const test::Bake tiled = test::bakeSceneText(
      "addon_tiles", terrain +
                         "[season]\ndays = 12\n[precompute]\nsun = false\n[[weather.snowfall]]\nstart_day = 0\nend_day = 4\n"
                         "[outputs]\nlayers = [\"depth\", \"snow_coverage\"]\nmeshes = [\"glb\"]\nmesh_tile_size_m = 640\nframes_days = [5, 10]\n");
  const fs::path log = render.dir / "blender.log";
  const std::string src = SNOWBAKE_SOURCE_DIR;
  const std::string command = "blender -b --factory-startup --python \"" + src + "/tools/blender_addon_check.py\" -- \"" + src +
                              "/python/blender/snowbake_import.py\" \"" + render.out().string() + "\" \"" + tiled.out().string() + "\" > \"" +
                              log.string() + "\" 2>&1";
  const int status = std::system(command.c_str());
  std::ifstream logIn(log);
  const std::string logText((std::istreambuf_iterator<char>(logIn)), {});
  ASSERT_EQ(status, 0) << logText;
  ASSERT_TRUE(fs::exists(render.out() / "blender_addon_check.json")) << logText;
  const auto r = nlohmann::json::parse(std::ifstream(render.out() / "blender_addon_check.json"));

  EXPECT_TRUE(r["registered"].get<bool>());
  EXPECT_TRUE(r["menu"].get<bool>());
  EXPECT_EQ(r["import_status"], nlohmann::json({"FINISHED"}));
  EXPECT_EQ(r["surface"]["objects"], 1);
  EXPECT_EQ(r["material"]["mask_textures"], nlohmann::json({"snow_coverage", "weight_snow"}));
  EXPECT_EQ(r["material"]["mask_colorspaces"], nlohmann::json({"Non-Color"}));
  EXPECT_TRUE(r["material"]["coverage_wired"].get<bool>());
  EXPECT_TRUE(r["material"]["normal_map_wired"].get<bool>());
  EXPECT_EQ(r["volume"]["objects"], 1);
  EXPECT_EQ(r["volume"]["density_attribute"], "density");

  // Snow pixels bright, bare ones dark: both sets large, their means apart, nearly every pixel on its side.
  const auto& px = r["render"];
  std::printf("[ measure ] render 32 x 32: %d snow pixels mean %.3f, %d bare pixels mean %.3f; %.1f %% / %.1f %% on their side; "
              "without the normal map the pixels change by %.3f on average\n",
              px["pixels_snow"].get<int>(), px["mean_snow"].get<double>(), px["pixels_bare"].get<int>(), px["mean_bare"].get<double>(),
              100 * px["snow_brighter_than_midpoint"].get<double>(), 100 * px["bare_darker_than_midpoint"].get<double>(),
              r["normal_map_effect"]["mean_abs_difference"].get<double>());
  EXPECT_GT(px["pixels_snow"].get<int>(), 50);
  EXPECT_GT(px["pixels_bare"].get<int>(), 50);
  EXPECT_GT(px["mean_snow"].get<double>(), 2.0 * px["mean_bare"].get<double>());
  EXPECT_GT(px["snow_brighter_than_midpoint"].get<double>(), 0.9);
  EXPECT_GT(px["bare_darker_than_midpoint"].get<double>(), 0.9);
  // The normal map changes the shading (the 5 m mesh is coarser than the map).
  EXPECT_GT(r["normal_map_effect"]["mean_abs_difference"].get<double>(), 0.01);

  // Mesh tiles: 2 x 2 of 32 cells; every border vertex has its twin in the neighbour.
  EXPECT_EQ(r["tiles"]["count"], 4);
  EXPECT_GT(r["tiles"]["border_vertices"].get<int>(), 60);
  EXPECT_LT(r["tiles"]["max_gap_m"].get<double>(), 1e-3);
  // Frames: days 5 and 10 as an image sequence, the timeline over them.
  EXPECT_EQ(r["frames"]["source"], "SEQUENCE");
  EXPECT_EQ(r["frames"]["scene_frames"], nlohmann::json({5, 10}));
  fs::remove_all(render.dir);
  fs::remove_all(tiled.dir);
}

}  // namespace
}  // namespace snow
