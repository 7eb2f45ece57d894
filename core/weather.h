// The season's weather timeline: keyframes interpolated linearly over days (held constant before
// the first and after the last), plus snowfall periods fixed by the scene.
#pragma once
#include <vector>

namespace snow {

struct WeatherState {
  double seaLevelTemperatureC = 0.0;  // T0
  double windDirectionDeg = 270.0;    // where the wind blows FROM, clockwise from north (270 = westerly)
  double windSpeedMps = 0.0;          // at sea level
  double snowfallIntensity = 1.0;     // multiplier on k_snow during snowfall
};

struct WeatherKeyframe {
  double day = 0.0;
  WeatherState state;
};

struct SnowfallPeriod {
  double startDay = 0.0;
  double endDay = 0.0;
};

struct WeatherTimeline {
  std::vector<WeatherKeyframe> keyframes;  // sorted by day
  // Fixed snowfall periods. When empty, snowfall starts at random (the paper's Poisson default).
  std::vector<SnowfallPeriod> snowfallPeriods;

  WeatherState at(double day) const;
  bool hasWind() const;  // any keyframe with a non-zero wind speed
};

}  // namespace snow
