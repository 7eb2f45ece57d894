// Stability change (paper §5.2): snow moves between the stable and unstable layers at a rate
// interpolated linearly in temperature: -k_w (toward unstable) at T_warm and above, +k_c
// (toward stable) at T_cool, 0 at T_freeze and below. Slope slows both ways as the paper says,
// through g = s / (s + s_U) with s = |grad A| and s_U the unstable critical slope: instability
// grows at g times its rate (slowly on gentle slopes), stability at (1 - g) times (slowly on
// steep ones). Wind loading adds instability where the wind-effect surface's vertical speed
// rises (§5.4): at wind_instability_per_mps2 times max(0, W . grad W_sz). Per cell, no neighbour
// writes; the slope comes from the SurfaceSlopeKernel snapshot (surface_slope.h) runStability
// takes just before (the TBB executor takes it a row at a time, fused with this pass).
// Scratch: surfaceSlope.
// Mass: moves snow between two layers only; the total changes only by float rounding.
// Backend: SnowBackend::stabilityChange (ExecBackend runs runStability). Season:
// SeasonRun::addStateChanges (core/season.cpp), which skips days colder than T_freeze without
// wind loading. Parameters: the §5.2 block of ModelParameters (core/parameters.h; scene keys in
// parameterTable, parameters.cpp), and wind_instability_per_mps2 in the §5.3/§5.4 block.
#pragma once
#include "../hd.h"
#include "../parameters.h"
#include "../snow_state.h"
#include "../weather.h"
#include "surface_slope.h"

namespace snow {

struct StabilityArgs {
  float dtDays = 0.5f;
  float seaLevelTemperatureC = 0.f;
  float warmTemperatureC = 5.f;
  float coolTemperatureC = -5.f;
  float freezeTemperatureC = -20.f;
  float instabilityByWarmthMPerDay = 1e4f;
  float stabilityByColdMPerDay = 1e4f;
  float unstableCriticalSlope = 0.3f;
  float windInstabilityPerMps2 = 0.f;  // m of snow per day per m/s^2 of wind loading
};

// Signed rate in m/day: > 0 stabilises (U -> S), < 0 destabilises (S -> U).
SNOW_HD SNOW_INLINE float stabilityRate(const StabilityArgs& a, float t) {
  if (t <= a.freezeTemperatureC) return 0.f;
  if (t <= a.coolTemperatureC) return a.stabilityByColdMPerDay * (t - a.freezeTemperatureC) / (a.coolTemperatureC - a.freezeTemperatureC);
  if (t < a.warmTemperatureC) {
    const float u = (t - a.coolTemperatureC) / (a.warmTemperatureC - a.coolTemperatureC);
    return a.stabilityByColdMPerDay * (1.f - u) - a.instabilityByWarmthMPerDay * u;
  }
  return -a.instabilityByWarmthMPerDay;
}

struct StabilityKernel {
  SnowFieldsView v;
  StabilityArgs a;

  SNOW_HD void operator()(int x, int y) const { withSlope(x, y, v.surfaceSlope[v.index(x, y)]); }
  // The change at (x, y) given its slope, read from the snapshot or a row of it (TbbExec).
  SNOW_HD void withSlope(int x, int y, float slope) const {
    const int i = v.index(x, y);
    if (!v.valid[i]) return;
    const float t = a.seaLevelTemperatureC + v.temperatureBase[i];
    const float g = slope / (slope + a.unstableCriticalSlope + 1e-12f);
    float rate = stabilityRate(a, t);
    rate = rate > 0.f ? rate * (1.f - g) : rate * g;
    rate -= a.windInstabilityPerMps2 * v.windLoading[i];
    const float s0 = v.stable[i], u0 = v.unstable[i];
    if (rate > 0.f) {
      const float moved = minf(u0, rate * a.dtDays);
      v.unstable[i] = u0 - moved;
      v.stable[i] = s0 + moved;
    } else if (rate < 0.f) {
      const float moved = minf(s0, -rate * a.dtDays);
      v.stable[i] = s0 - moved;
      v.unstable[i] = u0 + moved;
    }
  }
};

inline StabilityArgs makeStabilityArgs(const ModelParameters& p, double dtDays, const WeatherState& w) {
  StabilityArgs a;
  a.dtDays = static_cast<float>(dtDays);
  a.seaLevelTemperatureC = static_cast<float>(w.seaLevelTemperatureC);
  a.warmTemperatureC = static_cast<float>(p.warmTemperatureC);
  a.coolTemperatureC = static_cast<float>(p.coolTemperatureC);
  a.freezeTemperatureC = static_cast<float>(p.freezeTemperatureC);
  a.instabilityByWarmthMPerDay = static_cast<float>(p.instabilityByWarmthMPerDay);
  a.stabilityByColdMPerDay = static_cast<float>(p.stabilityByColdMPerDay);
  a.unstableCriticalSlope = static_cast<float>(p.unstableCriticalSlope);
  a.windInstabilityPerMps2 = static_cast<float>(p.windInstabilityPerMps2);
  return a;
}

// The slope snapshot, then the stability change (the TBB executor fuses them by rows, the
// slopes in row buffers: TbbExec::forEachCellThen, slope_pass_rows.h).
template <class Exec>
void runStability(Exec& exec, const SnowFieldsView& v, const StabilityArgs& a) {
  exec.forEachCellThen(v.width, v.height, SurfaceSlopeKernel{v}, StabilityKernel{v, a});
}

}  // namespace snow
