// Terrain input: a height field in metres with its NODATA mask, from a DEM (anything GDAL
// opens) or from the embedded generator. Coordinates in degrees become metric cell sizes at the
// grid's latitude, x and y separately.
#pragma once
#include <cstdint>
#include <string>

#include "core/default_terrain.h"
#include "core/grid.h"

namespace snow {

struct TerrainInfo {
  std::string source;            // file path or "builtin:ridged"
  std::string driver;            // GDAL driver short name, or "builtin"
  GridSpec spec;                 // metric cell sizes
  size_t nodataCells = 0;
  float minElevationM = 0.f, maxElevationM = 0.f;
  std::string coordinateSystem;  // e.g. "geographic (degrees)", "projected (metre)", "none"
  std::string coordinateDecision;// how snowbake decided (what it read, or why it assumed)
  double nativeCellSizeX = 0, nativeCellSizeY = 0;  // in the file's own units
  std::string nativeUnit;        // "degree", "metre", ...
  bool latitudeKnown = false;
  double centreLatitudeDeg = 0.0;
};

struct Terrain {
  Grid<float> heightsM;   // NODATA cells hold the lowest valid height (never NaN)
  Grid<uint8_t> valid;    // 0 where the source had NODATA
  TerrainInfo info;
};

// Throws InputError naming the file and the problem (unreadable, empty, NaN heights, too small,
// too large, rotated geotransform, all NODATA).
Terrain loadTerrainFile(const std::string& path);
Terrain makeBuiltinTerrain(const DefaultTerrainOptions& options);

// Metres per degree of latitude and of longitude at a latitude (WGS84 series).
double metresPerDegreeLatitude(double latitudeDeg);
double metresPerDegreeLongitude(double latitudeDeg);

}  // namespace snow
