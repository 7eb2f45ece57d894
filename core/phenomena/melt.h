// Melt (paper §5.2): snow melts where the cell's temperature is above the melt threshold,
//   D(t + dt) = D(t) - f dt * k_melt * max(0, T - T_0melt)   (f the scene's melt multiplier, 1 without)
// taken layer by layer from the top (powder, unstable, stable, compacted), and recorded in the
// meltedM field for the bakers. Per cell, no neighbour writes. T = T0 (the day's sea-level
// temperature) + the static temperatureBase (core/season.h: computeTemperatureBase).
// Scratch: delta (what each cell lost, negative).
// Mass: removes snow; runMelt returns the volume removed (negative, m^3) for the season's ledger.
// Backend: SnowBackend::melt (ExecBackend runs runMelt). Season: SeasonRun::addStateChanges
// (core/season.cpp), which skips days when no cell can melt. Parameters: the §5.2
// block of ModelParameters (core/parameters.h; scene keys in parameterTable, parameters.cpp).
#pragma once
#include "../hd.h"
#include "../parameters.h"
#include "../snow_state.h"
#include "../weather.h"

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
    if (v.melted) v.melted[i] = v.melted[i] + removed;  // null when no output reads it
  }
};

inline MeltArgs makeMeltArgs(const ModelParameters& p, double dtDays, const WeatherState& w) {
  MeltArgs a;
  a.dtDays = static_cast<float>(dtDays);
  a.seaLevelTemperatureC = static_cast<float>(w.seaLevelTemperatureC);
  a.meltRateMPerDayPerC = static_cast<float>(p.meltRateMPerDayPerC);
  a.meltThresholdC = static_cast<float>(p.meltThresholdC);
  return a;
}

// Returns the volume the melt removed (negative, m^3).
template <class Exec>
double runMelt(Exec& exec, const SnowFieldsView& v, const MeltArgs& a) {
  exec.forEachCell(v.width, v.height, MeltKernel{v, a});
  return exec.sum(v.delta, v.valid, v.width, v.height) * static_cast<double>(v.cellSizeXM) * v.cellSizeYM;
}

}  // namespace snow
