// Snowfall (paper §5.1): fresh snow on every cell above the rain-snow limit, shared between the
// powder, unstable and stable layers by the slope and the temperature.
//   depth added   = f * dt * k_snow * max(0, A - A_0precip)  (Foehn relation; f the scene's snowfall multiplier, 1 without)
//   powder share  x_p = clamp(k_powdery * (|grad A| - s_c), 0, 1)
//                 s_c = s_c0 + k_sc * max(0, T_0powdery - T)
//   of the rest, unstable share x_U = clamp(k_unstable * (|grad A| - s_U), 0, 1), stable the remainder.
// Per cell, no neighbour writes. The slope comes from the SurfaceSlopeKernel snapshot
// (surface_slope.h) runSnowfall takes just before, because this pass changes A (the TBB executor
// takes it a row at a time, fused with this pass).
// Scratch: surfaceSlope, delta (what each cell's layers gained).
// Mass: adds snow; runSnowfall returns the volume added (m^3) for the season's ledger.
// Backend: SnowBackend::snowfall (ExecBackend runs runSnowfall). Season: SeasonRun::addSnowfall
// (core/season.cpp). Parameters: §5.1's rows of parameterTable (core/parameters.cpp).
#pragma once
#include "../hd.h"
#include "../parameters.h"
#include "../snow_state.h"
#include "../weather.h"
#include "surface_slope.h"

namespace snow {

struct SnowfallArgs {
  float dtDays = 0.5f;
  float seaLevelTemperatureC = 0.f;
  float intensity = 1.f;  // multiplier on k_snow from the weather timeline
  float snowfallRatePerDay = 1e-4f;
  float rainSnowLimitM = 1000.f;
  float powderFromPrecipitation = 5.f;
  float powderCriticalSlopeMin = 0.5f;
  float powderCriticalSlopePerC = 0.05f;
  float powderSlopeTemperatureC = -10.f;
  float unstableFromPrecipitation = 1.f;
  float unstableCriticalSlope = 0.3f;
};

struct SnowfallKernel {
  SnowFieldsView v;
  SnowfallArgs a;

  SNOW_HD void operator()(int x, int y) const { withSlope(x, y, v.surfaceSlope[v.index(x, y)]); }
  // The snowfall at (x, y) given its slope, read from the snapshot or a row of it (TbbExec).
  SNOW_HD void withSlope(int x, int y, float slope) const {
    const int i = v.index(x, y);
    if (!v.valid[i]) {
      v.delta[i] = 0.f;
      return;
    }
    const float altitude = v.surface(i);
    const float factor = v.snowfallFactor ? v.snowfallFactor[i] : 1.f;  // art direction (precipitation map)
    const float added = factor * a.dtDays * a.intensity * a.snowfallRatePerDay * maxf(0.f, altitude - a.rainSnowLimitM);
    if (!(added > 0.f)) {
      v.delta[i] = 0.f;
      return;
    }
    const float temperature = a.seaLevelTemperatureC + v.temperatureBase[i];
    const float criticalSlope =
        a.powderCriticalSlopeMin + a.powderCriticalSlopePerC * maxf(0.f, a.powderSlopeTemperatureC - temperature);
    const float powderShare = clampf(a.powderFromPrecipitation * (slope - criticalSlope), 0.f, 1.f);
    const float unstableShare = clampf(a.unstableFromPrecipitation * (slope - a.unstableCriticalSlope), 0.f, 1.f);
    const float toPowder = powderShare * added;
    const float normal = added - toPowder;
    const float toUnstable = unstableShare * normal;
    const float toStable = normal - toUnstable;
    // Record what the layers actually gained (float sums round), so the mass ledger is exact.
    const float p0 = v.powder[i], u0 = v.unstable[i], s0 = v.stable[i];
    const float p1 = p0 + toPowder, u1 = u0 + toUnstable, s1 = s0 + toStable;
    v.powder[i] = p1;
    v.unstable[i] = u1;
    v.stable[i] = s1;
    v.delta[i] = (p1 - p0) + (u1 - u0) + (s1 - s0);
  }
};

inline SnowfallArgs makeSnowfallArgs(const ModelParameters& p, double dtDays, const WeatherState& w) {
  SnowfallArgs a;
  a.dtDays = static_cast<float>(dtDays);
  a.seaLevelTemperatureC = static_cast<float>(w.seaLevelTemperatureC);
  a.intensity = static_cast<float>(w.snowfallIntensity);
  a.snowfallRatePerDay = static_cast<float>(p.snowfallRatePerDay);
  a.rainSnowLimitM = static_cast<float>(p.rainSnowLimitM);
  a.powderFromPrecipitation = static_cast<float>(p.powderFromPrecipitation);
  a.powderCriticalSlopeMin = static_cast<float>(p.powderCriticalSlopeMin);
  a.powderCriticalSlopePerC = static_cast<float>(p.powderCriticalSlopePerC);
  a.powderSlopeTemperatureC = static_cast<float>(p.powderSlopeTemperatureC);
  a.unstableFromPrecipitation = static_cast<float>(p.unstableFromPrecipitation);
  a.unstableCriticalSlope = static_cast<float>(p.unstableCriticalSlope);
  return a;
}

// The slope snapshot, then the snowfall (the TBB executor fuses them by rows, the slopes in row
// buffers: TbbExec::forEachCellThen, slope_pass_rows.h); returns the volume added (m^3).
template <class Exec>
double runSnowfall(Exec& exec, const SnowFieldsView& v, const SnowfallArgs& a) {
  exec.forEachCellThen(v.width, v.height, SurfaceSlopeKernel{v}, SnowfallKernel{v, a});
  return exec.sum(v.delta, v.valid, v.width, v.height) * static_cast<double>(v.cellSizeXM) * v.cellSizeYM;
}

}  // namespace snow
