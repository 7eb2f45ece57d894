// Terrain input basics (every format and its checks: terrain_formats_test.cpp).
#include <gtest/gtest.h>

#include <filesystem>
#include <cmath>
#include <fstream>
#include <functional>

#include "core/errors.h"
#include "inputs/terrain_loader.h"
#include "temp_dir.h"

using namespace snow;
namespace fs = std::filesystem;

namespace {

fs::path terrainTempDir() {
  return snow::test::uniqueTestDir("terrain_test");
}

std::string writeAsc(const fs::path& dir, const std::string& name, const std::string& header, int w, int h,
                     const std::function<std::string(int, int)>& value) {
  const fs::path path = dir / name;
  std::ofstream out(path);
  out << "ncols " << w << "\nnrows " << h << "\n" << header;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) out << value(x, y) << (x + 1 < w ? " " : "\n");
  }
  return path.string();
}

std::string inputErrorOf(const std::string& path) {
  try {
    loadDem(path);
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error for " << path;
  return "";
}

const std::string kSharedDem = SNOWBAKE_SHARED_DATA_DIR "/dem/";

}  // namespace

TEST(TerrainLoader, ProjectedAsciiGridKeepsMetresAndNodata) {
  const fs::path dir = terrainTempDir();
  const std::string path =
      writeAsc(dir, "hill.asc", "xllcorner 1000\nyllcorner 2000\ncellsize 5\nNODATA_value -9999\n", 6, 4, [](int x, int y) {
        return x == 0 && y == 0 ? std::string("-9999") : std::to_string(100 + 10 * x + y);
      });
  const Terrain t = loadDem(path);
  EXPECT_EQ(t.info.spec.width, 6);
  EXPECT_EQ(t.info.spec.height, 4);
  EXPECT_DOUBLE_EQ(t.info.spec.cellSizeXM, 5.0);
  EXPECT_DOUBLE_EQ(t.info.spec.cellSizeYM, 5.0);
  EXPECT_EQ(t.info.nodataCells, 1u);
  EXPECT_EQ(t.valid(0, 0), 0);
  EXPECT_FLOAT_EQ(t.heightsM(5, 3), 153.f);  // row 0 of the file is the north edge
  EXPECT_FLOAT_EQ(t.info.minElevationM, 101.f);
  EXPECT_FLOAT_EQ(t.heightsM(0, 0), 101.f);  // NODATA filled with the lowest height, never NaN
  EXPECT_NE(t.info.coordinateSystem.find("metres"), std::string::npos);
  fs::remove_all(dir);
}

TEST(TerrainLoader, DegreesWithoutCoordinateSystemBecomeMetresAtTheLatitude) {
  const fs::path dir = terrainTempDir();
  const std::string path = writeAsc(dir, "geo.asc", "xllcorner -105.7\nyllcorner 40.0\ncellsize 0.000833333\nNODATA_value 0\n", 5,
                                    5, [](int x, int y) { return std::to_string(2000 + x + y); });
  const Terrain t = loadDem(path);
  EXPECT_NEAR(t.info.spec.cellSizeXM, 71.0, 0.5);  // cos(40 deg) shrinks longitude
  EXPECT_NEAR(t.info.spec.cellSizeYM, 92.5, 0.5);
  EXPECT_TRUE(t.info.latitudeKnown);
  EXPECT_NEAR(t.info.centreLatitudeDeg, 40.0, 0.01);
  EXPECT_NE(t.info.coordinateDecision.find("degrees"), std::string::npos) << t.info.coordinateDecision;
  fs::remove_all(dir);
}

TEST(TerrainLoader, BadFilesGiveOneLineErrorsNamingTheFile) {
  const fs::path dir = terrainTempDir();
  const std::string missing = (dir / "missing.asc").string();
  EXPECT_NE(inputErrorOf(missing).find(missing), std::string::npos);
  const std::string empty = (dir / "empty.asc").string();
  std::ofstream(empty).close();
  EXPECT_NE(inputErrorOf(empty).find("empty"), std::string::npos);
  const std::string garbage = (dir / "garbage.asc").string();
  std::ofstream(garbage) << "this is not a terrain\n";
  const std::string g = inputErrorOf(garbage);
  EXPECT_NE(g.find(garbage), std::string::npos) << g;
  const std::string tiny = writeAsc(dir, "tiny.asc", "xllcorner 0\nyllcorner 0\ncellsize 1\n", 2, 2,
                                    [](int, int) { return std::string("5"); });
  EXPECT_NE(inputErrorOf(tiny).find("too small"), std::string::npos);
  const std::string nan = writeAsc(dir, "nan.asc", "xllcorner 0\nyllcorner 0\ncellsize 1\n", 4, 4,
                                   [](int x, int y) { return x == 2 && y == 1 ? std::string("nan") : std::string("5.5"); });  // a float grid: GDAL reads integer grids as Int32
  const std::string n = inputErrorOf(nan);
  EXPECT_NE(n.find("not finite"), std::string::npos) << n;
  EXPECT_EQ(n.find('\n'), std::string::npos) << "one line";
  fs::remove_all(dir);
}

TEST(TerrainLoader, RealFrontRangeDemIsGeographic) {
  const std::string path = kSharedDem + "front_range_small_srtm3.asc";
  if (!fs::exists(path)) GTEST_SKIP() << "shared data not found: " << path;
  const Terrain t = loadDem(path);
  EXPECT_EQ(t.info.spec.width, 240);
  EXPECT_EQ(t.info.spec.height, 144);
  EXPECT_NEAR(t.info.spec.cellSizeXM, 71.0, 1.5);
  EXPECT_NEAR(t.info.spec.cellSizeYM, 92.5, 0.5);
  EXPECT_NEAR(t.info.minElevationM, 1943.f, 1.f);
  EXPECT_NEAR(t.info.maxElevationM, 3286.f, 1.f);
}

TEST(TerrainLoader, RealTyrolDemHasFiveMetreCellsAndMaskedOutline) {
  const std::string path = kSharedDem + "tyrol_avaWog_5m.asc";
  if (!fs::exists(path)) GTEST_SKIP() << "shared data not found: " << path;
  const Terrain t = loadDem(path);
  EXPECT_NEAR(t.info.spec.cellSizeXM, 5.0, 0.01);  // the file says 4.997678
  EXPECT_NEAR(t.info.spec.cellSizeYM, 5.0, 0.01);
  EXPECT_GT(t.info.nodataCells, t.heightsM.size() / 5);  // about a third of the cells
  EXPECT_NEAR(t.info.minElevationM, 1249.f, 1.f);
  EXPECT_NEAR(t.info.maxElevationM, 2544.f, 1.f);
}

TEST(TerrainLoader, MetresPerDegree) {
  EXPECT_NEAR(metresPerDegreeLatitude(0.0), 110574.0, 2.0);
  EXPECT_NEAR(metresPerDegreeLongitude(0.0), 111320.0, 2.0);
  EXPECT_NEAR(metresPerDegreeLongitude(60.0), 55800.0, 20.0);
}

TEST(TerrainLoader, RealLargeFrontRangeDem) {
  const std::string path = kSharedDem + "front_range_srtm3.asc";
  if (!fs::exists(path)) GTEST_SKIP() << "shared data not found: " << path;
  const Terrain t = loadDem(path);
  EXPECT_EQ(t.info.spec.width, 758);
  EXPECT_EQ(t.info.spec.height, 758);
  EXPECT_NEAR(t.info.spec.cellSizeXM, 71.0, 1.0);
  EXPECT_NEAR(t.info.spec.cellSizeYM, 92.5, 0.5);
  EXPECT_NEAR(t.info.minElevationM, 1547.f, 1.f);
  EXPECT_NEAR(t.info.maxElevationM, 4320.f, 1.f);
  EXPECT_EQ(t.info.nodataCells, 0u);  // NODATA_value 0 is declared but never used
}

TEST(TerrainLoader, RealTyrolOutlineIsMaskedWhereTheFileSaysNodata) {
  const std::string path = kSharedDem + "tyrol_avaKot_5m.asc";
  if (!fs::exists(path)) GTEST_SKIP() << "shared data not found: " << path;
  const Terrain t = loadDem(path);
  // Count -9999 tokens in the file itself and compare.
  std::ifstream in(path);
  std::string token;
  size_t header = 0, nodataTokens = 0;
  while (in >> token) {
    if (header < 12) {  // six "key value" header lines
      ++header;
      continue;
    }
    if (token == "-9999" || token == "-9999.0") ++nodataTokens;
  }
  EXPECT_EQ(t.info.nodataCells, nodataTokens);
  EXPECT_GT(nodataTokens, t.heightsM.size() / 5);
  for (size_t i = 0; i < t.heightsM.size(); ++i) ASSERT_TRUE(std::isfinite(t.heightsM.values()[i]));
}

TEST(TerrainLoader, CropKeepsTheWindowsCellsAndMovesTheOrigin) {
  // The builtin range (10 m cells) cropped to [205, 95, 405, 300] m: cells whose centres lie
  // inside, i.e. columns 20..39 and rows 9..29, the same heights, the origin moved to the
  // window's north-west corner; then resampled to 2.5 m (a finer window).
  TerrainSource whole;
  whole.builtin = true;
  whole.builtinOptions.size = 64;
  whole.builtinOptions.cellSizeM = 10.0;
  const Terrain t = loadTerrain(whole);
  TerrainSource crop = whole;
  crop.cropM = std::array<double, 4>{205.0, 95.0, 405.0, 300.0};
  const Terrain c = loadTerrain(crop);
  ASSERT_EQ(c.info.spec.width, 20);
  ASSERT_EQ(c.info.spec.height, 21);
  for (int y = 0; y < 21; ++y)
    for (int x = 0; x < 20; ++x) ASSERT_EQ(c.heightsM(x, y), t.heightsM(x + 20, y + 9));
  EXPECT_DOUBLE_EQ(c.info.spec.originX, t.info.spec.originX + 200.0);
  EXPECT_DOUBLE_EQ(c.info.spec.originY, t.info.spec.originY - 90.0);
  EXPECT_NE(c.info.resampling.find("cropped"), std::string::npos);
  TerrainSource fine = crop;
  fine.resampleCellSizeM = 2.5;
  const Terrain f = loadTerrain(fine);
  EXPECT_EQ(f.info.spec.width, 80);
  EXPECT_EQ(f.info.spec.height, 84);
  EXPECT_EQ(f.info.spec.cellSizeXM, 2.5);
  // A window off the terrain: an error naming the key and the terrain's extent.
  TerrainSource off = whole;
  off.cropM = std::array<double, 4>{700.0, 0.0, 800.0, 100.0};
  try {
    loadTerrain(off);
    FAIL() << "no error";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("terrain.crop_m"), std::string::npos) << m;
    EXPECT_NE(m.find("640"), std::string::npos) << m;
  }
}
