// Engine deliverables: [outputs.tiles] (every convention on the builtin range and a real DEM),
// [outputs.ranges] (season, fixed, NODATA) and their scene errors.
#include <gtest/gtest.h>
#include <unistd.h>  // getpid

#include <OpenImageIO/imageio.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <gdal_priv.h>
#include <nlohmann/json.hpp>
#include <ogr_spatialref.h>

#include "bake_support.h"
#include "cli_support.h"
#include "geotiff_support.h"
#include "bakers/grid_writer.h"
#include "core/errors.h"
#include "scene/scene.h"

using namespace snow;
namespace fs = std::filesystem;

namespace {

using snow::test::manifestOf;

// One channel of an image's pixels as stored (uint16 or uint8 PNG, raw r16 of a known size).
struct Pixels {
  int width = 0, height = 0;
  std::vector<uint32_t> v;
  uint32_t at(int x, int y) const { return v[static_cast<size_t>(y) * width + x]; }
};
Pixels readPixels(const fs::path& path, int rawWidth = 0, int rawHeight = 0) {
  Pixels p;
  if (path.extension() == ".r16") {
    std::ifstream in(path, std::ios::binary);
    std::vector<char> bytes((std::istreambuf_iterator<char>(in)), {});
    p.width = rawWidth, p.height = rawHeight;
    EXPECT_EQ(bytes.size(), static_cast<size_t>(rawWidth) * rawHeight * 2) << path;
    for (size_t i = 0; i + 1 < bytes.size(); i += 2)
      p.v.push_back(static_cast<uint8_t>(bytes[i]) | (static_cast<uint32_t>(static_cast<uint8_t>(bytes[i + 1])) << 8));
    return p;
  }
  auto in = OIIO::ImageInput::open(path.string());
  EXPECT_TRUE(in) << path;
  if (!in) return p;
  const auto& spec = in->spec();
  p.width = spec.width, p.height = spec.height;
  std::vector<uint16_t> wide(static_cast<size_t>(spec.width) * spec.height * spec.nchannels);
  in->read_image(0, 0, 0, 1, OIIO::TypeDesc::UINT16, wide.data());  // channel 0; uint8 scaled by 257
  const uint32_t scale = spec.format == OIIO::TypeDesc::UINT8 ? 257 : 1;
  for (size_t i = 0; i < static_cast<size_t>(spec.width) * spec.height; ++i) p.v.push_back(wide[i] / scale);
  return p;
}
Pixels readAny(const fs::path& path, int w, int h) {
  if (path.extension() == ".exr") {
    const Grid<float> g = readFloatImage(path.string());
    Pixels p{g.width(), g.height(), {}};
    for (float f : g.values()) {
      uint32_t bits;
      std::memcpy(&bits, &f, 4);
      p.v.push_back(bits);
    }
    return p;
  }
  return readPixels(path, w, h);
}

std::string terrainOf(const std::string& which) {
  if (which == "builtin") return "builtin = \"ridged\"\nsize = 200\ncell_size_m = 20.0\n";
  return "file = \"" + std::string(SNOWBAKE_SHARED_DATA_DIR) + "/dem/tyrol_avaWog_5m.asc\"\n";
}

std::string sceneText(const std::string& terrain, const std::string& tiles) {
  return "name = \"deliverables\"\n[terrain]\n" + terrainOf(terrain) +
         "[season]\ndays = 6\n[precompute]\nsun = false\n[[weather.snowfall]]\nstart_day = 0\nend_day = 4\n"
         "[outputs]\nlayers = [\"depth\", \"surface\", \"snow_coverage\", \"preview\"]\nencodings = [\"png16\", \"png8\", \"r16\"]\n"
         "[run]\nseed = 5\nthreads = 2\n" + tiles;
}

// Every tile of every tiled raster: the same size; neighbours share their overlap; the tiles
// put back together give the untiled file's pixels exactly.
void expectTilesReassemble(const fs::path& whole, const fs::path& tiled, int overlap) {
  const auto wm = manifestOf(whole), tm = manifestOf(tiled);
  std::map<std::string, nlohmann::json> wholeFiles;
  for (const auto& f : wm["files"]) wholeFiles[f["path"].get<std::string>()] = f;
  // Tiles grouped by their untiled file's path (the suffix taken out of the stem).
  std::map<std::string, std::vector<nlohmann::json>> groups;
  for (const auto& f : tm["files"]) {
    if (!f.contains("tile")) continue;
    const std::string path = f["path"];
    const auto& t = f["tile"];
    const std::string conv = t["convention"];
    const int c = t["column"], r = t["row"];
    std::string suffix = conv == "unity" ? "_" + std::to_string(c) + "_" : "_x" + std::to_string(c) + "_y" + std::to_string(r);
    size_t at = path.find(suffix);
    ASSERT_NE(at, std::string::npos) << path;
    size_t end = at + suffix.size();
    if (conv == "unity") end = path.find_first_not_of("0123456789", end);
    groups[path.substr(0, at) + path.substr(end)].push_back(f);
  }
  ASSERT_GE(groups.size(), 10u);
  for (const auto& [wholePath, tiles] : groups) {
    ASSERT_TRUE(wholeFiles.count(wholePath)) << wholePath;
    const auto& wf = wholeFiles[wholePath];
    const Pixels w = readAny(whole / wholePath, wf["width"], wf["height"]);
    const int size = tiles[0]["width"];
    const int step = size - overlap;
    std::map<std::pair<int, int>, Pixels> byPos;
    for (const auto& f : tiles) {
      EXPECT_EQ(f["width"], size);
      EXPECT_EQ(f["height"], size);
      const Pixels p = readAny(tiled / f["path"].get<std::string>(), size, size);
      ASSERT_EQ(p.width, size) << f["path"];
      ASSERT_EQ(p.height, size) << f["path"];
      const int x0 = f["tile"]["x"], y0 = f["tile"]["y"];
      EXPECT_EQ(x0, f["tile"]["column"].get<int>() * step);
      for (int y = 0; y < size && y0 + y < w.height; ++y)
        for (int x = 0; x < size && x0 + x < w.width; ++x)
          ASSERT_EQ(p.at(x, y), w.at(x0 + x, y0 + y)) << f["path"] << " pixel " << x << ", " << y;
      byPos[{f["tile"]["column"].get<int>(), f["tile"]["row"].get<int>()}] = p;
    }
    // Reaches the whole image, and neighbours' shared columns and rows hold the same pixels.
    int maxC = 0, maxR = 0;
    for (const auto& [pos, p] : byPos) maxC = std::max(maxC, pos.first), maxR = std::max(maxR, pos.second);
    EXPECT_GE(maxC * step + size, w.width) << wholePath;
    EXPECT_GE(maxR * step + size, w.height) << wholePath;
    EXPECT_EQ(byPos.size(), static_cast<size_t>((maxC + 1) * (maxR + 1)));
    for (const auto& [pos, p] : byPos) {
      if (byPos.count({pos.first + 1, pos.second})) {
        const Pixels& east = byPos[{pos.first + 1, pos.second}];
        for (int y = 0; y < size; ++y)
          for (int k = 0; k < overlap; ++k) ASSERT_EQ(p.at(step + k, y), east.at(k, y)) << wholePath;
      }
      if (byPos.count({pos.first, pos.second + 1})) {
        const Pixels& south = byPos[{pos.first, pos.second + 1}];
        for (int x = 0; x < size; ++x)
          for (int k = 0; k < overlap; ++k) ASSERT_EQ(p.at(x, step + k), south.at(x, k)) << wholePath;
      }
    }
  }
}

void tilesInEveryConvention(const std::string& terrain) {
  const test::Bake whole = test::bakeSceneText("tiles_whole_" + terrain, sceneText(terrain, ""));
  struct Case {
    std::string table;
    int overlap;
  };
  for (const Case& c : {Case{"convention = \"unreal\"\nsize_px = 127\n", 1}, Case{"convention = \"unity\"\nsize_px = 129\n", 1},
                        Case{"convention = \"grid\"\nsize_px = 150\noverlap_px = 6\n", 6}}) {
    SCOPED_TRACE(c.table);
    const test::Bake tiled = test::bakeSceneText("tiles_" + terrain, sceneText(terrain, "[outputs.tiles]\n" + c.table));
    expectTilesReassemble(whole.out(), tiled.out(), c.overlap);
    fs::remove_all(tiled.dir);
  }
  fs::remove_all(whole.dir);
}

}  // namespace

TEST(Deliverables, TilesOfTheBuiltinRangeMatchTheUntiledOutputsInEveryConvention) { tilesInEveryConvention("builtin"); }

TEST(Deliverables, TilesOfARealDemMatchTheUntiledOutputsInEveryConvention) {
  if (!fs::exists(std::string(SNOWBAKE_SHARED_DATA_DIR) + "/dem/tyrol_avaWog_5m.asc"))
    GTEST_SKIP() << "shared data not found: ../shared/data/dem/tyrol_avaWog_5m.asc";
  tilesInEveryConvention("dem");
}

TEST(Deliverables, TileNamesFollowTheConventions) {
  const test::Bake unity = test::bakeSceneText("names", sceneText("builtin", "[outputs.tiles]\nconvention = \"unity\"\nsize_px = 129\n"));
  // 200 pixels in tiles of 129 sharing one: 2 x 2; Unity counts rows from the south.
  EXPECT_TRUE(fs::exists(unity.out() / "depth_0_1.exr"));  // north-west
  EXPECT_TRUE(fs::exists(unity.out() / "depth_1_0.16.png"));
  EXPECT_FALSE(fs::exists(unity.out() / "depth.exr"));
  const auto m = manifestOf(unity.out());
  for (const auto& f : m["files"])
    if (f["path"] == "depth_0_1.exr") {
      EXPECT_EQ(f["tile"]["row"], 0);
      EXPECT_DOUBLE_EQ(f["tile"]["origin_y"].get<double>(), 4000.0);  // the builtin's north edge, 200 cells of 20 m
    }
  fs::remove_all(unity.dir);
}

// Two frame days' 16-bit depth under "season": one mapping, so one depth gives one pixel value.
TEST(Deliverables, SeasonRangeGivesEveryFrameOneMapping) {
  const std::string text = "name = \"season\"\n[terrain]\n" + terrainOf("builtin") +
                           "[season]\ndays = 8\n[precompute]\nsun = false\n[[weather.snowfall]]\nstart_day = 0\nend_day = 6\n"
                           "[outputs]\nlayers = [\"depth\"]\nencodings = [\"png16\"]\nframes_days = [2, 5]\n[run]\nseed = 5\n";
  const test::Bake s = test::bakeSceneText("season_frames", text);
  const auto m = manifestOf(s.out());
  std::vector<nlohmann::json> pngs;
  for (const auto& f : m["files"])
    if (f["path"].get<std::string>().find(".16.png") != std::string::npos) pngs.push_back(f);
  ASSERT_EQ(pngs.size(), 3u);
  double seasonMax = 0;
  for (const auto& f : pngs) {
    EXPECT_EQ(f["range"]["mode"], "season");
    EXPECT_EQ(f["range"]["lo"], pngs[0]["range"]["lo"]);
    EXPECT_EQ(f["range"]["hi"], pngs[0]["range"]["hi"]);
    const std::string path = f["path"];
    const Grid<float> depth = readFloatImage((s.out() / (path.substr(0, path.size() - 7) + ".exr")).string());
    seasonMax = std::max(seasonMax, static_cast<double>(*std::max_element(depth.values().begin(), depth.values().end())));
    const Pixels p = readPixels(s.out() / path);
    const double lo = f["range"]["lo"], hi = f["range"]["hi"];
    for (size_t i = 0; i < depth.size(); ++i)
      ASSERT_EQ(p.v[i], static_cast<uint32_t>(std::lround((depth.values()[i] - lo) / (hi - lo) * 65535))) << path;
  }
  // The frame of day 2 holds less snow than the season's deepest: its own range would differ.
  EXPECT_DOUBLE_EQ(pngs[0]["range"]["hi"].get<double>(), static_cast<double>(static_cast<float>(seasonMax)));
  fs::remove_all(s.dir);
}

// Masks map 0-1 straight; a fixed range clamps; NODATA is pixel 0 and left out of the range.
TEST(Deliverables, MasksMapStraightAndNodataIsLeftOutOfTheRange) {
  if (!fs::exists(std::string(SNOWBAKE_SHARED_DATA_DIR) + "/dem/tyrol_avaWog_5m.asc"))
    GTEST_SKIP() << "shared data not found: ../shared/data/dem/tyrol_avaWog_5m.asc";
  const test::Bake b = test::bakeSceneText(
      "masks", sceneText("dem", "[outputs.ranges]\ndepth = [0.0, 0.5]\nsurface = \"own\"\n") + "");
  const auto m = manifestOf(b.out());
  const Grid<float> valid = readFloatImage((b.out() / "valid_mask.exr").string());
  const Grid<float> coverage = readFloatImage((b.out() / "snow_coverage.exr").string());
  const Grid<float> depth = readFloatImage((b.out() / "depth.exr").string());
  const Grid<float> surface = readFloatImage((b.out() / "surface.exr").string());
  const Pixels cov8 = readPixels(b.out() / "snow_coverage.8.png"), depth16 = readPixels(b.out() / "depth.16.png"),
               surface16 = readPixels(b.out() / "surface.16.png");
  float lo = 1e30f, hi = -1e30f;
  size_t nodata = 0;
  for (size_t i = 0; i < valid.size(); ++i) {
    if (valid.values()[i] == 0.f) {
      ++nodata;
      EXPECT_EQ(surface16.v[i], 0u);
      continue;
    }
    lo = std::min(lo, surface.values()[i]), hi = std::max(hi, surface.values()[i]);
    ASSERT_EQ(cov8.v[i], static_cast<uint32_t>(std::lround(coverage.values()[i] * 255.0)));
    ASSERT_EQ(depth16.v[i], static_cast<uint32_t>(std::lround(std::clamp(depth.values()[i] / 0.5, 0.0, 1.0) * 65535)));
  }
  EXPECT_GT(nodata, 1000u);
  EXPECT_GT(lo, 1000.f);  // NODATA (written as 0 m in the float file) left out
  for (const auto& f : m["files"]) {
    if (f["path"] == "surface.16.png") {
      EXPECT_EQ(f["range"], (nlohmann::json{{"mode", "own"}, {"lo", lo}, {"hi", hi}, {"nodata_pixel", 0}}));
    }
    if (f["path"] == "depth.r16") {
      EXPECT_EQ(f["range"]["mode"], "fixed");
    }
    if (f["path"] == "snow_coverage.8.png") {
      EXPECT_EQ(f["range"]["hi"], 1.0);
    }
  }
  fs::remove_all(b.dir);
}

namespace {
std::string sceneError(const std::string& outputsTail) {
  const fs::path dir = fs::temp_directory_path() / ("snowbake_deliv_err_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string path = (dir / "scene.toml").string();
  std::ofstream(path) << "[terrain]\nbuiltin = \"ridged\"\n[outputs]\nencodings = [\"png16\"]\n" << outputsTail;
  std::string message;
  try {
    loadSceneFile(path);
  } catch (const InputError& e) {
    message = e.what();
  }
  fs::remove_all(dir);
  return message;
}
}  // namespace

TEST(Deliverables, BadTilesAndRangesAreSceneErrorsWithLineAndKey) {
  const std::string size = sceneError("[outputs.tiles]\nconvention = \"unreal\"\nsize_px = 512\n");
  EXPECT_NE(size.find("scene.toml:7"), std::string::npos) << size;
  EXPECT_NE(size.find("outputs.tiles.size_px"), std::string::npos) << size;
  EXPECT_NE(size.find("127, 253, 505, 1009, 2017, 4033, 8129"), std::string::npos) << size;
  const std::string unity = sceneError("[outputs.tiles]\nconvention = \"unity\"\nsize_px = 505\n");
  EXPECT_NE(unity.find("33, 65, 129, 257, 513, 1025, 2049, 4097"), std::string::npos) << unity;
  const std::string overlap = sceneError("[outputs.tiles]\nconvention = \"grid\"\nsize_px = 64\noverlap_px = 64\n");
  EXPECT_NE(overlap.find("outputs.tiles.overlap_px"), std::string::npos) << overlap;
  const std::string loHi = sceneError("[outputs.ranges]\ndepth = [2.0, 1.0]\n");
  EXPECT_NE(loHi.find("scene.toml:6"), std::string::npos) << loHi;
  EXPECT_NE(loHi.find("hi > lo"), std::string::npos) << loHi;
  const std::string unknown = sceneError("[outputs.ranges]\ndpeth = \"season\"\n");
  EXPECT_NE(unknown.find("outputs.ranges.dpeth"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("did you mean 'outputs.ranges.depth'"), std::string::npos) << unknown;
  const std::string word = sceneError("[outputs.ranges]\ndepth = \"fixed\"\n");
  EXPECT_NE(word.find("\"own\", \"season\" or [lo, hi]"), std::string::npos) << word;
}

namespace {
// A 90 x 70 GeoTIFF hill in UTM 32N (EPSG:32632), 10 m cells, north-west corner (600000, 5200000).
void writeUtmHill(const std::string& path) {
  test::GeoTiffSpec g;
  g.width = 90, g.height = 70;
  const double gt[6] = {600000.0, 10.0, 0, 5200000.0, 0, -10.0};
  std::copy(gt, gt + 6, g.geotransform);
  test::writeGeoTiff(path, g, [](int x, int y) {
    return static_cast<float>(1500.0 + 400.0 * std::exp(-((x - 45.0) * (x - 45.0) + (y - 35.0) * (y - 35.0)) / 600.0));
  });
}
}  // namespace

// outputs.format = "tiff": every float file a GeoTIFF with the input's CRS, and each tile its own
// geotransform (the source's, offset by the tile's first pixel), read back through GDAL.
TEST(Deliverables, GeoTiffTilesCarryTheInputsCoordinateSystemAndTheirOwnGeotransform) {
  const fs::path dir = fs::temp_directory_path() / ("snowbake_deliv_geotiff_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string dem = (dir / "hill.tif").string();
  writeUtmHill(dem);
  const test::Bake b = test::bakeSceneText(
      "geotiff", "[terrain]\nfile = \"" + dem + "\"\n[season]\ndays = 3\n[precompute]\nsun = false\n"
                 "[outputs]\nlayers = [\"depth\", \"surface\"]\nformat = \"tiff\"\n[outputs.tiles]\nconvention = \"grid\"\nsize_px = 40\noverlap_px = 1\n");
  OGRSpatialReference utm;
  utm.importFromEPSG(32632);
  int tiles = 0;
  const auto manifest = manifestOf(b.out());
  for (const auto& f : manifest["files"]) {
    if (!f.contains("tile")) continue;
    ++tiles;
    GDALDataset* ds = static_cast<GDALDataset*>(GDALOpen((b.out() / f["path"].get<std::string>()).string().c_str(), GA_ReadOnly));
    ASSERT_TRUE(ds) << f["path"];
    EXPECT_STREQ(ds->GetDriver()->GetDescription(), "GTiff");
    ASSERT_TRUE(ds->GetSpatialRef()) << f["path"];
    EXPECT_TRUE(ds->GetSpatialRef()->IsSame(&utm)) << f["path"];
    double gt[6];
    ASSERT_EQ(ds->GetGeoTransform(gt), CE_None);
    const int x0 = f["tile"]["x"], y0 = f["tile"]["y"];
    EXPECT_DOUBLE_EQ(gt[0], 600000.0 + 10.0 * x0) << f["path"];
    EXPECT_DOUBLE_EQ(gt[3], 5200000.0 - 10.0 * y0) << f["path"];
    EXPECT_DOUBLE_EQ(gt[1], 10.0);
    EXPECT_DOUBLE_EQ(gt[5], -10.0);
    EXPECT_EQ(ds->GetRasterXSize(), 40);
    EXPECT_EQ(ds->GetRasterYSize(), 40);
    GDALClose(ds);
  }
  EXPECT_EQ(tiles, 2 * 3 * 2);  // depth and surface, 3 x 2 tiles each (90 x 70 in steps of 39)
  if (!HasFailure()) fs::remove_all(b.dir), fs::remove_all(dir);
}

// An ESRI ASCII grid's georeference (no CRS in the file) survives to the GeoTIFF outputs.
TEST(Deliverables, EsriAsciiGeoreferenceSurvivesToGeoTiffOutputs) {
  const std::string asc = std::string(SNOWBAKE_SHARED_DATA_DIR) + "/dem/tyrol_avaWog_5m.asc";
  if (!fs::exists(asc)) GTEST_SKIP() << "shared data not found: ../shared/data/dem/tyrol_avaWog_5m.asc";
  const test::Bake b = test::bakeSceneText("ascii_geotiff", "[terrain]\nfile = \"" + asc + "\"\n[season]\ndays = 2\n[precompute]\nsun = false\n"
                                                            "[outputs]\nlayers = [\"depth\"]\nformat = \"tiff\"\n");
  GDALAllRegister();
  GDALDataset* src = static_cast<GDALDataset*>(GDALOpen(asc.c_str(), GA_ReadOnly));
  GDALDataset* out = static_cast<GDALDataset*>(GDALOpen((b.out() / "depth.tif").string().c_str(), GA_ReadOnly));
  ASSERT_TRUE(src && out);
  double a[6], o[6];
  ASSERT_EQ(src->GetGeoTransform(a), CE_None);
  ASSERT_EQ(out->GetGeoTransform(o), CE_None);
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(o[k], a[k], 1e-6) << k;
  EXPECT_EQ(out->GetRasterXSize(), src->GetRasterXSize());
  GDALClose(src);
  GDALClose(out);
  fs::remove_all(b.dir);
}

namespace {
std::string engineScene(const std::string& extra) {
  return "name = \"engine\"\n[terrain]\n" + terrainOf("builtin") +
         "[season]\ndays = 10\n[precompute]\nsun = false\n[[weather.snowfall]]\nstart_day = 0\nend_day = 8\n"
         "[outputs]\nlayers = [\"depth\", \"surface\", \"snow_coverage\", \"snow_coverage_hard\", \"weight_snow\", \"weight_rock\", "
         "\"weight_ground\", \"splat_map\", \"snow_normal\"]\nencodings = [\"png8\", \"r32\"]\n" + extra + "[run]\nseed = 5\n";
}
}  // namespace

// Splat channels sum to 255 at every pixel; weights in [0, 255] summing to about 255; coverage 0 on
// bare ground and 1 under deep snow; the hard mask is the soft one cut at 0.5; r32 holds the floats.
TEST(Deliverables, SplatSumsTo255AndWeightsAndCoverageFollowTheSnow) {
  const test::Bake b = test::bakeSceneText("engine", engineScene(""));
  const fs::path o = b.out();
  const Grid<float> depth = readFloatImage((o / "depth.exr").string()), coverage = readFloatImage((o / "snow_coverage.exr").string()),
                    hard = readFloatImage((o / "snow_coverage_hard.exr").string());
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);  // as stored: OIIO would multiply by A = 0
  auto in = OIIO::ImageInput::open((o / "splat_map.png").string(), &config);
  ASSERT_TRUE(in);
  ASSERT_EQ(in->spec().nchannels, 4);
  std::vector<uint8_t> splat(depth.size() * 4);
  ASSERT_TRUE(in->read_image(0, 0, 0, 4, OIIO::TypeDesc::UINT8, splat.data()));
  const Pixels ws = readPixels(o / "weight_snow.8.png"), wr = readPixels(o / "weight_rock.8.png"), wg = readPixels(o / "weight_ground.8.png");
  size_t bare = 0, deep = 0, rock = 0;
  for (size_t i = 0; i < depth.size(); ++i) {
    ASSERT_EQ(splat[4 * i] + splat[4 * i + 1] + splat[4 * i + 2], 255) << i;
    ASSERT_EQ(splat[4 * i + 3], 0);
    EXPECT_LE(ws.v[i], 255u);
    EXPECT_NEAR(static_cast<int>(ws.v[i] + wr.v[i] + wg.v[i]), 255, 1) << i;  // each rounded alone
    EXPECT_NEAR(splat[4 * i], static_cast<int>(ws.v[i]), 1);
    if (depth.values()[i] <= 0.02f) {
      ++bare;
      ASSERT_EQ(coverage.values()[i], 0.f);
    }
    if (depth.values()[i] >= 0.15f) {
      ++deep;
      ASSERT_EQ(coverage.values()[i], 1.f);
      ASSERT_EQ(splat[4 * i], 255);
    }
    ASSERT_EQ(hard.values()[i], coverage.values()[i] >= 0.5f ? 1.f : 0.f);
    rock += wr.v[i] > 128;
  }
  EXPECT_GT(bare, 100u);  // the test sees both ends
  EXPECT_GT(deep, 100u);
  EXPECT_GT(rock, 10u);
  // r32: the floats of the EXR, byte for byte.
  std::ifstream r32(o / "depth.r32", std::ios::binary);
  std::vector<float> raw(depth.size());
  r32.read(reinterpret_cast<char*>(raw.data()), static_cast<std::streamsize>(raw.size() * 4));
  EXPECT_EQ(raw, depth.values());
  fs::remove_all(b.dir);
}

// The normal map: flat snow (128, 128, 255); on a slope rising east R < 128; DirectX flips G only.
// outputs.resize writes the layers and the maps at the asked size, the simulation grid untouched.
TEST(Deliverables, NormalMapAndResizeAtTheOutputSize) {
  const test::Bake gl = test::bakeSceneText("normal_gl", engineScene("resize = [300, 250]\n"));
  const test::Bake dx = test::bakeSceneText("normal_dx", engineScene("resize = [300, 250]\nnormal_map_convention = \"directx\"\n"));
  const test::Bake whole = test::bakeSceneText("normal_whole", engineScene(""));
  auto rgbOf = [](const fs::path& p, int& w, int& h) {
    auto in = OIIO::ImageInput::open(p.string());
    w = in->spec().width, h = in->spec().height;
    std::vector<uint8_t> v(static_cast<size_t>(w) * h * 3);
    in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, v.data());
    return v;
  };
  int w = 0, h = 0, w2 = 0, h2 = 0;
  const auto a = rgbOf(gl.out() / "snow_normal.png", w, h), b = rgbOf(dx.out() / "snow_normal.png", w2, h2);
  EXPECT_EQ(w, 300);
  EXPECT_EQ(h, 250);
  const Grid<float> surface = readFloatImage((gl.out() / "surface.exr").string());
  EXPECT_EQ(surface.width(), 300);
  EXPECT_EQ(surface.height(), 250);
  EXPECT_EQ(readFloatImage((whole.out() / "surface.exr").string()).width(), 200);
  EXPECT_EQ(manifestOf(gl.out())["terrain"]["width"], 200);  // the simulation grid
  size_t checked = 0;
  for (int y = 1; y < h - 1; ++y)
    for (int x = 1; x < w - 1; ++x) {
      const size_t i = (static_cast<size_t>(y) * w + x) * 3;
      EXPECT_EQ(a[i], b[i]);
      EXPECT_EQ(a[i + 2], b[i + 2]);
      EXPECT_NEAR(a[i + 1] + b[i + 1], 255, 1);  // G flipped
      // n = (-dz/dx, -dz/dnorth, 1) / |...| from the surface's central differences.
      const double dxm = 4000.0 / 300, dym = 4000.0 / 250;
      const double gx = (surface(x + 1, y) - surface(x - 1, y)) / (2 * dxm), gn = (surface(x, y - 1) - surface(x, y + 1)) / (2 * dym);
      const double n = std::sqrt(gx * gx + gn * gn + 1);
      ASSERT_NEAR(a[i], 127.5 - 127.5 * gx / n, 0.51);
      ASSERT_NEAR(a[i + 1], 127.5 - 127.5 * gn / n, 0.51);
      ASSERT_NEAR(a[i + 2], 127.5 + 127.5 / n, 0.51);
      ++checked;
    }
  EXPECT_EQ(checked, 298u * 248u);
  for (const auto* bake : {&gl, &dx, &whole}) fs::remove_all(bake->dir);
}

TEST(Deliverables, ResizeToZeroIsASceneError) {
  const std::string zero = sceneError("resize = [0, 100]\n");
  EXPECT_NE(zero.find("scene.toml:5"), std::string::npos) << zero;
  EXPECT_NE(zero.find("outputs.resize"), std::string::npos) << zero;
}
