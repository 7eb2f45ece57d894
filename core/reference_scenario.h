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

// The avalanche benchmark: 5 m cells, a flat top, a slope of 0.8 over 800 m (rows c - 100 to
// c + 60) and a flat runout, a 200 m square of 2 m of unstable snow released at the centre. The
// same avalanche on any grid size: its cost per step should not depend on the size.
inline SnowState referenceAvalancheState(int size) {
  SnowState s;
  GridSpec spec;
  spec.width = spec.height = size;
  spec.cellSizeXM = spec.cellSizeYM = 5.0;
  s.allocate(spec);
  const int c = size / 2;
  for (int y = 0; y < size; ++y) {
    const int t = y - c < -100 ? -100 : (y - c > 60 ? 60 : y - c);
    for (int x = 0; x < size; ++x) s.bedrockM(x, y) = 2000.f - 0.8f * 5.f * static_cast<float>(t);
  }
  for (int y = c - 20; y < c + 20; ++y)
    for (int x = c - 20; x < c + 20; ++x) s.unstableM(x, y) = 2.f;
  s.temperatureBaseC.fill(-15.f);
  return s;
}

}  // namespace snow
