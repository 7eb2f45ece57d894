// The TBB executor's row paths for the passes it fuses with their slope snapshot
// (TbbExec::forEachCellThen): snowfall and the stability change, a row's cells eight at a time
// with AVX2, four with SSE2 (snowfall_lanes.inc, stability_lanes.inc), the tail by the per-cell
// body; the serial executor's bytes (CpuBackend.SlopeFusedWithSnowfallAndStabilityMatchesSerialOnAnyShape),
// and so CUDA's, which runs the same per-cell bodies. Host only.
#pragma once
#include "snowfall.h"
#include "stability_change.h"
#include "surface_slope_rows.h"

#include "../simd_lanes.h"

namespace snow {

#define SNOW_LANES_BODY "phenomena/snowfall_lanes.inc"
#include "../simd_lanes_for_each_isa.inc"
#define SNOW_LANES_BODY "phenomena/stability_lanes.inc"
#include "../simd_lanes_for_each_isa.inc"

// Row y of pass k, its slopes at slope[0 .. width): `avx2(x)` and then `sse2(x)` run the lanes
// from x and return where they stopped; the per-cell body takes the rest.
template <class K, class Avx2, class Sse2>
void slopeRowByLanes(const K& k, int y, int width, const float* slope, Avx2 avx2, Sse2 sse2) {
  int x = 0;
#if defined(__SSE2__)
#if SNOW_LANES_AVX2
  if (cpuHasAvx2() && lanesAvx2Allowed().load(std::memory_order_relaxed)) x = avx2(x);
#endif
  x = sse2(x);
#endif
  for (; x < width; ++x) k.withSlope(x, y, slope[x]);
}

#if SNOW_LANES_AVX2
#define SNOW_SLOPE_AVX2(call) avx2_lanes::call
#else
#define SNOW_SLOPE_AVX2(call) x  // never called: slopeRowByLanes tests SNOW_LANES_AVX2
#endif

#if defined(__SSE2__)
// Found by argument-dependent lookup in place of surface_slope_rows.h's per-cell withSlopeRow.
inline void withSlopeRow(const SnowfallKernel& k, int y, int width, const float* slope) {
  slopeRowByLanes(
      k, y, width, slope, [&](int x) { return SNOW_SLOPE_AVX2(snowfallLanes(k, y, slope, x, width)); },
      [&](int x) { return sse2_lanes::snowfallLanes(k, y, slope, x, width); });
}
inline void withSlopeRow(const StabilityKernel& k, int y, int width, const float* slope) {
  slopeRowByLanes(
      k, y, width, slope, [&](int x) { return SNOW_SLOPE_AVX2(stabilityLanes(k, y, slope, x, width)); },
      [&](int x) { return sse2_lanes::stabilityLanes(k, y, slope, x, width); });
}
#endif
#undef SNOW_SLOPE_AVX2

}  // namespace snow
