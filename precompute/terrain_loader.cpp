#include "terrain_loader.h"

#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <mutex>
#include <sstream>

#include "core/errors.h"

namespace snow {

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr int kMinCellsPerSide = 3;
constexpr double kMaxCells = 1.0e9;  // 4 GB per float field: more would not fit a bake in memory

void registerGdal() {
  static std::once_flag once;
  std::call_once(once, [] {
    GDALAllRegister();
    CPLSetErrorHandler(CPLQuietErrorHandler);  // errors are reported through InputError instead
  });
}

std::string lastGdalError() {
  const char* m = CPLGetLastErrorMsg();
  return m && *m ? std::string(m) : std::string("unknown format or unreadable file");
}

struct Closer {
  void operator()(GDALDataset* d) const { GDALClose(d); }
};
}  // namespace

double metresPerDegreeLatitude(double lat) {
  const double p = lat * kPi / 180.0;
  return 111132.92 - 559.82 * std::cos(2 * p) + 1.175 * std::cos(4 * p) - 0.0023 * std::cos(6 * p);
}
double metresPerDegreeLongitude(double lat) {
  const double p = lat * kPi / 180.0;
  return 111412.84 * std::cos(p) - 93.5 * std::cos(3 * p) + 0.118 * std::cos(5 * p);
}

Terrain loadTerrainFile(const std::string& path) {
  registerGdal();
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError(path + ": terrain file does not exist");
  if (std::filesystem::file_size(path, ec) == 0) throw InputError(path + ": terrain file is empty");
  CPLErrorReset();
  std::unique_ptr<GDALDataset, Closer> ds(static_cast<GDALDataset*>(GDALOpen(path.c_str(), GA_ReadOnly)));
  if (!ds) throw InputError(path + ": cannot read as a terrain: " + lastGdalError());
  if (ds->GetRasterCount() < 1) throw InputError(path + ": has no raster band");
  const int w = ds->GetRasterXSize(), h = ds->GetRasterYSize();
  if (w < kMinCellsPerSide || h < kMinCellsPerSide)
    throw InputError(path + ": grid " + std::to_string(w) + " x " + std::to_string(h) + " is too small to simulate (need at least " +
                     std::to_string(kMinCellsPerSide) + " x " + std::to_string(kMinCellsPerSide) + ")");
  if (static_cast<double>(w) * h > kMaxCells)
    throw InputError(path + ": grid " + std::to_string(w) + " x " + std::to_string(h) + " has more than 1e9 cells; resample it first");

  Terrain t;
  TerrainInfo& info = t.info;
  info.source = path;
  info.driver = ds->GetDriver() ? ds->GetDriver()->GetDescription() : "?";

  double gt[6] = {0, 1, 0, 0, 0, -1};
  const bool hasTransform = ds->GetGeoTransform(gt) == CE_None;
  if (hasTransform && (gt[2] != 0.0 || gt[4] != 0.0))
    throw InputError(path + ": rotated or sheared rasters are not supported; warp it north-up first (gdalwarp)");
  const double sizeX = std::abs(gt[1]), sizeY = std::abs(gt[5]);
  if (!(sizeX > 0.0) || !(sizeY > 0.0) || !std::isfinite(sizeX) || !std::isfinite(sizeY))
    throw InputError(path + ": cell size is zero or invalid");
  info.nativeCellSizeX = sizeX;
  info.nativeCellSizeY = sizeY;

  // North-west corner and centre in the file's coordinates.
  const double west = gt[0], north = gt[5] < 0 ? gt[3] : gt[3] + gt[5] * h;
  const double centreY = gt[3] + gt[5] * h * 0.5, centreX = gt[0] + gt[1] * w * 0.5;

  const OGRSpatialReference* srs = ds->GetSpatialRef();
  bool geographic = false;
  if (srs && !srs->IsEmpty()) {
    if (srs->IsGeographic()) {
      geographic = true;
      info.coordinateSystem = std::string("geographic (") + (srs->GetName() ? srs->GetName() : "degrees") + ")";
      info.coordinateDecision = "read from the file's coordinate system";
    } else {
      const char* unitName = nullptr;
      const double toMetre = srs->GetLinearUnits(&unitName);
      info.coordinateSystem = std::string("projected (") + (srs->GetName() ? srs->GetName() : "?") + ", " +
                              (unitName ? unitName : "?") + ")";
      info.coordinateDecision = "read from the file's coordinate system; linear unit " + std::to_string(toMetre) + " m";
      info.nativeUnit = unitName ? unitName : "?";
      info.spec.cellSizeXM = sizeX * toMetre;
      info.spec.cellSizeYM = sizeY * toMetre;
      OGRSpatialReference wgs84;
      wgs84.SetWellKnownGeogCS("WGS84");
      wgs84.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
      std::unique_ptr<OGRCoordinateTransformation> ct(OGRCreateCoordinateTransformation(srs, &wgs84));
      double lon = centreX, lat = centreY;
      if (ct && ct->Transform(1, &lon, &lat)) {
        info.latitudeKnown = true;
        info.centreLatitudeDeg = lat;
      }
    }
  } else {
    // No coordinate system: degrees if the numbers only make sense as degrees.
    const double east = west + sizeX * w, south = north - sizeY * h;
    const bool looksLikeDegrees = sizeX < 0.1 && sizeY < 0.1 && west >= -180.0 && east <= 180.0 && south >= -90.0 &&
                                  north <= 90.0 && hasTransform;
    if (looksLikeDegrees) {
      geographic = true;
      info.coordinateSystem = "none in the file; treated as geographic (degrees)";
      std::ostringstream o;
      o << "no coordinate system, but a cell size of " << sizeX << " and an extent inside longitude/latitude bounds only make "
        << "sense as degrees";
      info.coordinateDecision = o.str();
    } else {
      info.coordinateSystem = "none in the file; treated as metres";
      info.coordinateDecision = hasTransform ? "no coordinate system; cell size taken as metres"
                                             : "no georeference; 1 m cells assumed";
      info.nativeUnit = "metre (assumed)";
      info.spec.cellSizeXM = sizeX;
      info.spec.cellSizeYM = sizeY;
    }
  }
  if (geographic) {
    info.nativeUnit = "degree";
    info.latitudeKnown = true;
    info.centreLatitudeDeg = centreY;
    info.spec.cellSizeXM = sizeX * metresPerDegreeLongitude(centreY);
    info.spec.cellSizeYM = sizeY * metresPerDegreeLatitude(centreY);
  }
  info.spec.width = w;
  info.spec.height = h;
  info.spec.originX = west;
  info.spec.originY = north;

  GDALRasterBand* band = ds->GetRasterBand(1);
  t.heightsM.resize(w, h);
  t.valid.resize(w, h, 1);
  // Read north-up: when the transform is south-up (gt[5] > 0), flip rows.
  std::vector<float> rows(static_cast<size_t>(w) * h);
  CPLErrorReset();
  if (band->RasterIO(GF_Read, 0, 0, w, h, rows.data(), w, h, GDT_Float32, 0, 0) != CE_None)
    throw InputError(path + ": read failed (truncated or corrupt?): " + lastGdalError());
  int hasNodata = 0;
  const double nodata = band->GetNoDataValue(&hasNodata);
  const float nodataF = static_cast<float>(nodata);
  float lo = std::numeric_limits<float>::infinity(), hi = -lo;
  for (int y = 0; y < h; ++y) {
    const int srcY = gt[5] > 0 ? h - 1 - y : y;
    for (int x = 0; x < w; ++x) {
      const float v = rows[static_cast<size_t>(srcY) * w + x];
      if (hasNodata && (v == nodataF || (std::isnan(nodata) && std::isnan(v)))) {
        t.valid(x, y) = 0;
        ++info.nodataCells;
        continue;
      }
      if (!std::isfinite(v)) {
        std::ostringstream o;
        o << path << ": height at column " << x << ", row " << srcY << " is " << v
          << " (not finite); mark it NODATA or fix the file";
        throw InputError(o.str());
      }
      t.heightsM(x, y) = v;
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  }
  if (info.nodataCells == t.heightsM.size()) throw InputError(path + ": every cell is NODATA");
  for (size_t i = 0; i < t.heightsM.size(); ++i)
    if (!t.valid.values()[i]) t.heightsM.values()[i] = lo;
  // Vertical unit of projected data (e.g. US feet) when the file declares one.
  if (srs && !srs->IsGeographic() && !srs->IsEmpty()) {
    const double toMetre = srs->GetLinearUnits();
    if (toMetre != 1.0 && toMetre > 0.0)
      for (auto& v : t.heightsM.values()) v = static_cast<float>(v * toMetre);
    lo = static_cast<float>(lo * toMetre);
    hi = static_cast<float>(hi * toMetre);
  }
  info.minElevationM = lo;
  info.maxElevationM = hi;
  return t;
}

Terrain makeBuiltinTerrain(const DefaultTerrainOptions& options) {
  Terrain t;
  t.heightsM = generateDefaultTerrain(options, &t.info.spec);
  t.valid.resize(options.size, options.size, 1);
  t.info.source = "builtin:ridged";
  t.info.driver = "builtin";
  t.info.coordinateSystem = "local (metres)";
  t.info.coordinateDecision = "generated by snowbake";
  t.info.nativeUnit = "metre";
  t.info.nativeCellSizeX = t.info.nativeCellSizeY = options.cellSizeM;
  const auto [lo, hi] = std::minmax_element(t.heightsM.values().begin(), t.heightsM.values().end());
  t.info.minElevationM = *lo;
  t.info.maxElevationM = *hi;
  return t;
}

}  // namespace snow
