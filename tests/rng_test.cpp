#include <gtest/gtest.h>

#include <cmath>

#include "core/rng.h"

using namespace snow;

// Known-answer vectors of Random123's philox4x32-10 (kat_vectors).
TEST(Philox, MatchesRandom123KnownAnswers) {
  const Philox4x32 a = philox4x32(0, 0, 0, 0, 0, 0);
  EXPECT_EQ(a.v[0], 0x6627e8d5u);
  EXPECT_EQ(a.v[1], 0xe169c58du);
  EXPECT_EQ(a.v[2], 0xbc57ac4cu);
  EXPECT_EQ(a.v[3], 0x9b00dbd8u);
  const Philox4x32 b = philox4x32(0xffffffffu, 0xffffffffu, 0xffffffffu, 0xffffffffu, 0xffffffffu, 0xffffffffu);
  EXPECT_EQ(b.v[0], 0x408f276du);
  EXPECT_EQ(b.v[1], 0x41c83b0eu);
  EXPECT_EQ(b.v[2], 0xa20bc7c6u);
  EXPECT_EQ(b.v[3], 0x6d5451fdu);
  const Philox4x32 c = philox4x32(0x243f6a88u, 0x85a308d3u, 0x13198a2eu, 0x03707344u, 0xa4093822u, 0x299f31d0u);
  EXPECT_EQ(c.v[0], 0xd16cfe09u);
  EXPECT_EQ(c.v[1], 0x94fdccebu);
  EXPECT_EQ(c.v[2], 0x5001e420u);
  EXPECT_EQ(c.v[3], 0x24126ea1u);
}

TEST(Philox, KeyedByEventCellAndStream) {
  const RandomKey k{42};
  EXPECT_EQ(k.uniform(3, 5, RngStream::Snowfall), k.uniform(3, 5, RngStream::Snowfall));
  EXPECT_NE(k.uniform(3, 5, RngStream::Snowfall), k.uniform(4, 5, RngStream::Snowfall));
  EXPECT_NE(k.uniform(3, 5, RngStream::Snowfall), k.uniform(3, 6, RngStream::Snowfall));
  EXPECT_NE(k.uniform(3, 5, RngStream::Snowfall), k.uniform(3, 5, RngStream::Melt));
  EXPECT_NE(k.uniform(3, 5, RngStream::Snowfall), RandomKey{43}.uniform(3, 5, RngStream::Snowfall));
}

// Chi-square test of uniformity over 20 bins, 200000 draws: the 0.999 quantile of chi2(19) is 43.8.
TEST(Philox, UniformFloatIsUniform) {
  const RandomKey k{7};
  const int bins = 20, n = 200000;
  std::vector<int> counts(bins, 0);
  for (int i = 0; i < n; ++i) {
    const float u = k.uniform(static_cast<uint64_t>(i), 0, RngStream::Test);
    ASSERT_GE(u, 0.f);
    ASSERT_LT(u, 1.f);
    ++counts[static_cast<int>(u * bins)];
  }
  double chi2 = 0.0;
  const double expected = static_cast<double>(n) / bins;
  for (int c : counts) chi2 += (c - expected) * (c - expected) / expected;
  EXPECT_LT(chi2, 43.8);
}

TEST(Philox, OpenDoubleNeverZeroOrOne) {
  EXPECT_GT(uniformOpenDouble(0, 0), 0.0);
  EXPECT_LT(uniformOpenDouble(0xffffffffu, 0xffffffffu), 1.0);
  EXPECT_TRUE(std::isfinite(-std::log(uniformOpenDouble(0, 0))));
}
