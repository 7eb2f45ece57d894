// The TBB executor's row path for powder diffusion: a substep's two passes (powder_diffusion.h)
// over rows, the shares kept in row buffers instead of five floats a cell in memory, four cells
// at a time with SSE2. The arithmetic is the per-cell bodies' (powderSharesAt and
// PowderGatherKernel): the same IEEE operations in the same order (no fused multiply-add; MINPS /
// MAXPS are exactly minf / maxf, SQRTPS and DIVPS are correctly rounded), branch-free, the masks
// picking what the scalar body's early returns would have left. So the powder is the same bytes as
// the serial executor's and CUDA's, which run the per-cell bodies (the tests compare the serial
// and TBB executors byte for byte). Host only: never included by CUDA translation units.
#pragma once
#include <vector>

#include "powder_diffusion.h"

#include "field_lanes.h"

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

// The shares body four cells at a time with SSE2 and eight with AVX2 (used when the CPU has it):
// the same bytes as each other and as the per-cell body.
#define SNOW_LANES_BODY "phenomena/powder_diffusion_lanes.inc"
#include "../simd_lanes_for_each_isa.inc"

// Pass 1 on row y: every cell's shares and what it keeps, into `out` (PowderBaseKernel has run).
inline void powderSharesRow(const PowderFlowKernel& k, int y, const PowderRowShares& out) {
  const SnowFieldsView& v = k.v;
  auto scalar = [&](int x) {
    float share[4], keep;
    powderSharesAt(v, k.a, x, y, share, keep);
    for (int d = 0; d < 4; ++d) out.share[d][x] = share[d];
    out.keep[x] = keep;
  };
  int x = 0;
#if defined(__SSE2__)
  if (y > 0 && y < v.height - 1) {
    for (; x < v.width && x < 1; ++x) scalar(x);  // the west edge: its neighbour tests need bounds
#if SNOW_LANES_AVX2
    if (cpuHasAvx2() && lanesAvx2Allowed().load(std::memory_order_relaxed)) x = avx2_lanes::sharesLanes(k, y, out, x, v.width - 1);
#endif
    x = sse2_lanes::sharesLanes(k, y, out, x, v.width - 1);
  }
#endif
  for (; x < v.width; ++x) scalar(x);
}

// Pass 2 on row y, from the shares of rows y - 1, y and y + 1 (a zeroed buffer for a row beyond
// the grid): powderGathered's sum, in its order.
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
    if (valid[x]) powder[x] = powderGathered(row.keep[x], row.share[1][x + 1], row.share[0][x - 1], plusY.share[3][x], minusY.share[2][x]);
}

}  // namespace snow
