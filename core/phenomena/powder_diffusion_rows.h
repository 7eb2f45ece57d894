// The TBB executor's row path for powder diffusion: a substep's two passes (powder_diffusion.h)
// over rows, the shares kept in row buffers instead of five floats a cell in memory, four cells
// at a time with SSE2. The arithmetic is the per-cell bodies' (powderSharesAt and
// PowderGatherKernel): the same IEEE operations in the same order (no fused multiply-add; MINPS /
// MAXPS are exactly minf / maxf, SQRTPS and DIVPS are correctly rounded), branch-free, the masks
// picking what the scalar body's early returns would have left. So the powder is the same bytes as
// the serial executor's and CUDA's, which run the per-cell bodies (the tests compare the serial
// and TBB executors byte for byte). Host only: never included by CUDA translation units.
#pragma once
#include <atomic>
#include <cstring>
#include <vector>

#include "powder_diffusion.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
// The AVX2 body needs GCC's per-function target pragma (clang does not take it).
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && defined(__SSE2__)
#define SNOW_POWDER_AVX2 1
#else
#define SNOW_POWDER_AVX2 0
#endif
#if SNOW_POWDER_AVX2
#include <immintrin.h>
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

// Vector operations for powder_diffusion_lanes.inc: MINPS / MAXPS return the second operand
// unless the first is strictly less / greater, exactly minf / maxf.
struct Sse2 {
  using F = __m128;
  static constexpr int kLanes = 4;
  static F zero() { return _mm_setzero_ps(); }
  static F set1(float a) { return _mm_set1_ps(a); }
  static F load(const float* p) { return _mm_loadu_ps(p); }
  static void store(float* p, F a) { _mm_storeu_ps(p, a); }
  static F add(F a, F b) { return _mm_add_ps(a, b); }
  static F sub(F a, F b) { return _mm_sub_ps(a, b); }
  static F mul(F a, F b) { return _mm_mul_ps(a, b); }
  static F div(F a, F b) { return _mm_div_ps(a, b); }
  static F min(F a, F b) { return _mm_min_ps(a, b); }
  static F max(F a, F b) { return _mm_max_ps(a, b); }
  static F sqrt(F a) { return _mm_sqrt_ps(a); }
  static F gt(F a, F b) { return _mm_cmpgt_ps(a, b); }
  static F ge(F a, F b) { return _mm_cmpge_ps(a, b); }
  static F notGt(F a, F b) { return _mm_cmpngt_ps(a, b); }
  static F bitAnd(F a, F b) { return _mm_and_ps(a, b); }
  static F bitAndNot(F a, F b) { return _mm_andnot_ps(a, b); }
  static F select(F mask, F a, F b) { return simd_detail::select(mask, a, b); }
  static bool none(F mask) { return _mm_movemask_ps(mask) == 0; }
  static F byteMask(const uint8_t* p) { return simd_detail::byteMask(p); }
};
}  // namespace simd_detail

namespace sse2_lanes {
using V = simd_detail::Sse2;
#include "powder_diffusion_lanes.inc"
}  // namespace sse2_lanes
#endif

#if SNOW_POWDER_AVX2
// The same body eight cells at a time, compiled for AVX2 (no FMA) and used when the CPU has it:
// the same bytes as SSE2 and the per-cell body.
#pragma GCC push_options
#pragma GCC target("avx2")
namespace avx2_lanes {
struct Avx2 {
  using F = __m256;
  static constexpr int kLanes = 8;
  static F zero() { return _mm256_setzero_ps(); }
  static F set1(float a) { return _mm256_set1_ps(a); }
  static F load(const float* p) { return _mm256_loadu_ps(p); }
  static void store(float* p, F a) { _mm256_storeu_ps(p, a); }
  static F add(F a, F b) { return _mm256_add_ps(a, b); }
  static F sub(F a, F b) { return _mm256_sub_ps(a, b); }
  static F mul(F a, F b) { return _mm256_mul_ps(a, b); }
  static F div(F a, F b) { return _mm256_div_ps(a, b); }
  static F min(F a, F b) { return _mm256_min_ps(a, b); }
  static F max(F a, F b) { return _mm256_max_ps(a, b); }
  static F sqrt(F a) { return _mm256_sqrt_ps(a); }
  static F gt(F a, F b) { return _mm256_cmp_ps(a, b, _CMP_GT_OQ); }
  static F ge(F a, F b) { return _mm256_cmp_ps(a, b, _CMP_GE_OQ); }
  static F notGt(F a, F b) { return _mm256_cmp_ps(a, b, _CMP_NGT_UQ); }
  static F bitAnd(F a, F b) { return _mm256_and_ps(a, b); }
  static F bitAndNot(F a, F b) { return _mm256_andnot_ps(a, b); }
  static F select(F mask, F a, F b) { return _mm256_blendv_ps(b, a, mask); }
  static bool none(F mask) { return _mm256_movemask_ps(mask) == 0; }
  static F byteMask(const uint8_t* p) {
    const __m256i wide = _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p)));
    return _mm256_castsi256_ps(_mm256_xor_si256(_mm256_cmpeq_epi32(wide, _mm256_setzero_si256()), _mm256_set1_epi32(-1)));
  }
};
using V = Avx2;
#include "powder_diffusion_lanes.inc"
}  // namespace avx2_lanes
#pragma GCC pop_options

inline bool cpuHasAvx2() {
  static const bool has = __builtin_cpu_supports("avx2");
  return has;
}
#endif

// Whether the shares pass may take the AVX2 body where the CPU has it (tests turn it off to check
// the SSE2 body alone against the per-cell one).
inline std::atomic<bool>& powderAvx2Allowed() {
  static std::atomic<bool> allowed{true};
  return allowed;
}

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
#if SNOW_POWDER_AVX2
    if (cpuHasAvx2() && powderAvx2Allowed().load(std::memory_order_relaxed)) x = avx2_lanes::sharesLanes(k, y, out, x, v.width - 1);
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
