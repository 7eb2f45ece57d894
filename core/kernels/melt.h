// Melt step (paper §5.2): D(t + dt) = D(t) - f dt * k_melt * max(0, T - T_0melt) (f the scene's
// melt multiplier, 1 without), taken layer by
// layer from the top (powder, unstable, stable, compacted). Per cell, no neighbour writes.
#pragma once
#include "../hd.h"
#include "../snow_state.h"

namespace snow {

struct MeltArgs {
  float dtDays = 0.5f;
  float seaLevelTemperatureC = 0.f;
  float meltRateMPerDayPerC = 0.01f;
  float meltThresholdC = 0.f;
};

struct MeltKernel {
  SnowFieldsView v;
  MeltArgs a;

  // Removes up to `want` from `layer`; returns what was removed.
  SNOW_HD SNOW_INLINE static float take(float& layer, float want) {
    const float removed = minf(layer, want);
    layer = layer - removed;
    return removed;
  }

  SNOW_HD void operator()(int x, int y) const {
    const int i = v.index(x, y);
    v.delta[i] = 0.f;
    if (!v.valid[i]) return;
    const float temperature = a.seaLevelTemperatureC + v.temperatureBase[i];
    const float factor = v.meltFactor ? v.meltFactor[i] : 1.f;  // art direction
    float want = factor * a.dtDays * a.meltRateMPerDayPerC * maxf(0.f, temperature - a.meltThresholdC);
    if (!(want > 0.f)) return;
    float p = v.powder[i], u = v.unstable[i], s = v.stable[i], c = v.compacted[i];
    float removed = 0.f;
    float r = take(p, want); removed += r; want -= r;
    r = take(u, want); removed += r; want -= r;
    r = take(s, want); removed += r; want -= r;
    r = take(c, want); removed += r;
    v.powder[i] = p;
    v.unstable[i] = u;
    v.stable[i] = s;
    v.compacted[i] = c;
    v.delta[i] = -removed;
    v.melted[i] = v.melted[i] + removed;
  }
};

}  // namespace snow
