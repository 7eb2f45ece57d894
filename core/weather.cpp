#include "weather.h"

#include <cmath>

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
  if (day <= keyframes.front().day) return keyframes.front().state;
  if (day >= keyframes.back().day) return keyframes.back().state;
  for (size_t i = 1; i < keyframes.size(); ++i) {
    const auto& k0 = keyframes[i - 1];
    const auto& k1 = keyframes[i];
    if (day <= k1.day) {
      const double t = k1.day > k0.day ? (day - k0.day) / (k1.day - k0.day) : 1.0;
      WeatherState s;
      s.seaLevelTemperatureC = lerp(k0.state.seaLevelTemperatureC, k1.state.seaLevelTemperatureC, t);
      s.windDirectionDeg = lerpAngleDeg(k0.state.windDirectionDeg, k1.state.windDirectionDeg, t);
      s.windSpeedMps = lerp(k0.state.windSpeedMps, k1.state.windSpeedMps, t);
      s.snowfallIntensity = lerp(k0.state.snowfallIntensity, k1.state.snowfallIntensity, t);
      return s;
    }
  }
  return keyframes.back().state;
}

bool WeatherTimeline::hasWind() const {
  for (const auto& k : keyframes)
    if (k.state.windSpeedMps > 0.0) return true;
  return false;
}

}  // namespace snow
