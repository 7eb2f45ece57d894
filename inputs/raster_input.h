// Painted rasters as inputs (art direction): masks, multiplier maps and depth rasters, read from
// any grayscale image or raster (PNG 8/16-bit, EXR, TIFF through OpenImageIO; GeoTIFF and
// anything else GDAL opens), placed on the terrain and resampled to its grid.
//
// Placement: by georeference when both the raster and the terrain have one (the raster's
// geotransform), otherwise stretched over the terrain's extent
// (the raster's aspect ratio must match the terrain's within one pixel). Outside a georeferenced
// raster a cell takes the value a file value of 0 would map to.
// Resampling: each cell averages a k x k grid of bilinear samples of the raster (pixel centres
// at half-integers, edges clamped) spread over the cell's footprint, k = ceil(pixels per cell)
// (k = 1: one bilinear sample at the cell centre). Linear ramps come through exactly.
// Values: integer images read as value / max (0..1); float images and GDAL rasters as stored.
// Masks and multipliers: n = (v - lo) / (hi - lo) with `values = [lo, hi]` (default n = v), which
// must lie in [0, 1]; `invert` gives 1 - n; `range = [a, b]` maps n to a + n (b - a).
// Depth rasters: metres as stored (float rasters), or through values/range like a mask.
// NODATA pixels read 0. Every problem is an InputError naming the file.
#pragma once
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "core/grid.h"
#include "scene/raster_ref.h"
#include "terrain_loader.h"

namespace snow {


enum class RasterUse { Mask, Depth };

// One band of a raster as read, before placement.
struct RasterImage {
  int width = 0, height = 0;
  std::vector<float> values;      // row-major, north row first
  std::vector<uint8_t> nodata;    // 1 where the file says NODATA (empty: none)
  bool integer = false;           // integer pixels, read as value / max
  bool georeferenced = false;
  double geoTransform[6] = {0, 1, 0, 0, 0, 1};
  std::string crsWkt;
  std::string reader;             // "GDAL GTiff", "OpenImageIO png", ...
  int channels = 1;
};

struct MappedRaster {
  Grid<float> values;             // on the terrain grid (NODATA cells 0)
  std::string reader;
  int sourceWidth = 0, sourceHeight = 0;
  std::string placement;          // "georeferenced" or "stretched"
  std::string description;        // how it was placed and resampled, for the log and manifest
  double coverage = 1.0;          // fraction of the terrain's cells inside the raster
  double minValue = 0, maxValue = 0, meanValue = 0;  // over valid cells
};

// Reads the first band (channel) of a raster file.
RasterImage readRasterImage(const std::string& path);

// Reads, checks, places and resamples `ref` onto the terrain grid described by `terrain`.
// `valid` (the terrain's valid cells) only limits the statistics.
MappedRaster mapRaster(const RasterRef& ref, RasterUse use, const TerrainInfo& terrain, const Grid<uint8_t>& valid);

// The resampling alone (documented above): value of the raster (W x H pixel values) over a
// cell whose centre lies at pixel coordinates (px, py) (pixel centres at i + 0.5 minus 0.5, i.e.
// pixel i's centre is at i) and which spans (spanX, spanY) pixels. `outside` is returned for
// samples outside [-0.5, W - 0.5] x [-0.5, H - 0.5] when `clampOutside` is false.
float sampleRasterCell(const std::vector<float>& pixels, int width, int height, double px, double py, double spanX,
                       double spanY, bool clampOutside, float outside, bool* anyInside = nullptr);

}  // namespace snow
