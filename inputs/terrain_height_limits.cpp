// Heights a terrain may have (inputs/terrain_checks.h): by default the Earth's surface with a
// margin (-12 000 to +10 000 m); terrain.height_limits_m widens it for other planets or units.
#include <sstream>

#include "core/errors.h"
#include "terrain_checks.h"

namespace snow {

void checkHeightLimits(const Terrain& t, const TerrainSource& src) {
  const auto [lo, hi] = src.heightLimitsM;
  if (t.info.minElevationM >= lo && t.info.maxElevationM <= hi) return;
  std::ostringstream o;
  o << t.info.source << ": heights " << t.info.minElevationM << " to " << t.info.maxElevationM << " m"
    << (t.info.heightMapping.empty() ? "" : " (" + t.info.heightMapping + ")") << " leave terrain.height_limits_m = [" << lo << ", "
    << hi << "] m: check the file's units, scale and offset, or widen terrain.height_limits_m";
  throw InputError(o.str());
}

}  // namespace snow
