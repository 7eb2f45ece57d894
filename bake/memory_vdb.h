// The memory model's VDB term (memory_model.h, docs/memory.md): OpenVDB leaves of 8^3 voxels over
// the columns that hold a voxel of snow on the day written. A voxel exists where its centre lies
// in the snow, so at voxels coarser than the snow is deep only some columns hold one, and a
// leaf's 512 values are allocated as soon as one of its 64 columns does. The snow of a day is
// estimated from the scene before the season: the expected snowfall (its fixed periods, or the
// Poisson on/off process of the scheduler) times k_snow over the terrain above the rain-snow
// limit, melt left out.
#pragma once
#include "core/default_terrain.h"
#include "core/grid.h"
#include "scene/scene.h"

namespace snow {

// Where snow can fall: the share of the grid's cells that are valid and above
// parameters.rain_snow_limit_m, and their mean height above it. Unknown: every column snowed.
struct SnowReach {
  bool known = false;
  double share = 1.0;
  double meanExcessM = 0.0;
};
SnowReach snowReachOf(const Grid<float>& heightsM, const Grid<uint8_t>& valid, double rainSnowLimitM);
// The builtin terrain's, from the same mountains sampled at 256² over the same extent.
SnowReach builtinSnowReach(const DefaultTerrainOptions& terrain, double rainSnowLimitM);

// Days of snowfall expected in [0, day): the fixed periods' overlap (weather.snowfall), else the
// scheduler's Poisson process starting dry (start rate a, stop rate b):
// a/(a+b) (t - (1 - e^{-(a+b)t})/(a+b)); plus the scene's snowfall events.
double expectedSnowfallDays(const Scene& s, double day);

// Bytes the VDB writer holds at its peak for the snow of `day` on a grid of `spec`.
double vdbWriterBytes(const Scene& s, const GridSpec& spec, const SnowReach& reach, double day);

}  // namespace snow
