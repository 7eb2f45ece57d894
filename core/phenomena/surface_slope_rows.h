// The TBB executor's row path for SurfaceSlopeKernel: four cells at a time with SSE2 where a cell
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

inline void rowSpan(const SurfaceSlopeKernel& k, int y, int x0, int x1) {
  const SnowFieldsView& v = k.v;
  int x = x0;
#if defined(__SSE2__)
  if (y > 0 && y < v.height - 1) {
    for (; x < x1 && x < 1; ++x) k(x, y);  // the west edge: one-sided differences
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
        for (int lane = 0; lane < 4; ++lane) k(x + lane, y);
        continue;
      }
      const __m128 gx = _mm_div_ps(_mm_sub_ps(surfaceAt(i + 1), surfaceAt(i - 1)), twoDx);
      const __m128 gy = _mm_div_ps(_mm_sub_ps(surfaceAt(i + w), surfaceAt(i - w)), twoDy);
      _mm_storeu_ps(v.surfaceSlope + i, _mm_sqrt_ps(_mm_add_ps(_mm_mul_ps(gx, gx), _mm_mul_ps(gy, gy))));
    }
  }
#endif
  for (; x < x1; ++x) k(x, y);
}

}  // namespace snow
