// Counter-based random numbers (Philox4x32-10, Salmon et al. 2011), keyed by
// (seed, event index, cell, stream). The same key gives the same numbers on the CPU and
// the GPU, whatever the thread or block schedule, because nothing is carried between calls.
#pragma once
#include <cstdint>

#include "hd.h"

namespace snow {

struct Philox4x32 {
  uint32_t v[4];
};

namespace detail {
SNOW_HD SNOW_INLINE void mulhilo32(uint32_t a, uint32_t b, uint32_t& hi, uint32_t& lo) {
  const uint64_t p = static_cast<uint64_t>(a) * static_cast<uint64_t>(b);
  hi = static_cast<uint32_t>(p >> 32);
  lo = static_cast<uint32_t>(p);
}
}  // namespace detail

// Philox4x32 with 10 rounds: counter (c0..c3), key (k0, k1).
SNOW_HD SNOW_INLINE Philox4x32 philox4x32(uint32_t c0, uint32_t c1, uint32_t c2, uint32_t c3,
                                          uint32_t k0, uint32_t k1) {
  for (int round = 0; round < 10; ++round) {
    uint32_t hi0, lo0, hi1, lo1;
    detail::mulhilo32(0xD2511F53u, c0, hi0, lo0);
    detail::mulhilo32(0xCD9E8D57u, c2, hi1, lo1);
    const uint32_t n0 = hi1 ^ c1 ^ k0;
    const uint32_t n1 = lo1;
    const uint32_t n2 = hi0 ^ c3 ^ k1;
    const uint32_t n3 = lo0;
    c0 = n0; c1 = n1; c2 = n2; c3 = n3;
    k0 += 0x9E3779B9u;
    k1 += 0xBB67AE85u;
  }
  return Philox4x32{{c0, c1, c2, c3}};
}

// Uniform float in [0, 1) from the top 24 bits: exactly representable, identical on CPU and GPU.
SNOW_HD SNOW_INLINE float uniformFloat(uint32_t bits) { return static_cast<float>(bits >> 8) * (1.0f / 16777216.0f); }

// Uniform double in (0, 1): never 0, so -log(u) is finite.
SNOW_HD SNOW_INLINE double uniformOpenDouble(uint32_t hi, uint32_t lo) {
  const uint64_t m = ((static_cast<uint64_t>(hi) << 32) | lo) >> 12;  // 52 bits
  return (static_cast<double>(m) + 0.5) * (1.0 / 4503599627370496.0);  // (m + 1/2) / 2^52: in (0, 1)
}

// Streams separate independent uses of the same (seed, event, cell).
enum class RngStream : uint32_t { Scheduler = 1, Snowfall = 2, Melt = 3, Diffusion = 4, Terrain = 5, Avalanche = 6, Skier = 7, SkierStartMask = 8, BedformPoll = 9, BedformHop = 10, FallenSnowFlake = 11, SkierCount = 12, FallenSnowStability = 13, Test = 99 };

struct RandomKey {
  uint64_t seed = 0;
  SNOW_HD SNOW_INLINE Philox4x32 draw(uint64_t eventIndex, uint32_t cell, RngStream stream) const {
    return philox4x32(static_cast<uint32_t>(eventIndex), static_cast<uint32_t>(eventIndex >> 32), cell,
                      static_cast<uint32_t>(stream), static_cast<uint32_t>(seed),
                      static_cast<uint32_t>(seed >> 32));
  }
  SNOW_HD SNOW_INLINE float uniform(uint64_t eventIndex, uint32_t cell, RngStream stream) const {
    return uniformFloat(draw(eventIndex, cell, stream).v[0]);
  }
};

}  // namespace snow
