// Shared test fixtures (header-only, no TBB: the GPU test binary uses them too).
#pragma once
#include <cmath>
#include <cstdint>

#include <gtest/gtest.h>

#include "core/rng.h"
#include "core/snow_state.h"

namespace snow::test {

// Square cells of `cell` metres, bedrock f(x_m, y_m) (metres east and south of the north-west
// corner), no snow, temperature base `temperatureC` everywhere (T at T0 = 0).
template <class F>
SnowState terrainFrom(int w, int h, double cell, float temperatureC, F f) {
  SnowState s;
  GridSpec spec;
  spec.width = w;
  spec.height = h;
  spec.cellSizeXM = spec.cellSizeYM = cell;
  s.allocate(spec);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) s.bedrockM(x, y) = static_cast<float>(f(x * cell, y * cell));
  s.temperatureBaseC.fill(temperatureC);
  return s;
}

// A rough random terrain with cliffs, a one-cell spike, a flat plateau, NODATA holes and random
// snow in every layer: a state on which every kernel has something to do.
inline SnowState makeRoughState(int w, int h, uint64_t seed, double cellSizeXM = 5.0, double cellSizeYM = 5.0,
                                bool holes = true) {
  SnowState s;
  GridSpec spec;
  spec.width = w;
  spec.height = h;
  spec.cellSizeXM = cellSizeXM;
  spec.cellSizeYM = cellSizeYM;
  s.allocate(spec);
  const RandomKey key{seed};
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const uint32_t cell = static_cast<uint32_t>(y * w + x);
      const Philox4x32 r = key.draw(0, cell, RngStream::Test);
      float b = 1500.f + 40.f * static_cast<float>(x) + 25.f * std::sin(0.3f * static_cast<float>(y)) +
                30.f * uniformFloat(r.v[0]);
      if (x > w / 2) b += 300.f;                          // a cliff
      if (x == w / 4 && y == h / 4) b += 800.f;           // a one-cell spike
      if (x < w / 6 && y > h / 2) b = 1400.f;             // a flat plateau
      s.bedrockM(x, y) = b;
      s.compactedM(x, y) = 0.2f * uniformFloat(r.v[1]);
      s.stableM(x, y) = 0.5f * uniformFloat(r.v[2]);
      s.unstableM(x, y) = 0.3f * uniformFloat(r.v[3]);
      s.powderM(x, y) = (x + y) % 7 == 0 ? 0.f : 1.5f * uniformFloat(key.draw(1, cell, RngStream::Test).v[0]);
      s.temperatureBaseC(x, y) = -0.0065f * b + 2.f * uniformFloat(key.draw(2, cell, RngStream::Test).v[0]);
      // A westerly wind turning with the row, a shadow behind the cliff, some wind loading.
      s.windXMps(x, y) = 8.f;
      s.windYMps(x, y) = 3.f * std::sin(0.2f * static_cast<float>(y));
      s.windEffectZM(x, y) = x > w / 2 && x < w / 2 + 4 ? b + 50.f : b;
      s.windLoadingMps2(x, y) = 0.01f * uniformFloat(key.draw(3, cell, RngStream::Test).v[0]);
      if (holes && (x - w / 3) * (x - w / 3) + (y - h / 2) * (y - h / 2) < (w / 10) * (w / 10)) {
        s.validCell(x, y) = 0;
        s.compactedM(x, y) = s.stableM(x, y) = s.unstableM(x, y) = s.powderM(x, y) = 0.f;
      }
    }
  }
  return s;
}

// Every evolving field of two states is byte for byte the same (gtest expectations).
inline void expectSameBytes(const SnowState& a, const SnowState& b) {
  EXPECT_EQ(a.compactedM.values(), b.compactedM.values());
  EXPECT_EQ(a.stableM.values(), b.stableM.values());
  EXPECT_EQ(a.unstableM.values(), b.unstableM.values());
  EXPECT_EQ(a.powderM.values(), b.powderM.values());
  EXPECT_EQ(a.snowMoving.values(), b.snowMoving.values());
  EXPECT_EQ(a.windScourM.values(), b.windScourM.values());
  EXPECT_EQ(a.windDepositM.values(), b.windDepositM.values());
  EXPECT_EQ(a.meltedM.values(), b.meltedM.values());
  EXPECT_EQ(a.avalancheScourM.values(), b.avalancheScourM.values());
  EXPECT_EQ(a.avalancheDepositM.values(), b.avalancheDepositM.values());
}

}  // namespace snow::test
