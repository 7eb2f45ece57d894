// The season's continuous phenomena, one step, on a rank's local grid: snowfall, stability,
// melt, powder diffusion and wind transport over dt, each followed by a refresh of the halo of
// the evolved and record fields, so each next phenomenon reads its neighbours' cells as the
// single process would. The halo must be as wide as the widest phenomenon reaches
// (continuousStepHalo): each runs its passes on the whole local grid, the local edge's cells
// come out wrong, and the error moves inward a cell or two a pass, never to the owned cells.
#pragma once
#include <cstddef>

#include "communicator.h"
#include "core/backend.h"
#include "core/parameters.h"
#include "core/weather.h"
#include "decomposition.h"

namespace snow::dist {

// Cells the step's passes reach beyond a cell: powder diffusion two a substep (shares from the
// neighbours' surfaces, then the neighbours' shares), wind transport one a colour pass and two for
// the curvature of its snapshot, the slopes of snowfall and stability one.
int continuousStepHalo(const ModelParameters& p, double dtDays, double minCellSizeM);

struct StepCost {
  double computeS = 0.0, waitS = 0.0, exchangeS = 0.0;
  size_t bytesSent = 0;
};

// The ranks a step runs on; none (the defaults): the backend holds the whole grid.
struct RankContext {
  const Communicator* comm = nullptr;
  const Decomposition* decomposition = nullptr;
  const HaloPlan* plan = nullptr;
  bool measureWaits = false;  // a barrier before each exchange, so exchangeS is the transfer alone
};
// One step on `backend`, the halos refreshed after each phenomenon. The returned costs add up
// this rank's time in the kernels, waiting (with measureWaits) and exchanging, and the bytes it sent.
StepCost continuousStep(SnowBackend& backend, const RankContext& ranks, const ModelParameters& p, double dtDays,
                        const WeatherState& weather);

}  // namespace snow::dist
