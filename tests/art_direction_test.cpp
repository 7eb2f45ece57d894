// Art direction: painted rasters read and placed on the grid (inputs/raster_input.h), the
// initial snow cover, timeline edits (phenomena/timeline_edits.h), multipliers, the no-snow mask and masked
// events, through the season and the whole bake.
#include <OpenImageIO/imageio.h>
#include <gdal_priv.h>
#include <ogr_spatialref.h>
#include <gtest/gtest.h>
#include <unistd.h>  // getpid

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <sstream>

#include "bake_support.h"
#include "bakers/grid_writer.h"
#include "core/cpu_backend.h"
#include "core/errors.h"
#include "core/season.h"
#include "inputs/raster_input.h"
#include "scene/scene.h"
#include "test_support.h"

namespace snow {
namespace {

namespace fs = std::filesystem;

fs::path tempDir(const std::string& name) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const fs::path d = fs::temp_directory_path() / ("snowbake_art_" + name + "_" + info->name() + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// Writes a one-channel image with OpenImageIO (the pixels given as floats; integer formats
// store value * max, rounded).
void writeImage(const fs::path& path, int w, int h, const std::function<double(int, int)>& f, OIIO::TypeDesc format) {
  std::vector<float> pixels(static_cast<size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) pixels[static_cast<size_t>(y) * w + x] = static_cast<float>(f(x, y));
  auto out = OIIO::ImageOutput::create(path.string());
  ASSERT_TRUE(out);
  ASSERT_TRUE(out->open(path.string(), OIIO::ImageSpec(w, h, 1, format)));
  ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, pixels.data()));
  out->close();
}

// A float GeoTIFF through GDAL: north-up, origin the north-west corner, in `epsg`.
void writeGeoTiff(const fs::path& path, int w, int h, double west, double north, double cell, int epsg,
                  const std::function<double(int, int)>& f) {
  GDALAllRegister();
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
  ASSERT_NE(driver, nullptr);
  GDALDataset* ds = driver->Create(path.string().c_str(), w, h, 1, GDT_Float32, nullptr);
  ASSERT_NE(ds, nullptr);
  double gt[6] = {west, cell, 0, north, 0, -cell};
  ds->SetGeoTransform(gt);
  OGRSpatialReference srs;
  srs.importFromEPSG(epsg);
  ds->SetSpatialRef(&srs);
  std::vector<float> v(static_cast<size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) v[static_cast<size_t>(y) * w + x] = static_cast<float>(f(x, y));
  ASSERT_EQ(ds->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, w, h, v.data(), w, h, GDT_Float32, 0, 0), CE_None);
  GDALClose(ds);
}

TerrainInfo plainTerrain(int w, int h, double cell) {
  TerrainInfo t;
  t.spec.width = w;
  t.spec.height = h;
  t.spec.cellSizeXM = t.spec.cellSizeYM = cell;
  return t;
}

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

// The documented resampling, written again here: k x k bilinear samples (edges clamped) over
// the cell's footprint, k = ceil(pixels per cell).
double expectedCell(const std::function<double(int, int)>& pixel, int W, int H, int w, int h, int x, int y) {
  const double sx = static_cast<double>(W) / w, sy = static_cast<double>(H) / h;
  const int kx = std::max(1, static_cast<int>(std::ceil(sx - 1e-9))), ky = std::max(1, static_cast<int>(std::ceil(sy - 1e-9)));
  double sum = 0;
  for (int j = 0; j < ky; ++j)
    for (int i = 0; i < kx; ++i) {
      double u = (x + 0.5) * sx - 0.5 + ((i + 0.5) / kx - 0.5) * sx, v = (y + 0.5) * sy - 0.5 + ((j + 0.5) / ky - 0.5) * sy;
      u = std::clamp(u, 0.0, W - 1.0), v = std::clamp(v, 0.0, H - 1.0);
      const int x0 = std::min(static_cast<int>(u), W - 2), y0 = std::min(static_cast<int>(v), H - 2);
      const double fx = u - x0, fy = v - y0;
      sum += (1 - fx) * (1 - fy) * pixel(x0, y0) + fx * (1 - fy) * pixel(x0 + 1, y0) + (1 - fx) * fy * pixel(x0, y0 + 1) +
             fx * fy * pixel(x0 + 1, y0 + 1);
    }
  return sum / (kx * ky);
}

TEST(RasterInput, LinearRampsComeThroughExactlyUpAndDown) {
  // A ramp v = 0.25 + 0.01 px + 0.02 py sampled at cell centres: bilinear and the footprint
  // average both reproduce a linear function away from the clamped edges.
  for (const auto& [W, H, w, h] : {std::array<int, 4>{40, 30, 100, 75}, std::array<int, 4>{200, 150, 64, 48}}) {
    std::vector<float> p(static_cast<size_t>(W) * H);
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) p[static_cast<size_t>(y) * W + x] = 0.25f + 0.01f * x + 0.02f * y;
    const double sx = static_cast<double>(W) / w, sy = static_cast<double>(H) / h;
    double worst = 0;
    for (int y = 2; y < h - 2; ++y)
      for (int x = 2; x < w - 2; ++x) {
        const double px = (x + 0.5) * sx - 0.5, py = (y + 0.5) * sy - 0.5;
        const float v = sampleRasterCell(p, W, H, px, py, sx, sy, true, 0.f);
        worst = std::max(worst, std::abs(v - (0.25 + 0.01 * px + 0.02 * py)));
      }
    EXPECT_LT(worst, 2e-6) << W << "x" << H << " -> " << w << "x" << h;
  }
}

TEST(RasterInput, MaskAtTheTerrainSizeReadsItsPixelsAndValuesRangeInvertMapThem) {
  const fs::path d = tempDir("identity");
  writeImage(d / "m.png", 48, 32, [](int x, int y) { return ((x * 7 + y * 3) % 256) / 255.0; }, OIIO::TypeDesc::UINT8);
  const TerrainInfo t = plainTerrain(48, 32, 5.0);
  const Grid<uint8_t> valid(48, 32, 1);
  RasterRef ref;
  ref.file = (d / "m.png").string();
  const MappedRaster m = mapRaster(ref, RasterUse::Mask, t, valid);
  EXPECT_EQ(m.placement, "stretched");
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 48; ++x) ASSERT_NEAR(m.values(x, y), ((x * 7 + y * 3) % 256) / 255.0, 1e-6) << x << "," << y;
  // values = [0.2, 0.6] -> n, invert -> 1 - n, range = [0.5, 2.5] -> 0.5 + 2 (1 - n).
  writeImage(d / "v.exr", 48, 32, [](int x, int) { return 0.2 + 0.4 * x / 47.0; }, OIIO::TypeDesc::FLOAT);
  ref.file = (d / "v.exr").string();
  ref.values = std::array<double, 2>{0.2, 0.6};
  ref.range = std::array<double, 2>{0.5, 2.5};
  ref.invert = true;
  const MappedRaster v = mapRaster(ref, RasterUse::Mask, t, valid);
  for (int x = 0; x < 48; ++x) EXPECT_NEAR(v.values(x, 5), 0.5 + 2.0 * (1.0 - x / 47.0), 1e-5) << x;
  EXPECT_NEAR(v.minValue, 0.5, 1e-5);
  EXPECT_NEAR(v.maxValue, 2.5, 1e-5);
  fs::remove_all(d);
}

TEST(RasterInput, BadRastersAreRefusedNamingTheFile) {
  const fs::path d = tempDir("errors");
  const TerrainInfo t = plainTerrain(64, 64, 10.0);
  const Grid<uint8_t> valid(64, 64, 1);
  RasterRef ref;
  ref.declaredAt = "scene.toml:7: multipliers.melt";
  ref.file = (d / "missing.png").string();
  std::string e = errorOf([&] { mapRaster(ref, RasterUse::Mask, t, valid); });
  EXPECT_NE(e.find("scene.toml:7"), std::string::npos) << e;
  EXPECT_NE(e.find("missing.png"), std::string::npos) << e;
  EXPECT_NE(e.find("does not exist"), std::string::npos) << e;
  // Another aspect ratio and no georeference to place it by.
  writeImage(d / "wide.png", 100, 50, [](int, int) { return 0.5; }, OIIO::TypeDesc::UINT8);
  ref.file = (d / "wide.png").string();
  e = errorOf([&] { mapRaster(ref, RasterUse::Mask, t, valid); });
  EXPECT_NE(e.find("wide.png"), std::string::npos) << e;
  EXPECT_NE(e.find("100 x 50"), std::string::npos) << e;
  EXPECT_NE(e.find("georeference"), std::string::npos) << e;
  // One pixel off the terrain's aspect is fine.
  writeImage(d / "near.png", 65, 64, [](int, int) { return 0.5; }, OIIO::TypeDesc::UINT8);
  ref.file = (d / "near.png").string();
  EXPECT_NO_THROW(mapRaster(ref, RasterUse::Mask, t, valid));
  // Values out of [0, 1] in a float mask: the value and the pixel are named.
  writeImage(d / "hot.exr", 64, 64, [](int x, int y) { return x == 9 && y == 4 ? 1.5 : 0.5; }, OIIO::TypeDesc::FLOAT);
  ref.file = (d / "hot.exr").string();
  e = errorOf([&] { mapRaster(ref, RasterUse::Mask, t, valid); });
  EXPECT_NE(e.find("hot.exr"), std::string::npos) << e;
  EXPECT_NE(e.find("1.5"), std::string::npos) << e;
  EXPECT_NE(e.find("(9, 4)"), std::string::npos) << e;
  // ... unless values = [...] says what the file's numbers mean.
  ref.values = std::array<double, 2>{0.0, 2.0};
  EXPECT_NO_THROW(mapRaster(ref, RasterUse::Mask, t, valid));
  ref.values.reset();
  // An 8-bit image holds no metres; a negative depth is refused.
  writeImage(d / "depth8.png", 64, 64, [](int, int) { return 0.5; }, OIIO::TypeDesc::UINT8);
  ref.file = (d / "depth8.png").string();
  e = errorOf([&] { mapRaster(ref, RasterUse::Depth, t, valid); });
  EXPECT_NE(e.find("range = [0, deepest_m]"), std::string::npos) << e;
  ref.range = std::array<double, 2>{0.0, 3.0};
  EXPECT_NEAR(mapRaster(ref, RasterUse::Depth, t, valid).values(3, 3), 3.0 * 128.0 / 255.0, 1e-5);
  ref.range.reset();
  writeImage(d / "neg.exr", 64, 64, [](int x, int) { return x == 3 ? -0.25 : 1.0; }, OIIO::TypeDesc::FLOAT);
  ref.file = (d / "neg.exr").string();
  e = errorOf([&] { mapRaster(ref, RasterUse::Depth, t, valid); });
  EXPECT_NE(e.find("neg.exr"), std::string::npos) << e;
  EXPECT_NE(e.find("negative"), std::string::npos) << e;
  // Not an image at all.
  std::ofstream(d / "text.png") << "not a png";
  ref.file = (d / "text.png").string();
  e = errorOf([&] { mapRaster(ref, RasterUse::Mask, t, valid); });
  EXPECT_NE(e.find("text.png"), std::string::npos) << e;
  fs::remove_all(d);
}

// Both georeferenced: the mask lands by coordinates (a 100 x 60 m patch of a 400 x 300 m
// terrain), cells outside it read 0; another coordinate system is refused.
TEST(RasterInput, GeoreferencedMaskLandsByCoordinates) {
  const fs::path d = tempDir("geo");
  const double west = 600000, north = 5200000;
  writeGeoTiff(d / "terrain.tif", 40, 30, west, north, 10.0, 32632, [](int x, int y) { return 1000.0 + x + y; });
  // 5 m pixels from 100 m east, 50 m south of the terrain's corner: 20 x 12 pixels of 1.
  writeGeoTiff(d / "patch.tif", 20, 12, west + 100, north - 50, 5.0, 32632, [](int, int) { return 1.0; });
  const Terrain terrain = loadDem((d / "terrain.tif").string());
  ASSERT_TRUE(terrain.info.georeferenced);
  RasterRef ref;
  ref.file = (d / "patch.tif").string();
  const MappedRaster m = mapRaster(ref, RasterUse::Mask, terrain.info, terrain.valid);
  EXPECT_EQ(m.placement, "georeferenced");
  EXPECT_NEAR(m.coverage, 10.0 * 6.0 / (40.0 * 30.0), 1e-9);  // cells with a footprint sample inside the patch
  for (int y = 0; y < 30; ++y)
    for (int x = 0; x < 40; ++x) {
      const bool inside = x >= 10 && x < 20 && y >= 5 && y < 11;
      const bool outside = !inside;
      if (inside) {
        EXPECT_NEAR(m.values(x, y), 1.0, 1e-6) << x << "," << y;
      }
      if (outside) {
        EXPECT_EQ(m.values(x, y), 0.f) << x << "," << y;
      }
    }
  writeGeoTiff(d / "other.tif", 20, 12, 11.0, 47.0, 0.0001, 4326, [](int, int) { return 1.0; });
  ref.file = (d / "other.tif").string();
  const std::string e = errorOf([&] { mapRaster(ref, RasterUse::Mask, terrain.info, terrain.valid); });
  EXPECT_NE(e.find("other.tif"), std::string::npos) << e;
  EXPECT_NE(e.find("coordinate system"), std::string::npos) << e;
  fs::remove_all(d);
}

// Edits on the kernel level: set with w = 1 gives exactly d, w = 0 leaves the layer, grey
// blends; remove never goes below zero; move conserves the column.
TEST(ArtEdits, EditKernelSemantics) {
  SnowState s = test::terrainFrom(4, 1, 2.0, -10.f, [](double, double) { return 2000.0; });
  for (int x = 0; x < 4; ++x) s.unstableM(x, 0) = 0.4f, s.stableM(x, 0) = 0.3f;
  auto backend = createSerialBackend();
  backend->upload(s);
  const std::vector<float> w = {1.f, 0.f, 0.5f, 1.f};
  const double area = 4.0;
  EditArgs set{EditOp::Set, static_cast<int>(SnowLayer::Unstable), 0, 1.25f, true};
  double added = backend->applyEdit(set, w);
  backend->download(s);
  EXPECT_EQ(s.unstableM(0, 0), 1.25f);
  EXPECT_EQ(s.unstableM(1, 0), 0.4f);
  EXPECT_FLOAT_EQ(s.unstableM(2, 0), 0.825f);
  EXPECT_NEAR(added, area * ((1.25 - 0.4) * 2 + (0.825 - 0.4)), 1e-5);
  EditArgs remove{EditOp::Remove, static_cast<int>(SnowLayer::Stable), 0, 1.0f, true};
  added = backend->applyEdit(remove, w);
  backend->download(s);
  EXPECT_EQ(s.stableM(0, 0), 0.f);
  EXPECT_EQ(s.stableM(1, 0), 0.3f);
  EXPECT_EQ(s.stableM(2, 0), 0.f);  // 0.5 x 1 m asked, 0.3 m there
  EXPECT_NEAR(added, -area * 0.9, 1e-6);
  const LayerTotals before = backend->totals();
  EditArgs move{EditOp::Move, static_cast<int>(SnowLayer::Unstable), static_cast<int>(SnowLayer::Powder), 0.f, false};
  added = backend->applyEdit(move, w);
  backend->download(s);
  EXPECT_EQ(s.unstableM(0, 0), 0.f);
  EXPECT_EQ(s.powderM(0, 0), 1.25f);
  EXPECT_FLOAT_EQ(s.powderM(2, 0), 0.4125f);
  EXPECT_EQ(added, 0.0);
  EXPECT_NEAR(backend->totals().totalM3(), before.totalM3(), 1e-12);
  EditArgs add{EditOp::Add, static_cast<int>(SnowLayer::Compacted), 0, 0.1f, true};
  added = backend->applyEdit(add, w);
  EXPECT_NEAR(added, area * 0.25, 1e-6);
  // Without a mask (no weights): everywhere, w = 1.
  added = backend->applyEdit(add, {});
  EXPECT_NEAR(added, area * 0.4, 1e-6);
}

// A depth of -0 (which the scene's depth_m accepts, as it is not below zero) leaves no -0 in any
// layer, whatever the op and the weight: a step skipped at a zero rate keeps a cell's bits, where
// every kernel would turn -0 into +0, so a -0 left here would change the bytes a skip gives.
TEST(ArtEdits, AnEditOfDepthMinusZeroLeavesNoMinusZeroInAnyLayer) {
  const std::vector<float> w = {1.f, 0.f, 0.5f, 1.f};
  for (const EditOp op : {EditOp::Add, EditOp::Remove, EditOp::Set, EditOp::Move})
    for (const bool hasDepth : {true, false}) {
      SnowState s = test::terrainFrom(4, 1, 2.0, -10.f, [](double, double) { return 2000.0; });
      s.unstableM(0, 0) = 0.4f, s.unstableM(2, 0) = 0.4f;  // cells 1 and 3 hold +0
      auto backend = createSerialBackend();
      backend->upload(s);
      const EditArgs edit{op, static_cast<int>(SnowLayer::Unstable), static_cast<int>(SnowLayer::Powder), -0.0f, hasDepth};
      backend->applyEdit(edit, w);
      backend->download(s);
      for (const Grid<float>* layer : {&s.compactedM, &s.stableM, &s.unstableM, &s.powderM})
        for (const float v : layer->values()) EXPECT_FALSE(std::signbit(v)) << "op " << static_cast<int>(op) << (hasDepth ? "" : " without a depth");
    }
}

// The bake: an initial-depth raster of another resolution than the grid, read back from the
// first frame as the documented resampling gives it; a masked depth in another layer.
TEST(ArtDirection, InitialDepthRasterReadsBackFromTheFirstFrame) {
  const fs::path d = tempDir("initial");
  auto ramp = [](int x, int y) { return 0.5 + 0.01 * x + 0.02 * y + 0.001 * ((x * 13 + y * 7) % 5); };
  writeImage(d / "stable_depth.exr", 60, 60, ramp, OIIO::TypeDesc::FLOAT);          // 60^2 on a 96^2 grid: upsampled
  auto disc = [](int x, int y) { return (x - 100) * (x - 100) + (y - 60) * (y - 60) < 900 ? 1.0 : 0.0; };
  writeImage(d / "zone.png", 150, 150, disc, OIIO::TypeDesc::UINT8);                 // 150^2: downsampled (k = 2)
  std::ostringstream text;
  text << "[terrain]\nbuiltin = \"ridged\"\nsize = 96\ncell_size_m = 20\n[season]\ndays = 2\n"
       << "[masks.zone]\nfile = \"" << (d / "zone.png").string() << "\"\n"
       << "[initial_snow]\nstable = \"" << (d / "stable_depth.exr").string() << "\"\nunstable = { mask = \"zone\", depth_m = 0.8 }\n"
       << "compacted = 0.05\n[parameters]\nskiers_per_hour = 0\navalanche_rate_per_km2_per_day = 0\n"
       << "[outputs]\nlayers = [\"compacted\", \"stable\", \"unstable\"]\nframes_days = [0]\n";
  const test::Bake bake = test::bakeSceneText("art_initial", text.str());
  const Grid<float> stable = readFloatImage((bake.out() / "frames" / "stable.0000.exr").string());
  const Grid<float> unstable = readFloatImage((bake.out() / "frames" / "unstable.0000.exr").string());
  const Grid<float> compacted = readFloatImage((bake.out() / "frames" / "compacted.0000.exr").string());
  ASSERT_EQ(stable.width(), 96);
  double worstStable = 0, worstUnstable = 0;
  for (int y = 0; y < 96; ++y)
    for (int x = 0; x < 96; ++x) {
      worstStable = std::max(worstStable, std::abs(stable(x, y) - expectedCell(ramp, 60, 60, 96, 96, x, y)));
      worstUnstable = std::max(worstUnstable, std::abs(unstable(x, y) - 0.8 * expectedCell(disc, 150, 150, 96, 96, x, y)));
      ASSERT_EQ(compacted(x, y), 0.05f);
    }
  std::printf("[ measure ] initial depth raster 60^2 -> 96^2: worst %.2e m; mask x depth 150^2 -> 96^2: worst %.2e m\n", worstStable,
              worstUnstable);
  EXPECT_LT(worstStable, 2e-6);
  EXPECT_LT(worstUnstable, 2e-6);
  // Recorded in the manifest with the mapping.
  std::ifstream in(bake.out() / "manifest.json");
  const auto j = nlohmann::json::parse(in);
  ASSERT_TRUE(j.contains("art_direction"));
  ASSERT_EQ(j["art_direction"]["rasters"].size(), 2u);
  EXPECT_EQ(j["art_direction"]["rasters"][0]["role"], "initial_snow.stable");
  EXPECT_EQ(j["art_direction"]["rasters"][0]["width"], 60);
  EXPECT_EQ(j["art_direction"]["rasters"][1]["placement"], "stretched");
  fs::remove_all(d);
  fs::remove_all(bake.dir);
}

// A real slope: on tyrol_avaKot, the unstable depth set to 1.25 m within a mask and, the same
// day, a masked release: the avalanche starts from exactly the masked cells, and
// the snow is conserved (the edit's volume is the only change to the total).
TEST(ArtDirection, TyrolSetUnstableWithinMaskThenMaskedReleaseStartsFromExactlyTheMask) {
  const std::string dem = std::string(SNOWBAKE_SHARED_DATA_DIR) + "/dem/tyrol_avaKot_5m.asc";
  if (!fs::exists(dem)) GTEST_SKIP() << "shared data not found: ../shared/data/dem/tyrol_avaKot_5m.asc";
  const Terrain terrain = loadDem(dem);
  const int w = terrain.heightsM.width(), h = terrain.heightsM.height();
  // The release zone an expert would draw: a 40 m disc around the steepest valid cell of the
  // upper third of the slope (by altitude), painted at the DEM's size (1 pixel = 1 cell).
  const double cell = terrain.info.spec.cellSizeXM;
  const float lo = terrain.info.minElevationM, hi = terrain.info.maxElevationM;
  int cx = -1, cy = -1;
  double steepest = 0;
  for (int y = 10; y < h - 10; ++y)
    for (int x = 10; x < w - 10; ++x) {
      bool ok = true;
      for (int dy = -9; dy <= 9 && ok; ++dy)
        for (int dx = -9; dx <= 9 && ok; ++dx) ok = terrain.valid(x + dx, y + dy) != 0;
      if (!ok || terrain.heightsM(x, y) < lo + 0.66f * (hi - lo)) continue;
      const double gx = (terrain.heightsM(x + 1, y) - terrain.heightsM(x - 1, y)) / (2 * cell);
      const double gy = (terrain.heightsM(x, y + 1) - terrain.heightsM(x, y - 1)) / (2 * cell);
      const double s = std::hypot(gx, gy);
      if (s > steepest && s < 1.2) steepest = s, cx = x, cy = y;
    }
  ASSERT_GE(cx, 0);
  const fs::path d = tempDir("tyrol");
  auto disc = [&](int x, int y) { return std::hypot(x - cx, y - cy) * cell <= 40.0 ? 1.0 : 0.0; };
  writeImage(d / "release_zone.png", w, h, disc, OIIO::TypeDesc::UINT8);
  int maskCells = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) maskCells += disc(x, y) > 0.5 && terrain.valid(x, y);
  std::ostringstream text;
  text << "[terrain]\nfile = \"" << dem << "\"\n[season]\nstart_date = 2026-01-15\ndays = 1\n"
       << "[[weather.keyframe]]\nday = 0\nsea_level_temperature_c = -8.0\nsnowfall_intensity = 0\n"
       << "[masks.release]\nfile = \"" << (d / "release_zone.png").string() << "\"\n"
       << "[initial_snow]\nstable = 0.5\n"
       << "[[edits]]\nday = 0.5\nlayer = \"unstable\"\nop = \"set\"\ndepth_m = 1.25\nmask = \"release\"\n"
       << "[[events]]\ntype = \"avalanche\"\nday = 0.5\nmask = \"release\"\n"
       << "[parameters]\navalanche_rate_per_km2_per_day = 0\nskiers_per_hour = 0\nsnowfall_starts_per_day = 0\n"
       << "[outputs]\nlayers = [\"depth\", \"avalanche_deposit\"]\navalanche_maps = true\n";
  const test::Bake bake = test::bakeSceneText("art_tyrol", text.str());
  const SeasonReport& r = bake.result.season;
  ASSERT_EQ(r.avalanches.size(), 1u);
  const AvalancheRecord& a = r.avalanches[0];
  ASSERT_TRUE(a.released) << a.why;
  const Grid<float> release = readFloatImage((bake.out() / "avalanches" / "001_release.exr").string());
  int same = 0, extra = 0, missing = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const bool inMask = disc(x, y) > 0.5 && terrain.valid(x, y);
      const bool released = release(x, y) > 0.5f;
      same += inMask && released, extra += released && !inMask, missing += inMask && !released;
    }
  ASSERT_EQ(r.edits.size(), 1u);
  const double editM3 = r.edits[0].volumeM3;
  const double expectedEdit = maskCells * 1.25 * terrain.info.spec.cellAreaM2();
  std::printf("[ measure ] avaKot masked release at cell (%d, %d), slope %.2f: mask %d cells, released %d (%d outside, %d missed), "
              "%.0f m^3; runout %.0f m, fall %.0f m; edit %.1f m^3 (expected %.1f); totals %.6e -> %.6e m^3, balance error %.2e\n",
              cx, cy, steepest, maskCells, a.releaseCells, extra, missing, a.releasedM3, a.runoutM, a.fallHeightM, editM3, expectedEdit,
              r.initial.totalM3(), r.final.totalM3(), r.massBalanceRelativeError());
  EXPECT_EQ(a.releaseCells, maskCells);
  EXPECT_EQ(same, maskCells);
  EXPECT_EQ(extra, 0);
  EXPECT_EQ(missing, 0);
  EXPECT_NEAR(editM3, expectedEdit, 1e-5 * expectedEdit);
  EXPECT_GT(a.runoutM, 50.0);  // it ran
  EXPECT_NEAR(r.snowfallAddedM3, 0.0, 1e-9);
  EXPECT_NEAR(r.meltRemovedM3, 0.0, 1e-9);
  EXPECT_NEAR(r.final.totalM3(), r.initial.totalM3() + editM3, 1e-6 * r.final.totalM3());
  EXPECT_LT(r.massBalanceRelativeError(), 1e-6);
  fs::remove_all(d);
  fs::remove_all(bake.dir);
}

// A snowfall multiplier of 0 inside a mask: the masked half gets no new snow, the other half
// is covered. (No wind; powder diffusion may carry powder a few cells over the mask's edge.)
TEST(ArtDirection, SnowfallMultiplierZeroLeavesTheMaskedAreaBare) {
  const fs::path d = tempDir("snowfall");
  writeImage(d / "dry.png", 64, 64, [](int x, int) { return x < 32 ? 0.0 : 1.0; }, OIIO::TypeDesc::UINT8);
  std::ostringstream text;
  text << "[terrain]\nbuiltin = \"ridged\"\nsize = 96\ncell_size_m = 20\nmin_altitude_m = 1500\n[season]\ndays = 20\n"
       << "[[weather.keyframe]]\nday = 0\nsea_level_temperature_c = -5.0\n[[weather.snowfall]]\nstart_day = 1\nend_day = 15\n"
       << "[multipliers]\nsnowfall = \"" << (d / "dry.png").string() << "\"\n"
       << "[parameters]\nskiers_per_hour = 0\navalanche_rate_per_km2_per_day = 0\n"
       << "[outputs]\nlayers = [\"depth\"]\n";
  const test::Bake bake = test::bakeSceneText("art_snowfall", text.str());
  const Grid<float> depth = readFloatImage((bake.out() / "depth.exr").string());
  // Mask pixels 0..31 cover cells 0..47 (1.5 cells a pixel); cells up to 46 read exactly 0.
  double dryMean = 0, wetMean = 0, dryFar = 0;
  int dry = 0, wet = 0, far = 0;
  for (int y = 0; y < 96; ++y)
    for (int x = 0; x < 96; ++x) {
      if (x <= 46) dryMean += depth(x, y), ++dry;
      if (x <= 36) dryFar = std::max<double>(dryFar, depth(x, y)), ++far;
      if (x >= 49) wetMean += depth(x, y), ++wet;
    }
  dryMean /= dry, wetMean /= wet;
  std::printf("[ measure ] snowfall multiplier 0: masked half mean %.4f m (max %.4f m 10 cells in), rest %.3f m\n", dryMean, dryFar, wetMean);
  EXPECT_GT(wetMean, 0.2);
  EXPECT_LT(dryMean, 0.01 * wetMean);
  EXPECT_EQ(dryFar, 0.0);  // 200 m from the edge: bare
  EXPECT_LT(bake.result.season.massBalanceRelativeError(), 1e-6);
  fs::remove_all(d);
  fs::remove_all(bake.dir);
}

// A no-snow mask (a road across the slopes) stays bare through a season with storms, wind,
// spontaneous and user avalanches and skiers: no snow at any frame, none deposited by wind or
// avalanches, and the mass ledger closes.
TEST(ArtDirection, NoSnowMaskStaysBareThroughWindAndAvalanches) {
  const fs::path d = tempDir("nosnow");
  auto road = [](int x, int y) { return std::abs(y - 20 - 0.3 * x) < 2.5 ? 1.0 : 0.0; };
  writeImage(d / "road.png", 64, 64, road, OIIO::TypeDesc::UINT8);
  std::ostringstream text;
  text << "[terrain]\nbuiltin = \"ridged\"\nsize = 128\ncell_size_m = 10\nmin_altitude_m = 1500\n[season]\ndays = 40\n"
       << "[[weather.keyframe]]\nday = 0\nsea_level_temperature_c = -4.0\nwind_speed_mps = 12\nwind_direction_deg = 300\n"
       << "[[weather.keyframe]]\nday = 30\nsea_level_temperature_c = 6.0\nwind_speed_mps = 20\nwind_direction_deg = 200\n"
       << "[[weather.snowfall]]\nstart_day = 1\nend_day = 25\n"
       << "[initial_snow]\nstable = 0.3\n"
       << "[multipliers]\nno_snow = \"" << (d / "road.png").string() << "\"\n"
       << "[[events]]\ntype = \"avalanche\"\nday = 26\nmask = \"" << (d / "road.png").string() << "\"\n"
       << "[parameters]\navalanche_rate_per_km2_per_day = 5\nskiers_per_hour = 2\n"
       << "[outputs]\nlayers = [\"depth\", \"wind_deposit\", \"avalanche_deposit\", \"valid_mask\"]\nframes_days = [10, 26, 35]\n";
  const test::Bake bake = test::bakeSceneText("art_nosnow", text.str());
  const SeasonReport& r = bake.result.season;
  // The mask on the grid, as the bake placed it (2 cells a pixel, >= 0.5).
  const Grid<uint8_t> valid(128, 128, 1);
  RasterRef ref;
  ref.file = (d / "road.png").string();
  const MappedRaster m = mapRaster(ref, RasterUse::Mask, plainTerrain(128, 128, 10.0), valid);
  int roadCells = 0;
  for (float v : m.values.values()) roadCells += v >= 0.5f;
  ASSERT_GT(roadCells, 500);
  double worst = 0, nearRoad = 0;
  for (const char* f : {"frames/depth.0010.exr", "frames/depth.0026.exr", "frames/depth.0035.exr", "depth.exr",
                               "wind_deposit.exr", "avalanche_deposit.exr"}) {
    const Grid<float> g = readFloatImage((bake.out() / f).string());
    for (size_t i = 0; i < g.size(); ++i)
      if (m.values.values()[i] >= 0.5f) worst = std::max<double>(worst, g.values()[i]);
  }
  const Grid<float> depth = readFloatImage((bake.out() / "depth.exr").string());
  const Grid<float> validMask = readFloatImage((bake.out() / "valid_mask.exr").string());
  int roadValid = 0;
  for (size_t i = 0; i < depth.size(); ++i) {
    if (m.values.values()[i] >= 0.5f) roadValid += validMask.values()[i] > 0.5f;
    else nearRoad = std::max<double>(nearRoad, depth.values()[i]);
  }
  uint64_t windSteps = 0;
  for (const auto& p : r.phenomena)
    if (p.name == "wind transport") windSteps = p.steps;
  int released = 0;
  for (const auto& a : r.avalanches) released += a.released;
  std::printf("[ measure ] no-snow road: %d cells, worst snow on it %.3g m over 4 frames and the wind/avalanche deposits; "
              "snow elsewhere up to %.2f m; %llu wind steps, %d avalanches, %zu skiers; removed at start %.0f m^3; balance %.2e\n",
              roadCells, worst, nearRoad, static_cast<unsigned long long>(windSteps), released, r.skiers.size(), r.noSnowRemovedM3,
              r.massBalanceRelativeError());
  EXPECT_EQ(worst, 0.0);
  EXPECT_EQ(roadValid, roadCells);  // the road is terrain (valid in the outputs), only bare
  EXPECT_GT(nearRoad, 0.5);
  EXPECT_GT(windSteps, 10u);
  EXPECT_GE(released, 1);
  EXPECT_NEAR(r.noSnowRemovedM3, roadCells * 0.3 * 100.0, 1e-3 * roadCells * 30.0);
  EXPECT_LT(r.massBalanceRelativeError(), 1e-6);
  // The masked release on the road itself finds no unstable snow there: recorded, not released.
  bool roadRelease = false;
  for (const auto& a : r.avalanches)
    if (a.user) {
      roadRelease = true;
      EXPECT_FALSE(a.released);
      EXPECT_NE(a.why.find("release mask"), std::string::npos) << a.why;
    }
  EXPECT_TRUE(roadRelease);
  fs::remove_all(d);
  fs::remove_all(bake.dir);
}

// Skiers from a start mask start inside it; the skier_spawn multiplier keeps automatic skiers
// out of a zero area.
TEST(ArtDirection, SkiersStartInsideTheirStartMask) {
  const fs::path d = tempDir("skiers");
  auto top = [](int x, int y) { return x >= 40 && x < 56 && y >= 8 && y < 24 ? 1.0 : 0.0; };
  writeImage(d / "lift.png", 64, 64, top, OIIO::TypeDesc::UINT8);
  writeImage(d / "spawn.png", 64, 64, [](int x, int) { return x < 32 ? 1.0 : 0.0; }, OIIO::TypeDesc::UINT8);
  std::ostringstream text;
  text << "[terrain]\nbuiltin = \"ridged\"\nsize = 128\ncell_size_m = 10\nmin_altitude_m = 1500\n[season]\ndays = 6\n"
       << "[initial_snow]\nstable = 1.0\n"
       << "[multipliers]\nskier_spawn = \"" << (d / "spawn.png").string() << "\"\n"
       << "[[events]]\ntype = \"skier\"\nday = 2\ncount = 12\nmask = \"" << (d / "lift.png").string() << "\"\n"
       << "[parameters]\navalanche_rate_per_km2_per_day = 0\nskiers_per_hour = 2\nski_trigger_factor = 0\n"
       << "[outputs]\nlayers = [\"depth\"]\n";
  const test::Bake bake = test::bakeSceneText("art_skiers", text.str());
  int user = 0, automatic = 0, userInside = 0, autoInSpawn = 0;
  for (const auto& k : bake.result.season.skiers) {
    if (k.user) {
      ++user;
      userInside += k.startX >= 80 && k.startX < 112 && k.startY >= 16 && k.startY < 48;
    } else {
      ++automatic;
      autoInSpawn += k.startX <= 64;  // cell 64 straddles the painted edge (0.25)
    }
  }
  std::printf("[ measure ] start mask: %d/%d user skiers inside; skier_spawn: %d/%d automatic skiers in the painted half\n", userInside,
              user, autoInSpawn, automatic);
  EXPECT_EQ(user, 12);
  EXPECT_EQ(userInside, user);
  EXPECT_GT(automatic, 20);
  EXPECT_EQ(autoInSpawn, automatic);
  fs::remove_all(d);
  fs::remove_all(bake.dir);
}

TEST(ArtDirection, SceneFileErrorsNameTheKey) {
  const fs::path d = tempDir("scene");
  writeImage(d / "m.png", 8, 8, [](int, int) { return 1.0; }, OIIO::TypeDesc::UINT8);
  const std::string base = "[terrain]\nbuiltin = \"ridged\"\n[masks.zone]\nfile = \"m.png\"\n";
  auto err = [&](const std::string& extra) { return errorOf([&] { loadSceneText(base + extra, "s.toml", d.string()); }); };
  EXPECT_NE(err("[multipliers]\nmelt = \"zome\"\n").find("no mask named 'zome'"), std::string::npos);
  EXPECT_NE(err("[multipliers]\nmelt = \"gone.png\"\n").find("does not exist"), std::string::npos);
  EXPECT_NE(err("[[edits]]\nday = 1\nlayer = \"stable\"\nop = \"add\"\n").find("edits.depth_m: missing"), std::string::npos);
  EXPECT_NE(err("[[edits]]\nday = 1\nlayer = \"stable\"\nop = \"move\"\n").find("edits.to: missing"), std::string::npos);
  EXPECT_NE(err("[[edits]]\nday = 1\nlayer = \"stable\"\nop = \"smear\"\ndepth_m = 1\n").find("not one of"), std::string::npos);
  EXPECT_NE(err("[[events]]\ntype = \"avalanche\"\nday = 1\nmask = \"zone\"\nposition_m = [1, 2]\n").find("one of them"), std::string::npos);
  EXPECT_NE(err("[masks.zone2]\nfile = \"m.png\"\nvalues = [1, 1]\n").find("masks.zone2.values"), std::string::npos);
  EXPECT_NE(err("[masks.zone3]\nfile = \"m.png\"\nblur = 2\n").find("masks.zone3.blur: unknown key"), std::string::npos);
  EXPECT_NE(err("[initial_snow]\nstable = { mask = \"zone\" }\n").find("depth_m: missing"), std::string::npos);
  const std::string occlusion = errorOf([&] {
    loadSceneText("mode = \"occlusion\"\n" + base + "[[edits]]\nday = 1\nlayer = \"stable\"\nop = \"add\"\ndepth_m = 1\n", "s.toml", d.string());
  });
  EXPECT_NE(occlusion.find("no season to edit"), std::string::npos) << occlusion;
  // A good one parses: names resolve, paths resolve against the scene's folder.
  const Scene s = loadSceneText(base + "[initial_snow]\nunstable = { mask = \"zone\", depth_m = 0.5 }\n[multipliers]\nno_snow = \"m.png\"\n"
                                       "[[edits]]\nday = 3\nlayer = \"unstable\"\nop = \"move\"\nto = \"stable\"\nmask = \"zone\"\n",
                                "s.toml", d.string());
  EXPECT_EQ(s.initialSnow[2].kind, InitialSnowLayer::Kind::Mask);
  EXPECT_EQ(s.initialSnow[2].raster.name, "zone");
  ASSERT_TRUE(s.multipliers.noSnow);
  EXPECT_EQ(s.multipliers.noSnow->file, (d / "m.png").lexically_normal().string());
  ASSERT_EQ(s.edits.size(), 1u);
  EXPECT_FALSE(s.edits[0].depthM);
  fs::remove_all(d);
}

}  // namespace
}  // namespace snow

namespace snow {
namespace {

// The example scene in presets/ bakes (to its masked release, day 46) and uses what it shows:
// the edits, the masked release from the painted zone, the start-mask skiers and a bare road.
TEST(ArtDirection, ExamplePresetBakes) {
  const fs::path d = tempDir("preset");
  BakeOptions o;
  o.scene = std::string(SNOWBAKE_SOURCE_DIR) + "/presets/art_direction.toml";
  o.outDir = (d / "out").string();
  o.backend = "cpu";
  o.useCache = false;
  o.progress = false;
  // 50 days: the preset's skiers come on day 50 (an event after the season's end is refused).
  o.sets = {"season.days=50", "outputs.frames_days=[0]", "outputs.layers=[\"depth\"]"};
  std::ostringstream log;
  const BakeResult r = runBake(o, log);
  ASSERT_EQ(r.season.edits.size(), 2u);
  EXPECT_GT(r.season.edits[0].volumeM3, 0.0);
  EXPECT_GT(r.season.edits[1].volumeM3, 0.0);
  bool masked = false;
  for (const auto& a : r.season.avalanches) masked = masked || (a.user && a.released && a.releaseCells > 100);
  EXPECT_TRUE(masked) << log.str();
  EXPECT_GT(r.season.noSnowRemovedM3, 0.0);
  EXPECT_LT(r.season.massBalanceRelativeError(), 1e-6);
  std::ifstream in(d / "out" / "manifest.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_GE(j["art_direction"]["rasters"].size(), 6u);
  EXPECT_EQ(j["art_direction"]["edits"].size(), 2u);
  fs::remove_all(d);
}

}  // namespace
}  // namespace snow
