// The TBB executor's row path for the stability change fused with its slope snapshot
// (TbbExec::forEachCellThen): a row's cells eight at a time with AVX2, four with SSE2
// (stability_lanes.inc), the tail by the per-cell body; the same bytes as the serial executor and
// CUDA (CpuBackend.SlopeFusedWithSnowfallAndStabilityMatchesSerialOnAnyShape). Host only.
#pragma once
#include "stability_change.h"
#include "surface_slope_rows.h"

#include "../simd_lanes.h"

namespace snow {

#define SNOW_LANES_BODY "phenomena/stability_lanes.inc"
#include "../simd_lanes_for_each_isa.inc"

// Row y of the stability change, its slopes at slope[0 .. width) (found by argument-dependent
// lookup in place of surface_slope_rows.h's per-cell withSlopeRow).
inline void withSlopeRow(const StabilityKernel& k, int y, int width, const float* slope) {
  int x = 0;
#if defined(__SSE2__)
#if SNOW_LANES_AVX2
  if (cpuHasAvx2() && lanesAvx2Allowed().load(std::memory_order_relaxed)) x = avx2_lanes::stabilityLanes(k, y, slope, x, width);
#endif
  x = sse2_lanes::stabilityLanes(k, y, slope, x, width);
#endif
  for (; x < width; ++x) k.withSlope(x, y, slope[x]);
}

}  // namespace snow
