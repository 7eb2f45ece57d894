// The TBB executor's row path for SurfaceSlopeKernel (into the snapshot, or into a row buffer for a
// pass fused with it, surfaceSlopeRow): eight cells at a time with AVX2, four with SSE2
// (surface_slope_lanes.inc), where a cell and its four neighbours are all valid; the per-cell body
// elsewhere. The same IEEE operations in the same order as surfaceGradient / surfaceSlope, so the
// slopes are the same bytes as the serial executor's and CUDA's (the tests compare the serial and
// TBB executors byte for byte). Host only: never included by CUDA translation units.
//
// A row path is found by argument-dependent lookup: `rowSpan(kernel, y, x0, x1)` runs cells
// [x0, x1) of row y, and TbbExec::forEachCell calls it instead of the per-cell loop.
#pragma once
#include "surface_slope.h"

#include "field_lanes.h"

namespace snow {

template <class K>
concept HasRowSpan = requires(const K& k, int y, int x0, int x1) { rowSpan(k, y, x0, x1); };

// A pass that reads the slope snapshot at its own cell only, and takes it as an argument
// (withSlope): the TBB executor fuses it with the snapshot by rows (TbbExec::forEachCellThen).
template <class K>
concept ReadsOwnSlope = requires(const K& k, int x, int y, float slope) { k.withSlope(x, y, slope); };

// Row y of such a pass, its slopes at slope[0 .. width), cell by cell; a pass with lanes has an
// overload of its own (slope_pass_rows.h).
template <class K>
  requires ReadsOwnSlope<K>
void withSlopeRow(const K& k, int y, int width, const float* slope) {
  for (int x = 0; x < width; ++x) k.withSlope(x, y, slope[x]);
}

#define SNOW_LANES_BODY "phenomena/surface_slope_lanes.inc"
#include "../simd_lanes_for_each_isa.inc"

// The slopes of cells [x0, x1) of row y into out[x0 .. x1) (out points at the row's cell 0).
inline void surfaceSlopeRow(const SnowFieldsView& v, int y, int x0, int x1, float* out) {
  auto cell = [&](int x) {
    const int i = v.index(x, y);
    out[x] = v.valid[i] ? surfaceSlope(v, x, y) : 0.f;  // SurfaceSlopeKernel's value
  };
  int x = x0;
#if defined(__SSE2__)
  if (y > 0 && y < v.height - 1) {
    for (; x < x1 && x < 1; ++x) cell(x);  // the west edge: one-sided differences
    const int end = x1 < v.width - 1 ? x1 : v.width - 1;
#if SNOW_LANES_AVX2
    if (cpuHasAvx2() && lanesAvx2Allowed().load(std::memory_order_relaxed)) x = avx2_lanes::slopeLanes(v, y, out, x, end, cell);
#endif
    x = sse2_lanes::slopeLanes(v, y, out, x, end, cell);
  }
#endif
  for (; x < x1; ++x) cell(x);
}

inline void rowSpan(const SurfaceSlopeKernel& k, int y, int x0, int x1) {
  surfaceSlopeRow(k.v, y, x0, x1, k.v.surfaceSlope + static_cast<size_t>(y) * k.v.width);
}

}  // namespace snow
