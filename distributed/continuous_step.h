// The season's continuous phenomena, one step: snowfall, stability, melt, powder diffusion and
// wind transport over dt, in the season's order of slots. On a DistributedBackend each phenomenon
// refreshes the halo after it (and powder diffusion after each substep), so the halo need only be
// as wide as one phenomenon reaches (kContinuousHalo): each runs its passes on the whole local
// grid, the local edge's cells come out wrong, and the error moves inward a cell or two a pass,
// never to the owned cells.
#pragma once
#include "core/backend.h"
#include "core/parameters.h"
#include "core/weather.h"

namespace snow::dist {

// Cells a phenomenon's passes reach beyond a cell between two refreshes: wind transport two
// (shares from the neighbours' surfaces, then the neighbours' shares), powder diffusion two a
// substep (the same), the slopes of snowfall and stability one.
constexpr int kContinuousHalo = 2;

// What the step's snowfall added and its melt removed (m³), as the backend returns them.
struct StepVolumes {
  double snowfallM3 = 0.0, meltM3 = 0.0;
};
StepVolumes continuousStep(SnowBackend& backend, const ModelParameters& p, double dtDays, const WeatherState& weather);

}  // namespace snow::dist
