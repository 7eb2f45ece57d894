// Terrain input round trips: a known analytic height field written in each supported format,
// read back through the scene's reading options, compared within the format's precision.
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>
#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "core/errors.h"
#include "inputs/mesh.h"
#include "inputs/terrain_loader.h"
#include "tools/info.h"
#include "temp_dir.h"

using namespace snow;
namespace fs = std::filesystem;

namespace {

constexpr int kW = 64, kH = 48;
constexpr double kCell = 5.0;

// A Gaussian hill: 1000 m plain, 600 m peak at (140 m, 110 m) from the north-west corner.
double hill(double xM, double yFromNorthM) {
  const double dx = xM - 140.0, dy = yFromNorthM - 110.0;
  return 1000.0 + 600.0 * std::exp(-(dx * dx + dy * dy) / (2.0 * 50.0 * 50.0));
}
double hillAtCell(int x, int y, double cell = kCell) { return hill((x + 0.5) * cell, (y + 0.5) * cell); }

struct FormatsTempDir {
  fs::path path;
  FormatsTempDir() {
    path = snow::test::uniqueTestDir("formats");
  }
  ~FormatsTempDir() { fs::remove_all(path); }
  std::string operator/(const std::string& name) const { return (path / name).string(); }
};

void expectHill(const Terrain& t, double tolerance, double cell = kCell) {
  ASSERT_EQ(t.heightsM.width(), kW);
  ASSERT_EQ(t.heightsM.height(), kH);
  EXPECT_NEAR(t.info.spec.cellSizeXM, cell, 1e-9);
  EXPECT_NEAR(t.info.spec.cellSizeYM, cell, 1e-9);
  double worst = 0.0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) worst = std::max(worst, std::abs(t.heightsM(x, y) - hillAtCell(x, y)));
  EXPECT_LE(worst, tolerance);
}

void writeGeoTiff(const std::string& path, int epsg, double originX, double originY, double cellX, double cellY) {
  GDALAllRegister();
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
  GDALDataset* ds = driver->Create(path.c_str(), kW, kH, 1, GDT_Float32, nullptr);
  double gt[6] = {originX, cellX, 0, originY, 0, -cellY};
  ds->SetGeoTransform(gt);
  OGRSpatialReference srs;
  srs.importFromEPSG(epsg);
  ds->SetSpatialRef(&srs);
  std::vector<float> v(kW * kH);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) v[y * kW + x] = static_cast<float>(hillAtCell(x, y));
  EXPECT_EQ(ds->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, kW, kH, v.data(), kW, kH, GDT_Float32, 0, 0), CE_None);
  GDALClose(ds);
}

void writeImage(const std::string& path, OIIO::TypeDesc type, double lo, double hi) {
  std::vector<float> v(kW * kH);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) v[y * kW + x] = static_cast<float>((hillAtCell(x, y) - lo) / (hi - lo));
  auto out = OIIO::ImageOutput::create(path);
  ASSERT_TRUE(out);
  OIIO::ImageSpec spec(kW, kH, 1, type);
  ASSERT_TRUE(out->open(path, spec));
  ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, v.data()));
  out->close();
}

void writeRaw(const std::string& path, bool is32, bool big, double lo, double hi) {
  std::ofstream out(path, std::ios::binary);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      unsigned char b[4];
      if (is32) {
        const float f = static_cast<float>(hillAtCell(x, y));
        uint32_t u;
        std::memcpy(&u, &f, 4);
        for (int k = 0; k < 4; ++k) b[big ? 3 - k : k] = static_cast<unsigned char>(u >> (8 * k));
        out.write(reinterpret_cast<char*>(b), 4);
      } else {
        const auto u = static_cast<uint16_t>(std::lround((hillAtCell(x, y) - lo) / (hi - lo) * 65535.0));
        b[big ? 1 : 0] = static_cast<unsigned char>(u & 0xff);
        b[big ? 0 : 1] = static_cast<unsigned char>(u >> 8);
        out.write(reinterpret_cast<char*>(b), 2);
      }
    }
}

std::string sourceErrorOf(const TerrainSource& src) {
  try {
    loadTerrain(src);
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error for " << src.file;
  return "";
}

}  // namespace

TEST(TerrainFormats, ProjectedGeoTiffKeepsMetres) {
  FormatsTempDir dir;
  writeGeoTiff(dir / "utm.tif", 32632, 650000.0, 5150000.0, kCell, kCell);
  TerrainSource src;
  src.file = dir / "utm.tif";
  const Terrain t = loadTerrain(src);
  expectHill(t, 1e-3);
  EXPECT_EQ(t.info.format, "dem");
  EXPECT_NE(t.info.coordinateSystem.find("projected"), std::string::npos) << t.info.coordinateSystem;
  EXPECT_TRUE(t.info.latitudeKnown);
  EXPECT_NEAR(t.info.centreLatitudeDeg, 46.49, 0.05);  // UTM 32N, 5150 km north
}

TEST(TerrainFormats, GeographicGeoTiffBecomesMetricCells) {
  FormatsTempDir dir;
  const double deg = 1.0 / 1200.0;  // 3 arc-seconds
  writeGeoTiff(dir / "wgs84.tif", 4326, 11.0, 47.0, deg, deg);
  TerrainSource src;
  src.file = dir / "wgs84.tif";
  const Terrain t = loadTerrain(src);
  const double lat = 47.0 - kH * deg / 2;
  EXPECT_NEAR(t.info.spec.cellSizeXM, deg * metresPerDegreeLongitude(lat), 1e-6);
  EXPECT_NEAR(t.info.spec.cellSizeYM, deg * metresPerDegreeLatitude(lat), 1e-6);
  EXPECT_NEAR(t.info.spec.cellSizeXM, 63.2, 0.3);
  EXPECT_NEAR(t.info.spec.cellSizeYM, 92.6, 0.2);
  EXPECT_NEAR(t.heightsM(10, 20), hillAtCell(10, 20), 1e-3);
}

TEST(TerrainFormats, EsriAsciiCornerAndCentreHeaders) {
  FormatsTempDir dir;
  for (const char* kind : {"corner", "center"}) {
    const std::string path = dir / (std::string(kind) + ".asc");
    {
      std::ofstream out(path);
      const double x0 = std::string(kind) == "corner" ? 1000.0 : 1000.0 + kCell / 2;
      const double y0 = std::string(kind) == "corner" ? 2000.0 : 2000.0 + kCell / 2;
      out << "ncols " << kW << "\nnrows " << kH << "\nxll" << kind << " " << x0 << "\nyll" << kind << " " << y0 << "\ncellsize "
          << kCell << "\nNODATA_value -9999\n";
      out.precision(10);
      for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) out << hillAtCell(x, y) << (x + 1 < kW ? " " : "\n");
    }
    TerrainSource src;
    src.file = path;
    const Terrain t = loadTerrain(src);
    SCOPED_TRACE(kind);
    expectHill(t, 1e-3);
    EXPECT_NEAR(t.info.spec.originX, 1000.0, 1e-9);  // both headers give the same corner
    EXPECT_NEAR(t.info.spec.originY, 2000.0 + kH * kCell, 1e-9);
  }
}

TEST(TerrainFormats, SrtmHgtIsGeographicInt16) {
  FormatsTempDir dir;
  const std::string path = dir / "N46E011.hgt";
  {
    std::ofstream out(path, std::ios::binary);
    for (int y = 0; y < 1201; ++y)
      for (int x = 0; x < 1201; ++x) {
        const auto v = static_cast<int16_t>(std::lround(1000.0 + 0.5 * x + 0.25 * y));
        const unsigned char b[2] = {static_cast<unsigned char>(static_cast<uint16_t>(v) >> 8), static_cast<unsigned char>(v & 0xff)};
        out.write(reinterpret_cast<const char*>(b), 2);
      }
  }
  TerrainSource src;
  src.file = path;
  const Terrain t = loadTerrain(src);
  EXPECT_EQ(t.info.spec.width, 1201);
  EXPECT_NEAR(t.info.spec.cellSizeYM, 92.6, 0.2);
  EXPECT_NEAR(t.info.spec.cellSizeXM, 92.6 * std::cos(46.5 * M_PI / 180.0), 0.3);
  EXPECT_FLOAT_EQ(t.heightsM(200, 100), static_cast<float>(std::lround(1000.0 + 100.0 + 25.0)));
  EXPECT_NEAR(t.info.centreLatitudeDeg, 46.5, 1e-3);
}

TEST(TerrainFormats, SixteenBitPngWithHeightRange) {
  FormatsTempDir dir;
  writeImage(dir / "hill.png", OIIO::TypeDesc::UINT16, 900.0, 1700.0);
  TerrainSource src;
  src.file = dir / "hill.png";
  src.cellSizeM = kCell;
  src.heightRangeM = std::array<double, 2>{900.0, 1700.0};
  const Terrain t = loadTerrain(src);
  EXPECT_EQ(t.info.format, "heightmap");
  expectHill(t, 800.0 / 65535.0 * 0.51 + 1e-4);  // half a 16-bit step
}

TEST(TerrainFormats, FloatTiffAndExrHeightsInMetres) {
  FormatsTempDir dir;
  for (const char* name : {"hill.tif", "hill.exr"}) {
    // value = (h - 0) / 1: metres stored directly
    writeImage(dir / name, OIIO::TypeDesc::FLOAT, 0.0, 1.0);
    TerrainSource src;
    src.file = dir / name;
    src.cellSizeM = kCell;
    if (std::string(name) == "hill.tif") src.format = TerrainFormat::Heightmap;  // a .tif is a DEM unless told
    const Terrain t = loadTerrain(src);
    SCOPED_TRACE(name);
    expectHill(t, 1e-3);
  }
}

TEST(TerrainFormats, RawR16BothByteOrdersAndR32) {
  FormatsTempDir dir;
  for (bool big : {false, true}) {
    const std::string path = dir / (big ? "big.r16" : "little.r16");
    writeRaw(path, false, big, 900.0, 1700.0);
    TerrainSource src;
    src.file = path;
    src.cellSizeM = kCell;
    src.rawWidth = kW;
    src.rawHeight = kH;
    src.byteOrder = big ? ByteOrder::Big : ByteOrder::Little;
    src.heightRangeM = std::array<double, 2>{900.0, 1700.0};
    SCOPED_TRACE(path);
    expectHill(loadTerrain(src), 800.0 / 65535.0 * 0.51 + 1e-4);
  }
  writeRaw(dir / "hill.r32", true, false, 0, 1);
  TerrainSource src;
  src.file = dir / "hill.r32";
  src.cellSizeM = kCell;
  src.rawWidth = kW;
  src.rawHeight = kH;
  expectHill(loadTerrain(src), 1e-4);
}

// A square pyramid: base 100 m x 80 m at z = 0, apex 40 m, as an OBJ; rasterised at 1 m.
TEST(TerrainFormats, MeshPyramidRasterisesToItsAnalyticHeights) {
  FormatsTempDir dir;
  for (const char* up : {"z", "y"}) {
    const std::string path = dir / (std::string("pyramid_") + up + ".obj");
    {
      std::ofstream out(path);
      auto v = [&](double x, double y, double z) {
        if (std::string(up) == "z") out << "v " << x << " " << y << " " << z << "\n";
        else out << "v " << x << " " << z << " " << -y << "\n";  // y-up: (x, up, -north)
      };
      v(0, 0, 0), v(100, 0, 0), v(100, 80, 0), v(0, 80, 0), v(50, 40, 40);
      out << "f 1 2 5\nf 2 3 5\nf 3 4 5\nf 4 1 5\nf 1 4 3\nf 1 3 2\n";
    }
    TerrainSource src;
    src.file = path;
    src.cellSizeM = 1.0;
    src.upAxis = *enumFromName<UpAxis>(up);
    const Terrain t = loadTerrain(src);
    SCOPED_TRACE(up);
    ASSERT_EQ(t.heightsM.width(), 100);
    ASSERT_EQ(t.heightsM.height(), 80);
    EXPECT_EQ(t.info.nodataCells, 0u);
    double worst = 0.0;
    for (int j = 0; j < 80; ++j)
      for (int i = 0; i < 100; ++i) {
        const double x = i + 0.5, y = 80.0 - (j + 0.5);  // row 0 is the north edge
        const double h = 40.0 * std::min(1.0 - std::abs(x - 50.0) / 50.0, 1.0 - std::abs(y - 40.0) / 40.0);
        worst = std::max(worst, std::abs(t.heightsM(i, j) - h));
      }
    EXPECT_LT(worst, 1e-4);
    EXPECT_NEAR(t.info.maxElevationM, 40.0 - 0.5, 0.5);
  }
}

TEST(TerrainFormats, MeshWithGapsHasNodataAndOccludersLoad) {
  FormatsTempDir dir;
  const std::string path = dir / "two.obj";
  {
    std::ofstream out(path);
    out << "v 0 0 5\nv 10 0 5\nv 10 10 5\nv 0 10 5\n"      // a 10 m square at 5 m
        << "v 20 0 7\nv 30 0 7\nv 30 10 7\nv 20 10 7\n"    // another at 7 m, a 10 m gap between
        << "f 1 2 3\nf 1 3 4\nf 5 6 7\nf 5 7 8\n";
  }
  TerrainSource src;
  src.file = path;
  src.cellSizeM = 1.0;
  const Terrain t = loadTerrain(src);
  EXPECT_EQ(t.heightsM.width(), 30);
  EXPECT_EQ(t.info.nodataCells, 100u);
  EXPECT_EQ(t.valid(15, 5), 0);
  EXPECT_FLOAT_EQ(t.heightsM(25, 5), 7.f);
  OccluderSource occ;
  occ.file = path;
  occ.scale = 2.0;
  occ.offsetM = {100.0, 0.0, 3.0};
  const auto meshes = loadOccluders({occ});
  ASSERT_EQ(meshes.size(), 1u);
  EXPECT_EQ(meshes[0].triangles.size(), 4u);
  EXPECT_FLOAT_EQ(meshes[0].boundsMin[0], 100.f);
  EXPECT_FLOAT_EQ(meshes[0].boundsMax[0], 160.f);
  EXPECT_FLOAT_EQ(meshes[0].boundsMax[2], 17.f);
}

TEST(TerrainFormats, ResamplingCoarserAndFinerFollowsTheHill) {
  FormatsTempDir dir;
  writeGeoTiff(dir / "utm.tif", 32632, 650000.0, 5150000.0, kCell, kCell);
  TerrainSource src;
  src.file = dir / "utm.tif";
  src.resampleCellSizeM = 10.0;  // box filter: mean of 2 x 2 cells
  Terrain coarse = loadTerrain(src);
  EXPECT_EQ(coarse.heightsM.width(), kW / 2);
  EXPECT_EQ(coarse.heightsM.height(), kH / 2);
  EXPECT_DOUBLE_EQ(coarse.info.spec.cellSizeXM, 10.0);
  EXPECT_NE(coarse.info.resampling.find("box"), std::string::npos);
  for (int y = 0; y < kH / 2; ++y)
    for (int x = 0; x < kW / 2; ++x) {
      const double mean = (hillAtCell(2 * x, 2 * y) + hillAtCell(2 * x + 1, 2 * y) + hillAtCell(2 * x, 2 * y + 1) +
                           hillAtCell(2 * x + 1, 2 * y + 1)) / 4.0;
      ASSERT_NEAR(coarse.heightsM(x, y), mean, 1e-3);
    }
  src.resampleCellSizeM.reset();
  src.resampleSize = std::array<int, 2>{2 * kW, 2 * kH};  // bilinear at 2.5 m
  Terrain fine = loadTerrain(src);
  EXPECT_DOUBLE_EQ(fine.info.spec.cellSizeXM, 2.5);
  EXPECT_NE(fine.info.resampling.find("bilinear"), std::string::npos);
  double worst = 0.0;
  for (int y = 2; y < 2 * kH - 2; ++y)
    for (int x = 2; x < 2 * kW - 2; ++x) worst = std::max(worst, std::abs(fine.heightsM(x, y) - hillAtCell(x, y, 2.5)));
  EXPECT_LT(worst, 3.0);  // interpolation error of a 600 m hill sampled at 5 m, sigma 50 m
}

TEST(TerrainFormats, NodataIsMaskedOrFilled) {
  FormatsTempDir dir;
  const std::string path = dir / "holes.asc";
  {
    std::ofstream out(path);
    out << "ncols 20\nnrows 20\nxllcorner 0\nyllcorner 0\ncellsize 2\nNODATA_value -9999\n";
    for (int y = 0; y < 20; ++y)
      for (int x = 0; x < 20; ++x) {
        const bool hole = x >= 8 && x < 12 && y >= 8 && y < 12;
        out << (hole ? std::string("-9999") : std::to_string(100.0 + 2.0 * x)) << (x < 19 ? " " : "\n");
      }
  }
  TerrainSource src;
  src.file = path;
  const Terrain masked = loadTerrain(src);
  EXPECT_EQ(masked.info.nodataCells, 16u);
  EXPECT_EQ(masked.valid(9, 9), 0);
  src.fillNodata = true;
  const Terrain filled = loadTerrain(src);
  EXPECT_EQ(filled.info.nodataCells, 0u);
  EXPECT_EQ(filled.info.filledCells, 16u);
  for (int y = 8; y < 12; ++y)
    for (int x = 8; x < 12; ++x) EXPECT_NEAR(filled.heightsM(x, y), 100.0 + 2.0 * x, 0.05) << x << "," << y;  // a plane
}

TEST(TerrainFormats, HeightmapsNeedTheirCellSizeAndHeightMapping) {
  FormatsTempDir dir;
  writeImage(dir / "hill.png", OIIO::TypeDesc::UINT16, 900.0, 1700.0);
  TerrainSource src;
  src.file = dir / "hill.png";
  EXPECT_NE(sourceErrorOf(src).find("terrain.cell_size_m"), std::string::npos);
  src.cellSizeM = 5.0;
  EXPECT_NE(sourceErrorOf(src).find("terrain.height_range_m"), std::string::npos);
  writeRaw(dir / "hill.r16", false, false, 0, 1);
  TerrainSource raw;
  raw.file = dir / "hill.r16";
  raw.cellSizeM = 5.0;
  raw.heightRangeM = std::array<double, 2>{0.0, 1.0};
  EXPECT_NE(sourceErrorOf(raw).find("terrain.raw_width"), std::string::npos);
  raw.rawWidth = kW + 1;
  raw.rawHeight = kH;
  const std::string msg = sourceErrorOf(raw);
  EXPECT_NE(msg.find(raw.file), std::string::npos) << msg;
  EXPECT_NE(msg.find("has " + std::to_string(kW * kH * 2) + " bytes"), std::string::npos) << msg;
  raw.rawWidth = 200000;
  raw.rawHeight = 200000;
  const std::string huge = sourceErrorOf(raw);
  EXPECT_NE(huge.find("GiB"), std::string::npos) << huge;
}

namespace {
// A projected GeoTIFF of the hill in `bands` bands (band b holds the hill + 100 (b - 1) m),
// with a band scale and offset when given (stored = (height - offset) / scale).
void writeScaledGeoTiff(const std::string& path, int bands, double scale, double offset, bool georeferenced = true) {
  GDALAllRegister();
  GDALDataset* ds = GetGDALDriverManager()->GetDriverByName("GTiff")->Create(path.c_str(), kW, kH, bands, GDT_Float32, nullptr);
  if (georeferenced) {
    double gt[6] = {500000, kCell, 0, 5200000, 0, -kCell};
    ds->SetGeoTransform(gt);
    OGRSpatialReference srs;
    srs.importFromEPSG(32632);
    ds->SetSpatialRef(&srs);
  }
  for (int b = 1; b <= bands; ++b) {
    std::vector<float> v(kW * kH);
    for (int y = 0; y < kH; ++y)
      for (int x = 0; x < kW; ++x) v[y * kW + x] = static_cast<float>((hillAtCell(x, y) + 100.0 * (b - 1) - offset) / scale);
    GDALRasterBand* band = ds->GetRasterBand(b);
    EXPECT_EQ(band->RasterIO(GF_Write, 0, 0, kW, kH, v.data(), kW, kH, GDT_Float32, 0, 0), CE_None);
    if (scale != 1.0) band->SetScale(scale);
    if (offset != 0.0) band->SetOffset(offset);
  }
  GDALClose(ds);
}
}  // namespace

TEST(TerrainFormats, GdalScaleAndOffsetAreAppliedAndReportedByInfo) {
  FormatsTempDir dir;
  writeScaledGeoTiff(dir / "scaled.tif", 1, 0.1, 500.0);
  TerrainSource src;
  src.file = dir / "scaled.tif";
  const Terrain t = loadTerrain(src);
  expectHill(t, 1e-3);
  EXPECT_NE(t.info.heightMapping.find("GDAL offset and scale"), std::string::npos) << t.info.heightMapping;
  const std::string info = describeTerrain(dir / "scaled.tif", false);  // `snowbake info`
  EXPECT_NE(info.find("height = 500 + 0.1 x stored value"), std::string::npos) << info;
}

TEST(TerrainFormats, MultiBandDemNeedsTerrainBandAndReadsThatBand) {
  FormatsTempDir dir;
  writeScaledGeoTiff(dir / "bands.tif", 3, 1.0, 0.0);
  TerrainSource src;
  src.file = dir / "bands.tif";
  try {
    loadTerrain(src);
    ADD_FAILURE() << "a 3-band file without terrain.band was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("terrain.band"), std::string::npos) << e.what();
  }
  src.band = 3;
  const Terrain t = loadTerrain(src);
  EXPECT_NEAR(t.heightsM(0, 0), hillAtCell(0, 0) + 200.0, 1e-3);  // band 3: the hill + 200 m
  EXPECT_NEAR(t.heightsM(28, 22), hillAtCell(28, 22) + 200.0, 1e-3);
}

TEST(TerrainFormats, ImageWithoutGeoreferenceIsAHeightmapNeedingACellSize) {
  FormatsTempDir dir;
  writeScaledGeoTiff(dir / "plain.tif", 1, 1.0, 0.0, false);
  TerrainSource src;
  src.file = dir / "plain.tif";
  try {
    loadTerrain(src);
    ADD_FAILURE() << "a plain image was read as a DEM";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("terrain.cell_size_m"), std::string::npos) << e.what();
  }
  src.cellSizeM = kCell;
  const Terrain t = loadTerrain(src);
  EXPECT_EQ(t.info.format, "heightmap");
  expectHill(t, 1e-3);
}

TEST(TerrainFormats, HeightLimitsRefuseAbsurdHeightsAndWiden) {
  FormatsTempDir dir;
  writeScaledGeoTiff(dir / "hill.tif", 1, 1.0, 0.0);
  TerrainSource src;
  src.file = dir / "hill.tif";
  src.heightLimitsM = {0.0, 1500.0};  // the hill's top is 1600 m
  EXPECT_THROW(loadTerrain(src), InputError);
  src.heightLimitsM = {0.0, 1601.0};
  expectHill(loadTerrain(src), 1e-3);
}
