#include "continuous_step.h"

#include "core/phenomena/melt.h"
#include "core/phenomena/powder_diffusion.h"
#include "core/phenomena/snowfall.h"
#include "core/phenomena/stability_change.h"
#include "core/phenomena/wind_transport.h"

namespace snow::dist {

StepVolumes continuousStep(SnowBackend& backend, const ModelParameters& p, double dtDays, const WeatherState& weather) {
  StepVolumes v;
  v.snowfallM3 = backend.snowfall(makeSnowfallArgs(p, dtDays, weather));
  backend.stabilityChange(makeStabilityArgs(p, dtDays, weather));
  v.meltM3 = backend.melt(makeMeltArgs(p, dtDays, weather));
  backend.powderDiffusion(makePowderDiffusionArgs(p, dtDays));
  backend.windTransport(makeWindTransportArgs(p, dtDays));
  return v;
}

}  // namespace snow::dist
