#include <gtest/gtest.h>

#include <bit>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <thread>

#include <OpenImageIO/imageio.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "bake_support.h"
#include "core/atomic_file.h"
#include "bakers/grid_writer.h"
#include "core/grid_window.h"
#include "temp_dir.h"

using namespace snow;
namespace fs = std::filesystem;

namespace {
fs::path gridWriterTempDir() {
  return snow::test::uniqueTestDir("writer");
}
std::string bytesOf(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}
Grid<float> ramp() {
  Grid<float> g(37, 23);
  for (int y = 0; y < 23; ++y)
    for (int x = 0; x < 37; ++x) g(x, y) = 0.001f * static_cast<float>(x * y) + (x == 3 ? 1234.5678f : 0.f);
  return g;
}
}  // namespace

TEST(GridWriter, FloatImagesReadBackExactly) {
  const fs::path dir = gridWriterTempDir();
  const Grid<float> g = ramp();
  for (const char* format : {"exr", "tiff"}) {
    const WrittenImage img = writeFloatImage((dir / "layer").string(), format, g, "powder");
    EXPECT_EQ(readFloatImage(img.path).values(), g.values()) << format;
    EXPECT_FLOAT_EQ(img.minValue, 0.f);
    EXPECT_FLOAT_EQ(img.maxValue, 1234.5678f + 0.001f * 3 * 22);
  }
  fs::remove_all(dir);
}

// outputs.compression_level: every level reads back the same values; level 0 writes EXR
// uncompressed and PNG stored, higher levels write smaller files of a compressible grid.
TEST(GridWriter, CompressionLevelsKeepTheValuesAndChangeTheSize) {
  const fs::path dir = gridWriterTempDir();
  Grid<float> g(256, 128);
  for (int y = 0; y < 128; ++y)
    for (int x = 0; x < 256; ++x) g(x, y) = static_cast<float>((x / 16) * 0.25 + (y / 32));  // plateaus: compressible
  std::map<int, uintmax_t> exrSize, pngSize;
  for (int level : {0, 1, 9}) {
    const std::string base = (dir / ("l" + std::to_string(level))).string();
    const WrittenImage exr = writeFloatImage(base, "exr", g, "depth", level);
    EXPECT_EQ(readFloatImage(exr.path).values(), g.values()) << level;
    auto in = OIIO::ImageInput::open(exr.path);
    ASSERT_TRUE(in);
    EXPECT_EQ(in->spec().get_string_attribute("compression"), level == 0 ? "none" : "zip") << level;
    exrSize[level] = fs::file_size(exr.path);
    const WrittenImage png = writeNormalised(base, "png16", g, level);
    const Grid<float> back = readFloatImage(png.path);
    for (size_t i = 0; i < g.size(); ++i)
      ASSERT_NEAR(back.values()[i] * (png.maxValue - png.minValue) + png.minValue, g.values()[i], (png.maxValue - png.minValue) / 65535.0);
    pngSize[level] = fs::file_size(png.path);
  }
  EXPECT_GT(exrSize[0], 256u * 128u * 4u);  // raw floats
  EXPECT_LT(exrSize[1], exrSize[0] / 4);
  EXPECT_LE(exrSize[9], exrSize[1]);
  EXPECT_GT(pngSize[0], 256u * 128u * 2u);
  EXPECT_LT(pngSize[1], pngSize[0] / 4);
  EXPECT_LE(pngSize[9], pngSize[1]);
  EXPECT_EQ(exrCompressionName(0), "none");
  EXPECT_EQ(exrCompressionName(4), "zip:4");
  fs::remove_all(dir);
}

// No time stamps in the files: a bake repeated a second later gives the same bytes.
TEST(GridWriter, SameGridSameBytesAcrossTime) {
  const fs::path dir = gridWriterTempDir();
  for (const char* format : {"exr", "tiff"}) {
    const std::string a = writeFloatImage((dir / "a").string(), format, ramp(), "depth").path;
    std::this_thread::sleep_for(std::chrono::milliseconds(1100));
    const std::string b = writeFloatImage((dir / "b").string(), format, ramp(), "depth").path;
    EXPECT_TRUE(bytesOf(a) == bytesOf(b)) << format;
  }
  fs::remove_all(dir);
}

TEST(AtomicFile, FailedWriteLeavesTheOldFileAndNoTemporary) {
  const fs::path dir = gridWriterTempDir();
  const std::string path = (dir / "manifest.json").string();
  writeTextAtomically(path, "old");
  EXPECT_THROW(writeAtomically(path,
                               [](const std::string& temp) {
                                 std::ofstream(temp) << "half";
                                 throw std::runtime_error("interrupted");
                               }),
               std::runtime_error);
  EXPECT_EQ(bytesOf(path), "old");
  size_t entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++entries;
  EXPECT_EQ(entries, 1u);
  writeTextAtomically(path, "new");
  EXPECT_EQ(bytesOf(path), "new");
  fs::remove_all(dir);
}


// Two writers of one file (tasks, processes or farm nodes) never share a temporary: each call
// names its own, keeping the extension the writers choose the format by.
TEST(AtomicFile, EveryCallHasItsOwnTemporaryNameWithTheFinalExtension) {
  const std::string a = temporaryPathFor("/out/snow_depth.exr"), b = temporaryPathFor("/out/snow_depth.exr");
  EXPECT_NE(a, b);
  for (const std::string& t : {a, b}) {
    const fs::path p(t);
    EXPECT_EQ(p.parent_path(), fs::path("/out"));
    EXPECT_EQ(p.extension(), ".exr");
    EXPECT_EQ(p.filename().string().rfind(".snow_depth.tmp-", 0), 0u) << t;
    EXPECT_TRUE(isTemporaryFileName(p.filename().string())) << t;
  }
  EXPECT_FALSE(isTemporaryFileName("snow_depth.exr"));
  EXPECT_FALSE(isTemporaryFileName(".snow_depth.exr"));
}

TEST(AtomicFile, EightThreadsWritingOneFileDurablyLeaveOneWholeVersionAndNoTemporary) {
  const fs::path dir = gridWriterTempDir();
  const std::string path = (dir / "entry.bin").string();
  std::vector<std::thread> writers;
  for (int i = 0; i < 8; ++i)  // one file from eight threads at once: one whole version wins
    writers.emplace_back([&, i] {
      writeStreamAtomically(path, [&](std::ostream& out) { out << std::string(100000, static_cast<char>('a' + i)); }, Durability::Durable);
    });
  for (std::thread& t : writers) t.join();
  const std::string bytes = bytesOf(path);
  ASSERT_EQ(bytes.size(), 100000u);
  EXPECT_EQ(bytes, std::string(100000, bytes[0]));
  size_t entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++entries;
  EXPECT_EQ(entries, 1u);
  fs::remove_all(dir);
}
// The normalised encodings and the multi-channel EXR, read back by OpenImageIO (and the raw file
// by hand): each decodes, with the manifest's range, to the float layer within half a step of
// its quantisation; the EXR's channels are the layers, named, bit for bit.
TEST(GridWriter, EncodingsAndMultiChannelExrReadBackToTheLayers) {
  const test::Bake bake = test::bakeSceneText("encodings_test",
                                              "[terrain]\nbuiltin = \"ridged\"\nsize = 96\n[season]\ndays = 20\n"
                                              "[[weather.snowfall]]\nstart_day = 1\nend_day = 15\n[parameters]\nrain_snow_limit_m = 900\n"
                                              "[outputs]\nlayers = [\"depth\", \"powder\", \"surface\"]\n"
                                              "encodings = [\"png16\", \"png8\", \"r16\"]\nmultichannel_exr = true\n");
  const auto manifest = nlohmann::json::parse(std::ifstream(bake.out() / "manifest.json"));
  auto range = [&](const std::string& file) {
    for (const auto& f : manifest["files"])
      if (f["path"] == file) return std::pair<double, double>{f["min"].get<double>(), f["max"].get<double>()};
    ADD_FAILURE() << file << " not in the manifest";
    return std::pair<double, double>{0, 0};
  };
  auto oiioRead = [](const std::string& path, int& w, int& h) {
    auto in = OIIO::ImageInput::open(path);
    EXPECT_TRUE(in) << path;
    w = in->spec().width, h = in->spec().height;
    std::vector<float> v(static_cast<size_t>(w) * h * in->spec().nchannels);
    EXPECT_TRUE(in->read_image(0, 0, 0, in->spec().nchannels, OIIO::TypeDesc::FLOAT, v.data()));
    return std::make_pair(v, in->spec().channelnames);
  };
  int w = 0, h = 0;
  const auto [all, names] = oiioRead((bake.out() / "layers.exr").string(), w, h);
  ASSERT_EQ(names, (std::vector<std::string>{"depth.Y", "powder.Y", "surface.Y"}));
  for (int c = 0; c < 3; ++c) {
    const std::string layer = names[c].substr(0, names[c].size() - 2);
    const Grid<float> ref = readFloatImage((bake.out() / (layer + ".exr")).string());
    for (size_t i = 0; i < ref.size(); ++i) ASSERT_EQ(all[i * 3 + c], ref.values()[i]) << layer;
    const auto [lo, hi] = range(layer + ".16.png");
    ASSERT_GT(hi, lo) << layer;
    for (const auto& [suffix, levels] : {std::pair<std::string, double>{".16.png", 65535.0}, {".8.png", 255.0}}) {
      int pw = 0, ph = 0;
      const auto [pixels, _] = oiioRead((bake.out() / (layer + suffix)).string(), pw, ph);
      ASSERT_EQ(pw, ref.width());
      double worst = 0;
      for (size_t i = 0; i < ref.size(); ++i)
        worst = std::max(worst, std::abs(lo + (hi - lo) * std::round(pixels[i] * levels) / levels - ref.values()[i]));
      EXPECT_LE(worst, 0.5 * (hi - lo) / levels * 1.001 + 1e-6 * std::abs(hi)) << layer << suffix;
    }
    std::ifstream raw(bake.out() / (layer + ".r16"), std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(raw)), std::istreambuf_iterator<char>());
    ASSERT_EQ(bytes.size(), ref.size() * 2);
    double worst = 0;
    for (size_t i = 0; i < ref.size(); ++i) {
      const unsigned p = static_cast<unsigned char>(bytes[2 * i]) | (static_cast<unsigned char>(bytes[2 * i + 1]) << 8);
      worst = std::max(worst, std::abs(lo + (hi - lo) * p / 65535.0 - ref.values()[i]));
    }
    EXPECT_LE(worst, 0.5 * (hi - lo) / 65535.0 * 1.001 + 1e-6 * std::abs(hi)) << layer << ".r16";
  }
  std::filesystem::remove_all(bake.dir);
}

// Bilinear resampling reproduces a linear field exactly away from the clamped edge, keeps the
// extent, and the bake writes the displacement maps at the requested size.
TEST(GridWriter, DisplacementMapsAtTheRequestedResolution) {
  Grid<float> ramp(40, 30, 0.f);
  for (int y = 0; y < 30; ++y)
    for (int x = 0; x < 40; ++x) ramp(x, y) = 2.f * x + 3.f * y + 100.f;
  const Grid<float> up = resampleBilinear(ramp, 160, 90);
  ASSERT_EQ(up.width(), 160);
  ASSERT_EQ(up.height(), 90);
  for (int y = 3; y < 87; ++y)
    for (int x = 4; x < 156; ++x) {
      const double sx = (x + 0.5) * 40 / 160 - 0.5, sy = (y + 0.5) * 30 / 90 - 0.5;
      ASSERT_NEAR(up(x, y), 2 * sx + 3 * sy + 100, 1e-4) << x << "," << y;
    }
  const test::Bake bake = test::bakeSceneText("displacement_test",
                                              "[terrain]\nbuiltin = \"ridged\"\nsize = 64\n[season]\ndays = 10\n"
                                              "[[weather.snowfall]]\nstart_day = 1\nend_day = 8\n[parameters]\nrain_snow_limit_m = 900\n"
                                              "[outputs]\nlayers = [\"depth\"]\ndisplacement_size = [256, 200]\n");
  const Grid<float> depth = readFloatImage((bake.out() / "depth.exr").string());
  const Grid<float> disp = readFloatImage((bake.out() / "displacement_depth.exr").string());
  ASSERT_EQ(disp.width(), 256);
  ASSERT_EQ(disp.height(), 200);
  double a = 0, b = 0;
  for (float v : depth.values()) a += v;
  for (float v : disp.values()) b += v;
  EXPECT_NEAR(b / disp.size(), a / depth.size(), 0.02 * a / depth.size() + 1e-6);  // same mean depth
  EXPECT_TRUE(fs::exists(bake.out() / "displacement_surface.exr"));
  fs::remove_all(bake.dir);
}

// Previews per frame day and the season's contact sheet, read back by OpenImageIO: sizes, and
// snow-covered cells brighter than bare ones (the preview shows the snow).
TEST(GridWriter, PixelsResampledFromTheCellsTheyReadAreTheWholeImagesBitForBit) {
  // What a rank writes of a resampled image (outputs.resize, the displacement maps): any block of
  // pixels computed from the cells cellsReadBy names, finer and coarser than the grid, over valid
  // cells too, has the bits of the whole image's.
  const int sw = 37, sh = 29;
  Grid<float> g(sw, sh);
  Grid<uint8_t> valid(sw, sh, 1);
  for (int y = 0; y < sh; ++y)
    for (int x = 0; x < sw; ++x) {
      g(x, y) = static_cast<float>(std::sin(0.37 * x) * 100.0 + std::cos(0.23 * y * x) * 7.0 + 0.1 * y);
      if ((x * 7 + y * 3) % 11 == 0) valid(x, y) = 0;  // NODATA scattered, at the edges too
    }
  int blocks = 0;
  for (const auto& [W, H] : {std::pair{129, 65}, std::pair{17, 13}, std::pair{37, 29}}) {
    Grid<uint8_t> wholeValid;
    const Grid<float> wholeBilinear = resampleBilinear(g, W, H), wholeOverValid = resampleValid(g, valid, W, H, wholeValid);
    for (const CellRect to : {CellRect{0, 0, W, H}, CellRect{0, 0, 1, 1}, CellRect{W / 3, H / 4, W / 2 + 1, H - 1}, CellRect{W - 5, H - 3, W, H}}) {
      const auto [x0, x1] = cellsReadBy(to.x0, to.x1, W, sw);
      const auto [y0, y1] = cellsReadBy(to.y0, to.y1, H, sh);
      const CellRect from{x0, y0, x1, y1};
      ASSERT_FALSE(from.empty());
      const ResampleWindow w{from, sw, sh, to, W, H};
      // The cells named are all the whole-grid resamplers read for these pixels: with NaN in
      // every other cell (a read at weight 0 too gives NaN), the pixels keep their values.
      Grid<float> outside(sw, sh, std::numeric_limits<float>::quiet_NaN());
      for (int y = from.y0; y < from.y1; ++y)
        for (int x = from.x0; x < from.x1; ++x) outside(x, y) = g(x, y);
      Grid<uint8_t> outsideValid;
      const Grid<float> bilinearOutside = resampleBilinear(outside, W, H), overValidOutside = resampleValid(outside, valid, W, H, outsideValid);
      for (int y = to.y0; y < to.y1; ++y)
        for (int x = to.x0; x < to.x1; ++x) {
          EXPECT_EQ(std::bit_cast<uint32_t>(bilinearOutside(x, y)), std::bit_cast<uint32_t>(wholeBilinear(x, y))) << W << " x " << H << " at " << x << ", " << y;
          EXPECT_EQ(std::bit_cast<uint32_t>(overValidOutside(x, y)), std::bit_cast<uint32_t>(wholeOverValid(x, y))) << W << " x " << H << " at " << x << ", " << y;
        }
      const Grid<float> heldG = gridWindow(g, from);
      const Grid<uint8_t> heldValid = gridWindow(valid, from);
      Grid<uint8_t> validOut;
      const Grid<float> bilinear = resampleBilinear(heldG, w), overValid = resampleValid(heldG, heldValid, w, validOut);
      ASSERT_EQ(bilinear.width(), to.width());
      ASSERT_EQ(overValid.height(), to.height());
      for (int y = to.y0; y < to.y1; ++y)
        for (int x = to.x0; x < to.x1; ++x) {
          const int i = x - to.x0, j = y - to.y0;
          EXPECT_EQ(std::bit_cast<uint32_t>(bilinear(i, j)), std::bit_cast<uint32_t>(wholeBilinear(x, y))) << W << " x " << H << " at " << x << ", " << y;
          EXPECT_EQ(std::bit_cast<uint32_t>(overValid(i, j)), std::bit_cast<uint32_t>(wholeOverValid(x, y))) << W << " x " << H << " at " << x << ", " << y;
          EXPECT_EQ(validOut(i, j), wholeValid(x, y));
        }
      ++blocks;
    }
  }
  EXPECT_EQ(blocks, 12);
  // The cells read: none past the grid, and a block's first pixel's below-left cell.
  EXPECT_EQ(cellsReadBy(0, 129, 129, 37), std::make_pair(0, 37));
  EXPECT_EQ(cellsReadBy(64, 65, 129, 37), std::make_pair(18, 20));  // at 64.5 * 37 / 129 - 0.5 = 18.0: cells 18 and 19
  EXPECT_EQ(cellsReadBy(0, 1, 17, 37), std::make_pair(0, 2));       // at 0.588: cells 0 and 1
  EXPECT_EQ(cellsReadBy(0, 1, 129, 37), std::make_pair(0, 2));      // at -0.36: clamped to cell 0, and cell 1 at a weight of 0
  EXPECT_EQ(cellsReadBy(5, 5, 129, 37), std::make_pair(0, 0));
}

TEST(GridWriter, PreviewsAndContactSheet) {
  const test::Bake bake = test::bakeSceneText("preview_test",
                                              "[terrain]\nbuiltin = \"ridged\"\nsize = 80\n[season]\ndays = 30\n"
                                              "[[weather.keyframe]]\nday = 0\nsea_level_temperature_c = 16\n[[weather.snowfall]]\nstart_day = 1\nend_day = 10\n[parameters]\nrain_snow_limit_m = 1800\n"
                                              "[outputs]\nlayers = [\"depth\", \"preview\"]\nframes_days = [10, 20]\n");
  auto read = [](const fs::path& p, int& w, int& h) {
    auto in = OIIO::ImageInput::open(p.string());
    EXPECT_TRUE(in) << p;
    w = in->spec().width, h = in->spec().height;
    EXPECT_EQ(in->spec().nchannels, 3);
    std::vector<uint8_t> v(static_cast<size_t>(w) * h * 3);
    EXPECT_TRUE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, v.data()));
    return v;
  };
  int w = 0, h = 0;
  const std::vector<uint8_t> rgb = read(bake.out() / "preview.png", w, h);
  ASSERT_EQ(w, 80);
  ASSERT_EQ(h, 80);
  const Grid<float> depth = readFloatImage((bake.out() / "depth.exr").string());
  double snow = 0, snowN = 0, bare = 0, bareN = 0;
  for (size_t i = 0; i < depth.size(); ++i) {
    const double luma = rgb[3 * i] + rgb[3 * i + 1] + rgb[3 * i + 2];
    if (depth.values()[i] > 0.05f) snow += luma, snowN += 1;
    if (depth.values()[i] <= 0.001f) bare += luma, bareN += 1;
  }
  ASSERT_GT(snowN, 50);
  ASSERT_GT(bareN, 50);
  EXPECT_GT(snow / snowN, 1.3 * bare / bareN);
  EXPECT_TRUE(fs::exists(bake.out() / "frames" / "preview.0010.png"));
  int sw = 0, sh = 0;
  read(bake.out() / "contact_sheet.png", sw, sh);
  EXPECT_EQ(sw, 2 * 80 + 3 * 4);  // three previews (two frames and the end): two columns, two rows
  EXPECT_EQ(sh, 2 * 80 + 3 * 4);
  fs::remove_all(bake.dir);
}
