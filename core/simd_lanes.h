// Vector operations for the host row paths' lane bodies (powder_diffusion_lanes.inc,
// wind_transport_lanes.inc, avalanche_lanes.inc, surface_slope_lanes.inc, snowfall_lanes.inc,
// stability_lanes.inc, and field_lanes.inc, the helpers they share): one body written over a namespace V, compiled for SSE2 (four lanes)
// and, where GCC can target it per function, AVX2 (eight). Each operation is one IEEE operation
// or an exact select, so a body doing the per-cell kernel's operations in its order gives its
// bytes: MINPS / MAXPS return the second operand unless the first is strictly less / greater
// (exactly minf / maxf), SQRTPS and DIVPS are correctly rounded, the comparisons keep C's
// meaning for NaN (`!=` and `!(a <= b)` are true for it). Host only: never included by CUDA.
#pragma once
#include <atomic>
#include <cstdint>
#include <cstring>

#if defined(__SSE2__)
#include <emmintrin.h>
#include <xmmintrin.h>
#endif
// The AVX2 bodies need GCC's per-function target pragma (clang does not take it).
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && defined(__SSE2__)
#define SNOW_LANES_AVX2 1
#else
#define SNOW_LANES_AVX2 0
#endif
#if SNOW_LANES_AVX2
#include <immintrin.h>
#endif

namespace snow {

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
  static F abs(F a) { return _mm_andnot_ps(_mm_set1_ps(-0.f), a); }  // fabsf: the sign bit cleared
  static F neg(F a) { return _mm_xor_ps(_mm_set1_ps(-0.f), a); }     // unary minus: the sign bit flipped
  static F gt(F a, F b) { return _mm_cmpgt_ps(a, b); }
  static F ge(F a, F b) { return _mm_cmpge_ps(a, b); }
  static F lt(F a, F b) { return _mm_cmplt_ps(a, b); }
  static F le(F a, F b) { return _mm_cmple_ps(a, b); }
  static F notGt(F a, F b) { return _mm_cmpngt_ps(a, b); }
  static F notLe(F a, F b) { return _mm_cmpnle_ps(a, b); }
  static F neq(F a, F b) { return _mm_cmpneq_ps(a, b); }
  static F bitAnd(F a, F b) { return _mm_and_ps(a, b); }
  static F bitOr(F a, F b) { return _mm_or_ps(a, b); }
  static F bitAndNot(F a, F b) { return _mm_andnot_ps(a, b); }
  static F select(F mask, F a, F b) { return simd_detail::select(mask, a, b); }
  static bool none(F mask) { return _mm_movemask_ps(mask) == 0; }
  static int bits(F mask) { return _mm_movemask_ps(mask); }  // lane k's mask at bit k
  static F byteMask(const uint8_t* p) { return simd_detail::byteMask(p); }
  // Four floats a cell (cell j's at p[4 j ..]) as four vectors, one per float, and back.
  static void loadQuads(const float* p, F out[4]) {
    F r0 = _mm_loadu_ps(p), r1 = _mm_loadu_ps(p + 4), r2 = _mm_loadu_ps(p + 8), r3 = _mm_loadu_ps(p + 12);
    _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
    out[0] = r0, out[1] = r1, out[2] = r2, out[3] = r3;
  }
  static void storeQuads(float* p, const F in[4]) {
    F r0 = in[0], r1 = in[1], r2 = in[2], r3 = in[3];
    _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
    _mm_storeu_ps(p, r0), _mm_storeu_ps(p + 4, r1), _mm_storeu_ps(p + 8, r2), _mm_storeu_ps(p + 12, r3);
  }
};
}  // namespace simd_detail
#endif

#if SNOW_LANES_AVX2
#pragma GCC push_options
#pragma GCC target("avx2")
namespace simd_detail {
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
  static F abs(F a) { return _mm256_andnot_ps(_mm256_set1_ps(-0.f), a); }
  static F neg(F a) { return _mm256_xor_ps(_mm256_set1_ps(-0.f), a); }
  static F gt(F a, F b) { return _mm256_cmp_ps(a, b, _CMP_GT_OQ); }
  static F ge(F a, F b) { return _mm256_cmp_ps(a, b, _CMP_GE_OQ); }
  static F lt(F a, F b) { return _mm256_cmp_ps(a, b, _CMP_LT_OQ); }
  static F le(F a, F b) { return _mm256_cmp_ps(a, b, _CMP_LE_OQ); }
  static F notGt(F a, F b) { return _mm256_cmp_ps(a, b, _CMP_NGT_UQ); }
  static F notLe(F a, F b) { return _mm256_cmp_ps(a, b, _CMP_NLE_UQ); }
  static F neq(F a, F b) { return _mm256_cmp_ps(a, b, _CMP_NEQ_UQ); }
  static F bitAnd(F a, F b) { return _mm256_and_ps(a, b); }
  static F bitOr(F a, F b) { return _mm256_or_ps(a, b); }
  static F bitAndNot(F a, F b) { return _mm256_andnot_ps(a, b); }
  static F select(F mask, F a, F b) { return _mm256_blendv_ps(b, a, mask); }
  static bool none(F mask) { return _mm256_movemask_ps(mask) == 0; }
  static int bits(F mask) { return _mm256_movemask_ps(mask); }
  static F byteMask(const uint8_t* p) {
    const __m256i wide = _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p)));
    return _mm256_castsi256_ps(_mm256_xor_si256(_mm256_cmpeq_epi32(wide, _mm256_setzero_si256()), _mm256_set1_epi32(-1)));
  }
  static void loadQuads(const float* p, F out[4]) {
    __m128 lo[4], hi[4];
    Sse2::loadQuads(p, lo);
    Sse2::loadQuads(p + 16, hi);
    for (int d = 0; d < 4; ++d) out[d] = _mm256_set_m128(hi[d], lo[d]);
  }
  static void storeQuads(float* p, const F in[4]) {
    __m128 lo[4], hi[4];
    for (int d = 0; d < 4; ++d) lo[d] = _mm256_castps256_ps128(in[d]), hi[d] = _mm256_extractf128_ps(in[d], 1);
    Sse2::storeQuads(p, lo);
    Sse2::storeQuads(p + 16, hi);
  }
};
}  // namespace simd_detail
#pragma GCC pop_options

inline bool cpuHasAvx2() {
  static const bool has = __builtin_cpu_supports("avx2");
  return has;
}
#endif

// Whether the row paths may take their AVX2 bodies where the CPU has it (tests turn it off to
// check the SSE2 bodies alone against the per-cell ones).
inline std::atomic<bool>& lanesAvx2Allowed() {
  static std::atomic<bool> allowed{true};
  return allowed;
}

}  // namespace snow
