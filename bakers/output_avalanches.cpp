// OutputWriter's per-avalanche maps (outputs.avalanche_maps, outputs.avalanche_frame_interval_s),
// the layers' size and tiles, so they line up with the layers: avalanches/NNN_<map>,
// avalanches/NNN/depth.FFFF, each a crop of the avalanche's box over a background.
#include <algorithm>
#include <filesystem>
#include <iomanip>
#include <sstream>

#include "core/format.h"
#include "geotiff_writer.h"
#include "grid_writer.h"
#include "output_writer.h"

namespace snow {

namespace fs = std::filesystem;

// An avalanche map on the whole grid: its crop of the avalanche's box where that covers the cell,
// else the background (zero, or the depth at release for the motion frames).
struct OutputWriter::AvalancheMapImage {
  const GridCrop& crop;
  const Grid<float>* background;
  float operator()(int x, int y) const {
    const int cx = x - crop.x0, cy = y - crop.y0;
    if (cx >= 0 && cy >= 0 && cx < crop.grid.width() && cy < crop.grid.height()) return crop.grid(cx, cy);
    return background ? (*background)(x, y) : 0.f;
  }
  // The image's cells of `r`, as a grid of r's size.
  Grid<float> cells(const CellRect& r) const {
    Grid<float> out(r.width(), r.height());
    for (int y = r.y0; y < r.y1; ++y)
      for (int x = r.x0; x < r.x1; ++x) out(x - r.x0, y - r.y0) = (*this)(x, y);
    return out;
  }
};

void OutputWriter::writeAvalancheMaps(const std::vector<AvalancheRecord>& avalanches, const GridSpec& spec) {
  int number = 0;
  for (const AvalancheRecord& a : avalanches) {
    if (!a.released) continue;
    ++number;
    if (!a.maps) continue;
    std::ostringstream stem;
    stem << "avalanches/" << std::setw(3) << std::setfill('0') << number;
    const std::string which = "avalanche " + std::to_string(number) + " (day " + fixed(a.day, 2) + ")";
    auto write = [&](const std::string& rel, const std::string& tag, const AvalancheMapImage& image, const std::string& content,
                     const std::string& unit, double day) { writeAvalancheMap(rel, tag, image, content, unit, day, spec); };
    write(stem.str() + "_release", "", {a.maps->release, nullptr}, which + ": release zone (1 released, 0 not)", "1", a.day);
    write(stem.str() + "_scour", "", {a.maps->scour, nullptr}, which + ": snow taken away, net (m)", "m", a.day);
    write(stem.str() + "_deposit", "", {a.maps->deposit, nullptr}, which + ": snow left, net (m)", "m", a.day);
    write(stem.str() + "_peak_thickness", "", {a.maps->peakThickness, nullptr}, which + ": peak flowing thickness (m)", "m", a.day);
    write(stem.str() + "_peak_speed", "", {a.maps->peakSpeed, nullptr}, which + ": peak speed, the fastest flow (m/s)", "m/s", a.day);
    for (size_t k = 0; k < a.maps->frames.size(); ++k) {
      std::ostringstream rel;
      rel << "." << std::setw(4) << std::setfill('0') << k;
      const auto& [seconds, c] = a.maps->frames[k];
      write(stem.str() + "/depth", rel.str(), {c, &a.maps->depthAtRelease},
            which + ": snow depth C+S+U+P at " + fixed(seconds, 2) + " s after the release (m)", "m", a.day + seconds / 86400.0);
    }
  }
}

// In each raster set at its size (bilinear), whole or cut into its tiles (the suffix before a
// motion frame's tag, as on the layers). An unresized tile is cut from the image directly, and a
// resized set's tiles are resampled from the cells their pixels read, so a rank writing its tiles
// never makes the whole grid's image.
void OutputWriter::writeAvalancheMap(const std::string& rel, const std::string& tag, const AvalancheMapImage& image, const std::string& content,
                                     const std::string& unit, double day, const GridSpec& spec) {
  Grid<float> full;  // the whole grid's image, made where an untiled file of the grid's size needs it
  fs::create_directories((fs::path(src_.outDir) / rel).parent_path());
  for (const RasterSet& set : sets_) {
    const int width = set.resized() ? set.resizeWidth : spec.width, height = set.resized() ? set.resizeHeight : spec.height;
    // A resized set: the pixels of the tiles this writer writes (the whole image in one process),
    // from the cells they read.
    Grid<float> sized;
    ImageWindow sizedWindow;
    if (set.resized()) {
      const CellRect to = writtenPixels(set.tiles, width, height, 0), from = cellsReadBy(to, width, height, spec.width, spec.height);
      sized = resampleBilinear(image.cells(from), ResampleWindow{from, spec.width, spec.height, to, width, height});
      sizedWindow = ImageWindow{width, height, to.x0, to.y0, to.width(), to.height()};
    }
    const TileLayout l = tileLayout(set.tiles, width, height);
    const std::string what = !set.resized() ? content
                                            : content + ", resampled (bilinear) to " + std::to_string(width) + " x " + std::to_string(height) +
                                                  " over the same extent";
    for (int r = 0; r < l.rows; ++r)
      for (int col = 0; col < l.columns; ++col) {
        if (!writesTile(l, col, r, ImageWindow::whole(width, height))) continue;  // across ranks, another rank's tile
        const std::string base = (fs::path(src_.outDir) / (rel + tileSuffix(l, col, r) + tag)).string();
        Grid<float> cut;
        if (l.tiled() && set.resized()) cut = cutTile(sized, sizedWindow, l, col, r);
        if (l.tiled() && !set.resized()) {
          // The image's pixels under the tile, cut as from the whole image (edge pixels repeated).
          const ImageWindow w{width, height, col * l.step, r * l.step, std::min(l.tileWidth, width - col * l.step),
                              std::min(l.tileHeight, height - r * l.step)};
          cut = cutTile(image.cells({w.x0, w.y0, w.x0 + w.windowWidth, w.y0 + w.windowHeight}), w, l, col, r);
        }
        if (!l.tiled() && !set.resized() && full.size() == 0) full = image.cells(CellRect::whole(spec));
        const Grid<float>& tile = l.tiled() ? cut : set.resized() ? sized : full;
        writeAvalancheMapFile(base, tile, what, unit, day, l, col, r, width, height, l.tiled() || set.resized());
      }
  }
}

// One file of an avalanche map: GeoTIFF or EXR as the layers, listed with its range (and its
// tile's fields where `tile`: tiled or resized).
void OutputWriter::writeAvalancheMapFile(const std::string& base, const Grid<float>& image, const std::string& what, const std::string& unit,
                                         double day, const TileLayout& l, int col, int row, int width, int height, bool tile) {
  if (scene_.outputs.format == ImageFormat::Tiff) {
    const GeoFrame geo = tile ? src_.geo.pixels(width, height, col * l.step, row * l.step) : src_.geo;
    writeGeoTiff(base + ".tif", image, geo, "value");
    const auto [lo, hi] = std::minmax_element(image.values().begin(), image.values().end());
    listFile(base + ".tif", what, unit, floatImageFormat_, day, *lo, *hi);
  } else {
    const WrittenImage img = writeFloatImage(base, "exr", image, "value", scene_.outputs.compressionLevel);
    listFile(img.path, what, unit, floatImageFormat_, day, img.minValue, img.maxValue);
  }
  if (tile) noteTile(l, col, row, width, height);
}

void OutputWriter::planAvalancheMaps() {
  if (!scene_.outputs.avalancheMaps) return;
  const std::string ext = scene_.outputs.format == ImageFormat::Tiff ? ".tif" : ".exr";
  const std::string every = "one per released avalanche NNN: how many the season decides";
  // The maps are the grid's size (or the set's), tiled as the layers are.
  for (const RasterSet& set : sets_) {
    const TileLayout l = set.resized() ? tileLayout(set.tiles, set.resizeWidth, set.resizeHeight)
                                       : tileLayout(set.tiles, src_.geo.gridWidth, src_.geo.gridHeight);
    for (int r = 0; r < l.rows; ++r)
      for (int c = 0; c < l.columns; ++c) {
        const std::string tile = tileSuffix(l, c, r);
        for (const char* map : {"release", "scour", "deposit", "peak_thickness", "peak_speed"})
          planFile((fs::path(src_.outDir) / ("avalanches/NNN_" + std::string(map) + tile + ext)).string(), floatImageFormat_, map, 0.0, false,
                   every);
        if (scene_.outputs.avalancheFrameIntervalS > 0)
          planFile((fs::path(src_.outDir) / ("avalanches/NNN/depth" + tile + ".FFFF" + ext)).string(), floatImageFormat_, "motion frames", 0.0,
                   false, every + ", one frame per outputs.avalanche_frame_interval_s of its run");
      }
  }
}

}  // namespace snow
