#include <gtest/gtest.h>

#include "core/grid.h"
#include "core/snow_state.h"

using namespace snow;

TEST(Grid, RowMajorNorthToSouthIndexing) {
  Grid<float> g(4, 3, 0.f);
  g(3, 2) = 7.f;
  EXPECT_EQ(g.size(), 12u);
  EXPECT_EQ(g.values()[2 * 4 + 3], 7.f);
  GridView<float> v = g.view();
  EXPECT_EQ(v.index(3, 2), 11u);
  EXPECT_EQ(v(3, 2), 7.f);
}

TEST(Grid, ClampedReadRepeatsEdges) {
  Grid<float> g(3, 3, 0.f);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 3; ++x) g(x, y) = static_cast<float>(10 * y + x);
  auto v = g.view();
  EXPECT_EQ(v.clamped(-5, 0), 0.f);
  EXPECT_EQ(v.clamped(9, 1), 12.f);
  EXPECT_EQ(v.clamped(1, -1), 1.f);
  EXPECT_EQ(v.clamped(1, 3), 21.f);
}

TEST(Grid, NegativeSizeIsAnError) { EXPECT_THROW(Grid<float>(-1, 2), std::invalid_argument); }

TEST(SnowState, AllocatesEveryFieldWithNonSquareCells) {
  SnowState s;
  GridSpec spec;
  spec.width = 5;
  spec.height = 7;
  spec.cellSizeXM = 71.0;
  spec.cellSizeYM = 92.0;
  s.allocate(spec);
  EXPECT_EQ(s.powderM.width(), 5);
  EXPECT_EQ(s.windEffectZM.height(), 7);
  EXPECT_DOUBLE_EQ(s.spec.cellAreaM2(), 71.0 * 92.0);
  EXPECT_EQ(s.validCell(4, 6), 1);
  s.stableM(1, 1) = 0.5f;
  s.powderM(1, 1) = 0.25f;
  EXPECT_FLOAT_EQ(s.depthM(1, 1), 0.75f);
  EXPECT_EQ(&s.layer(SnowLayer::Powder), &s.powderM);
  EXPECT_STREQ(snowLayerName(SnowLayer::Unstable), "unstable");
}
