// Avalanches (paper §6.1): angle of repose, static friction, wet against dry, mass, stability,
// thread independence.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/avalanche_runs.h"
#include "core/cpu_backend.h"
#include "core/simd_lanes.h"
#include "core/rng.h"
#include "bakers/grid_writer.h"
#include "bake_support.h"
#include "test_support.h"

using namespace snow;

namespace {

constexpr double kTan30 = 0.57735026918962584;
constexpr AvalancheFlow kFlows[] = {AvalancheFlow::ShallowWater, AvalancheFlow::Pipes};

const char* flowName(AvalancheFlow f) { return f == AvalancheFlow::Pipes ? "pipes" : "shallow water"; }

ModelParameters withFlow(AvalancheFlow f, ModelParameters p = ModelParameters{}) {
  p.avalancheFlow = f;
  return p;
}

double totalSnow(const SnowState& s) {
  double t = 0;
  for (int y = 0; y < s.spec.height; ++y)
    for (int x = 0; x < s.spec.width; ++x)
      if (s.validCell(x, y)) t += s.depthM(x, y);
  return t * s.spec.cellAreaM2();
}

struct AvalancheOutcome {
  AvalancheRecord record;
  SnowState state;
};

AvalancheOutcome runAvalanche(SnowState s, int x, int y, const ModelParameters& p = ModelParameters{},
                     std::unique_ptr<SnowBackend> backend = createCpuBackend(), bool rowSpans = true) {
  backend->upload(s);
  AvalancheRun run(*backend, p, s);
  run.useRowSpans(rowSpans);
  AvalancheOutcome o;
  run.release(x, y, 0.0, 0.0, true);
  o.record = run.runToRest();
  backend->download(s);
  o.state = std::move(s);
  return o;
}

void expectFiniteNonNegative(const SnowState& s) {
  for (const Grid<float>* g : {&s.compactedM, &s.stableM, &s.unstableM, &s.powderM})
    for (float v : g->values()) {
      ASSERT_TRUE(std::isfinite(v));
      ASSERT_GE(v, 0.f);
    }
}

// Steepest surface slope between 8-neighbours where either cell holds snow.
double maxSnowSlope(const SnowState& s) {
  double m = 0;
  for (int y = 0; y + 1 < s.spec.height; ++y)
    for (int x = 0; x + 1 < s.spec.width; ++x)
      for (auto [dx, dy] : {std::pair{1, 0}, std::pair{0, 1}, std::pair{1, 1}}) {
        const int nx = x + dx, ny = y + dy;
        if (s.depthM(x, y) < 1e-3f && s.depthM(nx, ny) < 1e-3f) continue;
        const double a = s.bedrockM(x, y) + s.depthM(x, y), b = s.bedrockM(nx, ny) + s.depthM(nx, ny);
        m = std::max(m, std::abs(a - b) / std::hypot(dx * s.spec.cellSizeXM, dy * s.spec.cellSizeYM));
      }
  return m;
}

}  // namespace

// A cone of dry unstable snow (slopes of 1.5) on a flat plane settles until no slope in the
// snow surface exceeds tan(theta_c) by more than 15 %, and keeps its mass.
TEST(Avalanche, DryConeSettlesToTheRestAngle) {
  SnowState s = test::terrainFrom(61, 61, 1.0, -20.f, [](double, double) { return 1000.0; });
  for (int y = 0; y < 61; ++y)
    for (int x = 0; x < 61; ++x) s.unstableM(x, y) = static_cast<float>(std::max(0.0, 12.0 - 1.5 * std::hypot(x - 30.0, y - 30.0)));
  const double before = totalSnow(s);
  for (AvalancheFlow flow : kFlows) {
    ModelParameters p = withFlow(flow);
    p.avalancheReachMPerM = 100.0;
    const AvalancheOutcome o = runAvalanche(s, 30, 30, p);
    ASSERT_TRUE(o.record.released) << o.record.why;
    std::printf("[ measure ] cone, %s: %d steps, %.1f s simulated, %s; max slope %.3f (tan 30 = %.3f), mass %.3e relative\n",
                flowName(flow), o.record.steps, o.record.simulatedS, o.record.why.c_str(), maxSnowSlope(o.state), kTan30,
                std::abs(totalSnow(o.state) - before) / before);
    expectFiniteNonNegative(o.state);
    EXPECT_NEAR(totalSnow(o.state), before, 1e-5 * before) << flowName(flow);
    EXPECT_LE(maxSnowSlope(o.state), kTan30 * 1.15) << flowName(flow);
    EXPECT_LT(o.state.depthM(30, 30), 12.f) << flowName(flow);  // it did flow
  }
}

// Unstable snow 1 m deep on an inclined plane: below the rest angle nothing moves at all (the
// snow covers the whole plane, so there is no steep edge to slump); well above it the release
// zone empties.
TEST(Avalanche, InclinedPlaneFlowsOnlyAboveTheRestAngle) {
  for (double slope : {0.4, 1.2}) {
    SnowState s = test::terrainFrom(40, 120, 2.0, -20.f, [slope](double, double y) { return 2000.0 - slope * std::min(y, 160.0); });
    for (int y = slope < kTan30 ? 0 : 10; y < (slope < kTan30 ? 120 : 40); ++y)
      for (int x = slope < kTan30 ? 0 : 10; x < (slope < kTan30 ? 40 : 30); ++x) s.unstableM(x, y) = 1.f;
    const SnowState start = s;
    for (AvalancheFlow flow : kFlows) {
      const AvalancheOutcome o = runAvalanche(s, 20, 25, withFlow(flow));
      ASSERT_TRUE(o.record.released);
      double moved = 0, left = 0;
      for (int y = 0; y < 120; ++y)
        for (int x = 0; x < 40; ++x) {
          moved += std::abs(o.state.depthM(x, y) - start.depthM(x, y));
          if (y >= 10 && y < 40 && x >= 10 && x < 30) left += o.state.depthM(x, y);
        }
      std::printf("[ measure ] slope %.1f, %s: %d steps, moved %.3f m summed, %.1f m left in the zone (of 600)\n", slope,
                  flowName(flow), o.record.steps, moved, left);
      if (slope < kTan30) {
        EXPECT_EQ(moved, 0.0) << flowName(flow);
      } else {
        EXPECT_LT(left, 0.1 * 600.0) << flowName(flow);
        EXPECT_GT(o.record.runoutM, 100.0) << flowName(flow);
      }
    }
  }
}

// Thin-flow stop: 15 cm of released snow on a plane of slope 1.2 with h_stop = 20 cm does not
// flow at all (depths unchanged, the unstable snow below it still there); with the default
// h_stop (5 cm) the same release runs down and entrains the snow below.
TEST(Avalanche, MovingSnowNoThickerThanTheStopThicknessDoesNotFlow) {
  for (double stop : {0.2, 0.05}) {
    SnowState s = test::terrainFrom(40, 120, 2.0, -20.f, [](double, double y) { return 2000.0 - 1.2 * y; });
    for (int y = 10; y < 120; ++y)
      for (int x = 10; x < 30; ++x) s.unstableM(x, y) = y < 40 ? 0.15f : 0.5f;
    const SnowState start = s;
    ModelParameters p;
    p.avalancheStopThicknessM = stop;  // (the default reach releases 7.5 m around the rupture point)
    const AvalancheOutcome o = runAvalanche(s, 20, 25, p);
    ASSERT_TRUE(o.record.released) << o.record.why;
    double moved = 0;
    for (int y = 0; y < 120; ++y)
      for (int x = 0; x < 40; ++x) moved += std::abs(o.state.depthM(x, y) - start.depthM(x, y));
    std::printf("[ measure ] h_stop %.2f m: %d steps, moved %.3f m summed, unstable at (20, 80) %.3f m; %s\n", stop, o.record.steps, moved,
                o.state.unstableM(20, 80), o.record.why.c_str());
    expectFiniteNonNegative(o.state);
    if (stop > 0.15) {
      EXPECT_EQ(moved, 0.0);
      EXPECT_EQ(o.state.unstableM(20, 80), 0.5f);
    } else {
      EXPECT_GT(moved, 10.0);
      EXPECT_LT(o.state.unstableM(20, 80), 0.5f);
    }
  }
}

// The same release, cold (dry, granular) and warm (wet, viscous with the paper's small k_v): the
// wet one runs out farther and its deposit is thinner. This is what the model says: granular
// friction stops dry snow on the runout as soon as its slope is below theta_c, while wet snow
// only loses speed to viscosity and spreads until its surface is nearly flat.
TEST(Avalanche, WetSnowRunsOutFartherAndThinnerThanDry) {
  auto slope = [](double, double y) { return y < 120.0 ? 2000.0 - 1.0 * y : 2000.0 - 120.0 - 0.05 * (y - 120.0); };
  AvalancheOutcome result[2];
  for (int wet = 0; wet < 2; ++wet) {
    SnowState s = test::terrainFrom(40, 200, 2.0, wet ? 5.f : -20.f, slope);
    for (int y = 5; y < 30; ++y)
      for (int x = 12; x < 28; ++x) s.unstableM(x, y) = 1.5f;
    result[wet] = runAvalanche(s, 20, 15);
  }
  float maxDeposit[2] = {0, 0};
  for (int wet = 0; wet < 2; ++wet)
    for (float v : result[wet].state.stableM.values()) maxDeposit[wet] = std::max(maxDeposit[wet], v);
  std::printf("[ measure ] dry: runout %.0f m, deepest deposit %.2f m, %s; wet: runout %.0f m, deepest %.2f m, %s\n",
              result[0].record.runoutM, maxDeposit[0], result[0].record.why.c_str(), result[1].record.runoutM, maxDeposit[1],
              result[1].record.why.c_str());
  EXPECT_GT(result[1].record.runoutM, result[0].record.runoutM + 10.0);
  EXPECT_LT(maxDeposit[1], maxDeposit[0]);
}

// Static and dynamic friction (docs/models/avalanches.md): snow released on a steep slope keeps
// flowing down a run-out of slope 0.4 (21.8 degrees: steeper than delta = 14, gentler than the
// Flowing snow crosses slopes between the dynamic and the rest angle: released on a slope of 1.2
// above a run-out of 0.4 (a break at 60 m), it runs far down the run-out with delta = 14 degrees.
// With delta = theta_c the pipes, which carry no momentum, stop short of 100 m; the shallow water
// carries the snow's momentum past the break, but no farther than a block sliding from the top of
// the release (y = 10 m) with friction tan(theta_c): 60 + 50 (1.2 - mu) / (mu - 0.4) metres.
TEST(Avalanche, FlowingSnowCrossesSlopesBetweenTheDynamicAndTheRestAngle) {
  auto slope = [](double, double y) { return y < 60.0 ? 2000.0 - 1.2 * y : 2000.0 - 72.0 - 0.4 * (y - 60.0); };
  const double blockReach = 60.0 + 50.0 * (1.2 - kTan30) / (kTan30 - 0.4);
  for (AvalancheFlow flow : kFlows) {
    double reach[2] = {0, 0};
    for (int oneAngle = 0; oneAngle < 2; ++oneAngle) {
      SnowState s = test::terrainFrom(40, 200, 2.0, -20.f, slope);
      for (int y = 5; y < 25; ++y)
        for (int x = 12; x < 28; ++x) s.unstableM(x, y) = 1.f;
      ModelParameters p = withFlow(flow);
      if (oneAngle) p.avalancheDynamicFrictionDeg = p.avalancheRestAngleDeg;
      const AvalancheOutcome o = runAvalanche(s, 20, 15, p);
      for (int y = 0; y < 200; ++y)
        for (int x = 0; x < 40; ++x)
          if (o.state.stableM(x, y) > 0.01f) reach[oneAngle] = std::max(reach[oneAngle], 2.0 * y);
    }
    std::printf("[ measure ] %s: farthest deposit %.0f m with delta 14, %.0f m with delta = theta_c (slope break at 60 m, a block's reach %.0f m)\n",
                flowName(flow), reach[0], reach[1], blockReach);
    EXPECT_GT(reach[0], 200.0) << flowName(flow);  // 140 m or more down the 0.4 run-out
    EXPECT_LT(reach[1], flow == AvalancheFlow::Pipes ? 100.0 : blockReach) << flowName(flow);
    EXPECT_GT(reach[1], 60.0) << flowName(flow);  // past the break
  }
}

// The peak records: each avalanche's deepest moving snow and fastest pipe, reset at its release,
// and the season's maximum over every avalanche.
TEST(Avalanche, PeakFieldsHoldEachAvalanchesAndTheSeasonsMaximum) {
  SnowState s = test::terrainFrom(60, 120, 2.0, -20.f, [](double, double y) { return 2000.0 - 1.2 * y; });
  for (int y = 10; y < 20; ++y)
    for (int x = 5; x < 15; ++x) s.unstableM(x, y) = 1.f, s.unstableM(x + 40, y) = 2.f;
  auto backend = createCpuBackend();
  backend->upload(s);
  const ModelParameters params;
  AvalancheRun run(*backend, params, s);
  ASSERT_TRUE(run.release(10, 15, 0.0, 0.0, true));
  run.runToRest();
  SnowState first = s;
  backend->download(first);
  ASSERT_TRUE(run.release(50, 15, 0.0, 0.0, true));
  run.runToRest();
  SnowState second = s;
  backend->download(second);
  EXPECT_FLOAT_EQ(first.avalanchePeakThicknessM(10, 15), 1.f);  // the release depth, its deepest
  EXPECT_GT(first.avalanchePeakSpeedMps(10, 15), 0.f);
  EXPECT_EQ(first.avalanchePeakThicknessM(50, 15), 0.f);
  EXPECT_EQ(second.avalanchePeakThicknessM(10, 15), 0.f);       // reset at the second release
  EXPECT_FLOAT_EQ(second.avalancheSeasonPeakThicknessM(10, 15), 1.f);
  EXPECT_GE(second.avalancheSeasonPeakThicknessM(50, 15), 2.f);
  const double freeFall = std::sqrt(2.0 * 9.81 * 1.2 * 2.0 * 120.0);
  for (size_t i = 0; i < s.spec.cellCount(); ++i) {
    EXPECT_EQ(second.avalancheSeasonPeakSpeedMps.values()[i],
              std::max(first.avalanchePeakSpeedMps.values()[i], second.avalanchePeakSpeedMps.values()[i]));
    EXPECT_LE(second.avalancheSeasonPeakSpeedMps.values()[i], freeFall);
  }
}

// A release writes the avalanche scratch only in the box the avalanche reaches (AvalancheTouched):
// three avalanches in a row on one backend, the third across the first's track, give the same
// bytes as each run after a fresh upload of the state, where the release covers the whole grid.
TEST(Avalanche, ReleasesInTheirBoxGiveTheSameBytesAsWholeGridReleases) {
  SnowState s = test::terrainFrom(60, 120, 2.0, -20.f, [](double x, double y) { return 2000.0 - 1.2 * y + 0.1 * x; });
  for (int y = 10; y < 20; ++y)
    for (int x = 5; x < 15; ++x) s.unstableM(x, y) = 1.f, s.unstableM(x + 40, y) = 2.f, s.unstableM(x + 18, y + 50) = 1.5f;
  const ModelParameters params;
  const int releases[3][2] = {{28, 65}, {10, 15}, {50, 15}};
  for (auto make : {createSerialBackend, createCpuBackend}) {
    auto inRow = make();
    inRow->upload(s);
    AvalancheRun run(*inRow, params, s);
    SnowState fresh = s;
    for (const auto& r : releases) {
      ASSERT_TRUE(run.release(r[0], r[1], 0.0, 0.0, true));
      run.runToRest();
      auto once = make();  // the whole-grid release: the first after an upload
      once->upload(fresh);
      AvalancheRun alone(*once, params, fresh);
      ASSERT_TRUE(alone.release(r[0], r[1], 0.0, 0.0, true));
      alone.runToRest();
      once->download(fresh);
      EXPECT_EQ(run.record().steps, alone.record().steps);
    }
    SnowState inRowState = s;
    inRow->download(inRowState);
    test::expectSameBytes(fresh, inRowState);
    EXPECT_GT(fresh.avalancheDepositM(28, 100) + fresh.avalancheDepositM(10, 100), 0.f);  // the tracks reached the foot
  }
}

// The runner keeps its snapshot between spontaneous tries while only its own avalanches have run
// (settle copies their boxes in), and downloads it again after any other step (here a snowfall
// between the third and fourth tries): the tries draw the same cells and leave the same bytes as
// with the state uploaded again before each try, which forces a whole download.
TEST(Avalanche, KeptSnapshotDrawsAsAFreshDownloadBetweenTries) {
  SnowState s = test::makeRoughState(96, 80, 11);
  for (size_t i = 0; i < s.spec.cellCount(); ++i)
    if (s.validCell.values()[i]) s.unstableM.values()[i] = 0.15f;
  const ModelParameters params;
  SnowfallArgs fall;
  fall.intensity = 4000.f, fall.rainSnowLimitM = 0.f, fall.seaLevelTemperatureC = -10.f, fall.unstableCriticalSlope = 10.f;
  auto kept = createCpuBackend(), fresh = createCpuBackend();
  kept->upload(s);
  fresh->upload(s);
  AvalancheRun a(*kept, params, s), b(*fresh, params, s);
  int released = 0;
  for (double draw : {0.13, 0.71, 0.42, 0.95, 0.27, 0.58}) {
    if (released == 3) kept->snowfall(fall), fresh->snowfall(fall);
    SnowState again = s;
    fresh->download(again);
    fresh->upload(again);
    const bool ra = a.trySpontaneous(draw, 0.0, -10.0), rb = b.trySpontaneous(draw, 0.0, -10.0);
    ASSERT_EQ(ra, rb) << draw;
    if (!ra) continue;
    ++released;
    const AvalancheRecord x = a.runToRest(), y = b.runToRest();
    EXPECT_EQ(x.ruptureX, y.ruptureX) << draw;
    EXPECT_EQ(x.ruptureY, y.ruptureY) << draw;
    EXPECT_EQ(x.steps, y.steps) << draw;
  }
  EXPECT_GE(released, 5);
  SnowState ka = s, fb = s;
  kept->download(ka);
  fresh->download(fb);
  test::expectSameBytes(ka, fb);
}

// Spontaneous releases start only where a cell can release: none on a plane gentler than the
// rest angle however deep its unstable snow, and on a steep one at a cell steeper than it.
TEST(Avalanche, SpontaneousReleasesOnlyWhereACellCanRelease) {
  for (double slope : {0.5, 1.0}) {
    SnowState s = test::terrainFrom(30, 30, 5.0, -20.f, [slope](double, double y) { return 2000.0 - slope * y; });
    s.unstableM.fill(2.f);  // everywhere: a patch's edge would be a step steeper than the plane
    auto backend = createCpuBackend();
    backend->upload(s);
    const ModelParameters params;
    AvalancheRun run(*backend, params, s);
    const bool released = run.trySpontaneous(0.5, 0.0, 0.0);
    if (slope < kTan30) {
      EXPECT_FALSE(released);
    } else {
      ASSERT_TRUE(released);
      const AvalancheRecord& r = run.record();
      EXPECT_GE(s.unstableM(r.ruptureX, r.ruptureY), 2.f);
      EXPECT_GT(r.ruptureSlopeDeg, 30.0);
    }
  }
}

// Random rough terrains (cliffs, spikes, NODATA holes) with random releases, a release at the
// top of a vertical cliff and 1 m of snow on 5 m cells: no NaN, no negative snow, mass kept,
// flows bounded by free fall from the highest snow.
TEST(Avalanche, RandomTerrainsAndCliffsStayStableAndKeepMass) {
  double worst = 0;
  for (int k = 0; k < 12; ++k) {
    SnowState s = test::makeRoughState(48, 40, 100 + k);
    const RandomKey key{static_cast<uint64_t>(k)};
    for (int y = 0; y < 40; ++y)
      for (int x = 0; x < 48; ++x)
        if (s.validCell(x, y)) s.unstableM(x, y) = 1.f + 2.f * key.uniform(0, static_cast<uint32_t>(y * 48 + x), RngStream::Test);
    int rx = 24, ry = 20;
    for (int t = 0; t < 100 && !s.validCell(rx, ry); ++t) rx = (rx + 7) % 48, ry = (ry + 3) % 40;
    const double before = totalSnow(s);
    // Parameters drawn across their documented ranges (core/parameters.cpp).
    ModelParameters p;
    auto draw = [&](int j, double lo, double hi) { return lo + (hi - lo) * key.uniform(1000 + k, static_cast<uint32_t>(j), RngStream::Test); };
    p.avalancheMaxDurationS = 60.0;
    p.avalancheRestAngleDeg = draw(0, 1.0, 80.0);
    p.snowViscosityPerS2 = draw(1, 0.0, 10.0);
    p.avalancheWetGranularFraction = draw(2, 0.0, 1.0);
    p.avalancheStepS = draw(3, 0.001, 10.0);
    p.avalancheReachMPerM = draw(4, 0.0, 10000.0);
    p.avalancheStopSpeedMps = draw(5, 1e-4, 1.0);
    if (k % 2) p.avalancheDryTemperatureC = 50.0, p.avalancheWetTemperatureC = 60.0;  // all wet
    p.avalancheFlow = kFlows[(k / 2) % 2];  // each flow dry and wet
    const AvalancheOutcome o = runAvalanche(s, rx, ry, p);
    EXPECT_TRUE(o.record.released) << k << ": " << o.record.why;  // 1-3 m of unstable snow at every valid cell
    EXPECT_GT(o.record.releasedM3, 0.0) << k;
    expectFiniteNonNegative(o.state);
    const double err = std::abs(totalSnow(o.state) - before) / before;
    worst = std::max(worst, err);
    EXPECT_LT(err, 1e-5) << k;
    // Bounded flow: no pipe faster than free fall over the terrain's relief (plus the snow).
    float lo = 1e30f, hi = -1e30f;
    for (size_t i = 0; i < s.bedrockM.size(); ++i)
      if (s.validCell.values()[i]) lo = std::min(lo, s.bedrockM.values()[i]), hi = std::max(hi, s.bedrockM.values()[i] + 3.f);
    EXPECT_LT(o.record.maxSpeedMps, std::sqrt(2.0 * 9.8 * (hi - lo)) + 1.0) << k;
  }
  // A vertical cliff: a slope of 0.8 ending in a 200 m drop between two 5 m cells.
  SnowState cliff = test::terrainFrom(30, 60, 5.0, -20.f, [](double, double y) { return y < 100.0 ? 3000.0 - 0.8 * y : 2720.0 - 0.1 * (y - 100.0); });
  for (int y = 0; y < 20; ++y)
    for (int x = 5; x < 25; ++x) cliff.unstableM(x, y) = 1.f;
  const double before = totalSnow(cliff);
  for (AvalancheFlow flow : kFlows) {
    const AvalancheOutcome o = runAvalanche(cliff, 15, 18, withFlow(flow));
    ASSERT_TRUE(o.record.released) << o.record.why;
    expectFiniteNonNegative(o.state);
    EXPECT_NEAR(totalSnow(o.state), before, 1e-5 * before) << flowName(flow);
    EXPECT_LT(o.record.maxSpeedMps, std::sqrt(2.0 * 9.8 * 400.0)) << flowName(flow);
    std::printf("[ measure ] random terrains: worst mass error %.2e; cliff, %s: %d steps, %s, runout %.0f m\n", worst, flowName(flow),
                o.record.steps, o.record.why.c_str(), o.record.runoutM);
  }
}

// The serial executor and TBB limited to 1 and to 2 threads give the same bytes.
TEST(Avalanche, SameBytesSerialAndOnOneAndTwoThreads) {
  SnowState s = test::makeRoughState(64, 50, 7);
  for (int y = 0; y < 50; ++y)
    for (int x = 0; x < 64; ++x)
      if (s.validCell(x, y)) s.unstableM(x, y) = 1.5f;
  int rx = 30, ry = 25;
  while (!s.validCell(rx, ry)) ++rx;
  for (AvalancheFlow flow : kFlows) {
    const AvalancheOutcome a = runAvalanche(s, rx, ry, withFlow(flow), createSerialBackend());
    ASSERT_GT(a.record.steps, 1);
    for (int threads : {1, 2}) {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<size_t>(threads));
      const AvalancheOutcome b = runAvalanche(s, rx, ry, withFlow(flow), createCpuBackend());
      test::expectSameBytes(a.state, b.state);
      EXPECT_EQ(0, std::memcmp(a.state.avalancheDepositM.data(), b.state.avalancheDepositM.data(), 64 * 50 * sizeof(float)))
          << flowName(flow) << ", " << threads;
    }
  }
}

// A box of 2^17 cells or more shares its rows among TBB's threads (smaller ones run on the
// calling thread): a release over the whole of a 400 x 340 grid, a few steps, the serial
// executor's bytes on two threads.
TEST(Avalanche, ABoxLargeEnoughToShareAmongThreadsGivesTheSerialBytes) {
  constexpr int w = 400, h = 340;
  SnowState s = test::makeRoughState(w, h, 5);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (s.validCell(x, y)) s.unstableM(x, y) = 1.5f;
  ModelParameters p;
  p.avalancheMaxDurationS = 0.5;
  const std::vector<uint8_t> zone(static_cast<size_t>(w) * h, 1);
  auto run = [&](std::unique_ptr<SnowBackend> backend) {
    SnowState t = s;
    backend->upload(t);
    AvalancheRun r(*backend, p, t);
    EXPECT_TRUE(r.releaseZone(zone, 0.0, 0.0, true));
    AvalancheOutcome o;
    o.record = r.runToRest();
    backend->download(t);
    o.state = std::move(t);
    return o;
  };
  const AvalancheOutcome serial = run(createSerialBackend());
  ASSERT_GE(serial.record.boxCellsMax, 1 << 17);
  ASSERT_GE(serial.record.steps, 3);
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
  const AvalancheOutcome shared = run(createCpuBackend());
  test::expectSameBytes(serial.state, shared.state);
}

// The TBB executor's row paths for the avalanche passes (avalanche_rows.h: flow, scale and row
// statistics eight cells at a time with AVX2 or four with SSE2, heights four with AVX2; the
// grid's edges and the spans' tails cell by cell) give the per-cell bodies' bytes, as the serial
// executor runs them: on rough terrain with NODATA holes reaching the grid's edges, dry, wet and
// in between (the temperature crosses T_dry and T_wet from cell to cell), with and without the
// turbulent drag, with T_dry = T_wet, and with no stop thickness; every field, peaks included.
TEST(Avalanche, RowPathsGiveThePerCellBodiesBytesDryWetAndWithDrag) {
  SnowState s = test::makeRoughState(61, 47, 11);
  for (int y = 0; y < 47; ++y)
    for (int x = 0; x < 61; ++x) {
      s.temperatureBaseC(x, y) = static_cast<float>(-14.0 + 0.27 * x + 0.05 * y);  // -14 to 4.5 degrees
      if (s.validCell(x, y)) s.unstableM(x, y) = 0.4f + 0.02f * static_cast<float>((x * 7 + y * 3) % 50);
    }
  int rx = 30, ry = 23;
  while (!s.validCell(rx, ry)) ++rx;
  // The row paths are the pipes' (the shallow water runs its per-cell bodies on every executor).
  const ModelParameters pipes = withFlow(AvalancheFlow::Pipes);
  ModelParameters wetIsDry = pipes, noDrag = pipes, noStop = pipes;
  wetIsDry.avalancheWetTemperatureC = wetIsDry.avalancheDryTemperatureC = -5.0;
  noDrag.avalancheTurbulenceMps2 = 0.0;
  noStop.avalancheStopThicknessM = 0.0;
  const std::pair<const char*, ModelParameters> cases[] = {
      {"defaults", pipes}, {"T_dry = T_wet", wetIsDry}, {"no drag", noDrag}, {"no stop thickness", noStop}};
  for (const auto& [name, p] : cases) {
    const AvalancheOutcome serial = runAvalanche(s, rx, ry, p, createSerialBackend());
    ASSERT_GT(serial.record.steps, 5) << name;
    for (const bool avx2 : {true, false}) {
      SCOPED_TRACE(std::string(name) + (avx2 ? ", AVX2 allowed" : ", SSE2 alone"));
      lanesAvx2Allowed() = avx2;
      const AvalancheOutcome rows = runAvalanche(s, rx, ry, p, createCpuBackend());
      lanesAvx2Allowed() = true;
      test::expectSameBytes(serial.state, rows.state);
      EXPECT_EQ(serial.state.avalancheDepositM.values(), rows.state.avalancheDepositM.values());
      EXPECT_EQ(serial.record.steps, rows.record.steps);
    }
  }
}

// The spontaneous release weights four cells at a time with AVX2 (releaseWeightsLanes) are the
// per-cell loop's doubles, on a rough terrain with NODATA holes, cliffs and a grid width that is
// not a multiple of four, with and without the scene's release factors; some cells weigh
// something, some are capped at 1.
TEST(Avalanche, ReleaseWeightsInLanesAreThePerCellLoopsDoubles) {
  for (const bool factors : {false, true}) {
    SCOPED_TRACE(factors ? "release factors" : "no release factors");
    SnowState s = test::makeRoughState(61, 47, 5, 2.0, 6.0);
    for (int y = 0; y < 47; ++y)
      for (int x = 0; x < 61; ++x) s.unstableM(x, y) = 0.05f * static_cast<float>((3 * x + y) % 13);
    if (factors) {
      s.avalancheReleaseFactor.resize(61, 47);
      for (int y = 0; y < 47; ++y)
        for (int x = 0; x < 61; ++x) s.avalancheReleaseFactor(x, y) = 0.25f * static_cast<float>((x + 2 * y) % 9);
    }
    auto backend = createCpuBackend();
    backend->upload(s);
    const ModelParameters params;
    AvalancheRun run(*backend, params, s);
    ASSERT_TRUE(run.trySpontaneous(0.5, 10.0, -5.0));  // the try points the run at the layers
    std::vector<double> lanes(61 * 47), cells(61 * 47);
    run.releaseWeights(0, 47, lanes.data());
    lanesAvx2Allowed() = false;
    run.releaseWeights(0, 47, cells.data());
    lanesAvx2Allowed() = true;
    EXPECT_EQ(0, std::memcmp(lanes.data(), cells.data(), lanes.size() * sizeof(double)));
    EXPECT_GT(std::count_if(cells.begin(), cells.end(), [](double w) { return w > 0.0 && w < 1.0; }), 20);
    EXPECT_GT(std::count(cells.begin(), cells.end(), 1.0), 0);
    EXPECT_GT(std::count(cells.begin(), cells.end(), 0.0), 20);
  }
}

// A release on a rough diagonal slope runs along a band of snow across the grid, so its box holds
// far more cells than its path: the passes over the rows' spans give the same bytes as the passes
// over the whole box (state, scour and deposit, the record's steps and runout).
TEST(Avalanche, RowSpansGiveTheSameBytesAsTheWholeBox) {
  SnowState s = test::terrainFrom(96, 96, 5.0, -20.f, [](double x, double y) {
    return 2000.0 - 0.6 * (x + y) + 0.4 * std::sin(0.37 * x) * std::cos(0.29 * y);
  });
  int band = 0;
  for (int y = 0; y < 96; ++y)
    for (int x = 0; x < 96; ++x)
      if (std::abs(x - y) < 4) s.unstableM(x, y) = 1.2f, ++band;
  for (AvalancheFlow flow : kFlows) {
    const AvalancheOutcome spans = runAvalanche(s, 6, 6, withFlow(flow));
    const AvalancheOutcome box = runAvalanche(s, 6, 6, withFlow(flow), createCpuBackend(), false);
    ASSERT_TRUE(spans.record.released);
    ASSERT_GT(spans.record.steps, 5);
    // The spans leave out most of the box: the snow's band is a small share of it.
    EXPECT_LT(2 * band, spans.record.boxCellsMax) << flowName(flow);
    test::expectSameBytes(box.state, spans.state);
    EXPECT_EQ(box.state.avalancheScourM.values(), spans.state.avalancheScourM.values()) << flowName(flow);
    EXPECT_EQ(box.state.avalancheDepositM.values(), spans.state.avalancheDepositM.values()) << flowName(flow);
    EXPECT_EQ(box.record.steps, spans.record.steps) << flowName(flow);
    EXPECT_EQ(box.record.runoutM, spans.record.runoutM) << flowName(flow);
    std::printf("[ measure ] row spans against the box, %s: %d steps, box up to %d cells, band %d cells, runout %.0f m\n", flowName(flow),
                spans.record.steps, spans.record.boxCellsMax, band, spans.record.runoutM);
  }
}

// The live spans (AvalancheArgs::live: the passes also kept to the cells a pipe touched in the
// last two steps) give the source spans' bytes on four slopes (a diagonal band, a bowl, a runout
// where the deposit rests thick behind its front, a V valley); and so do an edit between the
// avalanche's steps that raises every other block of cells and a warm day's static fields, which
// set cells no pipe touched flowing (the next two steps keep to the source spans).
TEST(Avalanche, LiveSpansGiveTheSourceSpansBytesAlsoWhenTheStateIsEditedOrWarmedMidRun) {
  SnowState band = test::terrainFrom(96, 96, 5.0, -20.f, [](double x, double y) {
    return 2000.0 - 0.6 * (x + y) + 0.4 * std::sin(0.37 * x) * std::cos(0.29 * y);
  });
  for (int y = 0; y < 96; ++y)
    for (int x = 0; x < 96; ++x)
      if (std::abs(x - y) < 4) band.unstableM(x, y) = 1.2f;
  SnowState bowl = test::terrainFrom(80, 80, 10.0, -20.f, [](double x, double y) {
    return 1500.0 + 0.02 * (x - 40) * (x - 40) + 0.02 * (y - 40) * (y - 40) + 0.3 * std::sin(0.5 * x);
  });
  for (int y = 0; y < 80; ++y)
    for (int x = 0; x < 80; ++x) bowl.unstableM(x, y) = 0.8f + 0.01f * static_cast<float>((x * 7 + y * 3) % 13);
  // A slab that slides off a slope onto a flat runout, where its deposit rests behind the front.
  SnowState runout = test::terrainFrom(40, 140, 5.0, -20.f, [](double x, double y) {
    return 2000.0 - (y < 40 ? 0.8 * y : 32.0 + 0.05 * (y - 40)) + 0.2 * std::sin(0.7 * x);
  });
  for (int y = 4; y < 36; ++y)
    for (int x = 8; x < 32; ++x) runout.unstableM(x, y) = 2.0f;
  // A V valley of 45-degree sides: the snow runs up the far side, stops and slides back.
  SnowState valley = test::terrainFrom(60, 30, 5.0, -20.f, [](double x, double y) { return 2000.0 + std::abs(x - 150.0) + 0.1 * y; });
  for (int y = 5; y < 25; ++y)
    for (int x = 2; x < 14; ++x) valley.unstableM(x, y) = 2.0f;
  for (const SnowState* s : {&band, &bowl, &runout, &valley})
    for (int fallAt : {-1, 6, 30})
      for (bool warm : {false, true}) {
        if (fallAt < 0 && warm) continue;
        auto run = [&](bool live, int& liveSteps) {
          auto backend = createCpuBackend();
          backend->upload(*s);
          const ModelParameters p = withFlow(AvalancheFlow::Pipes);  // the live spans are the pipes'
          AvalancheRun r(*backend, p, *s);
          r.useLiveSpans(live);
          const int rx = s == &band ? 6 : (s == &valley ? 8 : 20), ry = s == &band ? 6 : (s == &bowl ? 20 : (s == &valley ? 15 : 10));
          r.release(rx, ry, 0.0, 0.0, true);
          for (int step = 0; !r.atRest() && !r.step(); ++step)
            if (step == fallAt && warm) {  // a day's static fields: +2 C everywhere, wet snow's smaller friction
              SnowState day = *s;
              day.temperatureBaseC.fill(2.f);
              backend->uploadStaticFields(day);
            } else if (step == fallAt) {  // 10 m of compacted snow on every other 3 x 3 block: steep new slopes
              std::vector<float> weights(s->spec.cellCount());
              for (int y = 0; y < s->spec.height; ++y)
                for (int x = 0; x < s->spec.width; ++x) weights[static_cast<size_t>(y) * s->spec.width + x] = (x / 3 + y / 3) % 2;
              EditArgs edit;
              edit.layer = 0;
              edit.depthM = 10.f;
              backend->applyEdit(edit, weights);
            }
          liveSteps = r.liveSteps();
          AvalancheOutcome o{r.settle(), *s};
          backend->download(o.state);
          return o;
        };
        int liveSteps = 0, none = 0;
        const AvalancheOutcome live = run(true, liveSteps), source = run(false, none);
        ASSERT_TRUE(source.record.released);
        EXPECT_EQ(none, 0);
        EXPECT_GT(liveSteps, source.record.steps / 2) << "the live spans were used";
        test::expectSameBytes(source.state, live.state);
        EXPECT_EQ(source.state.avalancheScourM.values(), live.state.avalancheScourM.values());
        EXPECT_EQ(source.state.avalancheDepositM.values(), live.state.avalancheDepositM.values());
        EXPECT_EQ(source.record.steps, live.record.steps);
        std::printf("[ measure ] %s, %s after step %d: %d steps, %d with live spans\n",
                    s == &band ? "band" : (s == &bowl ? "bowl" : (s == &runout ? "runout" : "valley")), warm ? "warm day" : "edit", fallAt,
                    live.record.steps, liveSteps);
      }
}

// The record's box-cell steps (the bench's cost per box cell) sum each step's box: at least a
// cell a step, at most the largest box every step, and more than the largest box once the run
// has more than one step.
TEST(Avalanche, BoxCellStepsSumEveryStepsBoxBetweenOneCellAndTheLargest) {
  SnowState s = test::terrainFrom(64, 64, 5.0, -20.f, [](double x, double y) { return 2000.0 - 0.7 * y + 0.1 * x; });
  for (int y = 4; y < 14; ++y)
    for (int x = 20; x < 40; ++x) s.unstableM(x, y) = 1.5f;
  const AvalancheOutcome o = runAvalanche(s, 30, 8);
  ASSERT_TRUE(o.record.released);
  ASSERT_GT(o.record.steps, 1);
  EXPECT_GE(o.record.boxCellSteps, o.record.steps);
  EXPECT_LE(o.record.boxCellSteps, static_cast<double>(o.record.steps) * o.record.boxCellsMax);
  EXPECT_GT(o.record.boxCellSteps, o.record.boxCellsMax);
}

// No unstable snow at the rupture point: nothing is released and the record says why.
TEST(Avalanche, NoUnstableSnowNoRelease) {
  SnowState s = test::terrainFrom(10, 10, 5.0, -20.f, [](double, double y) { return 1000.0 - y; });
  const AvalancheOutcome o = runAvalanche(s, 5, 5);
  EXPECT_FALSE(o.record.released);
  EXPECT_NE(o.record.why.find("no unstable snow"), std::string::npos);
}

// A real release: Tyrol (avaWog, 5 m). Three weeks of cold storms build unstable snow on the
// steep upper slopes (too cold for stability changes above 1500 m); on day 21 a user avalanche
// at 2330 m runs down the gully below and stops at its foot. Checked: released volume stays
// (mass), the runout and fall are those of a real path (hundreds of metres), the deposit lies
// far below the rupture and in a hollow of the terrain (bedrock below the mean of a 50 m ring
// around it), and the bake's preview shows it.
TEST(Avalanche, TyrolUserReleaseRunsDownTheGullyAndDepositsAtItsFoot) {
  const std::string dem = std::string(SNOWBAKE_SHARED_DATA_DIR) + "/dem/tyrol_avaWog_5m.asc";
  if (!std::filesystem::exists(dem)) GTEST_SKIP() << "shared data not found: ../shared/data/dem/tyrol_avaWog_5m.asc";
  namespace fs = std::filesystem;
  std::ostringstream text;
  text << "[terrain]\nfile = \"" << dem << "\"\n[season]\nstart_date = 2026-01-01\ndays = 22\n"
       << "[[weather.keyframe]]\nday = 0\nsea_level_temperature_c = -6.0\n"
       << "[[weather.snowfall]]\nstart_day = 1\nend_day = 20\n"
       << "[[events]]\ntype = \"avalanche\"\nday = 21\nposition_m = [1877, 2352]\n"
       << "[parameters]\nrain_snow_limit_m = 1000\navalanche_rate_per_km2_per_day = 0\nskiers_per_hour = 0\n"
       << "[outputs]\nlayers = [\"bedrock\", \"avalanche_deposit\", \"avalanche_scour\", \"avalanche_preview\"]\n"
       << "avalanche_maps = true\navalanche_frame_interval_s = 30\n";
  const test::Bake bake = test::bakeSceneText("tyrol_avalanche_test", text.str());
  const fs::path dir = bake.dir;
  const BakeResult& r = bake.result;
  ASSERT_EQ(r.season.avalanches.size(), 1u);
  const AvalancheRecord& a = r.season.avalanches[0];
  ASSERT_TRUE(a.released) << a.why;
  const Grid<float> bed = readFloatImage((dir / "out" / "bedrock.exr").string());
  const Grid<float> deposit = readFloatImage((dir / "out" / "avalanche_deposit.exr").string());
  const Grid<float> scour = readFloatImage((dir / "out" / "avalanche_scour.exr").string());
  double depositM3 = 0, scourM3 = 0, depositAltitude = 0, hollow = 0, weight = 0;
  const int w = bed.width(), h = bed.height();
  const float lowest = *std::min_element(bed.values().begin(), bed.values().end());  // what NODATA cells hold
  for (float v : deposit.values()) depositM3 += v * 25.0;
  for (float v : scour.values()) scourM3 += v * 25.0;
  for (int y = 10; y < h - 10; ++y)
    for (int x = 10; x < w - 10; ++x) {
      if (deposit(x, y) < 0.5f) continue;
      double ring = 0;
      bool ringValid = true;  // the ring's mean means something only on the terrain
      for (int k = 0; k < 16; ++k) {
        const float b = bed(x + static_cast<int>(std::lround(10 * std::cos(k * 0.3927))), y + static_cast<int>(std::lround(10 * std::sin(k * 0.3927))));
        ring += b;
        ringValid = ringValid && b > lowest;
      }
      if (!ringValid) continue;
      hollow += (ring / 16 - bed(x, y)) * deposit(x, y);
      depositAltitude += bed(x, y) * deposit(x, y);
      weight += deposit(x, y);
    }
  std::printf("[ measure ] Tyrol release: %d cells, %.0f m^3; runout %.0f m, fall %.0f m, %d steps (%.0f s simulated), "
              "%.3f ms a step; deposit %.0f m^3 (scour %.0f), deposit mean altitude %.0f m, %.1f m below its 50 m ring\n",
              a.releaseCells, a.releasedM3, a.runoutM, a.fallHeightM, a.steps, a.simulatedS, a.secondsPerStep() * 1e3, depositM3,
              scourM3, depositAltitude / weight, hollow / weight);
  EXPECT_NEAR(depositM3, scourM3, 1e-3 * scourM3);  // net changes of one avalanche balance
  EXPECT_GT(a.runoutM, 400.0);
  EXPECT_GT(a.fallHeightM, 200.0);
  ASSERT_GT(weight, 0);
  EXPECT_LT(depositAltitude / weight, 2330.0 - 200.0);
  EXPECT_GT(hollow / weight, 0.5);  // in a hollow: the gully's floor
  EXPECT_TRUE(std::filesystem::exists(dir / "out" / "avalanche_preview.png"));
  // The avalanche's own maps: its release zone has the released cells, its scour and deposit are
  // the season's (it is the only avalanche); frames every 30 s plus the first and the last, each
  // holding the same snow.
  const Grid<float> release = readFloatImage((dir / "out" / "avalanches" / "001_release.exr").string());
  const Grid<float> ownDeposit = readFloatImage((dir / "out" / "avalanches" / "001_deposit.exr").string());
  double released = 0;
  for (float v : release.values()) released += v;
  EXPECT_EQ(released, a.releaseCells);
  float worst = 0.f;  // the same net change, summed in another order
  for (size_t i = 0; i < deposit.size(); ++i) worst = std::max(worst, std::abs(ownDeposit.values()[i] - deposit.values()[i]));
  EXPECT_LT(worst, 1e-4f);
  const int frames = static_cast<int>(a.simulatedS / 30.0 + 1e-9) + 2;
  double first = -1;
  for (int k = 0; k < frames; ++k) {
    char name[32];
    std::snprintf(name, sizeof name, "depth.%04d.exr", k);
    const fs::path f = dir / "out" / "avalanches" / "001" / name;
    ASSERT_TRUE(fs::exists(f)) << f;
    const Grid<float> d = readFloatImage(f.string());
    double total = 0;
    for (float v : d.values()) total += v;
    if (first < 0) first = total;
    EXPECT_NEAR(total, first, 1e-5 * first) << k;
  }
  char extra[32];
  std::snprintf(extra, sizeof extra, "depth.%04d.exr", frames);
  EXPECT_FALSE(fs::exists(dir / "out" / "avalanches" / "001" / extra));
  fs::remove_all(dir);
}

// outputs.avalanche_frame_interval_s alone asks for the maps too (its key's text): the season keeps
// the peak records the maps read (it failed in downloadBox at the first release without
// avalanche_maps = true), and each released avalanche gets its maps and motion frames.
TEST(Avalanche, FrameIntervalAloneWritesEachAvalanchesMapsAndFrames) {
  namespace fs = std::filesystem;
  const fs::path dir = test::uniqueTestDir("frame_interval");
  BakeOptions o;
  o.outDir = (dir / "out").string();
  o.backend = "cpu";
  o.useCache = false;
  o.progress = false;
  o.sets = {"terrain.size=96", "season.days=40", "outputs.frames_days=[]", "outputs.vdb=false", "outputs.meshes=[]",
            "outputs.avalanche_frame_interval_s=5"};
  std::ostringstream log;
  const BakeResult r = runBake(o, log);
  int released = 0;
  for (const AvalancheRecord& a : r.season.avalanches) released += a.released;
  ASSERT_GT(released, 0) << "no avalanche released: nothing to map";
  EXPECT_TRUE(fs::exists(dir / "out" / "avalanches" / "001_deposit.exr"));
  EXPECT_TRUE(fs::exists(dir / "out" / "avalanches" / "001_peak_speed.exr"));
  EXPECT_TRUE(fs::exists(dir / "out" / "avalanches" / "001" / "depth.0000.exr"));
}
