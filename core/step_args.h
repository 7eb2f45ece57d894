// Kernel arguments built from the model parameters and the weather of the moment.
#pragma once
#include "kernels/melt.h"
#include "kernels/powder_diffusion.h"
#include "kernels/snowfall.h"
#include "parameters.h"
#include "weather.h"

namespace snow {

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

inline MeltArgs makeMeltArgs(const ModelParameters& p, double dtDays, const WeatherState& w) {
  MeltArgs a;
  a.dtDays = static_cast<float>(dtDays);
  a.seaLevelTemperatureC = static_cast<float>(w.seaLevelTemperatureC);
  a.meltRateMPerDayPerC = static_cast<float>(p.meltRateMPerDayPerC);
  a.meltThresholdC = static_cast<float>(p.meltThresholdC);
  return a;
}

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

inline WindTransportArgs makeWindTransportArgs(const ModelParameters& p, double dtDays) {
  WindTransportArgs a;
  a.dtDays = static_cast<float>(dtDays);
  a.erosionRate = static_cast<float>(p.windErosionRateMPerSPerDay);
  a.shadowToleranceM = static_cast<float>(p.windShadowToleranceM);
  return a;
}

inline PowderDiffusionArgs makePowderDiffusionArgs(const ModelParameters& p, double dtDays) {
  PowderDiffusionArgs a;
  a.dtDays = static_cast<float>(dtDays);
  a.diffusionRatePerDay = static_cast<float>(p.diffusionRatePerDay);
  a.restSlope = static_cast<float>(p.diffusionRestSlope);
  a.diffusionLengthM = static_cast<float>(p.diffusionLengthM);
  a.minDepthM = static_cast<float>(p.diffusionMinDepthM);
  return a;
}

}  // namespace snow
