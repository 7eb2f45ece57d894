#include "stability_study.h"

#include "cpu_backend.h"
#include "snow_state.h"

namespace snow {

namespace {

// Runs the stability change on the plane until the centre's `layer` is half its start.
template <class Layer>
StabilityOutcome halfLife(const ModelParameters& p, double temperatureC, double slope, double stableM, double unstableM,
                          double horizonDays, Layer layer) {
  GridSpec spec;
  spec.width = spec.height = 9;
  spec.cellSizeXM = spec.cellSizeYM = 5.0;
  SnowState s;
  s.allocate(spec);
  for (int y = 0; y < spec.height; ++y)
    for (int x = 0; x < spec.width; ++x) s.bedrockM(x, y) = static_cast<float>(2000.0 - slope * 5.0 * x);
  s.stableM.fill(static_cast<float>(stableM));
  s.unstableM.fill(static_cast<float>(unstableM));
  auto backend = createCpuBackend();
  backend->upload(s);
  WeatherState w;
  w.seaLevelTemperatureC = temperatureC;  // temperatureBase is 0: the cell's temperature
  const double dt = 1.0 / p.stateChangeStepsPerDay;
  const double start = layer(s);
  StabilityOutcome r;
  for (double t = dt; t <= horizonDays + 1e-9; t += dt) {
    backend->stabilityChange(makeStabilityArgs(p, dt, w));
    backend->download(s);
    if (layer(s) <= 0.5 * start) {
      r.days = t, r.reached = true;
      return r;
    }
  }
  r.days = horizonDays;
  return r;
}

}  // namespace

StabilityOutcome unstableHalfLife(const ModelParameters& p, double temperatureC, double slope, double unstableM, double horizonDays) {
  return halfLife(p, temperatureC, slope, unstableM, unstableM, horizonDays, [](const SnowState& s) { return s.unstableM(4, 4); });
}

StabilityOutcome stableHalfLife(const ModelParameters& p, double temperatureC, double slope, double stableM, double horizonDays) {
  return halfLife(p, temperatureC, slope, stableM, 0.0, horizonDays, [](const SnowState& s) { return s.stableM(4, 4); });
}

}  // namespace snow
