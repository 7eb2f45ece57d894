// [outputs.tiles] on every raster output: the multi-channel layers.exr and the avalanche maps are
// tiled like the layers (tiles put back together give the untiled files bit for bit), and a tile
// set's own size (outputs.tiles.resize) writes its tiles at that size beside the untiled files
// at the grid's; bad sizes are scene errors (exit 2) naming file, line and key.
#include <gtest/gtest.h>
#include <unistd.h>  // getpid

#include <OpenImageIO/imageio.h>
#include <sys/wait.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "bake_support.h"
#include "bake/tiles_on_ranks.h"
#include "bakers/raster_tiles.h"
#include "cli_support.h"
#include "distributed/continuous_step.h"

using namespace snow;
namespace fs = std::filesystem;

namespace {

using snow::test::manifestOf;
using snow::test::ProcessResult;
using snow::test::snowbake;

// Every channel of an image as float bits, channel-interleaved.
struct Image {
  int width = 0, height = 0, channels = 0;
  std::vector<std::string> names;
  std::vector<uint32_t> bits;
  uint32_t at(int x, int y, int c) const { return bits[(static_cast<size_t>(y) * width + x) * channels + c]; }
};
Image readImage(const fs::path& path) {
  Image im;
  auto in = OIIO::ImageInput::open(path.string());
  EXPECT_TRUE(in) << path;
  if (!in) return im;
  const auto& spec = in->spec();
  im.width = spec.width, im.height = spec.height, im.channels = spec.nchannels, im.names = spec.channelnames;
  std::vector<float> v(static_cast<size_t>(im.width) * im.height * im.channels);
  in->read_image(0, 0, 0, im.channels, OIIO::TypeDesc::FLOAT, v.data());
  im.bits.resize(v.size());
  std::memcpy(im.bits.data(), v.data(), v.size() * 4);
  return im;
}

// 96 x 96 cells of 20 m, six days of snow on 1.5 m of unstable snow, one user avalanche on day 5
// with its maps and motion frames, layers.exr, a frame day (so a contact sheet): 0.3 s to bake.
std::string avalancheScene(const std::string& outputs, const std::string& tiles) {
  return "[terrain]\nbuiltin = \"ridged\"\nsize = 96\ncell_size_m = 20.0\n[season]\ndays = 6\n[precompute]\nsun = false\n"
         "[[weather.keyframe]]\nday = 0\nsea_level_temperature_c = -8.0\n[[weather.snowfall]]\nstart_day = 0\nend_day = 4\n"
         "[initial_snow]\nunstable = 1.5\n[[events]]\ntype = \"avalanche\"\nday = 5\nposition_m = [960, 960]\n"
         "[parameters]\navalanche_rate_per_km2_per_day = 0\nskiers_per_hour = 0\n"
         "[outputs]\nlayers = [\"depth\", \"surface\", \"preview\"]\nmultichannel_exr = true\navalanche_maps = true\n"
         "avalanche_frame_interval_s = 60\nframes_days = [2]\n" +
         outputs + tiles + "[run]\nseed = 5\nthreads = 2\n";
}

// The untiled file a tile's manifest entry was cut from: its path less the tile suffix (Unity's
// "_<column>_<row from the south>", else "_x<column>_y<row>").
std::string untiledPath(const nlohmann::json& f) {
  const std::string path = f["path"];
  const auto& t = f["tile"];
  const bool unity = t["convention"] == "unity";
  const std::string suffix = unity ? "_" + std::to_string(t["column"].get<int>()) + "_"
                                   : "_x" + std::to_string(t["column"].get<int>()) + "_y" + std::to_string(t["row"].get<int>());
  const size_t at = path.rfind(suffix, path.find('.'));
  EXPECT_NE(at, std::string::npos) << path;
  if (at == std::string::npos) return path;
  const size_t end = unity ? path.find_first_not_of("0123456789", at + suffix.size()) : at + suffix.size();
  return path.substr(0, at) + path.substr(end);
}

// Each EXR tile listed under `tiled` whose path starts with one of `prefixes` holds, channel for
// channel and bit for bit, the pixels of the untiled file under `whole` at its position (the edge
// pixel repeated past the image); `covered`: the untiled files, with their tile counts.
void expectTilesAreCutFrom(const fs::path& whole, const fs::path& tiled, const std::vector<std::string>& prefixes, int size,
                           std::map<std::string, int>& covered) {
  std::map<std::string, Image> wholeImages;
  const nlohmann::json manifest = manifestOf(tiled);
  for (const auto& f : manifest["files"]) {
    const std::string path = f["path"];
    if (!f.contains("tile") || !path.ends_with(".exr") || std::none_of(prefixes.begin(), prefixes.end(), [&](const std::string& p) { return path.rfind(p, 0) == 0; })) continue;
    const std::string source = untiledPath(f);
    if (!wholeImages.count(source)) wholeImages[source] = readImage(whole / source);
    const Image& w = wholeImages[source];
    const Image t = readImage(tiled / path);
    ASSERT_EQ(t.width, size) << path;
    ASSERT_EQ(t.height, size) << path;
    ASSERT_EQ(t.names, w.names) << path;
    const int x0 = f["tile"]["x"], y0 = f["tile"]["y"];
    for (int y = 0; y < size; ++y)
      for (int x = 0; x < size; ++x)
        for (int c = 0; c < w.channels; ++c)
          ASSERT_EQ(t.at(x, y, c), w.at(std::min(x0 + x, w.width - 1), std::min(y0 + y, w.height - 1), c)) << path << " pixel " << x << ", " << y;
    ++covered[source];
  }
}


}  // namespace

// 96 pixels in grid tiles of 40 sharing 3: 3 x 3 tiles of layers.exr (both channels), of the
// frame's layers.exr, and of each avalanche map and motion frame; every one cut from the untiled
// file, bit for bit.
// Tiles sharing more rows than the season's halo widen it to their overlap and the next cell
// (their normals read it), so every tile and that cell lie in the local grid of the rank the
// tile starts in, and the ranks still write them; tiles sharing one row keep the season's halo.
TEST(TileSets, TilesSharingMoreThanTheSeasonsHaloWidenItSoTheRankATileStartsInHoldsIt) {
  Scene scene;
  scene.outputs.layers = {"depth"};
  scene.outputs.tiles.convention = TileConvention::Grid;
  scene.outputs.tiles.sizePx = 64;
  scene.outputs.tiles.overlapPx = 5;
  GridSpec spec;
  spec.width = 300, spec.height = 240;
  const TileLayout l = tileLayout(scene.outputs.tiles, spec.width, spec.height);
  ASSERT_EQ(l.step, 59);
  for (const int ranks : {2, 3, 4}) {
    const std::optional<dist::Decomposition> d = decompositionOnTiles(scene, spec, ranks, dist::kContinuousHalo);
    ASSERT_TRUE(d) << ranks << " ranks";
    EXPECT_EQ(d->halo, 6);
    int tiles = 0;
    for (int r = 0; r < ranks; ++r)
      for (int ty = 0; ty < l.rows; ++ty)
        for (int tx = 0; tx < l.columns; ++tx) {
          const int x0 = tx * l.step, y0 = ty * l.step;
          if (!d->owned(r).contains(x0, y0)) continue;
          ++tiles;
          const CellRect needs{x0, y0, std::min(spec.width, x0 + l.tileWidth + 1), std::min(spec.height, y0 + l.tileHeight + 1)};
          EXPECT_EQ(d->local(r).intersect(needs), needs) << "tile " << tx << ", " << ty << " on rank " << r << " of " << ranks;
        }
    EXPECT_EQ(tiles, l.columns * l.rows);
  }
  scene.outputs.tiles.overlapPx = 1;
  const std::optional<dist::Decomposition> d = decompositionOnTiles(scene, spec, 4, dist::kContinuousHalo);
  ASSERT_TRUE(d);
  EXPECT_EQ(d->halo, dist::kContinuousHalo);
}

// No rank's local grid is the whole grid where the ranks write their tiles and rank 0 the whole
// files one at a time: the writers tell a rank's window of the cells from an image every rank
// holds whole by its size, which must be alike on every rank (5 x 5 cells on 2 ranks with a halo
// of 2 give one rank all of them: there rank 0 gathers the grid instead, with or without tiles).
TEST(TileSets, NoSplitWhereARanksLocalGridWouldBeTheWholeGrid) {
  Scene scene;
  scene.outputs.layers = {"depth"};
  GridSpec spec;
  spec.width = spec.height = 5;
  EXPECT_FALSE(decompositionOnTiles(scene, spec, 2, dist::kContinuousHalo));
  scene.outputs.tiles.convention = TileConvention::Unity;
  scene.outputs.tiles.sizePx = 3;
  EXPECT_FALSE(decompositionOnTiles(scene, spec, 2, dist::kContinuousHalo));
  for (const TileConvention convention : {TileConvention::None, TileConvention::Unity}) {
    scene.outputs.tiles.convention = convention;
    spec.width = spec.height = 13;
    for (const int ranks : {2, 3, 4}) {
      const std::optional<dist::Decomposition> d = decompositionOnTiles(scene, spec, ranks, dist::kContinuousHalo);
      ASSERT_TRUE(d) << ranks << " ranks";
      for (int r = 0; r < ranks; ++r)
        EXPECT_FALSE(d->local(r).width() == spec.width && d->local(r).height() == spec.height) << "rank " << r << " of " << ranks;
    }
  }
}

// The memory guard predicts a rank that writes its tiles from sceneOfTheRanksTiles: each of its
// resampled images at least as wide and high as the window of pixels its tiles cover with the
// normal map's pixel around them (what OutputWriter::writtenPixels gives it), and, where the image
// is many tiles wide, well under the whole image (before, the whole image on every rank).
TEST(TileSets, ARanksPredictedResampledImagesHoldItsTilesWindowAndAreItsShareOfTheImage) {
  Scene scene;
  scene.outputs.layers = {"depth", "snow_normal"};
  scene.outputs.tiles.convention = TileConvention::Unity;
  scene.outputs.tiles.sizePx = 33;
  GridSpec spec;
  spec.width = 300, spec.height = 233;
  int checked = 0;
  for (const int pixels : {97, 289, 641, 1025})
    for (const int ranks : {2, 3, 4}) {
      scene.outputs.resizeWidth = scene.outputs.resizeHeight = pixels;
      scene.outputs.displacementWidth = pixels, scene.outputs.displacementHeight = 129;
      const std::optional<dist::Decomposition> d = decompositionOnTiles(scene, spec, ranks, dist::kContinuousHalo);
      ASSERT_TRUE(d) << ranks << " ranks";
      for (int r = 0; r < ranks; ++r) {
        const CellRect own = d->owned(r);
        const OutputRequest& o = sceneOfTheRanksTiles(scene, spec, own.width(), own.height()).outputs;
        auto window = [&](int width, int height) {  // the rank's tiles' pixels, a pixel more around (clamped)
          const TileLayout l = tileLayout(scene.outputs.tiles, width, height);
          CellRect px;
          for (int row = 0; row < l.rows; ++row)
            for (int column = 0; column < l.columns; ++column) {
              if (!tileStartsIn(own, spec.width, spec.height, l, column, row, width, height)) continue;
              const CellRect t{column * l.step, row * l.step, std::min(width, column * l.step + l.tileWidth), std::min(height, row * l.step + l.tileHeight)};
              px = px.empty() ? t : CellRect{std::min(px.x0, t.x0), std::min(px.y0, t.y0), std::max(px.x1, t.x1), std::max(px.y1, t.y1)};
            }
          return px.empty() ? px : CellRect{std::max(0, px.x0 - 1), std::max(0, px.y0 - 1), std::min(width, px.x1 + 1), std::min(height, px.y1 + 1)};
        };
        const CellRect resized = window(pixels, pixels), displaced = window(pixels, 129);
        EXPECT_LE(resized.width(), o.resizeWidth) << pixels << " px, rank " << r << " of " << ranks;
        EXPECT_LE(resized.height(), o.resizeHeight) << pixels << " px, rank " << r << " of " << ranks;
        EXPECT_LE(displaced.width(), o.displacementWidth) << pixels << " px, rank " << r << " of " << ranks;
        EXPECT_LE(displaced.height(), o.displacementHeight) << pixels << " px, rank " << r << " of " << ranks;
        EXPECT_LE(o.resizeWidth, pixels);
        EXPECT_LE(o.displacementHeight, 129);
        if (pixels >= 641) {  // 20 tiles or more across: the share of one of 2 or more ranks and a tile
          EXPECT_LT(static_cast<double>(o.resizeWidth) * o.resizeHeight, 0.6 * pixels * pixels) << pixels << " px, rank " << r << " of " << ranks;
        }
        ++checked;
      }
    }
  EXPECT_EQ(checked, 4 * (2 + 3 + 4));
}

TEST(TileSets, ATileCutFromAWindowOfTheImageIsTheTileCutFromTheWholeImage) {
  // What a rank writes from its local grid (bakers across ranks): any window holding the tile's
  // pixels, those past the image's edge repeated from it as the whole image's tiles have them.
  const int width = 61, height = 47, channels = 3;
  std::vector<uint16_t> image(static_cast<size_t>(width) * height * channels);
  for (size_t k = 0; k < image.size(); ++k) image[k] = static_cast<uint16_t>(k * 2654435761u >> 16);
  OutputTiles t;
  t.convention = TileConvention::Grid, t.sizePx = 20, t.overlapPx = 3;
  const TileLayout l = tileLayout(t, width, height);
  ASSERT_EQ(l.columns, 4);
  ASSERT_EQ(l.rows, 3);
  int checked = 0;
  for (int r = 0; r < l.rows; ++r)
    for (int c = 0; c < l.columns; ++c) {
      const std::vector<uint16_t> whole = cutTile(image.data(), width, height, channels, l, c, r);
      // Windows from the tile's own pixels to a margin of 5 around them, within the image.
      for (int margin : {0, 5}) {
        const int x0 = std::max(0, c * l.step - margin), y0 = std::max(0, r * l.step - margin);
        const int x1 = std::min(width, c * l.step + l.tileWidth + margin), y1 = std::min(height, r * l.step + l.tileHeight + margin);
        std::vector<uint16_t> window;
        for (int y = y0; y < y1; ++y)
          window.insert(window.end(), image.begin() + (static_cast<size_t>(y) * width + x0) * channels,
                        image.begin() + (static_cast<size_t>(y) * width + x1) * channels);
        const ImageWindow w{width, height, x0, y0, x1 - x0, y1 - y0};
        EXPECT_EQ(cutTile(window.data(), w, channels, l, c, r), whole) << "tile " << c << ", " << r << ", margin " << margin;
        ++checked;
      }
    }
  EXPECT_EQ(checked, 24);
}

TEST(TileSets, EachTileOfATextureFinerThanTheGridHasOneWriterTheRankOwningTheCellUnderItsFirstTexel) {
  // Across ranks the ski-track texture (f texels a cell each way) is cut into its own tiles: each
  // is written by the rank whose subdomain holds the cell under the tile's first texel, so every
  // tile has exactly one writer whatever the cuts. Here 3 x 2 subdomains of a 50 x 37 grid.
  const int gridWidth = 50, gridHeight = 37;
  const std::vector<int> xs = {0, 17, 33, 50}, ys = {0, 20, 37};
  for (int f : {1, 2, 3, 8}) {
    OutputTiles t;
    t.convention = TileConvention::Unity, t.sizePx = 33;
    const TileLayout l = tileLayout(t, gridWidth * f, gridHeight * f);
    for (int r = 0; r < l.rows; ++r)
      for (int c = 0; c < l.columns; ++c) {
        int writers = 0;
        for (size_t j = 0; j + 1 < ys.size(); ++j)
          for (size_t i = 0; i + 1 < xs.size(); ++i) {
            const CellRect owned{xs[i], ys[j], xs[i + 1], ys[j + 1]};
            if (!tileStartsIn(owned, gridWidth, gridHeight, l, c, r, gridWidth * f, gridHeight * f)) continue;
            ++writers;
            EXPECT_TRUE(owned.contains(c * l.step / f, r * l.step / f)) << "f " << f << ", tile " << c << ", " << r;
          }
        EXPECT_EQ(writers, 1) << "f " << f << ", tile " << c << ", " << r;
      }
  }
  // At the grid's size the writer is the rank whose cells hold the tile's first pixel itself.
  OutputTiles t;
  t.convention = TileConvention::Unity, t.sizePx = 33;
  const TileLayout l = tileLayout(t, gridWidth, gridHeight);
  EXPECT_TRUE(tileStartsIn(CellRect{32, 32, 50, 37}, gridWidth, gridHeight, l, 1, 1, gridWidth, gridHeight));
  EXPECT_FALSE(tileStartsIn(CellRect{33, 0, 50, 37}, gridWidth, gridHeight, l, 1, 1, gridWidth, gridHeight));
}

TEST(TileSets, LayersExrAndAvalancheMapTilesReassembleToTheUntiledFilesBitForBit) {
  const test::Bake whole = test::bakeSceneText("tilesets_whole", avalancheScene("", ""));
  const test::Bake tiled = test::bakeSceneText("tilesets_tiled", avalancheScene("", "[outputs.tiles]\nconvention = \"grid\"\nsize_px = 40\noverlap_px = 3\n"));
  ASSERT_EQ(whole.result.season.avalanches.size(), 1u);
  ASSERT_TRUE(whole.result.season.avalanches[0].released) << whole.result.season.avalanches[0].why;
  std::map<std::string, int> covered;
  expectTilesAreCutFrom(whole.out(), tiled.out(), {"layers", "frames/layers", "avalanches/"}, 40, covered);
  ASSERT_TRUE(covered.count("layers.exr"));
  ASSERT_TRUE(covered.count("frames/layers.0002.exr"));
  ASSERT_TRUE(covered.count("avalanches/001_release.exr"));
  ASSERT_TRUE(covered.count("avalanches/001/depth.0000.exr"));
  size_t avalancheFiles = 0;
  for (const auto& e : fs::recursive_directory_iterator(whole.out() / "avalanches")) avalancheFiles += e.is_regular_file();
  size_t avalancheCovered = 0;
  for (const auto& [path, tiles] : covered) {
    EXPECT_EQ(tiles, 9) << path;
    avalancheCovered += path.rfind("avalanches/", 0) == 0;
  }
  EXPECT_EQ(avalancheCovered, avalancheFiles);  // every map and frame
  EXPECT_FALSE(fs::exists(tiled.out() / "layers.exr"));
  EXPECT_FALSE(fs::exists(tiled.out() / "avalanches" / "001_release.exr"));
  EXPECT_EQ(readImage(tiled.out() / "layers_x0_y0.exr").names, (std::vector<std::string>{"depth.Y", "surface.Y"}));
  // The contact sheet stays whole (a picture of the previews, not a map) and says so.
  EXPECT_TRUE(fs::exists(tiled.out() / "contact_sheet.png"));
  const nlohmann::json tiledManifest = manifestOf(tiled.out());
  for (const auto& f : tiledManifest["files"]) {
    if (f["path"] == "contact_sheet.png") {
      EXPECT_NE(f["content"].get<std::string>().find("not a map"), std::string::npos);
    }
  }
  std::printf("[ measure ] %zu untiled files of layers.exr and avalanche maps, each cut into 9 tiles\n", covered.size());
  fs::remove_all(whole.dir);
  fs::remove_all(tiled.dir);
}

// A tile set with its own size: Unity tiles of 65 from the layers at 129 x 129 (2 x 2 tiles
// exactly), beside the untiled files at the grid's 96 x 96. The untiled files are the untiled
// bake's, bit for bit; the tiles are cut from what outputs.resize = [129, 129] writes.
TEST(TileSets, ATileSetsOwnSizeGivesTilesOfThatSizeWhileUntiledOutputsKeepTheGridSize) {
  const std::string more = "encodings = [\"png16\"]\n";
  const test::Bake whole = test::bakeSceneText("tileset_whole", avalancheScene(more, ""));
  const test::Bake resized = test::bakeSceneText("tileset_resized", avalancheScene(more + "resize = [129, 129]\n", ""));
  const test::Bake set = test::bakeSceneText(
      "tileset_own_size", avalancheScene(more, "[outputs.tiles]\nconvention = \"unity\"\nsize_px = 65\nresize = [129, 129]\n"));
  // The untiled files: the grid's size, the untiled bake's bytes.
  size_t untiled = 0;
  const nlohmann::json wholeManifest = manifestOf(whole.out()), setManifest = manifestOf(set.out());
  for (const auto& f : wholeManifest["files"]) {
    const std::string path = f["path"];
    if (path.find(".exr") == std::string::npos) continue;
    const Image a = readImage(whole.out() / path), b = readImage(set.out() / path);
    EXPECT_EQ(b.width, 96) << path;
    EXPECT_EQ(a.bits, b.bits) << path;
    ++untiled;
  }
  EXPECT_GE(untiled, 10u);
  // The tiles: 65 x 65, 2 x 2 of each raster at 129 x 129 (the EXRs: layers, layers.exr, avalanche
  // maps). Their 16-bit PNGs map the "season" range over both sets, the untiled bake's over one.
  std::map<std::string, int> covered;
  expectTilesAreCutFrom(resized.out(), set.out(), {"depth", "surface", "layers", "frames/", "avalanches/"}, 65, covered);
  for (const auto& [path, tiles] : covered) EXPECT_EQ(tiles, 4) << path;
  for (const char* p : {"depth.exr", "layers.exr", "frames/surface.0002.exr", "avalanches/001_deposit.exr"}) EXPECT_TRUE(covered.count(p)) << p;
  EXPECT_EQ(readImage(resized.out() / "depth.exr").width, 129);
  size_t tiles16 = 0;
  for (const auto& f : setManifest["files"])
    if (f.contains("tile") && f["path"].get<std::string>().find(".16.png") != std::string::npos) {
      EXPECT_EQ(f["width"], 65);
      ++tiles16;
    }
  EXPECT_EQ(tiles16, 2u * 2u * 4u);  // depth and surface, on the frame and the season's end
  std::printf("[ measure ] %zu untiled files at 96 x 96 equal to the untiled bake's; %zu files tiled 2 x 2 at 65 from 129 x 129\n", untiled,
              covered.size());
  for (const auto* b : {&whole, &resized, &set}) fs::remove_all(b->dir);
}

TEST(TileSets, BadTileSetSizesExitTwoNamingFileLineAndKeyAndWriteNothing) {
  const fs::path dir = fs::temp_directory_path() / ("snowbake_tileset_err_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  struct Case {
    std::string tiles, expect;
  };
  for (const Case& c : {Case{"convention = \"grid\"\nsize_px = 32\nresize = [0, 64]\n", "out of range [1, 65536]"},
                        Case{"convention = \"unreal\"\nsize_px = 127\nresize = [253, 300]\n", "allowed: 127, 253, 379, 505, ... n x 126 + 1"},
                        Case{"convention = \"unity\"\nsize_px = 65\nresize = [100, 129]\n", "allowed: 65, 129, 193, 257, ... n x 64 + 1"}}) {
    SCOPED_TRACE(c.tiles);
    std::ofstream(dir / "bad.toml") << "[terrain]\nbuiltin = \"ridged\"\nsize = 64\n[outputs]\nlayers = [\"depth\"]\n[outputs.tiles]\n" << c.tiles;
    const ProcessResult r = snowbake(dir, "bake '" + (dir / "bad.toml").string() + "' --out '" + (dir / "out").string() + "' --quiet");
    EXPECT_EQ(r.status, 2) << r.err;
    EXPECT_NE(r.err.find("bad.toml:9"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("outputs.tiles.resize"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(c.expect), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "out"));
  }
  fs::remove_all(dir);
}
