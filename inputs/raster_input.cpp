#include "raster_input.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <limits>
#include <memory>
#include <sstream>

#include "core/errors.h"
#include "gdal_support.h"

namespace snow {
namespace {

namespace fs = std::filesystem;

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string num(double v, int digits = 4) {
  std::ostringstream o;
  o << std::setprecision(digits) << v;
  return o.str();
}

RasterImage readWithOiio(const std::string& path) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) throw InputError(path + ": cannot read as an image: " + OIIO::geterror());
  const OIIO::ImageSpec spec = in->spec();
  RasterImage r;
  r.width = spec.width;
  r.height = spec.height;
  r.channels = spec.nchannels;
  if (r.width <= 0 || r.height <= 0 || r.channels <= 0) throw InputError(path + ": image has no pixels");
  const OIIO::TypeDesc::BASETYPE base = static_cast<OIIO::TypeDesc::BASETYPE>(spec.format.basetype);
  r.integer = base == OIIO::TypeDesc::UINT8 || base == OIIO::TypeDesc::UINT16 || base == OIIO::TypeDesc::INT8 ||
              base == OIIO::TypeDesc::INT16 || base == OIIO::TypeDesc::UINT32 || base == OIIO::TypeDesc::INT32;
  r.values.resize(static_cast<size_t>(r.width) * r.height);
  // The first channel only; OpenImageIO converts integer pixels to value / max.
  if (!in->read_image(0, 0, 0, 1, OIIO::TypeDesc::FLOAT, r.values.data()))
    throw InputError(path + ": cannot read the image's pixels: " + in->geterror());
  r.reader = std::string("OpenImageIO ") + in->format_name();
  return r;
}

RasterImage readWithGdal(const std::string& path) {
  const GdalDataset ds = openGdalReadOnly(path);
  if (!ds) throw InputError(path + ": cannot read as a raster: " + lastGdalError());
  if (ds->GetRasterCount() < 1) throw InputError(path + ": has no raster band");
  RasterImage r;
  r.width = ds->GetRasterXSize();
  r.height = ds->GetRasterYSize();
  r.channels = ds->GetRasterCount();
  r.reader = std::string("GDAL ") + (ds->GetDriver() ? ds->GetDriver()->GetDescription() : "?");
  GDALRasterBand* band = ds->GetRasterBand(1);
  const GDALDataType type = band->GetRasterDataType();
  double maxValue = 1.0;
  switch (type) {
    case GDT_Byte: maxValue = 255.0, r.integer = true; break;
    case GDT_UInt16: maxValue = 65535.0, r.integer = true; break;
    case GDT_Int16: maxValue = 32767.0, r.integer = true; break;
    case GDT_UInt32: maxValue = 4294967295.0, r.integer = true; break;
    case GDT_Int32: maxValue = 2147483647.0, r.integer = true; break;
    default: break;
  }
  std::vector<double> raw(static_cast<size_t>(r.width) * r.height);
  if (band->RasterIO(GF_Read, 0, 0, r.width, r.height, raw.data(), r.width, r.height, GDT_Float64, 0, 0) != CE_None)
    throw InputError(path + ": cannot read the raster's values: " + std::string(CPLGetLastErrorMsg()));
  int hasNodata = 0;
  const double nodata = band->GetNoDataValue(&hasNodata);
  r.values.resize(raw.size());
  if (hasNodata) r.nodata.assign(raw.size(), 0);
  for (size_t i = 0; i < raw.size(); ++i) {
    if (hasNodata && (raw[i] == nodata || (std::isnan(nodata) && std::isnan(raw[i])))) {
      r.nodata[i] = 1;
      r.values[i] = 0.f;
      continue;
    }
    r.values[i] = static_cast<float>(r.integer ? raw[i] / maxValue : raw[i]);
  }
  r.georeferenced = ds->GetGeoTransform(r.geoTransform) == CE_None;
  if (r.georeferenced && (r.geoTransform[2] != 0.0 || r.geoTransform[4] != 0.0))
    throw InputError(path + ": rotated or sheared rasters are not supported; warp it north-up first (gdalwarp)");
  r.crsWkt = crsWktOf(*ds);
  return r;
}

}  // namespace

float sampleRasterCell(const std::vector<float>& pixels, int width, int height, double px, double py, double spanX, double spanY,
                       bool clampOutside, float outside, bool* anyInside) {
  const int kx = std::max(1, static_cast<int>(std::ceil(spanX - 1e-9))), ky = std::max(1, static_cast<int>(std::ceil(spanY - 1e-9)));
  double sum = 0.0;
  bool inside = false;
  for (int j = 0; j < ky; ++j)
    for (int i = 0; i < kx; ++i) {
      const double x = px + ((i + 0.5) / kx - 0.5) * spanX, y = py + ((j + 0.5) / ky - 0.5) * spanY;
      const bool in = x >= -0.5 && y >= -0.5 && x <= width - 0.5 && y <= height - 0.5;
      inside = inside || in;
      sum += (in || clampOutside) ? sampleBilinearClamped(pixels.data(), width, height, x, y) : outside;
    }
  if (anyInside) *anyInside = inside;
  return static_cast<float>(sum / (static_cast<double>(kx) * ky));
}

RasterImage readRasterImage(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path + ": raster file does not exist");
  if (fs::is_directory(path, ec)) throw InputError(path + ": is a folder, not a raster file");
  if (fs::file_size(path, ec) == 0) throw InputError(path + ": raster file is empty");
  const std::string ext = lower(fs::path(path).extension().string());
  // Images through OpenImageIO; TIFFs (GeoTIFF keys) and everything else through GDAL.
  if (ext == ".png" || ext == ".exr" || ext == ".jpg" || ext == ".jpeg" || ext == ".tga" || ext == ".bmp" || ext == ".hdr")
    return readWithOiio(path);
  return readWithGdal(path);
}

namespace {

// The raster file, its errors prefixed with where the scene names it.
RasterImage readReferencedRaster(const RasterRef& ref) {
  try {
    return readRasterImage(ref.file);
  } catch (const InputError& e) {
    throw InputError(ref.declaredAt.empty() ? std::string(e.what()) : ref.declaredAt + ": " + e.what());
  }
}

// Checks the values on the file's own pixels (so a message can say where) and maps them through
// values/range/invert. Returns what 0 becomes outside a georeferenced raster (range's first value;
// 0 without a range).
float checkAndMapValues(const RasterRef& ref, RasterUse use, const std::string& who, RasterImage& img) {
  const bool transform = ref.values || ref.range || ref.invert || use == RasterUse::Mask;
  if (use == RasterUse::Depth && !transform && img.integer)
    throw InputError(who + ": an integer image holds no depths in metres: give range = [0, deepest_m] (its values 0..max map to it)");
  const double lo = ref.values ? (*ref.values)[0] : 0.0, hi = ref.values ? (*ref.values)[1] : 1.0;
  const double a = ref.range ? (*ref.range)[0] : 0.0, b = ref.range ? (*ref.range)[1] : 1.0;
  for (size_t i = 0; i < img.values.size(); ++i) {
    if (!img.nodata.empty() && img.nodata[i]) continue;
    float& v = img.values[i];
    const int px = static_cast<int>(i % img.width), py = static_cast<int>(i / img.width);
    auto where = [&] { return " at pixel (" + std::to_string(px) + ", " + std::to_string(py) + ")"; };
    if (!std::isfinite(v)) throw InputError(who + ": value " + num(v) + where() + " is not a finite number");
    if (!transform) {
      if (v < 0.f) throw InputError(who + ": depth " + num(v) + " m" + where() + " is negative");
      continue;
    }
    double n = (static_cast<double>(v) - lo) / (hi - lo);
    if (n < -1e-4 || n > 1.0 + 1e-4) {
      std::string msg = who + ": value " + num(v, 6) + where() + " is outside ";
      msg += ref.values ? "values = [" + num(lo, 6) + ", " + num(hi, 6) + "]" : "[0, 1]";
      msg += img.integer ? " (integer pixels read as value / max)" : "; give values = [lowest, highest] to map the file's values";
      throw InputError(msg);
    }
    n = std::clamp(n, 0.0, 1.0);
    if (ref.invert) n = 1.0 - n;
    v = static_cast<float>(a + n * (b - a));
  }
  return transform ? static_cast<float>(a) : 0.f;
}

// Both name a coordinate system: they must be the same one.
void checkSameCrs(const std::string& who, const RasterImage& img, const TerrainInfo& terrain) {
  if (img.crsWkt.empty() || terrain.crsWkt.empty()) return;
  OGRSpatialReference r1, r2;
  r1.importFromWkt(img.crsWkt.c_str());
  r2.importFromWkt(terrain.crsWkt.c_str());
  if (!r1.IsSame(&r2))
    throw InputError(who + ": its coordinate system (" + std::string(r1.GetName() ? r1.GetName() : "?") + ") is not the terrain's (" +
                     (r2.GetName() ? r2.GetName() : "?") + "); reproject it (gdalwarp -t_srs) first");
}

// Samples each terrain cell where it falls in the raster; returns the cells inside it.
size_t placeByGeoreference(const RasterImage& img, const TerrainInfo& terrain, const std::string& who, float outsideValue,
                           MappedRaster& out, std::ostream& how) {
  checkSameCrs(who, img, terrain);
  const GridSpec& g = terrain.spec;
  const double* gt = img.geoTransform;
  const double spanX = terrain.geoCellX / std::abs(gt[1]), spanY = terrain.geoCellY / std::abs(gt[5]);
  size_t insideCells = 0;
  for (int y = 0; y < g.height; ++y)
    for (int x = 0; x < g.width; ++x) {
      const double X = g.originX + (x + 0.5) * terrain.geoCellX, Y = g.originY - (y + 0.5) * terrain.geoCellY;
      const double px = (X - gt[0]) / gt[1] - 0.5, py = (Y - gt[3]) / gt[5] - 0.5;
      bool inside = false;
      out.values(x, y) = sampleRasterCell(img.values, img.width, img.height, px, py, spanX, spanY, false, outsideValue, &inside);
      insideCells += inside;
    }
  if (insideCells == 0)
    throw InputError(who + ": does not overlap the terrain (both are georeferenced; check the raster's extent and coordinate system)");
  out.placement = "georeferenced";
  how << "placed by georeference" << (img.crsWkt.empty() || terrain.crsWkt.empty() ? " (one of them names no coordinate system: assumed the same)" : "")
      << ", " << num(spanX, 3) << " x " << num(spanY, 3) << " pixels a cell";
  return insideCells;
}

// Without a shared georeference the raster must have the terrain's aspect ratio.
void checkAspectMatches(const RasterImage& img, const GridSpec& g, const std::string& who) {
  const double rasterAspect = static_cast<double>(img.width) / img.height;
  const double terrainAspect = (g.width * g.cellSizeXM) / (g.height * g.cellSizeYM);
  const double gridAspect = static_cast<double>(g.width) / g.height;
  // One pixel of slack either way (a 1025 x 1024 painting of a 1024^2 terrain is fine).
  const double tolerance = rasterAspect * (1.0 / img.width + 1.0 / img.height) + 1e-9;
  const bool matches = std::abs(rasterAspect - terrainAspect) <= tolerance || std::abs(rasterAspect - gridAspect) <= tolerance;
  if (matches) return;
  std::ostringstream o;
  o << who << ": is " << img.width << " x " << img.height << " pixels (aspect " << num(rasterAspect) << "), the terrain " << g.width << " x "
    << g.height << " cells (aspect " << num(terrainAspect) << "), and "
    << (img.georeferenced ? "the terrain has no georeference" : "the raster has no georeference")
    << " to map it by: paint it at the terrain's aspect ratio or georeference both";
  throw InputError(o.str());
}

// Stretches the raster over the terrain's whole extent; returns the cells covered (all).
size_t stretchOverTerrain(const RasterImage& img, const GridSpec& g, const std::string& who, MappedRaster& out, std::ostream& how) {
  checkAspectMatches(img, g, who);
  const double spanX = static_cast<double>(img.width) / g.width, spanY = static_cast<double>(img.height) / g.height;
  for (int y = 0; y < g.height; ++y)
    for (int x = 0; x < g.width; ++x)
      out.values(x, y) = sampleRasterCell(img.values, img.width, img.height, (x + 0.5) * spanX - 0.5, (y + 0.5) * spanY - 0.5, spanX, spanY,
                                          true, 0.f);
  out.placement = "stretched";
  how << "stretched over the terrain's extent, " << num(spanX, 3) << " x " << num(spanY, 3) << " pixels a cell";
  return g.cellCount();
}

// Zeroes the cells outside the terrain's valid mask and takes min, max and mean over the rest.
void summariseValidCells(const Grid<uint8_t>& valid, MappedRaster& out) {
  double sum = 0.0, n = 0.0;
  out.minValue = std::numeric_limits<double>::infinity();
  out.maxValue = -out.minValue;
  for (size_t i = 0; i < out.values.size(); ++i) {
    if (valid.size() == out.values.size() && !valid.values()[i]) {
      out.values.values()[i] = 0.f;
      continue;
    }
    const double v = out.values.values()[i];
    sum += v, n += 1.0;
    out.minValue = std::min(out.minValue, v), out.maxValue = std::max(out.maxValue, v);
  }
  out.meanValue = n > 0 ? sum / n : 0.0;
  if (!(n > 0)) out.minValue = out.maxValue = 0.0;
}

}  // namespace

MappedRaster mapRaster(const RasterRef& ref, RasterUse use, const TerrainInfo& terrain, const Grid<uint8_t>& valid) {
  const std::string who = ref.declaredAt.empty() ? ref.file : ref.declaredAt + ": " + ref.file;
  RasterImage img = readReferencedRaster(ref);
  const float outsideValue = checkAndMapValues(ref, use, who, img);

  const GridSpec& g = terrain.spec;
  MappedRaster out;
  out.reader = img.reader;
  out.sourceWidth = img.width;
  out.sourceHeight = img.height;
  out.values = Grid<float>(g.width, g.height, 0.f);
  std::ostringstream how;
  const size_t insideCells = img.georeferenced && terrain.georeferenced ? placeByGeoreference(img, terrain, who, outsideValue, out, how)
                                                                         : stretchOverTerrain(img, g, who, out, how);
  out.coverage = static_cast<double>(insideCells) / static_cast<double>(g.cellCount());
  how << " (" << img.width << " x " << img.height << " " << img.reader << " -> " << g.width << " x " << g.height << ")";
  if (out.coverage < 1.0) how << "; covers " << num(100.0 * out.coverage, 3) << " % of the terrain, " << num(outsideValue) << " outside";
  out.description = how.str();
  summariseValidCells(valid, out);
  return out;
}

}  // namespace snow
