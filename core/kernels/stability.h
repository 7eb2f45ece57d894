// Stability changes (paper §5.2): snow moves between the stable and unstable layers at a rate
// interpolated linearly in temperature: -k_w (toward unstable) at T_warm and above, +k_c
// (toward stable) at T_cool, 0 at T_freeze and below. Slope slows both ways as the paper says,
// through g = s / (s + s_U) with s = |grad A| and s_U the unstable critical slope: instability
// grows at g times its rate (slowly on gentle slopes), stability at (1 - g) times (slowly on
// steep ones). Wind loading adds instability where the wind-effect surface's vertical speed
// rises (§5.4): at wind_instability_per_mps2 times max(0, W . grad W_sz). Per cell; the slope
// comes from the SurfaceSlopeKernel snapshot. Mass moves between two layers: the total changes
// only by float rounding.
#pragma once
#include "../hd.h"
#include "../snow_state.h"

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

  SNOW_HD void operator()(int x, int y) const {
    const int i = v.index(x, y);
    if (!v.valid[i]) return;
    const float t = a.seaLevelTemperatureC + v.temperatureBase[i];
    const float slope = v.surfaceSlope[i];
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

}  // namespace snow
