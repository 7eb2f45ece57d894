// The TBB executor's row path for SurfaceSlopeKernel (into the snapshot, or into a row buffer for a
// pass fused with it, surfaceSlopeRow): four cells at a time with SSE2 where a cell
// and its four neighbours are all valid (central differences on both axes), the per-cell body
// elsewhere. The same IEEE operations in the same order as surfaceGradient / surfaceSlope (no
// fused multiply-add; 2 * dx is exact; division and square root correctly rounded), so the slopes
// are the same bytes as the serial executor's and CUDA's (the tests compare the serial and TBB
// executors byte for byte). Host only: never included by CUDA translation units.
//
// A row path is found by argument-dependent lookup: `rowSpan(kernel, y, x0, x1)` runs cells
// [x0, x1) of row y, and TbbExec::forEachCell calls it instead of the per-cell loop.
#pragma once
#include <cstring>

#include "surface_slope.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace snow {

template <class K>
concept HasRowSpan = requires(const K& k, int y, int x0, int x1) { rowSpan(k, y, x0, x1); };

// A pass that reads the slope snapshot at its own cell only, and takes it as an argument
// (withSlope): the TBB executor fuses it with the snapshot by rows (TbbExec::forEachCellThen).
template <class K>
concept ReadsOwnSlope = requires(const K& k, int x, int y, float slope) { k.withSlope(x, y, slope); };

// Row y of such a pass, its slopes at slope[0 .. width), cell by cell; a pass with lanes has an
// overload of its own (stability_rows.h).
template <class K>
  requires ReadsOwnSlope<K>
void withSlopeRow(const K& k, int y, int width, const float* slope) {
  for (int x = 0; x < width; ++x) k.withSlope(x, y, slope[x]);
}

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
    const int w = v.width;
    const __m128 twoDx = _mm_set1_ps(2.f * v.cellSizeXM), twoDy = _mm_set1_ps(2.f * v.cellSizeYM);
    // A = B + (((C + S) + U) + P), SnowFieldsView::surface's order.
    auto surfaceAt = [&v](int j) {
      const __m128 depth = _mm_add_ps(_mm_add_ps(_mm_add_ps(_mm_loadu_ps(v.compacted + j), _mm_loadu_ps(v.stable + j)), _mm_loadu_ps(v.unstable + j)),
                                      _mm_loadu_ps(v.powder + j));
      return _mm_add_ps(_mm_loadu_ps(v.bedrock + j), depth);
    };
    // All five cells of each of four crosses valid: one compare of the bytes.
    auto allValid = [&v](int j) {
      uint32_t word[5];
      const int at[5] = {j, j - 1, j + 1, j - v.width, j + v.width};
      for (int n = 0; n < 5; ++n) std::memcpy(&word[n], v.valid + at[n], 4);
      const uint32_t all = word[0] & word[1] & word[2] & word[3] & word[4];
      return ((all & 0xffu) != 0) && ((all & 0xff00u) != 0) && ((all & 0xff0000u) != 0) && ((all & 0xff000000u) != 0);
    };
    for (; x + 4 <= end; x += 4) {
      const int i = v.index(x, y);
      if (!allValid(i)) {
        for (int lane = 0; lane < 4; ++lane) cell(x + lane);
        continue;
      }
      const __m128 gx = _mm_div_ps(_mm_sub_ps(surfaceAt(i + 1), surfaceAt(i - 1)), twoDx);
      const __m128 gy = _mm_div_ps(_mm_sub_ps(surfaceAt(i + w), surfaceAt(i - w)), twoDy);
      _mm_storeu_ps(out + x, _mm_sqrt_ps(_mm_add_ps(_mm_mul_ps(gx, gx), _mm_mul_ps(gy, gy))));
    }
  }
#endif
  for (; x < x1; ++x) cell(x);
}

inline void rowSpan(const SurfaceSlopeKernel& k, int y, int x0, int x1) {
  surfaceSlopeRow(k.v, y, x0, x1, k.v.surfaceSlope + static_cast<size_t>(y) * k.v.width);
}

}  // namespace snow
