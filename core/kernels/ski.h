// The skiers' route map automaton (core/ski.h), as a per-cell kernel for every executor.
#pragma once
#include <cstdint>

#include "../hd.h"

namespace snow {

// One step of the route map's cellular automaton: out = max over lower valid neighbours of
// in(n) + |cn| (0 with none). Iterate until out == in.
struct RouteMapStepKernel {
  const float* altitude;
  const uint8_t* valid;
  const float* in;
  float* out;
  int width, height;
  float dx, dy, diagonal;
  SNOW_HD void operator()(int x, int y) const {
    const int i = y * width + x;
    float best = 0.f;
    if (valid[i]) {
      for (int oy = -1; oy <= 1; ++oy)
        for (int ox = -1; ox <= 1; ++ox) {
          if (ox == 0 && oy == 0) continue;
          const int nx = x + ox, ny = y + oy;
          if (nx < 0 || ny < 0 || nx >= width || ny >= height) continue;
          const int n = ny * width + nx;
          if (!valid[n] || !(altitude[n] < altitude[i])) continue;
          const float d = ox == 0 ? dy : oy == 0 ? dx : diagonal;
          const float through = in[n] + d;
          best = through > best ? through : best;
        }
    }
    out[i] = best;
  }
};

}  // namespace snow
