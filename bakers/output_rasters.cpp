// OutputWriter's raster files: each raster output whole or cut into tiles (its RasterSet), its
// 16- and 8-bit encodings mapped by [outputs.ranges] ("season" ranges written after the last
// day), and every file's mapping and tile listed in the manifest.
#include <filesystem>
#include <stdexcept>

#include "geotiff_writer.h"
#include "grid_writer.h"
#include "output_writer.h"

namespace snow {

namespace fs = std::filesystem;

OutputWriter::BaseOf OutputWriter::baseOf(const Day& d) const {
  return [outDir = src_.outDir, frame = d.frame, tag = d.dayTag](const std::string& stem) {
    return (fs::path(outDir) / (frame ? "frames" : "") / (stem + tag)).string();
  };
}

ImageWindow OutputWriter::windowOf(int width, int height) const {
  const CellRect& c = src_.stateCells;
  if (c.empty() || width != c.width() || height != c.height()) return ImageWindow::whole(width, height);
  return ImageWindow{src_.geo.gridWidth, src_.geo.gridHeight, c.x0, c.y0, width, height};
}

CellRect OutputWriter::writtenPixels(const OutputTiles& tiles, int width, int height, int marginPx) const {
  if (src_.tilesStartingIn.empty()) return CellRect{0, 0, width, height};
  // The pixels of the tiles this rank writes (one writer a tile: tileStartsIn), and the margin.
  const TileLayout l = tileLayout(tiles, width, height);
  CellRect pixels;
  for (int row = 0; row < l.rows; ++row)
    for (int column = 0; column < l.columns; ++column) {
      if (!tileStartsIn(src_.tilesStartingIn, src_.geo.gridWidth, src_.geo.gridHeight, l, column, row, width, height)) continue;
      const CellRect tile{column * l.step, row * l.step, std::min(width, column * l.step + l.tileWidth), std::min(height, row * l.step + l.tileHeight)};
      pixels = pixels.empty() ? tile : CellRect{std::min(pixels.x0, tile.x0), std::min(pixels.y0, tile.y0), std::max(pixels.x1, tile.x1), std::max(pixels.y1, tile.y1)};
    }
  if (pixels.empty()) return pixels;
  return CellRect{std::max(0, pixels.x0 - marginPx), std::max(0, pixels.y0 - marginPx), std::min(width, pixels.x1 + marginPx),
                  std::min(height, pixels.y1 + marginPx)};
}

OutputWriter::Resampled OutputWriter::resampled(const OutputTiles& tiles, int width, int height, const Grid<float>& grid,
                                                const Grid<uint8_t>* valid, int marginPx) const {
  ResampledLayers r = resampled(tiles, width, height, {&grid}, valid, marginPx);
  return Resampled{std::move(r.pixels[0]), std::move(r.valid), r.window};
}

OutputWriter::ResampledLayers OutputWriter::resampled(const OutputTiles& tiles, int width, int height, const std::vector<const Grid<float>*>& grids,
                                                      const Grid<uint8_t>* valid, int marginPx) const {
  ResampledLayers r;
  if (grids.empty()) return r;
  const ImageWindow cells = windowOf(grids[0]->width(), grids[0]->height());
  if (!src_.gatherCells) {
    r.window = ImageWindow::whole(width, height);
    for (const Grid<float>* g : grids) r.pixels.push_back(valid ? resampleValid(*g, *valid, width, height, r.valid) : resampleBilinear(*g, width, height));
    return r;
  }
  const CellRect pixels = writtenPixels(tiles, width, height, marginPx);
  const CellRect from = cellsReadBy(pixels, width, height, cells.width, cells.height);
  const ResampleWindow w{from, cells.width, cells.height, pixels, width, height};
  Grid<uint8_t> heldValid(valid ? from.width() : 0, valid ? from.height() : 0);
  if (valid) src_.gatherCells(valid->data(), sizeof(uint8_t), from, heldValid.data());
  for (const Grid<float>* g : grids) {
    Grid<float> held(from.width(), from.height());
    src_.gatherCells(g->data(), sizeof(float), from, held.data());
    r.pixels.push_back(valid ? resampleValid(held, heldValid, w, r.valid) : resampleBilinear(held, w));
  }
  r.window = ImageWindow{width, height, pixels.x0, pixels.y0, pixels.width(), pixels.height()};
  return r;
}

bool OutputWriter::writesTile(const TileLayout& l, int column, int row, const ImageWindow& w) const {
  if (src_.tilesStartingIn.empty()) return true;
  if (tileStartsIn(src_.tilesStartingIn, src_.geo.gridWidth, src_.geo.gridHeight, l, column, row, w.width, w.height)) {
    if (!l.tiled() && (w.windowWidth != w.width || w.windowHeight != w.height))
      throw std::logic_error("a whole file whose writer holds part of it (OutputWriter::untiledWindow)");
    return true;
  }
  ++listings_;  // another rank's file
  return false;
}

std::optional<ImageWindow> OutputWriter::untiledWindow(const TileLayout& l, const ImageWindow& w) const {
  const CellRect& c = src_.stateCells;
  // Every rank decides alike (no rank's local grid is the whole grid: decompositionOnTiles).
  if (src_.plan || !src_.gatherCells || l.tiled() || c.empty()) return std::nullopt;
  if (w.width != src_.geo.gridWidth || w.height != src_.geo.gridHeight || w.x0 != c.x0 || w.y0 != c.y0 || w.windowWidth != c.width() ||
      w.windowHeight != c.height())
    return std::nullopt;  // a resampled image's window, or an image every rank holds whole
  if (tileStartsIn(src_.tilesStartingIn, w.width, w.height, l, 0, 0, w.width, w.height)) return ImageWindow::whole(w.width, w.height);
  return ImageWindow{w.width, w.height, 0, 0, 0, 0};
}

SeenRange OutputWriter::seenOnOwnCells(const Grid<float>& grid, const Grid<uint8_t>* valid, const ImageWindow* held) const {
  SeenRange seen;
  const ImageWindow w = held ? *held : windowOf(grid.width(), grid.height());
  if (held || src_.tilesStartingIn.empty() || (w.windowWidth == w.width && w.windowHeight == w.height)) {
    seen.widen(grid, valid);
    return seen;
  }
  // A rank's window: the cells it owns alone (at its local grid's edge a layer reading the next
  // cells, as the slope's weights do, reads them clamped).
  const CellRect& own = src_.tilesStartingIn;
  const CellRect mine{own.x0 - w.x0, own.y0 - w.y0, own.x1 - w.x0, own.y1 - w.y0};
  const bool masked = valid && valid->width() == grid.width() && valid->height() == grid.height();
  const Grid<uint8_t> ownValid = masked ? gridWindow(*valid, mine) : Grid<uint8_t>();
  seen.widen(gridWindow(grid, mine), masked ? &ownValid : nullptr);
  return seen;
}

void OutputWriter::noteTile(const TileLayout& l, int column, int row, int imageWidth, int imageHeight) const {
  ManifestFile& f = currentSink().files.back();
  if (imageWidth != src_.geo.gridWidth || imageHeight != src_.geo.gridHeight || l.tiled()) f.width = l.tileWidth, f.height = l.tileHeight;
  if (!l.tiled()) return;
  const GeoFrame g = src_.geo.pixels(imageWidth, imageHeight, column * l.step, row * l.step);
  f.tileConvention = enumName(l.convention);
  f.tileColumn = column, f.tileRow = row, f.tileX = column * l.step, f.tileY = row * l.step;
  f.tileOriginX = g.originX, f.tileOriginY = g.originY, f.pixelSizeX = g.cellX, f.pixelSizeY = g.cellY;
}

void OutputWriter::writeFloatRaster(const RasterSet& set, const BaseOf& base, double day, const std::string& stem, const Grid<float>& grid,
                                    const Grid<uint8_t>* valid, const std::string& layerName, const std::string& content,
                                    const std::string& unit, const ImageWindow* held) {
  const auto& out = scene_.outputs;
  ImageWindow w = held ? *held : windowOf(grid.width(), grid.height());
  const TileLayout l = tileLayout(set.tiles, w.width, w.height);
  const bool masked = valid && valid->width() == grid.width() && valid->height() == grid.height();
  Grid<float> whole;  // across ranks, an untiled file's pixels on the rank that writes it
  Grid<uint8_t> wholeValid;
  const std::optional<ImageWindow> to = untiledWindow(l, w);
  if (to) {
    whole.adopt(to->windowWidth, to->windowHeight, gatheredTo(*to, grid.data()));
    if (masked) wholeValid.adopt(to->windowWidth, to->windowHeight, gatheredTo(*to, valid->data()));
    w = *to;
  }
  const Grid<float>& image = to ? whole : grid;
  const Grid<uint8_t>* imageValid = !masked ? nullptr : to ? &wholeValid : valid;
  Grid<float> cut;
  Grid<uint8_t> cutValid;
  for (int r = 0; r < l.rows; ++r)
    for (int c = 0; c < l.columns; ++c) {
      const std::string tileBase = base(stem + tileSuffix(l, c, r));
      if (src_.plan) {
        planFile(tileBase + (out.format == ImageFormat::Tiff ? ".tif" : ".exr"), floatImageFormat_, content, 4.0 * l.tileWidth * l.tileHeight);
        continue;
      }
      if (!writesTile(l, c, r, w)) continue;
      // Untiled, the image itself (no copy).
      if (l.tiled()) cut = cutTile(image, w, l, c, r), cutValid = masked ? cutTile(*imageValid, w, l, c, r) : Grid<uint8_t>();
      const Grid<float>& tile = l.tiled() ? cut : image;
      const Grid<uint8_t>* tileValid = !masked ? nullptr : l.tiled() ? &cutValid : imageValid;
      // TIFF through GDAL with the terrain's CRS and this tile's geotransform; EXR through OpenImageIO.
      const std::string path = out.format == ImageFormat::Tiff ? tileBase + ".tif" : writeFloatImage(tileBase, "exr", tile, layerName, out.compressionLevel).path;
      if (out.format == ImageFormat::Tiff)
        writeGeoTiff(path, tile, src_.geo.pixels(w.width, w.height, c * l.step, r * l.step), layerName);
      SeenRange seen;  // NODATA left out
      seen.widen(tile, tileValid);
      listFile(path, content, unit, floatImageFormat_, day, static_cast<float>(seen.mapping(RangeMode::Own).lo),
               static_cast<float>(seen.mapping(RangeMode::Own).hi));
      noteTile(l, c, r, w.width, w.height);
    }
}

void OutputWriter::writeEncodedRaster(const RasterSet& set, const BaseOf& base, double day, const std::string& stem, const std::string& encoding,
                                      const Grid<float>& grid, const Grid<uint8_t>* valid, const ValueMapping& m,
                                      const std::string& content, const std::string& unit, bool write, const ImageWindow* held) {
  const auto& out = scene_.outputs;
  ImageWindow w = held ? *held : windowOf(grid.width(), grid.height());
  const TileLayout l = tileLayout(set.tiles, w.width, w.height);
  const bool masked = valid && valid->width() == grid.width() && valid->height() == grid.height();
  // Quantised once for every tile: a pixel depends on its cell alone, so cutting the pixels
  // gives each tile's bytes (and gathering them, an untiled file's across ranks).
  std::vector<uint16_t> pixels = write && !src_.plan ? quantisedPixels(encoding, grid, masked ? valid : nullptr, m.lo, m.hi, kNodataPixel)
                                                     : std::vector<uint16_t>();
  if (const std::optional<ImageWindow> to = untiledWindow(l, w)) {
    if (write) pixels = gatheredTo(*to, pixels.data());
    w = *to;
  }
  for (int r = 0; r < l.rows; ++r)
    for (int c = 0; c < l.columns; ++c) {
      const std::string path = base(stem + tileSuffix(l, c, r)) + encodingExtension(encoding);
      if (src_.plan) {  // r16: the samples alone; png16 and png8 compressed
        planFile(path, normalisedFormat(encoding, l.tileWidth, l.tileHeight), content,
                 (encoding == "png8" ? 1.0 : 2.0) * l.tileWidth * l.tileHeight, encoding == "r16");
        continue;
      }
      if (!writesTile(l, c, r, w)) continue;
      if (write && l.tiled())
        writeQuantisedPixels(path, encoding, l.tileWidth, l.tileHeight, cutTile(pixels.data(), w, 1, l, c, r).data(), out.compressionLevel);
      else if (write)
        writeQuantisedPixels(path, encoding, w.width, w.height, pixels.data(), out.compressionLevel);
      listFile(path, content, unit, normalisedFormat(encoding, l.tileWidth, l.tileHeight), day, static_cast<float>(m.lo), static_cast<float>(m.hi),
               write);
      ManifestFile& f = currentSink().files.back();
      f.rangeMode = rangeModeName(m.mode), f.rangeLo = m.lo, f.rangeHi = m.hi, f.nodataPixel = kNodataPixel;
      noteTile(l, c, r, w.width, w.height);
    }
}

void OutputWriter::writeRgbRaster(const RasterSet& set, const BaseOf& base, double day, const std::string& stem, int width, int height,
                                  const std::vector<uint8_t>& pixels, const std::string& content, const std::string& unit, int channels,
                                  const std::string& format, const ImageWindow* held) {
  ImageWindow w = held ? *held : windowOf(width, height);
  const TileLayout l = tileLayout(set.tiles, w.width, w.height);
  std::vector<uint8_t> whole;  // across ranks, an untiled file's pixels on the rank that writes it
  const std::optional<ImageWindow> to = untiledWindow(l, w);
  if (to) whole = gatheredTo(*to, pixels.data(), channels), w = *to;
  const std::vector<uint8_t>& image = to ? whole : pixels;
  for (int r = 0; r < l.rows; ++r)
    for (int c = 0; c < l.columns; ++c) {
      const std::string path = base(stem + tileSuffix(l, c, r)) + ".png";
      if (src_.plan) {
        planFile(path, format.empty() ? kRgbPngFormat : format, content, static_cast<double>(channels) * l.tileWidth * l.tileHeight);
        continue;
      }
      if (!writesTile(l, c, r, w)) continue;
      writePng8(path, l.tileWidth, l.tileHeight, channels, l.tiled() ? cutTile(image.data(), w, channels, l, c, r) : image,
                scene_.outputs.compressionLevel);
      listFile(path, content, unit, format.empty() ? kRgbPngFormat : format, day, 0.f, 255.f);
      noteTile(l, c, r, w.width, w.height);
    }
}

void OutputWriter::writeRawFloatRaster(const RasterSet& set, const BaseOf& base, double day, const std::string& stem, const Grid<float>& grid,
                                       const std::string& content, const std::string& unit, const ImageWindow* held) {
  ImageWindow w = held ? *held : windowOf(grid.width(), grid.height());
  const TileLayout l = tileLayout(set.tiles, w.width, w.height);
  Grid<float> whole;  // across ranks, an untiled file's pixels on the rank that writes it
  const std::optional<ImageWindow> to = untiledWindow(l, w);
  if (to) whole.adopt(to->windowWidth, to->windowHeight, gatheredTo(*to, grid.data())), w = *to;
  const Grid<float>& image = to ? whole : grid;
  for (int r = 0; r < l.rows; ++r)
    for (int c = 0; c < l.columns; ++c) {
      const std::string path = base(stem + tileSuffix(l, c, r)) + ".r32";
      const std::string format = "raw float32 little-endian, " + std::to_string(l.tileWidth) + " x " + std::to_string(l.tileHeight) +
                                 ", row 0 north, no header, in the layer's unit (NODATA 0)";
      if (src_.plan) {
        planFile(path, format, content, 4.0 * l.tileWidth * l.tileHeight, true);
        continue;
      }
      if (!writesTile(l, c, r, w)) continue;
      const Grid<float> cut = l.tiled() ? cutTile(image, w, l, c, r) : Grid<float>();
      const Grid<float>& tile = l.tiled() ? cut : image;
      writeRawFloat32(path, tile);
      SeenRange seen;
      seen.widen(tile, nullptr);
      listFile(path, content, unit, format, day, static_cast<float>(seen.mapping(RangeMode::Own).lo), static_cast<float>(seen.mapping(RangeMode::Own).hi));
      noteTile(l, c, r, w.width, w.height);
    }
}

void OutputWriter::writeEncodings(const Day& d, const RasterSet& set, const LayerInfo& layer, const Grid<float>& grid, const Grid<uint8_t>* valid,
                                  const std::string& content, const ImageWindow* held) {
  const auto& out = scene_.outputs;
  if (out.encodings.empty()) return;
  const LayerRange range = rangeOf(out, layer);
  ValueMapping m{range.mode, range.lo, range.hi};
  if (range.mode != RangeMode::Fixed && !src_.plan) {
    SeenRange seen = seenOnOwnCells(grid, valid, held);
    if (src_.wholeRange) seen = src_.wholeRange(seen);  // across ranks: every rank's cells
    m = seen.mapping(range.mode);
    if (range.mode == RangeMode::Season) {
      const std::lock_guard lock(seasonMutex_);
      seasonRanges_[layer.name].widen(seen);
    }
  }
  const bool now = range.mode != RangeMode::Season || src_.plan;  // plan: listed once, on the day
  SpillFile::Extent values, mask;  // the layer and its mask on disk, once for all its encodings
  for (const std::string& encoding : out.encodings) {
    if (encoding == "r32") {  // floats as they are: no range
      writeRawFloatRaster(set, baseOf(d), d.day, layer.name, grid, content, layer.unit, held);
      continue;
    }
    writeEncodedRaster(set, baseOf(d), d.day, layer.name, encoding, grid, valid, m, content, layer.unit, now, held);
    if (now) continue;
    const std::lock_guard lock(seasonMutex_);
    const bool masked = valid->width() == grid.width() && valid->height() == grid.height();
    if (!spill_) spill_ = std::make_unique<SpillFile>(src_.outDir);
    if (values.bytes == 0) {
      values = spill_->put(grid.values());
      if (masked) mask = spill_->put(valid->values());
    }
    seasonEncodings_.push_back({d.frame, d.dayTag, layer.name, encoding, content, layer.unit, d.day, grid.width(), grid.height(), values, mask, set,
                                held ? std::optional<ImageWindow>(*held) : std::nullopt});
  }
}

void OutputWriter::writeSeasonEncodings() {
  if (seasonEncodings_.empty()) return;
  OutputSink written;
  {
    SinkScope scope(written);
    for (const SeasonEncoding& e : seasonEncodings_) {
      const BaseOf base = [outDir = src_.outDir, &e](const std::string& stem) {
        return (fs::path(outDir) / (e.frame ? "frames" : "") / (stem + e.dayTag)).string();
      };
      const ValueMapping m = seasonRanges_[e.layer].mapping(RangeMode::Season);
      Grid<float> grid;
      grid.adopt(e.width, e.height, spill_->get<float>(e.grid));
      Grid<uint8_t> valid;
      if (e.valid.bytes > 0) valid.adopt(e.width, e.height, spill_->get<uint8_t>(e.valid));
      writeEncodedRaster(e.set, base, e.day, e.layer, e.encoding, grid, e.valid.bytes > 0 ? &valid : nullptr, m, e.content, e.unit, true,
                         e.held ? &*e.held : nullptr);
    }
  }
  // The entries listed on the day, in the manifest's order, take the season's mapping.
  std::map<std::string, const ManifestFile*> byPath;
  for (const ManifestFile& f : written.files) byPath[f.path] = &f;
  OutputSink& sink = currentSink();
  for (ManifestFile& f : sink.files)
    if (const auto it = byPath.find(f.path); it != byPath.end()) {
      const long long listing = f.listing;  // the day's place in the manifest
      f = *it->second;
      f.listing = listing;
    }
  for (const auto& [kind, seconds] : written.seconds) sink.addSeconds(kind, seconds);
  seasonEncodings_.clear();
  spill_.reset();
}

}  // namespace snow
