// The TBB executor's row paths for wind transport's two passes (wind_transport.h), four cells at a
// time with SSE2 or eight with AVX2 on the grid's inner cells (the lane bodies,
// wind_transport_lanes.inc), the per-cell bodies on its edges. The same IEEE operations in the
// same order as the per-cell bodies, so the shares and the powder are the serial executor's and
// CUDA's bytes (the tests compare the serial and TBB executors byte for byte). Host only: never
// included by CUDA translation units.
#pragma once
#include "wind_transport.h"

#include "field_lanes.h"

namespace snow {

#define SNOW_LANES_BODY "phenomena/wind_transport_lanes.inc"
#include "../simd_lanes_for_each_isa.inc"

// Cells [x0, x1) of row y of either pass: the lanes on the inner cells, the per-cell body elsewhere.
template <class K>
void windRowSpan(const K& k, int y, int x0, int x1) {
  const SnowFieldsView& v = k.v;
  int x = x0;
#if defined(__SSE2__)
  if (y > 0 && y < v.height - 1) {
    for (; x < x1 && x < 1; ++x) k(x, y);  // the west edge: its neighbour reads need bounds
    const int end = x1 < v.width - 1 ? x1 : v.width - 1;
#if SNOW_LANES_AVX2
    if (cpuHasAvx2() && lanesAvx2Allowed().load(std::memory_order_relaxed)) x = avx2_lanes::windLanes(k, y, x, end);
#endif
    x = sse2_lanes::windLanes(k, y, x, end);
  }
#endif
  for (; x < x1; ++x) k(x, y);
}

inline void rowSpan(const WindSharesKernel& k, int y, int x0, int x1) { windRowSpan(k, y, x0, x1); }
inline void rowSpan(const WindGatherKernel& k, int y, int x0, int x1) { windRowSpan(k, y, x0, x1); }

}  // namespace snow
