#include "terrain_loader.h"

#include <gdal_priv.h>
#include <ogr_spatialref.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <iomanip>
#include <sstream>

#include "core/errors.h"
#include "core/util.h"
#include "gdal_support.h"
#include "terrain_checks.h"

namespace snow {

namespace {
constexpr int kMinCellsPerSide = 3;
// What reading a grid holds per cell: the heights and validity (5 bytes) and the reader's
// buffer (a heightmap's pixels as floats, up to four channels). A grid whose reading alone would
// pass 80 % of physical memory is refused before it is read; the whole bake is checked after
// loading by the memory model (bake/memory_model.h), against run.max_memory_gb.
constexpr double kBytesPerCell = 32.0;

}  // namespace

double metresPerDegreeLatitude(double lat) {
  const double p = lat * kPi / 180.0;
  return 111132.92 - 559.82 * std::cos(2 * p) + 1.175 * std::cos(4 * p) - 0.0023 * std::cos(6 * p);
}
double metresPerDegreeLongitude(double lat) {
  const double p = lat * kPi / 180.0;
  return 111412.84 * std::cos(p) - 93.5 * std::cos(3 * p) + 0.118 * std::cos(5 * p);
}

void checkGridSize(const std::string& what, int64_t w, int64_t h) {
  if (w < kMinCellsPerSide || h < kMinCellsPerSide)
    throw InputError(what + ": grid " + std::to_string(w) + " x " + std::to_string(h) + " is too small to simulate (need at least " +
                     std::to_string(kMinCellsPerSide) + " x " + std::to_string(kMinCellsPerSide) + ")");
  const double pages = static_cast<double>(::sysconf(_SC_PHYS_PAGES)), pageSize = static_cast<double>(::sysconf(_SC_PAGESIZE));
  const double available = pages > 0 && pageSize > 0 ? 0.8 * pages * pageSize : 16.0 * (1ull << 30);
  const double needed = static_cast<double>(w) * static_cast<double>(h) * kBytesPerCell;
  if (needed > available || w > (1 << 24) || h > (1 << 24)) {
    std::ostringstream o;
    o << what << ": grid " << w << " x " << h << " needs about " << std::fixed << std::setprecision(1) << needed / (1ull << 30)
      << " GiB to read; this machine has " << available / 0.8 / (1ull << 30)
      << " GiB: resample it (terrain.resample_cell_size_m) or crop it";
    throw InputError(o.str());
  }
}

void updateTerrainStatistics(Terrain& t) {
  float lo = std::numeric_limits<float>::infinity(), hi = -lo;
  size_t nodata = 0;
  for (size_t i = 0; i < t.heightsM.size(); ++i) {
    if (!t.valid.values()[i]) {
      ++nodata;
      continue;
    }
    lo = std::min(lo, t.heightsM.values()[i]);
    hi = std::max(hi, t.heightsM.values()[i]);
  }
  if (nodata == t.heightsM.size()) throw InputError(t.info.source + ": every cell is NODATA");
  for (size_t i = 0; i < t.heightsM.size(); ++i)
    if (!t.valid.values()[i]) t.heightsM.values()[i] = lo;
  t.info.nodataCells = nodata;
  t.info.minElevationM = lo;
  t.info.maxElevationM = hi;
  t.info.spec.width = t.heightsM.width();
  t.info.spec.height = t.heightsM.height();
}

namespace {

GdalDataset openDem(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError(path + ": terrain file does not exist");
  if (std::filesystem::file_size(path, ec) == 0) throw InputError(path + ": terrain file is empty");
  if (isEsriAsciiGrid(path)) checkEsriAsciiGrid(path);  // before GDAL, which reads some hostile grids as others
  GdalDataset ds = openGdalReadOnly(path);
  if (!ds) throw InputError(path + ": cannot read as a terrain: " + lastGdalError());
  if (ds->GetRasterCount() < 1) throw InputError(path + ": has no raster band");
  return ds;
}

// The band that holds the heights: the only one, or terrain.band's.
GDALRasterBand* heightBand(const std::string& path, GDALDataset& ds, int band) {
  const int bands = ds.GetRasterCount();
  if (band == 0 && bands > 1)
    throw InputError(path + ": has " + std::to_string(bands) + " bands: set terrain.band to the one that holds the heights (from 1)");
  if (band > bands) throw InputError(path + ": terrain.band = " + std::to_string(band) + ", but the file has " + std::to_string(bands));
  return ds.GetRasterBand(band == 0 ? 1 : band);
}

// A file with neither a geotransform nor a coordinate system is an image, not a map.
void requireGeoreference(const std::string& path, GDALDataset& ds) {
  double gt[6];
  const OGRSpatialReference* srs = ds.GetSpatialRef();
  if (ds.GetGeoTransform(gt) == CE_None || (srs && !srs->IsEmpty())) return;
  throw InputError(path + ": has no georeference (no geotransform or coordinate system), so no cell size: read it as a heightmap "
                          "with terrain.cell_size_m (metres between pixel centres), and terrain.height_range_m for integer pixels");
}

// Where the file sits in its own coordinates: its geotransform, cell size, corner and centre.
struct DemPlacement {
  double gt[6] = {0, 1, 0, 0, 0, -1};
  bool hasTransform = false;
  double sizeX = 1.0, sizeY = 1.0;  // cell size in the file's units
  double west = 0.0, north = 0.0;   // north-west corner
  double centreX = 0.0, centreY = 0.0;
};

DemPlacement readPlacement(const std::string& path, GDALDataset& ds, int w, int h) {
  DemPlacement p;
  double* gt = p.gt;
  p.hasTransform = ds.GetGeoTransform(gt) == CE_None;
  if (p.hasTransform && (gt[2] != 0.0 || gt[4] != 0.0))
    throw InputError(path + ": rotated or sheared rasters are not supported; warp it north-up first (gdalwarp)");
  p.sizeX = std::abs(gt[1]), p.sizeY = std::abs(gt[5]);
  if (!(p.sizeX > 0.0) || !(p.sizeY > 0.0) || !std::isfinite(p.sizeX) || !std::isfinite(p.sizeY))
    throw InputError(path + ": cell size is zero or invalid");
  p.west = gt[0], p.north = gt[5] < 0 ? gt[3] : gt[3] + gt[5] * h;
  p.centreY = gt[3] + gt[5] * h * 0.5, p.centreX = gt[0] + gt[1] * w * 0.5;
  return p;
}

// A projected coordinate system: cell sizes through its linear unit, the latitude by
// transforming the centre to WGS84 (left unknown when that fails).
void readProjectedCrs(const OGRSpatialReference& srs, const DemPlacement& p, TerrainInfo& info) {
  const char* unitName = nullptr;
  const double toMetre = srs.GetLinearUnits(&unitName);
  info.coordinateSystem = std::string("projected (") + (srs.GetName() ? srs.GetName() : "?") + ", " +
                          (unitName ? unitName : "?") + ")";
  info.coordinateDecision = "read from the file's coordinate system; linear unit " + std::to_string(toMetre) + " m";
  info.nativeUnit = unitName ? unitName : "?";
  info.spec.cellSizeXM = p.sizeX * toMetre;
  info.spec.cellSizeYM = p.sizeY * toMetre;
  OGRSpatialReference wgs84;
  wgs84.SetWellKnownGeogCS("WGS84");
  wgs84.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  std::unique_ptr<OGRCoordinateTransformation> ct(OGRCreateCoordinateTransformation(&srs, &wgs84));
  double lon = p.centreX, lat = p.centreY;
  if (ct && ct->Transform(1, &lon, &lat)) {
    info.latitudeKnown = true;
    info.centreLatitudeDeg = lat;
  }
}

// The file's own coordinate system decides; returns whether it is geographic.
bool readFileCrs(const OGRSpatialReference& srs, const DemPlacement& p, TerrainInfo& info) {
  if (!srs.IsGeographic()) {
    readProjectedCrs(srs, p, info);
    return false;
  }
  info.coordinateSystem = std::string("geographic (") + (srs.GetName() ? srs.GetName() : "degrees") + ")";
  info.coordinateDecision = "read from the file's coordinate system";
  return true;
}

void takeCellSizeAsMetres(const DemPlacement& p, TerrainInfo& info) {
  info.spec.cellSizeXM = p.sizeX;
  info.spec.cellSizeYM = p.sizeY;
}

// No coordinate system: the scene's terrain.coordinates decides, else degrees if the numbers
// only make sense as degrees, else metres. Returns whether it is geographic.
bool chooseCoordinatesWithoutCrs(TerrainCoordinates coordinates, const DemPlacement& p, int w, int h, TerrainInfo& info) {
  const double east = p.west + p.sizeX * w, south = p.north - p.sizeY * h;
  const bool looksLikeDegrees = p.sizeX < 0.1 && p.sizeY < 0.1 && p.west >= -180.0 && east <= 180.0 && south >= -90.0 &&
                                p.north <= 90.0 && p.hasTransform;
  if (coordinates == TerrainCoordinates::Geographic) {
    info.coordinateSystem = "none in the file; geographic (degrees) as the scene says";
    info.coordinateDecision = "terrain.coordinates = \"geographic\"";
    return true;
  }
  if (coordinates == TerrainCoordinates::Metres) {
    info.coordinateSystem = "none in the file; metres as the scene says";
    info.coordinateDecision = "terrain.coordinates = \"metres\"";
    info.nativeUnit = "metre";
    takeCellSizeAsMetres(p, info);
    return false;
  }
  if (looksLikeDegrees) {
    info.coordinateSystem = "none in the file; treated as geographic (degrees)";
    std::ostringstream o;
    o << "no coordinate system, but a cell size of " << p.sizeX << " and an extent inside longitude/latitude bounds only make "
      << "sense as degrees (set terrain.coordinates = \"metres\" if they are metres)";
    info.coordinateDecision = o.str();
    return true;
  }
  info.coordinateSystem = "none in the file; treated as metres";
  info.coordinateDecision = "no coordinate system; cell size taken as metres";
  info.nativeUnit = "metre (assumed)";
  takeCellSizeAsMetres(p, info);
  return false;
}

// Geographic cells in metres at the centre's latitude.
void setGeographicCellSize(const DemPlacement& p, TerrainInfo& info) {
  info.nativeUnit = "degree";
  info.latitudeKnown = true;
  info.centreLatitudeDeg = p.centreY;
  info.spec.cellSizeXM = p.sizeX * metresPerDegreeLongitude(p.centreY);
  info.spec.cellSizeYM = p.sizeY * metresPerDegreeLatitude(p.centreY);
}

// Decides the units and fills the grid spec of `info` from the file's georeference.
void describeDemCoordinates(const std::string& path, GDALDataset& ds, const DemPlacement& p, TerrainCoordinates coordinates,
                            TerrainInfo& info) {
  const OGRSpatialReference* srs = ds.GetSpatialRef();
  const bool hasSrs = srs && !srs->IsEmpty();
  if (hasSrs && coordinates != TerrainCoordinates::Auto)
    throw InputError(path + ": terrain.coordinates = \"" + enumName(coordinates) +
                     "\" only applies to files without a coordinate system; this one has " +
                     (srs->GetName() ? srs->GetName() : "one"));
  const int w = info.nativeWidth, h = info.nativeHeight;
  const bool geographic = hasSrs ? readFileCrs(*srs, p, info) : chooseCoordinatesWithoutCrs(coordinates, p, w, h, info);
  if (geographic) setGeographicCellSize(p, info);
  info.spec.width = w;
  info.spec.height = h;
  info.spec.originX = p.west;
  info.spec.originY = p.north;
  info.georeferenced = p.hasTransform;
  info.geoCellX = p.sizeX;
  info.geoCellY = p.sizeY;
  info.crsWkt = crsWktOf(ds);
}

// Vertical unit of projected data (e.g. US feet) when the file declares one.
double verticalUnitToMetre(GDALDataset& ds) {
  const OGRSpatialReference* srs = ds.GetSpatialRef();
  const bool hasSrs = srs && !srs->IsEmpty();
  return hasSrs && !srs->IsGeographic() && srs->GetLinearUnits() > 0.0 ? srs->GetLinearUnits() : 1.0;
}

// GDAL's scale and offset of a band (value = offset + scale x stored), when it has them.
struct BandScaling {
  bool given = false;
  double scale = 1.0, offset = 0.0;
};

BandScaling bandScaling(const std::string& path, GDALRasterBand& band) {
  int hasScale = 0, hasOffset = 0;
  BandScaling b;
  const double scale = band.GetScale(&hasScale), offset = band.GetOffset(&hasOffset);
  if (hasScale) b.scale = scale;
  if (hasOffset) b.offset = offset;
  if (!std::isfinite(b.scale) || !std::isfinite(b.offset) || b.scale == 0.0)
    throw InputError(path + ": the band's scale or offset is zero or not finite");
  b.given = b.scale != 1.0 || b.offset != 0.0;
  return b;
}

// The band into t.heightsM (metres, north-up) and t.valid (0 where NODATA).
void readDemHeights(const std::string& path, GDALDataset& ds, GDALRasterBand& band, const DemPlacement& p, Terrain& t) {
  const int w = t.info.nativeWidth, h = t.info.nativeHeight;
  t.heightsM.resize(w, h);
  t.valid.resize(w, h, 1);
  std::vector<float> rows(static_cast<size_t>(w) * h);
  CPLErrorReset();
  if (band.RasterIO(GF_Read, 0, 0, w, h, rows.data(), w, h, GDT_Float32, 0, 0) != CE_None)
    throw InputError(path + ": read failed (truncated or corrupt?): " + lastGdalError());
  int hasNodata = 0;
  const double nodata = band.GetNoDataValue(&hasNodata);
  const float nodataF = static_cast<float>(nodata);
  const double verticalToMetre = verticalUnitToMetre(ds);
  const BandScaling scaling = bandScaling(path, band);
  if (scaling.given) {
    std::ostringstream o;
    o << "height = " << scaling.offset << " + " << scaling.scale << " x stored value (the band's GDAL offset and scale)";
    t.info.heightMapping = o.str();
  }
  for (int y = 0; y < h; ++y) {
    const int srcY = p.gt[5] > 0 ? h - 1 - y : y;  // north-up: flip south-up rasters
    for (int x = 0; x < w; ++x) {
      const float v = rows[static_cast<size_t>(srcY) * w + x];
      if (hasNodata && (v == nodataF || (std::isnan(nodata) && std::isnan(v)))) {
        t.valid(x, y) = 0;
        continue;
      }
      if (!std::isfinite(v)) {
        std::ostringstream o;
        o << path << ": height at column " << x << ", row " << srcY << " is " << v << " (not finite); mark it NODATA or fix the file";
        throw InputError(o.str());
      }
      // Without a scale and offset the value is used as read (the same bytes as before they were read).
      const double stored = scaling.given ? scaling.offset + scaling.scale * static_cast<double>(v) : v;
      t.heightsM(x, y) = static_cast<float>(stored * verticalToMetre);
    }
  }
}

}  // namespace

Terrain loadDem(const std::string& path, TerrainCoordinates coordinates, int bandNumber) {
  const GdalDataset ds = openDem(path);
  GDALRasterBand* band = heightBand(path, *ds, bandNumber);
  requireGeoreference(path, *ds);
  const int w = ds->GetRasterXSize(), h = ds->GetRasterYSize();
  checkGridSize(path, w, h);

  Terrain t;
  TerrainInfo& info = t.info;
  info.source = path;
  info.format = "dem";
  info.nativeWidth = w;
  info.nativeHeight = h;
  info.driver = ds->GetDriver() ? ds->GetDriver()->GetDescription() : "?";

  const DemPlacement placement = readPlacement(path, *ds, w, h);
  info.nativeCellSizeX = placement.sizeX;
  info.nativeCellSizeY = placement.sizeY;
  describeDemCoordinates(path, *ds, placement, coordinates, info);
  readDemHeights(path, *ds, *band, placement, t);
  updateTerrainStatistics(t);
  return t;
}

bool hasGeoreference(const std::string& path) {
  const GdalDataset ds = openGdalReadOnly(path);
  if (!ds) return false;
  double gt[6];
  const OGRSpatialReference* srs = ds->GetSpatialRef();
  return ds->GetGeoTransform(gt) == CE_None || (srs && !srs->IsEmpty());
}

Terrain makeBuiltinTerrain(const DefaultTerrainOptions& options) {
  Terrain t;
  t.heightsM = generateDefaultTerrain(options, &t.info.spec);
  t.valid.resize(options.size, options.size, 1);
  t.info.source = "builtin:ridged";
  t.info.format = "builtin";
  t.info.nativeWidth = t.info.nativeHeight = options.size;
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

namespace snow {

TerrainFormat detectTerrainFormat(const TerrainSource& src) {
  if (src.builtin) return TerrainFormat::Builtin;
  if (src.format != TerrainFormat::Auto) return src.format;
  std::string ext = std::filesystem::path(src.file).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".r16" || ext == ".r32" || ext == ".raw") return TerrainFormat::Raw;
  if (ext == ".png" || ext == ".exr") return TerrainFormat::Heightmap;
  if (ext == ".obj" || ext == ".gltf" || ext == ".glb" || ext == ".fbx" || ext == ".ply" || ext == ".stl" || ext == ".dae")
    return TerrainFormat::Mesh;
  if ((ext == ".tif" || ext == ".tiff") && src.hasHeightmapKeys()) return TerrainFormat::Heightmap;
  return TerrainFormat::Dem;
}

Terrain loadTerrain(const TerrainSource& src) {
  const TerrainFormat format = detectTerrainFormat(src);
  Terrain t;
  if (format == TerrainFormat::Builtin) {
    t = makeBuiltinTerrain(src.builtinOptions);
  } else if (format == TerrainFormat::Dem && src.cellSizeM && src.format == TerrainFormat::Auto && !hasGeoreference(src.file)) {
    t = loadHeightmapImage(src);  // an image without georeference: the scene gives its cell size
  } else if (format == TerrainFormat::Dem) {
    if (src.cellSizeM)
      throw InputError(src.file + ": a DEM carries its own cell size: use terrain.resample_cell_size_m to bake at another one");
    if (src.hasHeightmapKeys())
      throw InputError(src.file + ": terrain.height_range_m/height_scale_m apply to heightmaps; set terrain.format = \"heightmap\"");
    t = loadDem(src.file, src.coordinates, src.band);
  } else if (format == TerrainFormat::Heightmap) {
    t = loadHeightmapImage(src);
  } else if (format == TerrainFormat::Raw) {
    t = loadRawHeightmap(src);
  } else if (format == TerrainFormat::Mesh) {
    t = loadMeshTerrain(src);
  } else {
    throw InputError(src.file + ": unknown terrain.format '" + enumName(format) + "'");
  }
  checkHeightLimits(t, src);
  if (src.fillNodata && t.info.nodataCells > 0) fillNodata(t);
  if (src.cropM) t = cropTerrain(t, src);
  if (src.resampleCellSizeM || src.resampleSize) t = resampleTerrain(t, src);
  return t;
}

}  // namespace snow
