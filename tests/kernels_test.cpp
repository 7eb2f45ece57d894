// Per-cell kernels on tiny constructed cases with exact expected answers.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "core/serial_exec.h"
#include "core/phenomena/melt.h"
#include "core/phenomena/powder_diffusion.h"
#include "core/phenomena/snowfall.h"
#include "core/phenomena/stability_change.h"
#include "core/phenomena/wind_transport.h"
#include "test_support.h"

using namespace snow;

namespace {

SnowState plane(int w, int h, double cell, float slopeX, float base, float temperatureBase) {
  return test::terrainFrom(w, h, cell, temperatureBase, [=](double xm, double) { return base + slopeX * static_cast<float>(xm); });
}

SnowFieldsView viewOf(SnowState& s, std::vector<float>& delta) {
  // One buffer holds the four scratch fields (delta, slope, surface and powder snapshots) and
  // powder diffusion's five shares per cell.
  SnowFieldsView v = test::stateView(s);
  delta.assign(9 * s.spec.cellCount(), 0.f);
  v.delta = delta.data();
  v.surfaceSlope = delta.data() + s.spec.cellCount();
  v.scratchSurface = delta.data() + 2 * s.spec.cellCount();
  v.scratchPowder = delta.data() + 3 * s.spec.cellCount();
  v.powderFlow = delta.data() + 4 * s.spec.cellCount();
  return v;
}

double totalDepth(const SnowState& s) {
  double t = 0;
  for (int y = 0; y < s.spec.height; ++y)
    for (int x = 0; x < s.spec.width; ++x) t += s.depthM(x, y);
  return t;
}

}  // namespace

TEST(SnowfallKernel, FlatPlaneGetsFoehnDepthAllStable) {
  SnowState s = plane(6, 5, 10.0, 0.f, 2000.f, -15.f);
  std::vector<float> delta;
  SnowFieldsView v = viewOf(s, delta);
  SerialExec exec;
  SnowfallArgs a;  // paper defaults: k_snow = 1e-4 /day
  a.dtDays = 0.5f;
  a.rainSnowLimitM = 1000.f;
  const double volume = runSnowfall(exec, v, a);
  for (int y = 0; y < 5; ++y)
    for (int x = 0; x < 6; ++x) {
      EXPECT_FLOAT_EQ(s.stableM(x, y), 0.05f);  // 0.5 day * 1e-4 /day * 1000 m
      EXPECT_EQ(s.powderM(x, y), 0.f);
      EXPECT_EQ(s.unstableM(x, y), 0.f);
    }
  EXPECT_NEAR(volume, 30 * 0.05 * 100.0, 1e-4);
}

TEST(SnowfallKernel, NothingBelowTheRainSnowLimitNorOnNodata) {
  SnowState s = plane(5, 5, 10.0, 0.f, 900.f, -15.f);
  s.bedrockM(2, 2) = 3000.f;
  s.validCell(2, 2) = 0;
  std::vector<float> delta;
  SerialExec exec;
  SnowfallArgs a;
  a.rainSnowLimitM = 1000.f;
  EXPECT_EQ(runSnowfall(exec, viewOf(s, delta), a), 0.0);
  EXPECT_EQ(totalDepth(s), 0.0);
}

// On an inclined plane of slope 0.55 at T = -10 degC: s_c = 0.5, x_p = 5 * 0.05 = 0.25;
// x_U = 1 * (0.55 - 0.3) = 0.25 of the remaining 0.75.
TEST(SnowfallKernel, SlopeSplitsPowderUnstableStable) {
  SnowState s = plane(7, 5, 10.0, 0.55f, 2000.f, -10.f);
  std::vector<float> delta;
  SerialExec exec;
  SnowfallArgs a;
  a.dtDays = 1.f;
  a.rainSnowLimitM = 1000.f;
  runSnowfall(exec, viewOf(s, delta), a);
  const int x = 3, y = 2;  // interior: central differences are exact on a plane
  const float added = 1e-4f * (s.bedrockM(x, y) - 1000.f);
  EXPECT_NEAR(s.powderM(x, y), 0.25f * added, 1e-6f);
  EXPECT_NEAR(s.unstableM(x, y), 0.75f * 0.25f * added, 1e-6f);
  EXPECT_NEAR(s.stableM(x, y), 0.75f * 0.75f * added, 1e-6f);
}

// Colder ground raises the critical slope: at T = -20 degC s_c = 0.5 + 0.05 * 10 = 1.0 > 0.55.
TEST(SnowfallKernel, ColdRaisesTheCriticalSlope) {
  SnowState s = plane(7, 5, 10.0, 0.55f, 2000.f, -20.f);
  std::vector<float> delta;
  SerialExec exec;
  SnowfallArgs a;
  a.rainSnowLimitM = 1000.f;
  runSnowfall(exec, viewOf(s, delta), a);
  EXPECT_EQ(s.powderM(3, 2), 0.f);
  EXPECT_GT(s.unstableM(3, 2), 0.f);
}

TEST(MeltKernel, MeltsFromTheTopDown) {
  SnowState s = plane(3, 3, 10.0, 0.f, 500.f, 5.f);  // T = 5 degC
  s.powderM(1, 1) = 0.01f;
  s.unstableM(1, 1) = 0.01f;
  s.stableM(1, 1) = 0.002f;
  s.compactedM(1, 1) = 1.f;
  std::vector<float> delta;
  SerialExec exec;
  MeltArgs a;  // k_melt = 0.01 m/day/degC, T_0melt = 0
  a.dtDays = 0.5f;
  const double volume = runMelt(exec, viewOf(s, delta), a);  // wants 0.025 m
  EXPECT_EQ(s.powderM(1, 1), 0.f);
  EXPECT_EQ(s.unstableM(1, 1), 0.f);
  EXPECT_EQ(s.stableM(1, 1), 0.f);
  EXPECT_NEAR(s.compactedM(1, 1), 1.f - 0.003f, 1e-6f);
  EXPECT_NEAR(volume, -0.025 * 100.0, 1e-4);
}

TEST(MeltKernel, NothingMeltsBelowTheThreshold) {
  SnowState s = plane(3, 3, 10.0, 0.f, 500.f, -1.f);
  s.powderM.fill(0.3f);
  std::vector<float> delta;
  SerialExec exec;
  EXPECT_EQ(runMelt(exec, viewOf(s, delta), MeltArgs{}), 0.0);
  EXPECT_EQ(s.powderM(1, 1), 0.3f);
}

TEST(PowderDiffusion, FlatPowderStaysPut) {
  SnowState s = plane(8, 8, 5.0, 0.f, 1000.f, -5.f);
  s.powderM.fill(0.4f);
  std::vector<float> delta;
  SerialExec exec;
  PowderDiffusionArgs a;
  runPowderDiffusion(exec, viewOf(s, delta), a);
  for (float p : s.powderM.values()) EXPECT_EQ(p, 0.4f);
}

// A 6 m column of powder on flat ground spreads until no slope between neighbours exceeds the
// rest slope s_d0 = 0.5 (with a tolerance of 2 %: the spreading slows as slopes near rest).
TEST(PowderDiffusion, PileSettlesToTheRestSlopeAndConservesMass) {
  SnowState s = plane(31, 31, 2.0, 0.f, 1000.f, -5.f);
  s.powderM(15, 15) = 6.f;
  std::vector<float> delta;
  SnowFieldsView v = viewOf(s, delta);
  SerialExec exec;
  PowderDiffusionArgs a;
  const double before = totalDepth(s);
  for (int i = 0; i < 4000; ++i) runPowderDiffusion(exec, v, a);
  EXPECT_NEAR(totalDepth(s), before, 1e-5 * before);
  float maxSlope = 0.f;
  for (int y = 0; y < 31; ++y)
    for (int x = 0; x + 1 < 31; ++x) {
      maxSlope = std::max(maxSlope, std::abs(s.powderM(x + 1, y) - s.powderM(x, y)) / 2.f);
      maxSlope = std::max(maxSlope, std::abs(s.powderM(y, x + 1) - s.powderM(y, x)) / 2.f);
    }
  EXPECT_LE(maxSlope, 0.5f * 1.02f);
  EXPECT_LT(s.powderM(15, 15), 6.f);
}

// Transport on the rough fixture (cliffs, spike, plateau, NODATA hole): mass conserved to float
// rounding, nothing negative or NaN, NODATA cells never receive snow.
TEST(PowderDiffusion, RoughTerrainMassExactAndNonNegative) {
  SnowState s = test::makeRoughState(64, 48, 11);
  std::vector<float> delta;
  SnowFieldsView v = viewOf(s, delta);
  SerialExec exec;
  PowderDiffusionArgs a;
  a.dtDays = 5.f;  // long events: the kernel substeps
  const double before = exec.sum(s.powderM.data(), s.validCell.data(), 64, 48);
  for (int i = 0; i < 50; ++i) runPowderDiffusion(exec, v, a);
  const double after = exec.sum(s.powderM.data(), s.validCell.data(), 64, 48);
  // float rounding: about one ulp of a cell's powder per transfer
  EXPECT_NEAR(after, before, 1e-5 * before);
  for (size_t i = 0; i < s.powderM.size(); ++i) {
    ASSERT_TRUE(std::isfinite(s.powderM.values()[i]));
    ASSERT_GE(s.powderM.values()[i], 0.f);
    if (!s.validCell.values()[i]) {
      ASSERT_EQ(s.powderM.values()[i], 0.f);
    }
  }
}

TEST(PowderDiffusion, SubstepsGrowWithEventLengthAndShrinkingCells) {
  EXPECT_EQ(powderDiffusionSubsteps(0.5f, 0.5f, 10.f, 10.f), 1);
  EXPECT_EQ(powderDiffusionSubsteps(0.5f, 0.5f, 400.f, 10.f), 10);  // defaults at 10 m: one cell a substep
  EXPECT_EQ(powderDiffusionSubsteps(0.5f, 0.5f, 400.f, 2.f), 50);
  EXPECT_EQ(powderDiffusionSubsteps(1e9f, 1e9f, 10.f, 0.01f), 256);
}

namespace {
// Powder that leaves a thin layer on one cell of a plane of gradient (gx, gy) in one event.
float powderLeaving(float gx, float gy) {
  SnowState s = plane(9, 9, 10.0, 0.f, 2000.f, -5.f);
  for (int y = 0; y < 9; ++y)
    for (int x = 0; x < 9; ++x) s.bedrockM(x, y) = 2000.f - gx * 10.f * x - gy * 10.f * y;
  s.powderM(4, 4) = 1e-3f;
  std::vector<float> delta;
  SerialExec exec;
  PowderDiffusionArgs a;  // dt 0.5 day, k_m 0.5 /day, s_d0 0.5
  a.diffusionLengthM = 10.f;  // L_d = dx: the paper's per-cell share, one substep
  a.minDepthM = 0.f;
  runPowderDiffusion(exec, viewOf(s, delta), a);
  return 1e-3f - s.powderM(4, 4);
}
}  // namespace

// On a slope along an axis the share that leaves is the paper's m_d = dt k_m (s - s_d0):
// 0.5 * 0.5 * (0.7 - 0.5) = 0.05 of the powder.
TEST(PowderDiffusion, AxisSlopeMovesThePapersShare) {
  EXPECT_NEAR(powderLeaving(0.7f, 0.f), 0.05f * 1e-3f, 0.002f * 0.05f * 1e-3f);
}

// The same slope along a diagonal moves the same share (the literal per-direction threshold
// would move nothing: each axis component is 0.49 < 0.5).
TEST(PowderDiffusion, DiagonalSlopeMovesLikeAnAxisSlope) {
  const float axis = powderLeaving(0.7f, 0.f);
  const float diagonal = powderLeaving(0.7f / std::sqrt(2.f), 0.7f / std::sqrt(2.f));
  EXPECT_NEAR(diagonal, axis, 0.002f * axis);
  EXPECT_EQ(powderLeaving(0.45f, 0.f), 0.f);  // below the rest slope nothing moves
}

// A film thinner than diffusion_min_depth_m stays on a steep slope; a thicker one slides.
TEST(PowderDiffusion, ThinFilmSticksThickerPowderSlides) {
  for (float depth : {0.5e-3f, 5e-3f}) {
    SnowState s = plane(9, 9, 10.0, 0.f, 2000.f, -5.f);
    for (int y = 0; y < 9; ++y)
      for (int x = 0; x < 9; ++x) s.bedrockM(x, y) = 2000.f - 10.f * x;  // slope 1
    s.powderM(4, 4) = depth;
    std::vector<float> delta;
    SerialExec exec;
    runPowderDiffusion(exec, viewOf(s, delta), PowderDiffusionArgs{});  // min depth 1 mm
    if (depth < 1e-3f) {
      EXPECT_EQ(s.powderM(4, 4), depth);
    } else {
      EXPECT_LT(s.powderM(4, 4), 0.5f * depth);
    }
  }
}

// A lone heap spreads even though central differences at its top read zero.
TEST(PowderDiffusion, LonePeakSpreads) {
  SnowState s = plane(5, 5, 1.0, 0.f, 1000.f, -5.f);
  s.powderM(2, 2) = 3.f;
  std::vector<float> delta;
  SerialExec exec;
  runPowderDiffusion(exec, viewOf(s, delta), PowderDiffusionArgs{});
  EXPECT_LT(s.powderM(2, 2), 3.f);
  EXPECT_GT(s.powderM(1, 2), 0.f);
  EXPECT_FLOAT_EQ(s.powderM(1, 2), s.powderM(3, 2));  // symmetric
  EXPECT_FLOAT_EQ(s.powderM(2, 1), s.powderM(2, 3));
}

// Shares far below a deep receiver's last bit stay at the source: a film running off a ledge into
// a pit holding 100 m of powder (one ulp there is 7.6e-6 m). Adding such a share to the pile would
// round it away while the source lost it, a loss that adds up over a season; each share is what
// the receiver gains on its starting powder, so the total stays the same to the last bit.
TEST(PowderDiffusion, TinySharesIntoADeepPileKeepEveryBit) {
  for (float film : {1e-7f, 1e-5f, 3e-4f}) {
    SCOPED_TRACE(film);
    SnowState s = plane(3, 1, 10.0, 0.f, 0.f, -5.f);
    s.bedrockM(1, 0) = -1000.f;  // the pit
    s.powderM(1, 0) = 100.f;
    s.powderM(0, 0) = film;
    s.powderM(2, 0) = film;
    std::vector<float> delta;
    SnowFieldsView v = viewOf(s, delta);
    SerialExec exec;
    PowderDiffusionArgs a;
    a.minDepthM = 0.f;  // let the thinnest film slide
    const double before = static_cast<double>(s.powderM(0, 0)) + s.powderM(1, 0) + s.powderM(2, 0);
    for (int i = 0; i < 200; ++i) runPowderDiffusion(exec, v, a);
    const double after = static_cast<double>(s.powderM(0, 0)) + s.powderM(1, 0) + s.powderM(2, 0);
    EXPECT_EQ(after, before);
    EXPECT_GE(s.powderM(0, 0), 0.f);
    if (film > 1e-5f) {
      EXPECT_LT(s.powderM(0, 0), film) << "the film never slid";
    }
  }
}

TEST(StabilityKernel, RateFollowsTemperatureAndSlope) {
  StabilityArgs a;  // T_warm 5, T_cool -5, T_freeze -20, k_w = k_c = 1e4 m/day (Table 2)
  a.instabilityByWarmthMPerDay = 0.2f;
  a.stabilityByColdMPerDay = 0.1f;
  EXPECT_FLOAT_EQ(stabilityRate(a, -30.f), 0.f);
  EXPECT_FLOAT_EQ(stabilityRate(a, -20.f), 0.f);
  EXPECT_FLOAT_EQ(stabilityRate(a, -12.5f), 0.05f);  // half way from freeze to cool
  EXPECT_FLOAT_EQ(stabilityRate(a, -5.f), 0.1f);
  EXPECT_NEAR(stabilityRate(a, 0.f), 0.5f * 0.1f - 0.5f * 0.2f, 1e-7f);
  EXPECT_FLOAT_EQ(stabilityRate(a, 8.f), -0.2f);
  // Warm snow on a steep slope destabilises faster than on a gentle one; cool snow stabilises
  // faster on the gentle one.
  auto run = [&](float slope, float temperature) {
    SnowState s = plane(7, 5, 10.0, slope, 2000.f, temperature - 0.f);
    s.stableM.fill(1.f);
    s.unstableM.fill(1.f);
    std::vector<float> delta;
    SerialExec exec;
    a.dtDays = 1.f;
    runStability(exec, viewOf(s, delta), a);
    EXPECT_NEAR(s.stableM(3, 2) + s.unstableM(3, 2), 2.f, 1e-6f);  // snow only changes layer
    return s.unstableM(3, 2) - 1.f;  // gained by the unstable layer
  };
  const float steepWarm = run(1.0f, 10.f), gentleWarm = run(0.1f, 10.f);
  EXPECT_NEAR(steepWarm, 0.2f * 1.0f / 1.3f, 1e-5f);
  EXPECT_NEAR(gentleWarm, 0.2f * 0.1f / 0.4f, 1e-5f);
  const float steepCool = run(1.0f, -5.f), gentleCool = run(0.1f, -5.f);
  EXPECT_NEAR(-steepCool, 0.1f * 0.3f / 1.3f, 1e-5f);
  EXPECT_NEAR(-gentleCool, 0.1f * 0.3f / 0.4f, 1e-5f);
  EXPECT_EQ(run(0.5f, -25.f), 0.f);
}

TEST(StabilityKernel, NeverMovesMoreThanTheLayerHolds) {
  SnowState s = plane(5, 5, 10.0, 0.5f, 2000.f, 20.f);  // hot: k_w = 1e4 m/day wants everything
  s.stableM.fill(0.3f);
  s.unstableM.fill(0.1f);
  std::vector<float> delta;
  SerialExec exec;
  runStability(exec, viewOf(s, delta), StabilityArgs{});
  for (int y = 0; y < 5; ++y)
    for (int x = 0; x < 5; ++x) {
      EXPECT_EQ(s.stableM(x, y), 0.f);
      EXPECT_FLOAT_EQ(s.unstableM(x, y), 0.4f);
    }
}

namespace {
// A ridge along y (crest at x = 10) with 1 m of powder everywhere, wind from the west.
SnowState ridge(float windX, float windY, float shadowHeight) {
  SnowState s = plane(21, 9, 10.0, 0.f, 2000.f, -10.f);
  for (int y = 0; y < 9; ++y)
    for (int x = 0; x < 21; ++x) {
      s.bedrockM(x, y) = 2000.f - 3.f * std::abs(static_cast<float>(x - 10)) * std::abs(static_cast<float>(x - 10)) * 0.1f;
      s.powderM(x, y) = 1.f;
      s.windXMps(x, y) = windX;
      s.windYMps(x, y) = windY;
      s.windEffectZM(x, y) = s.bedrockM(x, y) + 1.f + shadowHeight;
    }
  return s;
}
}  // namespace

TEST(WindTransport, ScoursTheCrestAndDepositsDownwind) {
  SnowState s = ridge(10.f, 0.f, 0.f);
  std::vector<float> delta;
  SnowFieldsView v = viewOf(s, delta);
  SerialExec exec;
  const double before = totalDepth(s);
  runWindTransport(exec, v, WindTransportArgs{});
  // The parabolic ridge has d2A/dx2 = -0.6 m / (10 m)^2 everywhere: curv_W = 10 * -0.006 =
  // -0.06 /s, so every cell erodes 0.5 day * 0.1 * 0.06 = 0.003 m and hands it east (no W_y).
  for (int x = 1; x < 20; ++x) {
    EXPECT_NEAR(s.windScourM(x, 4), 0.003f, 1e-5f) << x;
    EXPECT_NEAR(s.windDepositM(x + 1, 4), 0.003f, 1e-5f) << x;
  }
  for (int y = 0; y < 9; ++y) {
    EXPECT_EQ(s.windDepositM(0, y), 0.f);  // nothing blows upwind
    EXPECT_EQ(s.windScourM(20, y), 0.f);   // the east edge has no receiver: its snow stays
  }
  EXPECT_NEAR(totalDepth(s), before, 1e-5 * before);
}

// One step moves what each cell erodes at the step's start (windSharesAt reads nothing else) to
// its downwind neighbours: the powder is, cell for cell, what moving every cell's shares one after
// another in double gives, to float rounding; no share is lost, doubled or sent the wrong way, and
// no visiting order enters. Winds of every sign and calm cells, NODATA holes, a wind shadow.
TEST(WindTransport, OneStepIsEveryCellsShareFromTheStepsStartMovedOneAfterAnotherInDouble) {
  SnowState s = test::makeRoughState(41, 29, 6, 4.0, 5.0);
  for (int y = 0; y < 29; ++y)
    for (int x = 0; x < 41; ++x) {
      const int k = (3 * x + 5 * y) % 11;
      s.windXMps(x, y) = k < 3 ? 0.f : (k < 7 ? 9.f : -6.f);
      s.windYMps(x, y) = k % 3 == 0 ? 0.f : (k % 3 == 1 ? 4.f : -7.f);
    }
  std::vector<float> delta;
  const SnowFieldsView v = viewOf(s, delta);
  const WindTransportArgs a{0.5f, 0.05f, 0.1f};
  std::vector<double> expected(s.powderM.values().begin(), s.powderM.values().end());
  int givers = 0, capped = 0;
  for (int y = 0; y < 29; ++y)
    for (int x = 0; x < 41; ++x) {
      float shareX, shareY;
      windSharesAt(v, a, x, y, shareX, shareY);
      const int i = v.index(x, y);
      if (shareX != 0.f) expected[i] -= std::fabs(shareX), expected[i + (shareX > 0.f ? 1 : -1)] += std::fabs(shareX);
      if (shareY != 0.f) expected[i] -= std::fabs(shareY), expected[i + (shareY > 0.f ? 41 : -41)] += std::fabs(shareY);
      givers += shareX != 0.f || shareY != 0.f;
      capped += std::fabs(shareX) + std::fabs(shareY) > 0.99f * s.powderM.values()[i];
    }
  ASSERT_GT(givers, 200);
  ASSERT_GT(capped, 10);  // cells that give (almost) all their powder: the cap is exercised
  SerialExec exec;
  runWindTransport(exec, v, a);
  for (size_t i = 0; i < expected.size(); ++i) {
    EXPECT_GE(s.powderM.values()[i], 0.f) << i;
    EXPECT_NEAR(s.powderM.values()[i], expected[i], 4e-7 * (1.0 + expected[i])) << i;
  }
}

TEST(WindTransport, NothingMovesInTheShadowOrWithoutWindOrOnFlatGround) {
  for (int c = 0; c < 3; ++c) {
    SnowState s = c == 0 ? ridge(10.f, 0.f, 5.f) : (c == 1 ? ridge(0.f, 0.f, 0.f) : plane(9, 9, 10.0, 0.f, 2000.f, -10.f));
    if (c == 2) {
      s.powderM.fill(1.f);
      s.windXMps.fill(10.f);
      s.windEffectZM = s.bedrockM;
    }
    const std::vector<float> before = s.powderM.values();
    std::vector<float> delta;
    SerialExec exec;
    runWindTransport(exec, viewOf(s, delta), WindTransportArgs{});
    EXPECT_EQ(s.powderM.values(), before) << c;
  }
}

TEST(WindTransport, DiagonalWindSplitsTheDepositAndEdgesKeepTheirSnow) {
  SnowState s = ridge(6.f, 8.f, 0.f);
  std::vector<float> delta;
  SerialExec exec;
  const double before = totalDepth(s);
  runWindTransport(exec, viewOf(s, delta), WindTransportArgs{});
  // From the crest cell (10, 4): 6/14 of it east, 8/14 south.
  const float eroded = s.windScourM(10, 4);
  ASSERT_GT(eroded, 0.f);
  EXPECT_NEAR(totalDepth(s), before, 1e-5 * before);
  // The top row (y = 0) receives only from its west neighbour, its east share 6/14.
  for (int x = 2; x < 20; ++x) EXPECT_NEAR(s.windDepositM(x, 0), 6.f / 14.f * s.windScourM(x - 1, 0), 1e-7f) << x;
  // The west column (x = 0) receives only from its north neighbour, its south share 8/14.
  for (int y = 1; y < 9; ++y) EXPECT_NEAR(s.windDepositM(0, y), 8.f / 14.f * s.windScourM(0, y - 1), 1e-7f) << y;
  // The crest's bottom row (y = 8) cannot send south and the east column cannot send east: what
  // they scour lands inside the grid, so nothing leaves it.
  double scour = 0, deposit = 0;
  for (size_t i = 0; i < s.windScourM.size(); ++i) scour += s.windScourM.values()[i], deposit += s.windDepositM.values()[i];
  EXPECT_NEAR(deposit, scour, 1e-5 * scour);  // float sums of 189 cells
  for (float v : s.powderM.values()) ASSERT_GE(v, 0.f);
}
