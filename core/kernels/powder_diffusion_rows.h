// The TBB executor's fast path for PowderFlowKernel: four cells at a time with SSE2, the same
// IEEE operations in the same order as the per-cell body in powder_diffusion.h (no fused
// multiply-add, MINPS / MAXPS are exactly minf / maxf, SQRTPS and DIVPS are correctly rounded),
// branch-free: every lane computes every term and the masks pick what the scalar body's early
// returns would have left. So the flows and bits are the same bytes as the per-cell body's, which
// the serial executor and CUDA run (tests compare the serial and TBB executors' seasons byte for
// byte). Host only: never included by CUDA translation units.
//
// A row kernel is found by argument-dependent lookup: `rowSpan(kernel, y, x0, x1)` runs cells
// [x0, x1) of row y; the executor calls it instead of the per-cell loop when it exists.
#pragma once
#include <cstring>

#include "powder_diffusion.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace snow {

template <class K>
concept HasRowSpan = requires(const K& k, int y, int x0, int x1) { rowSpan(k, y, x0, x1); };

#if defined(__SSE2__)
namespace simd_detail {
// Four bytes (0 / non-zero) as a four-lane mask.
inline __m128 byteMask(const uint8_t* p) {
  int32_t word;
  std::memcpy(&word, p, 4);
  const __m128i zero = _mm_setzero_si128();
  const __m128i wide = _mm_unpacklo_epi16(_mm_unpacklo_epi8(_mm_cvtsi32_si128(word), zero), zero);
  return _mm_castsi128_ps(_mm_xor_si128(_mm_cmpeq_epi32(wide, zero), _mm_set1_epi32(-1)));
}
inline __m128 select(__m128 mask, __m128 a, __m128 b) { return _mm_or_ps(_mm_and_ps(mask, a), _mm_andnot_ps(mask, b)); }
}  // namespace simd_detail
#endif

inline void rowSpan(const PowderFlowKernel& k, int y, int x0, int x1) {
  const SnowFieldsView& v = k.v;
  int x = x0;
#if defined(__SSE2__)
  using namespace simd_detail;
  if (y > 0 && y < v.height - 1) {
    for (; x < x1 && x < 1; ++x) k(x, y);  // the west edge: its neighbour tests need bounds
    const int end = x1 < v.width - 1 ? x1 : v.width - 1;
    const float minCell = minf(v.cellSizeXM, v.cellSizeYM);
    const __m128 zero = _mm_setzero_ps();
    const __m128 perMetreX = _mm_set1_ps(1.f / v.cellSizeXM), perMetreY = _mm_set1_ps(1.f / v.cellSizeYM);
    const __m128 rest = _mm_set1_ps(k.a.restSlope), minDepth = _mm_set1_ps(k.a.minDepthM);
    const __m128 rate = _mm_set1_ps(k.a.dtDays * k.a.diffusionRatePerDay * (k.a.diffusionLengthM / minCell));
    const __m128 fifth = _mm_set1_ps(0.2f), one = _mm_set1_ps(1.f), keep = _mm_set1_ps(1.f - 1e-6f);
    const int w = v.width;
    // A = B + (((C + S) + U) + P), in SnowFieldsView::surface's order.
    auto surfaceAt = [&v](int j) {
      const __m128 depth = _mm_add_ps(_mm_add_ps(_mm_add_ps(_mm_loadu_ps(v.compacted + j), _mm_loadu_ps(v.stable + j)), _mm_loadu_ps(v.unstable + j)),
                                      _mm_loadu_ps(v.powder + j));
      return _mm_add_ps(_mm_loadu_ps(v.bedrock + j), depth);
    };
    for (; x + 4 <= end; x += 4) {
      const int i = v.index(x, y);
      // Four cells without a powder film to move (most of a season's grid): nothing else to do.
      const __m128 powder = _mm_loadu_ps(v.powder + i);
      __m128 active = _mm_and_ps(byteMask(v.valid + i), _mm_cmpgt_ps(powder, minDepth));
      if (_mm_movemask_ps(active) == 0) {
        std::memset(v.powderMoves + i, 0, 4);
        continue;
      }
      const __m128 ap = surfaceAt(i);
      const __m128 an[4] = {surfaceAt(i + 1), surfaceAt(i - 1), surfaceAt(i + w), surfaceAt(i - w)};
      const __m128 okN[4] = {byteMask(v.valid + i + 1), byteMask(v.valid + i - 1), byteMask(v.valid + i + w), byteMask(v.valid + i - w)};
      __m128 drop[4], slope[4];
      for (int d = 0; d < 4; ++d) {
        drop[d] = _mm_and_ps(okN[d], _mm_max_ps(zero, _mm_sub_ps(ap, an[d])));
        slope[d] = _mm_mul_ps(drop[d], d < 2 ? perMetreX : perMetreY);
      }
      const __m128 sx = _mm_max_ps(slope[0], slope[1]), sy = _mm_max_ps(slope[2], slope[3]);
      const __m128 excess = _mm_sub_ps(_mm_sqrt_ps(_mm_add_ps(_mm_mul_ps(sx, sx), _mm_mul_ps(sy, sy))), rest);
      const __m128 weightSum = _mm_add_ps(_mm_add_ps(_mm_add_ps(slope[0], slope[1]), slope[2]), slope[3]);
      if (v.bedformActive) active = _mm_andnot_ps(byteMask(v.bedformActive + i), active);
      active = _mm_and_ps(active, _mm_and_ps(_mm_cmpgt_ps(excess, zero), _mm_cmpgt_ps(weightSum, zero)));
      const __m128 perWeight = _mm_div_ps(_mm_mul_ps(_mm_mul_ps(rate, excess), powder), weightSum);
      __m128 out[4];
      __m128 total = zero;
      for (int d = 0; d < 4; ++d) {
        const __m128 o = _mm_min_ps(_mm_mul_ps(perWeight, slope[d]), _mm_mul_ps(fifth, drop[d]));
        out[d] = _mm_and_ps(_mm_cmpgt_ps(slope[d], zero), o);
        total = _mm_add_ps(total, out[d]);
      }
      active = _mm_and_ps(active, _mm_cmpgt_ps(total, zero));
      const __m128 scale = select(_mm_cmpge_ps(total, powder), _mm_mul_ps(_mm_div_ps(powder, total), keep), one);
      int bits[4];
      for (int d = 0; d < 4; ++d) {
        bits[d] = _mm_movemask_ps(_mm_and_ps(active, _mm_cmpgt_ps(out[d], zero)));
        out[d] = _mm_mul_ps(out[d], scale);
      }
      _MM_TRANSPOSE4_PS(out[0], out[1], out[2], out[3]);  // now out[lane] holds that cell's four flows
      for (int lane = 0; lane < 4; ++lane) {
        const int moves = ((bits[0] >> lane) & 1) | (((bits[1] >> lane) & 1) << 1) | (((bits[2] >> lane) & 1) << 2) |
                          (((bits[3] >> lane) & 1) << 3);
        v.powderMoves[i + lane] = static_cast<uint8_t>(moves);
        _mm_storeu_ps(v.powderFlow + 4 * (i + lane), out[lane]);
      }
    }
  }
#endif
  for (; x < x1; ++x) k(x, y);
}

// A tile-gated kernel with a row fast path: each run of flagged tiles in the span at once.
template <class K>
  requires HasRowSpan<K>
void rowSpan(const TileGated<K>& g, int y, int x0, int x1) {
  if (!g.mask) {
    rowSpan(g.kernel, y, x0, x1);
    return;
  }
  const uint8_t* tiles = g.mask + (y >> SnowFieldsView::kTileShift) * g.tilesX;
  int x = x0;
  while (x < x1) {
    if (!tiles[x >> SnowFieldsView::kTileShift]) {
      x = ((x >> SnowFieldsView::kTileShift) + 1) << SnowFieldsView::kTileShift;
      continue;
    }
    int end = x;
    while (end < x1 && tiles[end >> SnowFieldsView::kTileShift]) end = ((end >> SnowFieldsView::kTileShift) + 1) << SnowFieldsView::kTileShift;
    if (end > x1) end = x1;
    rowSpan(g.kernel, y, x, end);
    x = end;
  }
}

}  // namespace snow
