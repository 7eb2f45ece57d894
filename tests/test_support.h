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

// Every field that a backend's download fills (snow_fields.h: the evolved layers and the
// records) is byte for byte the same in the two states (gtest expectations).
inline void expectSameBytes(const SnowState& a, const SnowState& b) {
#define SNOW_EXPECT_SAME_FIELD(member, view, Element, role, access, fill) \
  if (downloadedWithState(FieldRole::role)) {                         \
    EXPECT_EQ(a.member.values(), b.member.values()) << #member;          \
  }
  SNOW_STATE_FIELDS(SNOW_EXPECT_SAME_FIELD)
#undef SNOW_EXPECT_SAME_FIELD
}

// The kernels' view of a host state: every field of snow_fields.h that has a view pointer (an
// absent optional field null); no scratch fields (the caller gives those).
inline SnowFieldsView stateView(SnowState& s) {
  SnowFieldsView v;
  v.width = s.spec.width;
  v.height = s.spec.height;
  v.cellSizeXM = static_cast<float>(s.spec.cellSizeXM);
  v.cellSizeYM = static_cast<float>(s.spec.cellSizeYM);
#define SNOW_STATE_VIEW(member, view, Element, role, access, fill) \
  SNOW_IF_VIEW(access, v.view = optionalField(FieldRole::role) && s.member.size() == 0 ? nullptr : s.member.data();)
  SNOW_STATE_FIELDS(SNOW_STATE_VIEW)
#undef SNOW_STATE_VIEW
  return v;
}

}  // namespace snow::test
