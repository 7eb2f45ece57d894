// Float grids as single-channel 32-bit float images (OpenEXR or TIFF), linear values in the
// grid's own unit (metres for snow layers), row 0 at the north edge.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "core/grid.h"
#include "core/grid_window.h"
#include "core/snow_state.h"

namespace snow {

// Deflate effort for the lossless image formats, 0 (none) to 9 (smallest, slowest): PNG's zlib
// level and OpenEXR's zip level (0 writes EXR uncompressed). 1 by default, as OpenCV's PNG
// writer. Measured on a 1024² season's layers: EXR zip at level 4 (OpenImageIO's default) is
// within 0.2 % of level 1's size for 28 % more time, 16-bit PNG at level 6 (libpng's default,
// all row filters) 2-16 % smaller than level 1 (the "sub" row filter) for 1.6-4.8 times the
// time; a sparse texture (the 8192² ski tracks) is 2.5-2.7 times smaller at those levels.
constexpr int kDefaultCompressionLevel = 1;
// The EXR compression a level gives, as OpenImageIO names it ("zip:1", "none"), for the manifest.
std::string exrCompressionName(int level);

struct WrittenImage {
  std::string path;
  float minValue = 0.f, maxValue = 0.f;
};

// `format` is "exr" or "tiff"; the file gets that extension. Written atomically. The one channel
// is "Y" (greyscale); `layerName` goes into the metadata (snowbake:layer, ImageDescription).
WrittenImage writeFloatImage(const std::string& pathWithoutExtension, const std::string& format, const Grid<float>& grid,
                             const std::string& layerName, int compressionLevel = kDefaultCompressionLevel);

// A grid normalised to its own range [min, max] and quantised: "png16" (1-channel 16-bit PNG,
// `<base>.16.png`), "png8" (8-bit PNG mask for engines' weight layers, `<base>.8.png`) or "r16"
// (raw little-endian uint16, row 0 north, `<base>.r16`: Unity and Unreal heightmap import).
// value = min + (max - min) * p / (2^bits - 1); min and max are returned for the manifest. Linear
// data, never sRGB. Written atomically.
WrittenImage writeNormalised(const std::string& pathWithoutExtension, const std::string& encoding, const Grid<float>& grid,
                             int compressionLevel = kDefaultCompressionLevel);
// How writeNormalised encodes, for the manifest.
std::string normalisedFormat(const std::string& encoding, int width, int height);

// The grid as raw little-endian float32, row 0 north, no header (encoding "r32"). Written atomically.
void writeRawFloat32(const std::string& path, const Grid<float>& grid);
// The extension an encoding's files take (".16.png", ".8.png", ".r16").
std::string encodingExtension(const std::string& encoding);
// A grid quantised over [lo, hi] (values outside clamp; lo == hi writes 0 everywhere) in an
// encoding of writeNormalised, to `path` as given; cells where `valid` (when given, of the grid's
// size) is 0 are written as pixel `nodataPixel`. Written atomically.
void writeQuantised(const std::string& path, const std::string& encoding, const Grid<float>& grid, const Grid<uint8_t>* valid,
                    double lo, double hi, int nodataPixel, int compressionLevel = kDefaultCompressionLevel);
// writeQuantised in two halves, so that the tiles of one image share the quantising: the pixels
// (0..255 for png8, 0..65535 otherwise, one a cell), and `width` x `height` of them written.
std::vector<uint16_t> quantisedPixels(const std::string& encoding, const Grid<float>& grid, const Grid<uint8_t>* valid, double lo,
                                      double hi, int nodataPixel);
void writeQuantisedPixels(const std::string& path, const std::string& encoding, int width, int height, const uint16_t* pixels,
                          int compressionLevel = kDefaultCompressionLevel);

// Bilinear resampling of a cell-centred grid to width x height cells over the same extent (the
// displacement maps at a requested resolution). Edge cells clamp. Exact for linear fields.
Grid<float> resampleBilinear(const Grid<float>& grid, int width, int height);
// outputs.resize: the same over valid cells only. A pixel is valid where the cell nearest its
// centre is (`validOut`); its value is the bilinear weights of the valid cells among the four,
// renormalised, so NODATA's zeros do not pull the edge of a heightmap down. 0 at invalid pixels.
Grid<float> resampleValid(const Grid<float>& grid, const Grid<uint8_t>& valid, int width, int height, Grid<uint8_t>& validOut);

// The same pixels computed from part of the grid, as a writer across ranks holds it: `held` is
// the cells `from` of a grid of fromWidth x fromHeight cells, which must hold every cell the
// pixels `to` of the width x height image read (cellsReadBy); the result is those pixels alone,
// each the whole image's bytes.
struct ResampleWindow {
  CellRect from;                        // the cells held, in the whole grid
  int fromWidth = 0, fromHeight = 0;    // the whole grid
  CellRect to;                          // the pixels made, in the whole image
  int width = 0, height = 0;            // the whole image
};
Grid<float> resampleBilinear(const Grid<float>& held, const ResampleWindow& w);
Grid<float> resampleValid(const Grid<float>& held, const Grid<uint8_t>& heldValid, const ResampleWindow& w, Grid<uint8_t>& validOut);
// The cells [first, last) of a grid of `cells` along one axis that pixels [firstPixel, lastPixel)
// of an image of `pixels` across the same extent read, resampled by either of the above.
std::pair<int, int> cellsReadBy(int firstPixel, int lastPixel, int pixels, int cells);
// The same for the block `pixels` of a width x height image over a grid of cellsWide x
// cellsHigh: the cells it reads (empty for no pixels).
CellRect cellsReadBy(const CellRect& pixels, int width, int height, int cellsWide, int cellsHigh);

// Several grids of one size in one 32-bit float EXR (zip at `compressionLevel`), channel
// "<name>.Y" per grid (an EXR layer per grid). Written atomically.
void writeMultiChannelExr(const std::string& path, const std::vector<std::string>& names, const std::vector<const Grid<float>*>& grids,
                          int compressionLevel = kDefaultCompressionLevel);

// The manifest's format line of writeRgbPng's files (previews and the contact sheet).
constexpr const char* kRgbPngFormat = "PNG, 3 channels uint8, sRGB";
// An 8-bit sRGB PNG preview, three bytes per pixel, row 0 at the north edge. Written atomically.
void writeRgbPng(const std::string& path, int width, int height, const std::vector<uint8_t>& rgb,
                 int compressionLevel = kDefaultCompressionLevel);
// The same with 1 to 4 interleaved 8-bit channels (the splat map's RGBA, linear). Written atomically.
void writePng8(const std::string& path, int width, int height, int channels, const std::vector<uint8_t>& pixels,
               int compressionLevel = kDefaultCompressionLevel);

// A shaded-relief preview of the snow surface (bedrock + snow, lit from the north-west), with
// avalanche scour tinted red (full at 1 m) and deposit tinted blue (full at 2 m); NODATA black.
std::vector<uint8_t> avalanchePreviewRgb(const Grid<float>& surfaceM, const Grid<uint8_t>& valid, const Grid<float>& scourM,
                                         const Grid<float>& depositM, double cellSizeXM, double cellSizeYM);

// A shaded-relief preview of the snow-covered terrain: bare ground coloured by altitude (green
// low, brown, grey rock high, over the grid's own range), snow shaded by its top layer (powder
// white, unstable pale blue, stable cream, compacted grey), both lit by a sun at `sunDirection`
// (unit vector x east, y north, z up) with some sky light; NODATA black. 8-bit sRGB, 3 channels.
// `altitudes`: the bare rock's colour range, the state's valid cells' lowest and highest bedrock
// (the whole grid's, where the state is a rank's window of it).
struct AltitudeRange {
  float lo = 1e30f, hi = -1e30f;
};
AltitudeRange bedrockRange(const SnowState& state);
std::vector<uint8_t> snowPreviewRgb(const SnowState& state, const double sunDirection[3], const AltitudeRange& altitudes);
inline std::vector<uint8_t> snowPreviewRgb(const SnowState& state, const double sunDirection[3]) {
  return snowPreviewRgb(state, sunDirection, bedrockRange(state));
}

// Tiles RGB images of one size into a contact sheet `columns` wide (a grey gap between them).
std::vector<uint8_t> contactSheetRgb(const std::vector<std::vector<uint8_t>>& images, int width, int height, int columns,
                                     int& sheetWidth, int& sheetHeight);

// Reads one channel of a float image back (for tests and `snowbake info`).
Grid<float> readFloatImage(const std::string& path);

}  // namespace snow
