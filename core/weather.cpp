#include "weather.h"

#include <cmath>

#include "bracket.h"

namespace snow {

namespace {
double lerp(double a, double b, double t) { return a + (b - a) * t; }
// Shortest way round the compass, so 350 -> 10 passes through 0, not 180.
double lerpAngleDeg(double a, double b, double t) {
  double d = std::fmod(b - a, 360.0);
  if (d > 180.0) d -= 360.0;
  if (d < -180.0) d += 360.0;
  double r = std::fmod(a + d * t, 360.0);
  return r < 0 ? r + 360.0 : r;
}
}  // namespace

WeatherState WeatherTimeline::at(double day) const {
  if (keyframes.empty()) return WeatherState{};
  const Bracket b = bracketOf(keyframes.size(), day, [&](size_t i) { return keyframes[i].day; });
  const WeatherState& s0 = keyframes[b.first].state;
  const WeatherState& s1 = keyframes[b.second].state;
  const double t = b.weight;
  WeatherState s;
  s.seaLevelTemperatureC = lerp(s0.seaLevelTemperatureC, s1.seaLevelTemperatureC, t);
  s.windDirectionDeg = lerpAngleDeg(s0.windDirectionDeg, s1.windDirectionDeg, t);
  s.windSpeedMps = lerp(s0.windSpeedMps, s1.windSpeedMps, t);
  s.snowfallIntensity = lerp(s0.snowfallIntensity, s1.snowfallIntensity, t);
  return s;
}

bool WeatherTimeline::hasWind() const {
  for (const auto& k : keyframes)
    if (k.state.windSpeedMps > 0.0) return true;
  return false;
}

}  // namespace snow
