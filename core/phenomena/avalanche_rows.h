// The TBB executor's row paths for the avalanche's passes (avalanches.h): each row's span of
// cells (InRowSpans) several at a time, the cells at the grid's edge and the span's tail by the
// per-cell body. The flow and scale passes and the row statistics take four or eight cells
// (avalanche_lanes.inc, SSE2 or AVX2), the heights four with AVX2 (avalanche_height_avx2.inc;
// the per-cell body without it). The per-cell bodies branch on every pipe; the lanes do their
// operations in their order, so the results are the serial executor's and CUDA's bytes (the
// tests compare them). Host only: never included by CUDA translation units.
#pragma once
#include "../simd_lanes.h"
#include "avalanche_kernels.h"

namespace snow {

#if defined(__SSE2__)
namespace sse2_lanes {
using V = simd_detail::Sse2;
#include "avalanche_lanes.inc"
}  // namespace sse2_lanes
#endif

#if SNOW_LANES_AVX2
#pragma GCC push_options
#pragma GCC target("avx2")
namespace avx2_lanes {
using V = simd_detail::Avx2;
#include "avalanche_lanes.inc"
}  // namespace avx2_lanes
#include "avalanche_height_avx2.inc"
#pragma GCC pop_options
#endif

// Row `row` of the box at k's substep: the per-cell body where a neighbour may be outside the
// grid (the first and last row and column) and on the span's tail, `lanes(kernel, y, x, end)` on
// the cells between, which returns where it stopped; then `sse2` the same way.
template <class K, class Avx2, class Sse2Lanes>
void avalancheRowSpan(const InRowSpans<K>& k, int row, Avx2 avx2, Sse2Lanes sse2) {
  const SnowFieldsView& v = k.v;
  const int y = k.a.y0 + row;
  int lo = 0, hi = -1;
  avalancheRowSpan(v, k.a, y, k.k, lo, hi);
  int x = lo;
  if (y > 0 && y < v.height - 1) {
    for (; x <= hi && x < 1; ++x) k.kernel(x, y);
    const int end = hi + 1 < v.width - 1 ? hi + 1 : v.width - 1;
#if SNOW_LANES_AVX2
    if (cpuHasAvx2() && lanesAvx2Allowed().load(std::memory_order_relaxed)) x = avx2(k.kernel, y, x, end);
#endif
    x = sse2(k.kernel, y, x, end);
  }
  for (; x <= hi; ++x) k.kernel(x, y);
}

#if SNOW_LANES_AVX2
#define SNOW_LANES_AVX2_CALL(call) avx2_lanes::call
#else
#define SNOW_LANES_AVX2_CALL(call) x  // never called: avalancheRowSpan tests SNOW_LANES_AVX2
#endif

#if defined(__SSE2__)
// TbbExec::forEachCell calls these for the box's rows (found by argument-dependent lookup).
inline void rowSpan(const InRowSpans<AvalancheFlowKernel>& k, int row, int, int) {
  avalancheRowSpan(
      k, row, [](const AvalancheFlowKernel& f, int y, int x, int end) { return SNOW_LANES_AVX2_CALL(flowLanes(f, y, x, end)); },
      [](const AvalancheFlowKernel& f, int y, int x, int end) { return sse2_lanes::flowLanes(f, y, x, end); });
}
inline void rowSpan(const InRowSpans<AvalancheScaleKernel>& k, int row, int, int) {
  avalancheRowSpan(
      k, row, [](const AvalancheScaleKernel& f, int y, int x, int end) { return SNOW_LANES_AVX2_CALL(scaleLanes(f, y, x, end)); },
      [](const AvalancheScaleKernel& f, int y, int x, int end) { return sse2_lanes::scaleLanes(f, y, x, end); });
}
inline void rowSpan(const InRowSpans<AvalancheHeightKernel>& k, int row, int, int) {
  avalancheRowSpan(
      k, row, [](const AvalancheHeightKernel& f, int y, int x, int end) { return SNOW_LANES_AVX2_CALL(heightLanes(f, y, x, end)); },
      [](const AvalancheHeightKernel&, int, int x, int) { return x; });  // no SSE2 body: the per-cell one
}

// The row statistics after a step's substeps: the per-cell part (AvalancheRowStatsKernel::cell)
// at the grid's edges and the span's tail, lanes between, in column order.
inline void rowSpan(const AvalancheRowStatsKernel& k, int row, int, int) {
  const SnowFieldsView& v = k.v;
  const int y = k.a.y0 + row;
  float speed = 0.f, energy = 0.f;
  int lo = v.width, hi = -1, x0 = 0, x1 = -1;
  avalancheRowSpan(v, k.a, y, k.k, x0, x1);
  int x = x0;
  if (y > 0 && y < v.height - 1) {
    for (; x <= x1 && x < 1; ++x) k.cell(x, y, speed, energy, lo, hi);
    const int end = x1 + 1 < v.width - 1 ? x1 + 1 : v.width - 1;
#if SNOW_LANES_AVX2
    if (cpuHasAvx2() && lanesAvx2Allowed().load(std::memory_order_relaxed))
      x = avx2_lanes::rowStatsLanes(k, y, x, end, speed, energy, lo, hi);
#endif
    x = sse2_lanes::rowStatsLanes(k, y, x, end, speed, energy, lo, hi);
  }
  for (; x <= x1; ++x) k.cell(x, y, speed, energy, lo, hi);
  k.store(y, speed, energy, lo, hi);
}
#endif
#undef SNOW_LANES_AVX2_CALL

}  // namespace snow
