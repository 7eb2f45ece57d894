// Terrain input: a height field in metres with its NODATA mask, from a DEM (anything GDAL opens),
// a heightmap image (OpenImageIO), a raw .r16/.r32 file, a mesh (assimp), or the embedded
// generator. Degrees become metric cell sizes at the grid's latitude, x and y separately.
// Every failure is an InputError naming the file and the problem, raised before anything is
// written.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "core/default_terrain.h"
#include "core/grid.h"
#include "scene/terrain_source.h"

namespace snow {

struct TerrainInfo {
  std::string source;            // file path or "builtin:ridged"
  std::string format;            // dem | heightmap | raw | mesh | builtin
  std::string driver;            // GDAL driver, OIIO format, assimp importer, "raw" or "builtin"
  GridSpec spec;                 // metric cell sizes (after any resampling)
  size_t nodataCells = 0;        // cells masked out of the simulation
  size_t filledCells = 0;        // NODATA cells filled on request (terrain.fill_nodata)
  float minElevationM = 0.f, maxElevationM = 0.f;
  std::string coordinateSystem;   // e.g. "geographic (WGS 84)", "projected (..., metre)", "none"
  std::string coordinateDecision; // how snowbake decided (what it read, or why it assumed)
  double nativeCellSizeX = 0, nativeCellSizeY = 0;  // in the source's own units
  std::string nativeUnit;         // "degree", "metre", ...
  int nativeWidth = 0, nativeHeight = 0;
  std::string heightMapping;      // heightmaps, raw: how pixel values became metres
  std::string resampling;         // empty, or what was done (filter, from, to)
  // Georeference (DEMs with a geotransform): cell (i, j)'s centre lies at
  // (spec.originX + (i + 0.5) geoCellX, spec.originY - (j + 0.5) geoCellY) in the file's own
  // coordinates (crsWkt, empty when the file names none). Painted masks map by it.
  bool georeferenced = false;
  double geoCellX = 0, geoCellY = 0;
  std::string crsWkt;
  bool latitudeKnown = false;
  double centreLatitudeDeg = 0.0;
};

struct Terrain {
  Grid<float> heightsM;   // NODATA cells hold the lowest valid height (never NaN)
  Grid<uint8_t> valid;    // 0 where the source had NODATA (or a mesh had no surface)
  TerrainInfo info;
};

// What terrain.format "auto" resolves to for a path (Builtin for terrain.builtin; never Auto).
TerrainFormat detectTerrainFormat(const TerrainSource& source);

// Reads the terrain the source describes, fills or masks NODATA, resamples if asked.
Terrain loadTerrain(const TerrainSource& source);

// `band` from 1; 0 when the file must have a single band. A file without georeference is refused
// (it is an image: a heightmap with terrain.cell_size_m).
Terrain loadDem(const std::string& path, TerrainCoordinates coordinates = TerrainCoordinates::Auto, int band = 0);
// Whether GDAL reads a geotransform or a coordinate system in the file (false when it cannot open it).
bool hasGeoreference(const std::string& path);
Terrain loadHeightmapImage(const TerrainSource& source);
Terrain loadRawHeightmap(const TerrainSource& source);
Terrain loadMeshTerrain(const TerrainSource& source);
Terrain makeBuiltinTerrain(const DefaultTerrainOptions& options);

// Fills NODATA cells from their valid neighbours (rings inward, then smoothed); returns the count.
size_t fillNodata(Terrain& terrain);
// Keeps the cells whose centres lie in source.cropM (metres east and south of the north-west
// corner); throws InputError naming the key and the terrain's extent when nothing is left.
Terrain cropTerrain(const Terrain& terrain, const TerrainSource& source);
// Resamples to a cell size or a grid size (filters documented in docs/terrain.md).
Terrain resampleTerrain(const Terrain& terrain, const TerrainSource& source);

// Throws InputError when a width x height grid would not fit in this machine's memory
// (or is too small to simulate).
void checkGridSize(const std::string& what, int64_t width, int64_t height);

// Metres per degree of latitude and of longitude at a latitude (WGS84 series).
double metresPerDegreeLatitude(double latitudeDeg);
double metresPerDegreeLongitude(double latitudeDeg);

// Lowest/highest valid height, NODATA count: recomputed after any change to the grid.
void updateTerrainStatistics(Terrain& terrain);

}  // namespace snow
