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

// The avalanche benchmark: a flat top, a slope of 0.8 over 800 m (from 500 m before the grid's
// centre row to 300 m after it) and a flat runout, a 200 m square of 2 m of unstable snow released
// at the centre; 5 m cells, or `cellM` (a divisor of 100 m) for the same avalanche on a coarser or
// finer grid. The same avalanche on any grid size: its cost per step should not depend on the size.
inline SnowState referenceAvalancheState(int size, double cellM = 5.0) {
  SnowState s;
  GridSpec spec;
  spec.width = spec.height = size;
  spec.cellSizeXM = spec.cellSizeYM = cellM;
  s.allocate(spec);
  const int c = size / 2;
  const int top = static_cast<int>(500.0 / cellM), foot = static_cast<int>(300.0 / cellM), half = static_cast<int>(100.0 / cellM);
  for (int y = 0; y < size; ++y) {
    const int t = y - c < -top ? -top : (y - c > foot ? foot : y - c);
    for (int x = 0; x < size; ++x) s.bedrockM(x, y) = 2000.f - 0.8f * static_cast<float>(cellM) * static_cast<float>(t);
  }
  for (int y = c - half; y < c + half; ++y)
    for (int x = c - half; x < c + half; ++x) s.unstableM(x, y) = 2.f;
  s.temperatureBaseC.fill(-15.f);
  return s;
}

}  // namespace snow
