#include "continuous_step.h"

#include <algorithm>
#include <chrono>

#include "core/phenomena/melt.h"
#include "core/phenomena/powder_diffusion.h"
#include "core/phenomena/snowfall.h"
#include "core/phenomena/stability_change.h"
#include "core/phenomena/wind_transport.h"
#include "halo_exchange.h"

namespace snow::dist {

int continuousStepHalo(const ModelParameters& p, double dtDays, double minCellSizeM) {
  const int substeps = powderDiffusionSubsteps(static_cast<float>(dtDays), static_cast<float>(p.diffusionRatePerDay),
                                               static_cast<float>(p.diffusionLengthM), static_cast<float>(minCellSizeM));
  const int windTransport = 5 + 2;
  return std::max(2 * substeps, windTransport);
}

StepCost continuousStep(SnowBackend& backend, const RankContext& ranks, const ModelParameters& p, double dtDays,
                        const WeatherState& weather) {
  using Clock = std::chrono::steady_clock;
  StepCost cost;
  auto timed = [&](double& into, auto&& f) {
    const auto t0 = Clock::now();
    f();
    into += std::chrono::duration<double>(Clock::now() - t0).count();
  };
  auto phenomenon = [&](auto&& run) {
    timed(cost.computeS, run);
    if (!ranks.comm) return;
    if (ranks.measureWaits) timed(cost.waitS, [&] { ranks.comm->barrier(); });
    timed(cost.exchangeS, [&] {
      cost.bytesSent += exchangeBackendHalos(*ranks.comm, *ranks.decomposition, *ranks.plan, backend,
                                             [](FieldRole r) { return r == FieldRole::Evolved || r == FieldRole::Record; });
    });
  };
  phenomenon([&] { backend.snowfall(makeSnowfallArgs(p, dtDays, weather)); });
  phenomenon([&] { backend.stabilityChange(makeStabilityArgs(p, dtDays, weather)); });
  phenomenon([&] { backend.melt(makeMeltArgs(p, dtDays, weather)); });
  phenomenon([&] { backend.powderDiffusion(makePowderDiffusionArgs(p, dtDays)); });
  phenomenon([&] { backend.windTransport(makeWindTransportArgs(p, dtDays)); });
  return cost;
}

}  // namespace snow::dist
