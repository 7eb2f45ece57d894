// The bake's outputs of one day (a frame day, or the season's end): every layer in its float
// format and encodings, previews, displacement maps, the multi-channel EXR, the VDB and the
// meshes; then the season's contact sheet and each avalanche's maps. Every file is listed in the
// current sink (output_sink.h), which becomes the manifest's file list.
#pragma once
#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "core/avalanche_runs.h"
#include "core/snow_state.h"
#include "core/spill_file.h"
#include "georeference.h"
#include "output_sink.h"
#include "raster_tiles.h"
#include "value_range.h"
#include "precompute/exposure.h"
#include "inputs/mesh.h"
#include "scene/scene.h"
#include "precompute/wind_timeline.h"
#include "scene/layers.h"

namespace snow {

// What the outputs are made from beyond the day's snow state. Pointers may be null where a
// scene has none (no exposure with precompute.sun = false, no occlusion fields in a season).
struct OutputSources {
  const Scene* scene = nullptr;
  std::string outDir{};
  double latitudeDeg = 0.0;
  std::vector<std::string> layers{};    // the scene's, with valid_mask added on terrains with NODATA
  const WindTimeline* wind = nullptr;
  const Exposure* exposure = nullptr;
  const OcclusionGrids* occlusion = nullptr;
  const Grid<float>* routeMap = nullptr;  // the skiers' route map (empty without skiers)
  int skiTrackFactor = 0;                 // the ski-track texture's texels per cell, 0 without one
  const std::vector<TriangleMesh>* occluders = nullptr;
  const TriangleMesh* snowMesh = nullptr;  // occlusion mode on a mesh terrain: the mesh with its snow
  GeoFrame geo{};                         // the terrain's georeference (tiles and GeoTIFFs)
  // `snowbake plan`: every writer lists its files (PlannedFile, output_sink.h) from the grid's
  // size and the scene alone; no value is computed, nothing is written. The state given to
  // writeDay then needs only its spec.
  bool plan = false;
  bool planSnowMesh = false;  // plan mode: occlusion on a mesh terrain writes snow_mesh (occlusionWritesSnowMesh)
  bool planNodata = false;    // plan mode: the terrain has NODATA cells (mesh tiles over them may be left out)
  // Called as each file is written (from the writers' threads): the progress's live "file" events.
  std::function<void(const std::string& path, double day)> fileWritten{};
  // Across ranks, where each rank writes the tiles that start in its subdomain (docs/distributed.md):
  // the states given to writeDay are this rank's local grid, which lies at `stateCells` of the
  // whole grid (empty: the state is the whole grid); the writer writes the tiles whose first
  // pixel lies in `tilesStartingIn` (empty: every file; a whole file is the tile of the rank
  // owning its first cell, rank 0's, gathered for it: untiledWindow); `wholeRange` combines a
  // layer's range seen on this rank's cells with every other rank's (on every rank alike, in the
  // same order).
  // `wholeThumbnail` puts each rank's pixels of a preview's thumbnail (0 on the others' cells)
  // together on rank 0 (the contact sheet's).
  // There, the files that are never tiled (the contact sheet) are rank 0's: `wholeFilesElsewhere`
  // on the others, which count them in the listing order only.
  // `gatherCells` fills `held` with the cells `want` of a grid of `elementBytes` values a cell laid
  // out on `stateCells` (`local`), each from the rank that owns it, every rank calling at once with
  // its own `want`: the cells a rank's tiles of a resampled image read.
  CellRect stateCells{}, tilesStartingIn{};
  bool wholeFilesElsewhere = false;
  std::function<void(const void* local, size_t elementBytes, const CellRect& want, void* held)> gatherCells{};
  std::function<SeenRange(const SeenRange&)> wholeRange{};
  std::function<std::vector<uint8_t>(std::vector<uint8_t>)> wholeThumbnail{};
};

class OutputWriter {
 public:
  OutputWriter(OutputSources sources, std::ostream& log);

  // The outputs of season day `day` (a frame, under frames/ with a .DDDD tag), or of the
  // season's end for day < 0. `skiDepth`: the ski-track texture of that day (null without one).
  void writeDay(const SnowState& s, double day, const Grid<float>* skiDepth);
  // After the last day: the encodings of layers with "season" ranges, over the range of every
  // day and tile (their manifest entries, listed when the day was written, get the mapping).
  void writeSeasonEncodings();
  // After the last day: the previews of every day on one sheet (when there were several).
  void writeContactSheet();
  // Each released avalanche's release zone, scour, deposit and motion frames (outputs.avalanche_maps).
  void writeAvalancheMaps(const std::vector<AvalancheRecord>& avalanches, const GridSpec& spec);
  // Occlusion mode on a mesh terrain: the mesh with its snow, known once the occlusion ran.
  void setSnowMesh(const TriangleMesh* mesh) { src_.snowMesh = mesh; }
  // Lines about snow on the occluders, gathered while the writers ran beside each other.
  const std::string& occluderNotes() const { return occluderNotes_; }

  // Plan mode: lists a file the bake would write in the current sink.
  void planFile(const std::string& path, const std::string& format, const std::string& content, double dataBytes, bool exactBytes = false,
                const std::string& condition = {}) const;
  // Plan mode: the per-avalanche maps, whose number the season decides.
  void planAvalancheMaps();

  // Lists a file written in the current sink.
  // `written` false: listed now, written later (encodings with "season" ranges).
  void listFile(const std::string& path, const std::string& content, const std::string& unit, const std::string& format, double day,
                float minValue, float maxValue, bool written = true) const;

 private:
  // One day's outputs: what they show and where they go.
  struct Day {
    const SnowState& s;
    double day;             // the frame's day, or < 0 for the season's end
    double outputDay;       // the season day the outputs show
    bool frame;
    std::string dayTag;     // ".DDDD" on frame days
    const Grid<float>* skiDepth;
    // DIR/STEM at the season's end, DIR/frames/STEM.DDDD on a frame day (zero-padded, so DCC
    // tools read the frames as a sequence), less the extension.
    std::string base(const std::string& stem, const std::string& outDir) const;
  };
  // The output path of `stem` (with the day's tag) less its extension: outDir/stem, or
  // outDir/frames/stem on a frame day.
  using BaseOf = std::function<std::string(const std::string& stem)>;
  BaseOf baseOf(const Day& d) const;
  // One raster output of raster set `set`, whole or as tiles; each file listed (output_rasters.cpp).
  // `held`: where the raster's pixels lie in its image (a resampled image's window, Resampled);
  // null: windowOf the raster's size.
  void writeFloatRaster(const RasterSet& set, const BaseOf& base, double day, const std::string& stem, const Grid<float>& grid,
                        const Grid<uint8_t>* valid, const std::string& layerName, const std::string& content, const std::string& unit,
                        const ImageWindow* held = nullptr);
  void writeEncodedRaster(const RasterSet& set, const BaseOf& base, double day, const std::string& stem, const std::string& encoding,
                          const Grid<float>& grid, const Grid<uint8_t>* valid, const ValueMapping& mapping, const std::string& content,
                          const std::string& unit, bool write, const ImageWindow* held = nullptr);
  void writeRgbRaster(const RasterSet& set, const BaseOf& base, double day, const std::string& stem, int width, int height,
                      const std::vector<uint8_t>& pixels, const std::string& content, const std::string& unit, int channels = 3,
                      const std::string& format = {}, const ImageWindow* held = nullptr);
  void writeRawFloatRaster(const RasterSet& set, const BaseOf& base, double day, const std::string& stem, const Grid<float>& grid,
                           const std::string& content, const std::string& unit, const ImageWindow* held = nullptr);
  // A layer on the state's grid resampled to width x height pixels over the same extent (over
  // valid cells where `valid` is given): the whole image, or across ranks the window of it that
  // holds this rank's tiles of `tiles` and `marginPx` pixels around them (clamped to the image),
  // from the cells those pixels read, gathered from their ranks (every rank calls at once).
  struct Resampled {
    Grid<float> pixels;
    Grid<uint8_t> valid;  // empty without `valid`
    ImageWindow window;
  };
  Resampled resampled(const OutputTiles& tiles, int width, int height, const Grid<float>& grid, const Grid<uint8_t>* valid, int marginPx = 0) const;
  // The same of several layers over one mask (gathered and resampled once).
  struct ResampledLayers {
    std::vector<Grid<float>> pixels;  // one a layer, in order
    Grid<uint8_t> valid;
    ImageWindow window;
  };
  ResampledLayers resampled(const OutputTiles& tiles, int width, int height, const std::vector<const Grid<float>*>& grids,
                            const Grid<uint8_t>* valid, int marginPx = 0) const;
  // The pixels of an image of width x height this writer holds of its tiles of `tiles`, with
  // `marginPx` more around them (clamped to the image): the whole image, or across ranks the
  // smallest rectangle holding the tiles this rank writes (empty where it writes none).
  CellRect writtenPixels(const OutputTiles& tiles, int width, int height, int marginPx) const;
  // A layer on the state's grid at `set`'s size over valid cells: itself, or resampled().
  Resampled atSetSize(const RasterSet& set, const Grid<float>& g, const Grid<uint8_t>& valid, int marginPx) const;
  // The splat map and the snow surface's normal map (output_engine_maps.cpp).
  void writeSplatMap(const Day& d, const RasterSet& set, const LayerInfo& layer);
  void writeNormalMap(const Day& d, const RasterSet& set, const LayerInfo& layer);
  // One per-avalanche map (output_avalanches.cpp): the image, each raster set's files of it, one file.
  struct AvalancheMapImage;
  void writeAvalancheMap(const std::string& rel, const std::string& tag, const AvalancheMapImage& image, const std::string& content,
                         const std::string& unit, double day, const GridSpec& spec);
  void writeAvalancheMapFile(const std::string& base, const Grid<float>& image, const std::string& what, const std::string& unit, double day,
                             const TileLayout& l, int col, int row, int width, int height, bool tile);
  // The tile fields of the file just listed.
  void noteTile(const TileLayout& l, int column, int row, int imageWidth, int imageHeight) const;
  void writeEncodings(const Day& d, const RasterSet& set, const LayerInfo& layer, const Grid<float>& grid, const Grid<uint8_t>* valid, const std::string& content,
                      const ImageWindow* held = nullptr);
  void writeLayers(const Day& d);
  // Where a raster's pixels lie in its image: the rank's window of the grid's image for a grid of
  // the state's size across ranks, else the raster is the whole image.
  ImageWindow windowOf(int width, int height) const;
  // The range of a raster's valid values: over the cells this rank owns, in a rank's window (a
  // resampled window, `held`, holds the whole image's pixels alone: over all of them).
  SeenRange seenOnOwnCells(const Grid<float>& grid, const Grid<uint8_t>* valid, const ImageWindow* held = nullptr) const;
  // Whether this rank writes tile (column, row) of the image `w` is a window of (the tile's first
  // pixel over its cells); counts a listing of the tiles it does not, so every rank numbers each
  // file alike (ManifestFile::listing).
  bool writesTile(const TileLayout& l, int column, int row, const ImageWindow& w) const;
  // Across ranks, an untiled file held as this rank's local window of the grid's cells: the window
  // its writer holds instead (the whole image on the rank that writes it, writesTile's owner of
  // its first cell; none on the others), whose pixels gatheredTo brings, one file at a time. None
  // in one process or plan mode, for tiles, and for a resampled image's window (already whole or
  // empty).
  std::optional<ImageWindow> untiledWindow(const TileLayout& l, const ImageWindow& w) const;
  // `to`'s pixels of an image of `channels` values a pixel laid out on the rank's local grid
  // (`local`), from their owners; every rank calls it at once.
  template <class T>
  std::vector<T> gatheredTo(const ImageWindow& to, const T* local, int channels = 1) const {
    std::vector<T> held(static_cast<size_t>(to.windowWidth) * to.windowHeight * channels);
    src_.gatherCells(local, sizeof(T) * channels, CellRect{to.x0, to.y0, to.x0 + to.windowWidth, to.y0 + to.windowHeight}, held.data());
    return held;
  }
  // Plan mode: a grid of the size `layer` is written at (values unset).
  Grid<float> planGrid(const Day& d, const LayerInfo& layer) const;
  void writeFloatLayer(const Day& d, const RasterSet& set, const LayerInfo& layer, Grid<float> grid, std::vector<std::string>& channelNames,
                       std::vector<Grid<float>>& channels, std::optional<ImageWindow>& channelsWindow);
  void writePreview(const Day& d, const LayerInfo& layer);
  void writeDisplacement(const Day& d);
  void writeMultiChannel(const Day& d, const RasterSet& set, const std::vector<std::string>& names,
                         const std::vector<Grid<float>>& channels, const ImageWindow* held);
  void writeVdb(const Day& d);
  void writeMeshes(const Day& d);
  void planMeshes(const Day& d);
  void writeGridMeshParts(const Day& d);
  void writeOccluderSnow(const Day& d);
  void writeSnowMesh(const Day& d);

  OutputSources src_;
  const Scene& scene_;
  std::ostream& log_;
  std::string exrCompression_;    // the EXR compression name of the scene's level
  std::string floatImageFormat_;  // the manifest's format line of every float image
  std::string occluderNotes_;
  std::vector<RasterSet> sets_;  // rasterSets(outputs): every raster output is written in each
  // Encodings with "season" ranges, written after the last day (writeSeasonEncodings): the layer
  // and its mask wait on disk (5 bytes a pixel a layer were held through the season).
  struct SeasonEncoding {
    bool frame;
    std::string dayTag, layer, encoding, content, unit;
    double day;
    int width, height;
    SpillFile::Extent grid, valid;  // valid: empty where the layer has no mask
    RasterSet set;
    std::optional<ImageWindow> held;  // a resampled image's window
  };
  std::unique_ptr<SpillFile> spill_;
  std::mutex seasonMutex_;
  std::vector<SeasonEncoding> seasonEncodings_;
  std::map<std::string, SeenRange> seasonRanges_;  // by layer
  mutable std::atomic<long long> listings_{0};  // files listed or left to another rank so far
  std::vector<std::vector<uint8_t>> previews_;  // every preview written, subsampled, for the contact sheet
  int previewWidth_ = 0, previewHeight_ = 0;
};

}  // namespace snow
