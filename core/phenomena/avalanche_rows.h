// The TBB executor's row paths for the avalanche's passes (avalanches.h): each row's span of
// cells (InRowSpans) several at a time, the cells at the grid's edge and the span's tail by the
// per-cell body. The flow and scale passes and the row statistics take four or eight cells
// (avalanche_lanes.inc, SSE2 or AVX2), the heights four with AVX2 (avalanche_height_avx2.inc;
// the per-cell body without it). The per-cell bodies branch on every pipe; the lanes do their
// operations in their order, so the results are the serial executor's and CUDA's bytes (the
// tests compare them). Host only: never included by CUDA translation units.
#pragma once
#include "field_lanes.h"
#include "avalanche_kernels.h"

namespace snow {

#define SNOW_LANES_BODY "phenomena/avalanche_lanes.inc"
#define SNOW_LANES_AVX2_EXTRA "phenomena/avalanche_height_avx2.inc"
#include "../simd_lanes_for_each_isa.inc"

// Where lanes `lanes` wide starting at x stop for cells [x, end): at end, or past it to the end of
// their last whole vector when that stays within `limit`. The box's cells past a row's span hold
// no flows and no snow that can flow, so every pass leaves them as they are (InRowSpans): the
// bytes are the span's, and the span's tail takes no per-cell loop.
inline int lanesEnd(int x, int end, int limit, int lanes) {
  if (end <= x) return end;
  const int whole = x + (end - x + lanes - 1) / lanes * lanes;
  return whole <= limit ? whole : end;
}

// Row y's span at substep k (avalancheRowSpan, with `live` for the passes) in column order: `cell(x)` where a neighbour may
// be outside the grid (the first and last row and column) and on what the lanes leave of the
// span, `avx2(x, end)` (avx2Lanes wide) on the cells between, which returns where it stopped,
// then `sse2(x, end)` (four wide) the same way.
template <class Cell, class Avx2, class Sse2Lanes>
void avalancheSpanByLanes(const SnowFieldsView& v, const AvalancheArgs& a, int y, int k, bool live, Cell cell, Avx2 avx2, int avx2Lanes,
                          Sse2Lanes sse2) {
  int lo = 0, hi = -1;
  avalancheRowSpan(v, a, y, k, lo, hi, live);
  int x = lo;
  if (y > 0 && y < v.height - 1) {
    for (; x <= hi && x < 1; ++x) cell(x);
    const int limit = a.x1 < v.width - 1 ? a.x1 : v.width - 1;  // in the box, every neighbour in the grid
    const int end = hi + 1 < limit ? hi + 1 : limit;
#if SNOW_LANES_AVX2
    if (cpuHasAvx2() && lanesAvx2Allowed().load(std::memory_order_relaxed)) x = avx2(x, lanesEnd(x, end, limit, avx2Lanes));
#endif
    x = sse2(x, lanesEnd(x, end, limit, 4));
  }
  for (; x <= hi; ++x) cell(x);
}

#if SNOW_LANES_AVX2
#define SNOW_LANES_AVX2_CALL(call) avx2_lanes::call
#else
#define SNOW_LANES_AVX2_CALL(call) x  // never called: avalancheSpanByLanes tests SNOW_LANES_AVX2
#endif

#if defined(__SSE2__)
// TbbExec::forEachCell calls these for the box's rows (found by argument-dependent lookup).
inline void rowSpan(const InRowSpans<AvalancheFlowKernel>& k, int row, int, int) {
  const int y = k.a.y0 + row;
  avalancheSpanByLanes(
      k.v, k.a, y, k.k, true, [&](int x) { k.kernel(x, y); }, [&](int x, int end) { return SNOW_LANES_AVX2_CALL(flowLanes(k.kernel, y, x, end)); }, 8,
      [&](int x, int end) { return sse2_lanes::flowLanes(k.kernel, y, x, end); });
}
inline void rowSpan(const InRowSpans<AvalancheScaleKernel>& k, int row, int, int) {
  const int y = k.a.y0 + row;
  avalancheSpanByLanes(
      k.v, k.a, y, k.k, true, [&](int x) { k.kernel(x, y); }, [&](int x, int end) { return SNOW_LANES_AVX2_CALL(scaleLanes(k.kernel, y, x, end)); }, 8,
      [&](int x, int end) { return sse2_lanes::scaleLanes(k.kernel, y, x, end); });
}
inline void rowSpan(const InRowSpans<AvalancheHeightKernel>& k, int row, int, int) {
  const int y = k.a.y0 + row;
  avalancheSpanByLanes(
      k.v, k.a, y, k.k, true, [&](int x) { k.kernel(x, y); }, [&](int x, int end) { return SNOW_LANES_AVX2_CALL(heightLanes(k.kernel, y, x, end)); }, 4,
      [](int x, int) { return x; });  // no SSE2 body: the per-cell one
}

// The row statistics after a step's substeps: the per-cell part (AvalancheRowStatsKernel::cell)
// at the grid's edges and on what the lanes leave of the span, lanes between, in column order.
inline void rowSpan(const AvalancheRowStatsKernel& k, int row, int, int) {
  const int y = k.a.y0 + row;
  float speed = 0.f, energy = 0.f;
  int lo = k.v.width, hi = -1, touchedLo = k.v.width, touchedHi = -1;
  avalancheSpanByLanes(
      k.v, k.a, y, k.k, false, [&](int x) { k.cell(x, y, speed, energy, lo, hi, touchedLo, touchedHi); },
      [&](int x, int end) { return SNOW_LANES_AVX2_CALL(rowStatsLanes(k, y, x, end, speed, energy, lo, hi, touchedLo, touchedHi)); }, 8,
      [&](int x, int end) { return sse2_lanes::rowStatsLanes(k, y, x, end, speed, energy, lo, hi, touchedLo, touchedHi); });
  k.store(y, speed, energy, lo, hi, touchedLo, touchedHi);
}
#endif
#undef SNOW_LANES_AVX2_CALL

}  // namespace snow
