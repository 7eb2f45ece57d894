// The benchmark scenario shared by `snowbake bench` and the GPU test binary, so CPU and GPU
// figures are for the same work: the embedded range over a 10.24 km square at any grid size,
// a 120-day winter warming from 3 to 14 degC at sea level, the paper's event rates.
#pragma once
#include "default_terrain.h"
#include "season.h"

namespace snow {

inline SnowState referenceRangeState(int size, double extentM = 10240.0) {
  DefaultTerrainOptions o;
  o.size = size;
  o.cellSizeM = extentM / size;
  GridSpec spec;
  Grid<float> heights = generateDefaultTerrain(o, &spec);
  SnowState s;
  s.allocate(spec);
  s.bedrockM = heights;
  return s;
}

inline SeasonConfig referenceWinter(double days = 120.0) {
  SeasonConfig c;
  c.days = days;
  c.seed = 11;
  c.params.rainSnowLimitM = 1200.0;
  WeatherKeyframe a, b;
  a.state.seaLevelTemperatureC = 3.0;
  b.day = days;
  b.state.seaLevelTemperatureC = 14.0;
  c.weather.keyframes = {a, b};
  return c;
}

}  // namespace snow
