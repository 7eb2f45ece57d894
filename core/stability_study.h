// The stability rates' study (docs/models/season.md): how the unstable snow a storm leaves on a
// slope changes at a fixed temperature under the §5.2 stability change with given k_w, k_c.
// A uniform plane of `slope` (tan) at 5 m cells on the CPU backend, steps of 1 / state-change
// steps per day; the centre cell is read. Used by `snowbake bench --stage stability` and the tests.
#pragma once
#include "parameters.h"

namespace snow {

struct StabilityOutcome {
  double days = 0;        // when the tracked layer first reached half its start (or the horizon)
  bool reached = false;   // false: not within the horizon
};

// Unstable snow `unstableM` (over as much stable snow) at `temperatureC`: when half of it has
// become stable.
StabilityOutcome unstableHalfLife(const ModelParameters& p, double temperatureC, double slope, double unstableM, double horizonDays);
// Stable snow `stableM` (no unstable) at `temperatureC`: when half of it has become unstable.
StabilityOutcome stableHalfLife(const ModelParameters& p, double temperatureC, double slope, double stableM, double horizonDays);

}  // namespace snow
