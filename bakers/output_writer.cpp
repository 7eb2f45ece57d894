// OutputWriter: a day's layers, previews, displacement maps, multi-channel EXR and VDB, and the
// contact sheet. The meshes are in output_meshes.cpp, each avalanche's maps in output_avalanches.cpp.
#include "output_writer.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "core/format.h"
#include "core/release_memory.h"
#include "core/stop_request.h"
#include "grid_writer.h"
#include "precompute/solar.h"
#include "vdb_writer.h"

namespace snow {

namespace fs = std::filesystem;

namespace {
thread_local OutputSink* tlSink = nullptr;
}  // namespace

OutputSink& currentSink() { return *tlSink; }
SinkScope::SinkScope(OutputSink& sink) : previous_(tlSink) {
  tlSink = &sink;
  sink.last = std::chrono::steady_clock::now();
}
SinkScope::~SinkScope() { tlSink = previous_; }

std::string OutputWriter::Day::base(const std::string& stem, const std::string& outDir) const {
  return (fs::path(outDir) / (frame ? "frames" : "") / (stem + dayTag)).string();
}

OutputWriter::OutputWriter(OutputSources sources, std::ostream& log) : src_(std::move(sources)), scene_(*src_.scene), log_(log) {
  exrCompression_ = exrCompressionName(scene_.outputs.compressionLevel);
  sets_ = rasterSets(scene_.outputs);
  floatImageFormat_ = scene_.outputs.format == ImageFormat::Exr ? "OpenEXR, 1 channel float32 (" + exrCompression_ + "), linear"
                                                                : "GeoTIFF (GDAL), 1 band float32 (deflate, floating-point predictor), linear, the terrain's coordinate system and the file's geotransform";
}

void OutputWriter::listFile(const std::string& path, const std::string& content, const std::string& unit, const std::string& format,
                            double day, float minValue, float maxValue, bool written) const {
  // A writer without its plan branch has just written a file during `snowbake plan`.
  if (src_.plan) throw std::logic_error(path + ": written in plan mode (a writer lacks its plan branch: OutputSources::plan)");
  if (written && src_.fileWritten) src_.fileWritten(path, day);
  OutputSink& sink = currentSink();
  sink.addSeconds(format.substr(0, format.find(',')));
  ManifestFile f;
  f.path = fs::relative(path, src_.outDir).string();
  f.content = content;
  f.unit = unit;
  f.format = format;
  f.day = day;
  f.minValue = minValue;
  f.maxValue = maxValue;
  f.listing = listings_++;
  sink.files.push_back(f);
  sink.paths.push_back(path);
}

void OutputWriter::planFile(const std::string& path, const std::string& format, const std::string& content, double dataBytes,
                            bool exactBytes, const std::string& condition) const {
  currentSink().planned.push_back({path, format, content, dataBytes, exactBytes, condition, {}});
}

void OutputWriter::writeDay(const SnowState& s, double day, const Grid<float>* skiDepth) {
  OutputSink& parent = currentSink();
  Day d{s, day, day >= 0.0 ? day : scene_.days, day >= 0.0, "", skiDepth};
  if (d.frame) {
    if (!src_.plan) fs::create_directories(fs::path(src_.outDir) / "frames");
    std::ostringstream o;
    o << "." << std::setw(4) << std::setfill('0') << static_cast<long>(std::lround(day));
    d.dayTag = o.str();
  }
  // The layers, the VDB and the meshes one after the other, so that only one of their working
  // sets is held at a time (side by side they were the bake's peak: the VDB's tree and the
  // mesh's buffers beside every layer), each handed back to the system when it ends (else each
  // stood on the last one's); each lists into its own sink, merged in a fixed order.
  OutputSink layerSink, vdbSink, meshSink;
  {
    SinkScope scope(layerSink);
    writeLayers(d);
  }
  releaseFreedMemory();
  {
    SinkScope scope(vdbSink);
    writeVdb(d);
  }
  releaseFreedMemory();
  {
    SinkScope scope(meshSink);
    writeMeshes(d);
  }
  releaseFreedMemory();
  parent.merge(layerSink);
  parent.merge(vdbSink);
  parent.merge(meshSink);
}

void OutputWriter::writeLayers(const Day& d) {
  // The day's wind and sun, fetched once when a layer needs them.
  uint8_t needs = layersNeeds(src_.layers);
  WindFieldsAtDay wind;
  Grid<float> sunHours;
  if (src_.plan) needs = 0;  // nothing computed
  LayerInputs in;
  in.state = &d.s;
  in.params = &scene_.params;
  in.outputs = &scene_.outputs;
  if (needs & kNeedsWind) {
    wind = src_.wind->at(d.outputDay);
    in.windXMps = &wind.windXMps, in.windYMps = &wind.windYMps, in.windEffectZM = &wind.windEffectZM;
  }
  if (needs & kNeedsSun) {
    sunHours = src_.exposure ? src_.exposure->totalAt(d.outputDay) : Grid<float>(d.s.spec.width, d.s.spec.height, 0.f);
    in.sunHours = &sunHours;
    in.seaLevelTemperatureC = scene_.weather.at(d.outputDay).seaLevelTemperatureC;
  }
  in.skiDepth = d.skiDepth;
  in.routeMap = src_.routeMap;
  in.occlusion = src_.occlusion;
  // Each raster set's channels of layers.exr (one set, or the whole files and the tiles at their size).
  std::vector<std::vector<std::string>> channelNames(sets_.size());
  std::vector<std::vector<Grid<float>>> channels(sets_.size());
  std::vector<std::optional<ImageWindow>> channelsWindow(sets_.size());  // a resized set's window of its image
  for (const auto& name : src_.layers) {
    throwIfStopRequested();  // Ctrl-C between two layers' files, never within one
    if (d.frame && name == "valid_mask") continue;
    const LayerInfo& layer = *findLayer(name);
    if (layer.kind == LayerKind::Preview) {
      writePreview(d, layer);
      continue;
    }
    // Plan: a grid of the layer's size, its values never read.
    Grid<float> grid = src_.plan ? planGrid(d, layer) : layer.compute(in);
    // Across ranks every rank holds the whole ski-track texture: at one texel a cell it is a layer
    // of the grid's cells like the others, cut to the rank's window (resized with them and a
    // channel of layers.exr, as in one process; no rank's window is the whole grid).
    if (!src_.plan && (layer.needs & kNeedsSkiTracks) && !src_.stateCells.empty() && grid.width() == src_.geo.gridWidth &&
        grid.height() == src_.geo.gridHeight)
      grid = gridWindow(grid, src_.stateCells);
    for (size_t k = 0; k < sets_.size(); ++k)  // the last set takes the grid itself
      writeFloatLayer(d, sets_[k], layer, k + 1 == sets_.size() ? std::move(grid) : Grid<float>(grid), channelNames[k], channels[k],
                      channelsWindow[k]);
  }
  writeDisplacement(d);
  for (size_t k = 0; k < sets_.size(); ++k)
    writeMultiChannel(d, sets_[k], channelNames[k], channels[k], channelsWindow[k] ? &*channelsWindow[k] : nullptr);
}

Grid<float> OutputWriter::planGrid(const Day& d, const LayerInfo& layer) const {
  // The ski-track texture is the one layer finer than the grid (LayerInputs::skiDepth).
  const int f = (layer.needs & kNeedsSkiTracks) ? src_.skiTrackFactor : 1;
  return Grid<float>(d.s.spec.width * f, d.s.spec.height * f);
}

void OutputWriter::writeFloatLayer(const Day& d, const RasterSet& set, const LayerInfo& layer, Grid<float> grid,
                                   std::vector<std::string>& channelNames, std::vector<Grid<float>>& channels,
                                   std::optional<ImageWindow>& channelsWindow) {
  std::string content = layer.content;
  const bool ownSize = grid.width() != d.s.spec.width || grid.height() != d.s.spec.height;
  // The ski-track texture is finer than the grid: its texels per cell, listed with each file.
  if (layer.needs & kNeedsSkiTracks)
    content += " (" + std::to_string(src_.skiTrackFactor) + " x " + std::to_string(src_.skiTrackFactor) + " texels per cell)";
  // The set's size (outputs.resize or the tiles' own): the grid's layers at the requested size, over
  // valid cells (finer textures keep theirs).
  Grid<uint8_t> resizedValid;
  const Grid<uint8_t>* valid = &d.s.validCell;
  std::optional<ImageWindow> held;  // across ranks, the rank's window of the resampled image
  if (set.resized() && !ownSize) {
    if (src_.plan) {
      grid = Grid<float>(set.resizeWidth, set.resizeHeight);
    } else {
      Resampled r = resampled(set.tiles, set.resizeWidth, set.resizeHeight, grid, &d.s.validCell);
      grid = std::move(r.pixels), resizedValid = std::move(r.valid), held = r.window;
    }
    valid = &resizedValid;
    content += ", resampled (bilinear over valid cells) to " + std::to_string(set.resizeWidth) + " x " + std::to_string(set.resizeHeight) +
               " over the same extent";
  }
  const ImageWindow* window = held ? &*held : nullptr;
  writeFloatRaster(set, baseOf(d), d.day, layer.name, grid, valid, layer.name, content, layer.unit, window);
  writeEncodings(d, set, layer, grid, valid, content, window);
  if (scene_.outputs.multichannelExr && !ownSize) {
    channelNames.push_back(layer.name);
    channels.push_back(std::move(grid));
    channelsWindow = held;
  }
}

void OutputWriter::writePreview(const Day& d, const LayerInfo& layer) {
  const SnowState& s = d.s;
  // The engine maps at each set's size; the previews at the grid's, cut as each set's tiles.
  const std::string name = layer.name;
  if (name == "splat_map" || name == "snow_normal") {
    for (const RasterSet& set : sets_) name == "splat_map" ? writeSplatMap(d, set, layer) : writeNormalMap(d, set, layer);
    return;
  }
  auto write = [&](const std::vector<uint8_t>& rgb) {
    for (const RasterSet& set : sets_)
      writeRgbRaster(set, baseOf(d), d.day, layer.name, s.spec.width, s.spec.height, rgb, layer.content, layer.unit);
  };
  if (src_.plan) {  // an sRGB preview of the grid's size; the snow preview also goes on the contact sheet
    write({});
    if (std::string(layer.name) != "avalanche_preview") previews_.emplace_back();
    return;
  }
  if (std::string(layer.name) == "avalanche_preview") {
    const Grid<float> surface = findLayer("surface")->compute(LayerInputs{&s});
    write(avalanchePreviewRgb(surface, s.validCell, s.avalancheScourM, s.avalancheDepositM, s.spec.cellSizeXM, s.spec.cellSizeYM));
    return;
  }
  // The sun at solar noon of the output's day at the site, or low in the south in a polar night.
  const double latitude = src_.latitudeDeg;
  SunPosition sun = sunPosition(latitude, scene_.startDayOfYear() + d.outputDay, 12.0);
  double direction[3] = {sun.direction[0], sun.direction[1], sun.direction[2]};
  if (sun.elevationDeg < 5.0) direction[0] = 0.0, direction[1] = latitude >= 0 ? -0.966 : 0.966, direction[2] = 0.259;
  // Bare rock coloured over the whole grid's altitudes (across ranks, every rank's range combined).
  AltitudeRange altitudes = bedrockRange(s);
  if (src_.wholeRange) {
    const SeenRange whole = src_.wholeRange(SeenRange{altitudes.lo, altitudes.hi});
    altitudes = {static_cast<float>(whole.lo), static_cast<float>(whole.hi)};
  }
  const std::vector<uint8_t> rgb = snowPreviewRgb(s, direction, altitudes);
  write(rgb);
  // Every preview, subsampled to at most 512 pixels across, for the season's contact sheet (a
  // rank's window gives the pixels it owns, put together on rank 0).
  const ImageWindow w = windowOf(s.spec.width, s.spec.height);
  const int stride = std::max(1, (std::max(w.width, w.height) + 511) / 512);
  const int tw = (w.width + stride - 1) / stride, th = (w.height + stride - 1) / stride;
  std::vector<uint8_t> thumb(static_cast<size_t>(tw) * th * 3, 0);
  for (int y = 0; y < th; ++y)
    for (int x = 0; x < tw; ++x) {
      const int ix = x * stride, iy = y * stride;  // in the whole image
      if (!src_.tilesStartingIn.empty() && !src_.tilesStartingIn.contains(ix, iy)) continue;
      std::copy_n(&rgb[(static_cast<size_t>(iy - w.y0) * w.windowWidth + (ix - w.x0)) * 3], 3, &thumb[(static_cast<size_t>(y) * tw + x) * 3]);
    }
  if (src_.wholeThumbnail) thumb = src_.wholeThumbnail(std::move(thumb));
  previews_.push_back(std::move(thumb));
  previewWidth_ = tw, previewHeight_ = th;
}

// Snow depth (for a displacement modifier on the terrain) and the snow surface's height at the
// requested resolution, bilinear from the grid.
void OutputWriter::writeDisplacement(const Day& d) {
  const auto& out = scene_.outputs;
  if (out.displacementWidth <= 0) return;
  for (const std::string what : {"depth", "surface"}) {
    const LayerInfo& layer = *findLayer(what);
    const Grid<float> cells = src_.plan ? Grid<float>() : layer.compute(LayerInputs{&d.s});
    std::optional<Resampled> whole;  // one process: the same whole image for every set
    for (const RasterSet& set : sets_) {  // their own size in every set, cut as its tiles (across ranks, the rank's window of them)
      Resampled mine;
      if (src_.plan) mine.pixels = Grid<float>(out.displacementWidth, out.displacementHeight);
      else if (src_.gatherCells) mine = resampled(set.tiles, out.displacementWidth, out.displacementHeight, cells, nullptr);
      else if (!whole) whole = resampled(set.tiles, out.displacementWidth, out.displacementHeight, cells, nullptr);
      const Resampled& r = whole ? *whole : mine;
      writeFloatRaster(set, baseOf(d), d.day, "displacement_" + std::string(what), r.pixels, nullptr, what,
                       std::string(layer.content) + ", resampled (bilinear) to " + std::to_string(out.displacementWidth) + " x " +
                           std::to_string(out.displacementHeight) + " over the same extent",
                       "m", src_.plan ? nullptr : &r.window);
    }
  }
}

void OutputWriter::writeMultiChannel(const Day& d, const RasterSet& set, const std::vector<std::string>& names,
                                     const std::vector<Grid<float>>& channels, const ImageWindow* held) {
  if (channels.empty()) return;
  std::string list;
  for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
  const std::string content = "all layers as named channels: " + list;
  const std::string format = "OpenEXR, " + std::to_string(channels.size()) + " channels float32 (" + exrCompression_ + "), linear";
  // Tiled like the single-layer files: every channel cut at the same pixels.
  ImageWindow w = held ? *held : windowOf(channels[0].width(), channels[0].height());
  const int width = w.width, height = w.height;
  const TileLayout l = tileLayout(set.tiles, width, height);
  std::vector<Grid<float>> whole;  // across ranks, an untiled file's channels on the rank that writes it
  const std::optional<ImageWindow> to = untiledWindow(l, w);
  if (to) {
    for (const Grid<float>& g : channels) whole.emplace_back().adopt(to->windowWidth, to->windowHeight, gatheredTo(*to, g.data()));
    w = *to;
  }
  const std::vector<Grid<float>>& image = to ? whole : channels;
  const BaseOf base = baseOf(d);
  for (int r = 0; r < l.rows; ++r)
    for (int c = 0; c < l.columns; ++c) {
      const std::string path = base("layers" + tileSuffix(l, c, r)) + ".exr";
      if (src_.plan) {
        planFile(path, format, content, 4.0 * l.tileWidth * l.tileHeight * static_cast<double>(channels.size()));
        continue;
      }
      if (!writesTile(l, c, r, w)) continue;
      std::vector<Grid<float>> cut;
      if (l.tiled())
        for (const auto& g : image) cut.push_back(cutTile(g, w, l, c, r));
      std::vector<const Grid<float>*> grids;
      for (const auto& g : l.tiled() ? cut : image) grids.push_back(&g);
      writeMultiChannelExr(path, names, grids, scene_.outputs.compressionLevel);
      listFile(path, content, "per channel, as the single-layer files", format, d.day, 0.f, 0.f);
      if (l.tiled()) noteTile(l, c, r, width, height);
    }
}

void OutputWriter::writeVdb(const Day& d) {
  if (!scene_.outputs.vdb) return;
  VdbOptions vo;
  vo.voxelSizeM = vdbVoxelSizeM(scene_.outputs.vdbVoxelSizeM, d.s.spec);
  const std::string path = d.base("snow", src_.outDir) + ".vdb";
  if (src_.plan) return planFile(path, "OpenVDB", "snow body: snow_sdf (level set), density and the layers' densities (fog)", 0.0);
  const VdbSummary v = writeSnowVdb(path, d.s, vo);
  listFile(path,
           "snow body: snow_sdf (level set), density (fog, 1 in snow), compacted/stable/unstable/powder (fog, kg/m^3: " +
               fixed(vo.compactedKgPerM3, 0) + "/" + fixed(vo.stableKgPerM3, 0) + "/" + fixed(vo.unstableKgPerM3, 0) + "/" +
               fixed(vo.powderKgPerM3, 0) + "); " + std::to_string(v.snowVoxels) +
               " snow voxels; x east, y north from the south-west corner, z altitude",
           "m (voxel size " + fixed(vo.voxelSizeM, 3) + ")", "OpenVDB", d.day, 0.f, 0.f);
}

void OutputWriter::writeContactSheet() {
  if (previews_.size() <= 1) return;
  int sw = 0, sh = 0;
  const int columns = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(previews_.size()))));
  const std::vector<uint8_t> sheet = contactSheetRgb(previews_, previewWidth_, previewHeight_, columns, sw, sh);
  const std::string path = (fs::path(src_.outDir) / "contact_sheet.png").string();
  // Never tiled: a mosaic of subsampled previews for people to look at, not a map of the terrain
  // (its pixels lie on no one grid, so a tile would have no place or georeference).
  const bool tiled = scene_.outputs.tiles.convention != TileConvention::None;
  const std::string whole = tiled ? " (whole under [outputs.tiles]: a picture to look at, not a map)" : "";
  if (src_.plan) {
    planFile(path, kRgbPngFormat, "contact sheet of the season: the previews of the frame days, then the season's end" + whole, 0.0);
    if (tiled) currentSink().planned.back().note = "not tiled: a picture of the previews, not a map";
    return;
  }
  if (src_.wholeFilesElsewhere) {
    ++listings_;  // rank 0's file
    return;
  }
  writeRgbPng(path, sw, sh, sheet, scene_.outputs.compressionLevel);
  listFile(path,
           "contact sheet of the season: the previews of the frame days in order, then the season's end, " + std::to_string(columns) +
               " to a row" + whole,
           "sRGB", kRgbPngFormat, -1.0, 0.f, 255.f);
}

}  // namespace snow
