// The TBB executor's row path for powder diffusion: a substep's two passes (powder_diffusion.h)
// over rows, the shares kept in row buffers instead of five floats a cell in memory, four cells
// at a time with SSE2. The arithmetic is the per-cell bodies' (powderSharesAt and
// PowderGatherKernel): the same IEEE operations in the same order (no fused multiply-add; MINPS /
// MAXPS are exactly minf / maxf, SQRTPS and DIVPS are correctly rounded), branch-free, the masks
// picking what the scalar body's early returns would have left. So the powder is the same bytes as
// the serial executor's and CUDA's, which run the per-cell bodies (the tests compare the serial
// and TBB executors byte for byte). Host only: never included by CUDA translation units.
#pragma once
#include <cstring>
#include <limits>
#include <vector>

#include "powder_diffusion.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace snow {

// One row's shares: share[d][x] toward +x, -x, +y, -y and keep[x], for x in [0, width). The
// share arrays also hold x = -1 and x = width, which stay zero, so the gather reads a
// neighbour's share without testing the row's ends.
struct PowderRowShares {
  float* share[4];
  float* keep;
};

// Zeroed storage for `rows` row buffers of a grid `width` cells wide.
class PowderRowBuffer {
 public:
  PowderRowBuffer() = default;
  PowderRowBuffer(int rows, int width) { resize(rows, width); }
  // Zeroed storage of this shape; kept as it is when the shape is unchanged (the padding is
  // never written, so it stays zero).
  void resize(int rows, int width) {
    if (rows == rows_ && width + 2 == stride_) return;
    rows_ = rows;
    stride_ = width + 2;
    data_.assign(static_cast<size_t>(rows) * 5 * stride_, 0.f);
  }
  PowderRowShares row(int k) {
    float* base = data_.data() + static_cast<size_t>(k) * 5 * stride_;
    return PowderRowShares{{base + 1, base + stride_ + 1, base + 2 * stride_ + 1, base + 3 * stride_ + 1}, base + 4 * stride_ + 1};
  }

 private:
  std::vector<float> data_;
  int rows_ = 0;
  int stride_ = 0;
};

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

// The snow surface A = B + (((C + S) + U) + P) of row y (SnowFieldsView::surface's order), +inf
// at NODATA cells: the shares' pass reads it five times a cell, so each row computes it once. A
// NODATA neighbour then has no drop (max(0, A - inf) = 0), as the per-cell body's validity test
// leaves it.
inline void powderSurfaceRow(const SnowFieldsView& v, int y, float* out) {
  const size_t base = static_cast<size_t>(y) * v.width;
  const float inf = std::numeric_limits<float>::infinity();
  for (int x = 0; x < v.width; ++x) {
    const size_t i = base + x;
    const float a = v.bedrock[i] + (((v.compacted[i] + v.stable[i]) + v.unstable[i]) + v.powder[i]);
    out[x] = v.valid[i] ? a : inf;
  }
}

// Pass 1 on row y: every cell's shares and what it keeps, into `out`. For a row with rows on
// both sides, `surface` holds rows y - 1, y and y + 1 (powderSurfaceRow); the first and last rows
// of the grid take the per-cell body (pass nullptr).
inline void powderSharesRow(const PowderFlowKernel& k, int y, const PowderRowShares& out, const float* const* surface) {
  const SnowFieldsView& v = k.v;
  auto scalar = [&](int x) {
    float share[4], keep;
    powderSharesAt(v, k.a, x, y, share, keep);
    for (int d = 0; d < 4; ++d) out.share[d][x] = share[d];
    out.keep[x] = keep;
  };
  int x = 0;
#if defined(__SSE2__)
  using namespace simd_detail;
  if (surface && y > 0 && y < v.height - 1) {
    for (; x < v.width && x < 1; ++x) scalar(x);  // the west edge: its neighbour tests need bounds
    const int end = v.width - 1;
    const float minCell = minf(v.cellSizeXM, v.cellSizeYM);
    const __m128 zero = _mm_setzero_ps();
    const __m128 perMetreX = _mm_set1_ps(1.f / v.cellSizeXM), perMetreY = _mm_set1_ps(1.f / v.cellSizeYM);
    const __m128 rest = _mm_set1_ps(k.a.restSlope), minDepth = _mm_set1_ps(k.a.minDepthM);
    const __m128 rate = _mm_set1_ps(k.a.dtDays * k.a.diffusionRatePerDay * (k.a.diffusionLengthM / minCell));
    const __m128 fifth = _mm_set1_ps(0.2f), one = _mm_set1_ps(1.f), keepAll = _mm_set1_ps(1.f - 1e-6f);
    const int w = v.width;
    const int offset[4] = {1, -1, w, -w};
    const float* minusY = surface[0];
    const float* row = surface[1];
    const float* plusY = surface[2];
    for (; x + 4 <= end; x += 4) {
      const int i = v.index(x, y);
      const __m128 powder = _mm_loadu_ps(v.powder + i);
      __m128 active = _mm_and_ps(byteMask(v.valid + i), _mm_cmpgt_ps(powder, minDepth));
      if (_mm_movemask_ps(active) == 0) {
        // Four cells without a powder film to move (most of a season's grid): they keep it all.
        for (int d = 0; d < 4; ++d) _mm_storeu_ps(out.share[d] + x, zero);
        _mm_storeu_ps(out.keep + x, powder);
        continue;
      }
      const __m128 ap = _mm_loadu_ps(row + x);
      const __m128 an[4] = {_mm_loadu_ps(row + x + 1), _mm_loadu_ps(row + x - 1), _mm_loadu_ps(plusY + x), _mm_loadu_ps(minusY + x)};
      __m128 drop[4], slope[4];
      for (int d = 0; d < 4; ++d) {
        drop[d] = _mm_max_ps(zero, _mm_sub_ps(ap, an[d]));
        slope[d] = _mm_mul_ps(drop[d], d < 2 ? perMetreX : perMetreY);
      }
      const __m128 sx = _mm_max_ps(slope[0], slope[1]), sy = _mm_max_ps(slope[2], slope[3]);
      const __m128 excess = _mm_sub_ps(_mm_sqrt_ps(_mm_add_ps(_mm_mul_ps(sx, sx), _mm_mul_ps(sy, sy))), rest);
      const __m128 weightSum = _mm_add_ps(_mm_add_ps(_mm_add_ps(slope[0], slope[1]), slope[2]), slope[3]);
      if (v.bedformActive) active = _mm_andnot_ps(byteMask(v.bedformActive + i), active);
      active = _mm_and_ps(active, _mm_and_ps(_mm_cmpgt_ps(excess, zero), _mm_cmpgt_ps(weightSum, zero)));
      const __m128 perWeight = _mm_div_ps(_mm_mul_ps(_mm_mul_ps(rate, excess), powder), weightSum);
      __m128 outflow[4];
      __m128 total = zero;
      for (int d = 0; d < 4; ++d) {
        const __m128 o = _mm_min_ps(_mm_mul_ps(perWeight, slope[d]), _mm_mul_ps(fifth, drop[d]));
        outflow[d] = _mm_and_ps(_mm_cmpgt_ps(slope[d], zero), o);
        total = _mm_add_ps(total, outflow[d]);
      }
      active = _mm_and_ps(active, _mm_cmpgt_ps(total, zero));
      const __m128 scale = select(_mm_cmpge_ps(total, powder), _mm_mul_ps(_mm_div_ps(powder, total), keepAll), one);
      __m128 remaining = powder;
      for (int d = 0; d < 4; ++d) {
        const __m128 amount = _mm_and_ps(active, _mm_mul_ps(outflow[d], scale));
        const __m128 before = _mm_loadu_ps(v.powder + i + offset[d]);
        const __m128 gained = _mm_sub_ps(_mm_add_ps(before, amount), before);
        const __m128 given = _mm_and_ps(_mm_cmpgt_ps(gained, zero), _mm_cmpngt_ps(gained, remaining));
        _mm_storeu_ps(out.share[d] + x, _mm_and_ps(given, gained));
        remaining = select(given, _mm_sub_ps(remaining, gained), remaining);
      }
      _mm_storeu_ps(out.keep + x, remaining);
    }
  }
#endif
  for (; x < v.width; ++x) scalar(x);
}

// Pass 2 on row y, from the shares of rows y - 1, y and y + 1 (a zeroed buffer for a row beyond
// the grid): PowderGatherKernel's sum, in its order.
inline void powderGatherRow(const SnowFieldsView& v, int y, const PowderRowShares& minusY, const PowderRowShares& row,
                            const PowderRowShares& plusY) {
  float* powder = v.powder + static_cast<size_t>(y) * v.width;
  const uint8_t* valid = v.valid + static_cast<size_t>(y) * v.width;
  int x = 0;
#if defined(__SSE2__)
  using namespace simd_detail;
  for (; x + 4 <= v.width; x += 4) {
    const __m128 sum = _mm_add_ps(_mm_add_ps(_mm_add_ps(_mm_add_ps(_mm_loadu_ps(row.keep + x), _mm_loadu_ps(row.share[1] + x + 1)),
                                                        _mm_loadu_ps(row.share[0] + x - 1)),
                                             _mm_loadu_ps(plusY.share[3] + x)),
                                  _mm_loadu_ps(minusY.share[2] + x));
    _mm_storeu_ps(powder + x, select(byteMask(valid + x), sum, _mm_loadu_ps(powder + x)));
  }
#endif
  for (; x < v.width; ++x)
    if (valid[x]) powder[x] = (((row.keep[x] + row.share[1][x + 1]) + row.share[0][x - 1]) + plusY.share[3][x]) + minusY.share[2][x];
}

}  // namespace snow
