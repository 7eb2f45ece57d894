// Checks that refuse a hostile terrain file before anything is baked: the text of an ESRI ASCII
// grid (every header value and height a finite number, positive cell sizes, as many heights as
// the header says), and heights outside terrain.height_limits_m after any scale and offset.
// Each throws InputError naming the file (and the line, for text).
#pragma once
#include <string>

#include "terrain_loader.h"

namespace snow {

// An ESRI ASCII grid (.asc) read as text: GDAL reads a `nan` in an integer grid as 0 and a
// negative cellsize as another grid, so the text is checked before GDAL reads it.
void checkEsriAsciiGrid(const std::string& path);
// Whether the file starts as an ESRI ASCII grid does (its first word a header key).
bool isEsriAsciiGrid(const std::string& path);

// Every valid height within source.heightLimitsM (metres, after scale and offset).
void checkHeightLimits(const Terrain& terrain, const TerrainSource& source);

}  // namespace snow
