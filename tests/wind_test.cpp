// The wind field and the wind-effect surface (paper §4.2) against analytic cases.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "core/default_terrain.h"
#include "core/grid_window.h"
#include "precompute/wind.h"
#include "precompute/wind_timeline.h"

#include <filesystem>
#include "temp_dir.h"

using namespace snow;

namespace {

GridSpec squareSpec(int w, int h, double cell) {
  GridSpec s;
  s.width = w;
  s.height = h;
  s.cellSizeXM = s.cellSizeYM = cell;
  return s;
}

// Analytic lee cap behind a step of height H with a uniform wind U across it: past the edge
// W_sz = -c s / U and W_z = H - c s^2 / (2 U^2) until it meets the ground at L = U sqrt(2H / c).
double analyticCap(double s, double H, double U, double c) { return std::max(0.0, H - c * s * s / (2.0 * U * U)); }

struct StepCase {
  Grid<float> altitude, windX, windY, wz, wsz;
  Grid<uint8_t> valid;
  GridSpec spec;
  WindSolveStats stats;
};

// A step down of H metres across a line through the grid centre at `angleDeg` to the x axis;
// a uniform wind of U m/s blows perpendicular to it, from the high side.
StepCase solveStep(int n, double cell, double H, double U, double c, double angleDeg, WindOrdering ordering = WindOrdering::UpwindSweep) {
  StepCase k;
  k.spec = squareSpec(n, n, cell);
  k.altitude.resize(n, n);
  k.valid.resize(n, n, 1);
  k.windX.resize(n, n);
  k.windY.resize(n, n);
  const double t = angleDeg * M_PI / 180.0, ux = std::cos(t), uy = std::sin(t);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const double s = ((x + 0.5) - n * 0.3) * cell * ux + ((y + 0.5) - n * 0.3) * cell * uy;  // along the wind
      k.altitude(x, y) = s < 0 ? static_cast<float>(H) : 0.f;
      k.windX(x, y) = static_cast<float>(U * ux);
      k.windY(x, y) = static_cast<float>(U * uy);
    }
  WindSolverOptions o;
  o.ordering = ordering;
  o.toleranceM = 1e-6;
  k.stats = solveWindEffectSurface(k.altitude, k.valid, k.spec, k.windX, k.windY, k.windX, k.windY, c, o, k.wz, k.wsz);
  return k;
}

}  // namespace

TEST(WindField, FlatTerrainIsTheVenturiScaledDominantWind) {
  const GridSpec spec = squareSpec(20, 10, 10.0);
  Grid<float> a(20, 10, 1500.f);
  Grid<uint8_t> valid(20, 10, 1);
  ModelParameters p;  // k_venturi = 1e-3 /m
  const WindField f = computeWindField(a, valid, spec, WindState{270.0, 10.0}, p);
  for (int y = 0; y < 10; ++y)
    for (int x = 0; x < 20; ++x) {
      EXPECT_FLOAT_EQ(f.windXMps(x, y), 25.f);  // (1 + 1e-3 * 1500) * 10, eastward
      EXPECT_FLOAT_EQ(f.windYMps(x, y), 0.f);
      EXPECT_EQ(f.windEffectZM(x, y), 1500.f);
      EXPECT_EQ(f.verticalSpeedMps(x, y), 0.f);
    }
  EXPECT_TRUE(f.stats.converged);
  // From the north (0 deg) the wind moves south: +y in grid rows.
  const WindField n = computeWindField(a, valid, spec, WindState{0.0, 4.0}, p);
  EXPECT_FLOAT_EQ(n.windXMps(3, 3), 0.f);
  EXPECT_FLOAT_EQ(n.windYMps(3, 3), 10.f);
}

TEST(WindField, SlopesTurnTheWindAlongThem) {
  // A plane rising northward (toward row 0) with a westerly wind: n_xy points south (downhill),
  // so the wind gains a component along the slope and loses (1 - |n_xy|) of its speed.
  const GridSpec spec = squareSpec(9, 9, 10.0);
  Grid<float> a(9, 9);
  for (int y = 0; y < 9; ++y)
    for (int x = 0; x < 9; ++x) a(x, y) = static_cast<float>(1000.0 - 5.0 * y);  // slope 0.5
  Grid<uint8_t> valid(9, 9, 1);
  ModelParameters p;
  p.venturiPerM = 0.0;
  Grid<float> wx, wy;
  computeWindVectors(a, valid, spec, WindState{270.0, 10.0}, p, wx, wy);
  const double nLen = 0.5 / std::sqrt(1.25);  // sin(atan(0.5))
  EXPECT_NEAR(wx(4, 4), 10.0 * (1.0 - nLen) + 0.5 * 10.0 * nLen, 1e-4);  // n_perp along +x, toward the wind
  EXPECT_NEAR(wy(4, 4), 0.0, 1e-4);
}

TEST(WindEffectSurface, CalmWindHugsTheGround) {
  const GridSpec spec = squareSpec(16, 16, 5.0);
  Grid<float> a(16, 16);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) a(x, y) = static_cast<float>(100.0 + 30.0 * std::sin(x * 0.7) * std::cos(y * 0.4));
  Grid<uint8_t> valid(16, 16, 1);
  const WindField f = computeWindField(a, valid, spec, WindState{90.0, 0.0}, ModelParameters{});
  EXPECT_EQ(f.windEffectZM.values(), a.values());
  for (float v : f.verticalSpeedMps.values()) EXPECT_EQ(v, 0.f);
}

// The lee cap behind a 50 m step, 10 m/s wind, c = 0.7 m/s^2: L = 119.5 m over 1 m cells. The
// first-order upwind scheme's error grows as dx / L of the cap height at most (0.8 % here).
TEST(WindEffectSurface, LeeCapMatchesTheAnalyticParabola) {
  const double H = 50.0, U = 10.0, c = 0.7, cell = 1.0;
  const StepCase k = solveStep(400, cell, H, U, c, 0.0);
  ASSERT_TRUE(k.stats.converged);
  const int y = 200;
  const int edge = static_cast<int>(400 * 0.3) - 1;  // the last high cell
  for (int x = edge + 1; x < 400; ++x) {
    // W_sz falls linearly while in the cap.
    const double s = (x - edge) * cell;
    if (analyticCap(s, H, U, c) > 2.0) {
      EXPECT_NEAR(k.wsz(x, y), -c * s / U, 0.01 * c * s / U);
    }
  }
  double worstCap = 0.0;
  for (int x = edge + 1; x < 400; ++x) {
    const double s = (x - edge) * cell;
    worstCap = std::max(worstCap, std::abs(k.wz(x, y) - analyticCap(s, H, U, c)));
  }
  EXPECT_LT(worstCap, 0.01 * H) << "largest deviation " << worstCap << " m";
  std::printf("[ measure ] lee cap: largest deviation from the analytic parabola %.3f m of %.0f m (%.2f %%)\n", worstCap, H,
              100.0 * worstCap / H);
}

// L = U sqrt(2H / c): a quarter of c, twice the cap length.
TEST(WindEffectSurface, CapLengthScalesAsTheAnalyticSolution) {
  auto capLength = [](double c) {
    const StepCase k = solveStep(600, 1.0, 30.0, 8.0, c, 0.0);
    int x = static_cast<int>(600 * 0.3);
    while (x < 600 && k.wz(x, 300) > 0.05f) ++x;
    return static_cast<double>(x - (static_cast<int>(600 * 0.3) - 1));
  };
  const double l1 = capLength(1.0), l4 = capLength(0.25);
  EXPECT_NEAR(l1, 8.0 * std::sqrt(60.0), 3.0);
  EXPECT_NEAR(l4 / l1, 2.0, 0.05);
}

// The same step and wind rotated by 30 and 45 degrees to the grid: the cap profile along the
// wind, as a function of distance from the step line, stays within 4 % of H of the aligned one
// (the staircase of the rotated step line and the upwind scheme's cross-wind diffusion).
TEST(WindEffectSurface, RotatedStepGivesTheSameCap) {
  const double H = 40.0, U = 10.0, c = 0.7, cell = 1.0;
  const int n = 420;
  for (double angle : {30.0, 45.0}) {
    const StepCase k = solveStep(n, cell, H, U, c, angle);
    ASSERT_TRUE(k.stats.converged);
    const double t = angle * M_PI / 180.0;
    double worst = 0.0;
    int samples = 0;
    for (int y = n / 4; y < 3 * n / 4; ++y)
      for (int x = n / 4; x < 3 * n / 4; ++x) {
        const double s = ((x + 0.5) - n * 0.3) * cell * std::cos(t) + ((y + 0.5) - n * 0.3) * cell * std::sin(t);
        if (s < 2.0 || s > 150.0) continue;
        worst = std::max(worst, std::abs(k.wz(x, y) - analyticCap(s, H, U, c)));
        ++samples;
      }
    EXPECT_GT(samples, 1000);
    EXPECT_LT(worst, 0.04 * H) << angle << " degrees: largest deviation " << worst << " m";
    std::printf("[ measure ] step at %.0f degrees: largest deviation from the aligned analytic cap %.3f m of %.0f m (%.2f %%)\n",
                angle, worst, H, 100.0 * worst / H);
  }
}

// Both orderings reach the same fixed point on a real-looking terrain.
TEST(WindEffectSurface, RedBlackAndUpwindSweepAgree) {
  DefaultTerrainOptions o;
  o.size = 96;
  o.cellSizeM = 20.0;
  GridSpec spec;
  const Grid<float> a = generateDefaultTerrain(o, &spec);
  Grid<uint8_t> valid(96, 96, 1);
  for (int y = 40; y < 50; ++y)
    for (int x = 30; x < 45; ++x) valid(x, y) = 0;  // a NODATA hole
  ModelParameters p;
  WindSolverOptions sweep, redBlack;
  sweep.toleranceM = redBlack.toleranceM = 1e-7;
  redBlack.ordering = WindOrdering::RedBlack;
  const WindField fs = computeWindField(a, valid, spec, WindState{300.0, 12.0}, p, sweep);
  const WindField fr = computeWindField(a, valid, spec, WindState{300.0, 12.0}, p, redBlack);
  ASSERT_TRUE(fs.stats.converged) << fs.stats.iterations << " " << fs.stats.lastUpdate;
  ASSERT_TRUE(fr.stats.converged) << fr.stats.iterations << " " << fr.stats.lastUpdate;
  EXPECT_LT(fs.stats.iterations, fr.stats.iterations);
  double worst = 0.0, capCells = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    worst = std::max(worst, static_cast<double>(std::abs(fs.windEffectZM.values()[i] - fr.windEffectZM.values()[i])));
    if (fs.windEffectZM.values()[i] > a.values()[i] + 1.f) ++capCells;
    ASSERT_GE(fs.windEffectZM.values()[i], a.values()[i]);  // never below the ground
  }
  EXPECT_LT(worst, 1e-3);
  EXPECT_GT(capCells, 100) << "the range should cast wind shadows";
  EXPECT_LT(fs.stats.residual, 1e-6);
}

namespace {
WeatherTimeline twoWinds() {
  WeatherTimeline t;
  WeatherKeyframe a, b, c;
  a.day = 0;
  a.state.windDirectionDeg = 270;
  a.state.windSpeedMps = 10;
  b.day = 10;
  b.state.windDirectionDeg = 270;
  b.state.windSpeedMps = 10;  // the same state again: computed once
  c.day = 20;
  c.state.windDirectionDeg = 180;
  c.state.windSpeedMps = 6;
  t.keyframes = {a, b, c};
  return t;
}
std::string tempCacheDir() {
  return test::uniqueTestDir("wind_cache").string();
}
}  // namespace

TEST(WindTimeline, NoWindNoWork) {
  DefaultTerrainOptions o;
  o.size = 32;
  GridSpec spec;
  const Grid<float> a = generateDefaultTerrain(o, &spec);
  const Grid<uint8_t> valid(32, 32, 1);
  WeatherTimeline calm;
  calm.keyframes = {WeatherKeyframe{}};  // speed 0
  const WindTimeline t(a, valid, spec, calm, ModelParameters{}, PrecomputeCache("", false));
  EXPECT_FALSE(t.hasWind());
  EXPECT_EQ(t.computedStates(), 0u);
  const WindFieldsAtDay f = t.at(5.0);
  EXPECT_EQ(f.windEffectZM.values(), a.values());
}

TEST(WindTimeline, OneFieldPerDistinctStateBlendedBetweenKeyframes) {
  DefaultTerrainOptions o;
  o.size = 48;
  GridSpec spec;
  const Grid<float> a = generateDefaultTerrain(o, &spec);
  const Grid<uint8_t> valid(48, 48, 1);
  const WindTimeline t(a, valid, spec, twoWinds(), ModelParameters{}, PrecomputeCache("", false));
  ASSERT_EQ(t.stateCount(), 2u);
  EXPECT_EQ(t.computedStates(), 2u);
  const WindFieldsAtDay early = t.at(5.0), mid = t.at(15.0), late = t.at(30.0);
  EXPECT_EQ(early.windXMps.values(), t.field(0).windXMps.values());
  EXPECT_EQ(late.windYMps.values(), t.field(1).windYMps.values());
  for (int i : {0, 100, 1000, 2000})
    EXPECT_NEAR(mid.windEffectZM.values()[i],
                0.5f * (t.field(0).windEffectZM.values()[i] + t.field(1).windEffectZM.values()[i]), 1e-3f);
}

namespace {

// The timelines of a rank's part: a 40² range with a NODATA cell, two winds with a calm keyframe
// between them.
struct CalmBetweenWinds {
  GridSpec spec;
  Grid<float> altitude;
  Grid<uint8_t> valid{40, 40, 1};
  WeatherTimeline weather = twoWinds();
  CalmBetweenWinds() {
    DefaultTerrainOptions o;
    o.size = 40;
    altitude = generateDefaultTerrain(o, &spec);
    valid(20, 20) = 0;
    weather.keyframes[1].state.windSpeedMps = 0;
  }
};

// On every day, calm ones included, `part`'s fields are `whole`'s cells `c`, byte for byte.
void expectTheWholesCellsOnEveryDay(const WindTimeline& whole, const WindTimeline& part, const CellRect& c) {
  for (double day : {0.0, 4.0, 10.0, 14.5, 20.0, 30.0}) {
    const WindFieldsAtDay all = whole.at(day), cut = part.at(day);
    EXPECT_EQ(gridWindow(all.windXMps, c), cut.windXMps) << day;
    EXPECT_EQ(gridWindow(all.windYMps, c), cut.windYMps) << day;
    EXPECT_EQ(gridWindow(all.windEffectZM, c), cut.windEffectZM) << day;
    EXPECT_EQ(gridWindow(all.windLoadingMps2, c), cut.windLoadingMps2) << day;
  }
}

}  // namespace

// A rank's window of the timeline (a bake across ranks): on every day the whole timeline's cells.
TEST(WindTimeline, AWindowGivesItsCellsOfTheWholeFieldsOnEveryDay) {
  const CalmBetweenWinds k;
  const WindTimeline whole(k.altitude, k.valid, k.spec, k.weather, ModelParameters{}, PrecomputeCache("", false));
  ASSERT_TRUE(whole.varies());
  expectTheWholesCellsOnEveryDay(whole, whole.window(7, 11, 25, 19), CellRect{7, 11, 32, 30});
}

// A timeline made for part of the grid (a rank's local grid) whose solve declines a state (the
// free stream turns) solves the whole grid and keeps its cells: on every day the bytes of the
// whole timeline's window; the states the part solves are asked for in keyframe order.
TEST(WindTimeline, APartWhoseSolveDeclinesKeepsItsCellsOfTheWholeGridsSolve) {
  const CalmBetweenWinds k;
  const WindTimeline whole(k.altitude, k.valid, k.spec, k.weather, ModelParameters{}, PrecomputeCache("", false));
  std::vector<double> asked;
  const WindPart part{CellRect{7, 11, 32, 30}, [&](const Grid<float>&, const Grid<uint8_t>&, const GridSpec&, const WindState& s,
                                                   const ModelParameters&, const WindSolverOptions&, WindField&, Grid<float>&) {
                        asked.push_back(s.directionDeg);
                        return false;
                      }};
  const WindTimeline mine(k.altitude, k.valid, k.spec, k.weather, ModelParameters{}, PrecomputeCache("", false), WindSolverOptions{},
                          nullptr, &part);
  ASSERT_EQ(asked.size(), whole.stateCount());
  for (size_t i = 0; i < asked.size(); ++i) EXPECT_EQ(asked[i], whole.states()[i].directionDeg);
  ASSERT_TRUE(mine.cells() && *mine.cells() == part.cells);
  expectTheWholesCellsOnEveryDay(whole, mine, part.cells);
}

// A rank's part is cached as an entry of its own (the whole grid's key and its cells) and read back
// only where every rank found its own (everyRankFound); else the part is solved again.
TEST(WindTimeline, APartIsCachedAsItsOwnEntryAndReadOnlyWhereEveryRankFoundItsOwn) {
  const CalmBetweenWinds k;
  const WindTimeline whole(k.altitude, k.valid, k.spec, k.weather, ModelParameters{}, PrecomputeCache("", false));
  const std::string dir = tempCacheDir();
  const PrecomputeCache cache(dir, true);
  size_t solves = 0;
  bool othersFound = true;
  std::vector<bool> asked;  // this rank's finding, each state
  const WindPart part{CellRect{7, 11, 32, 30},
                      [&](const Grid<float>&, const Grid<uint8_t>&, const GridSpec&, const WindState&, const ModelParameters&,
                          const WindSolverOptions&, WindField&, Grid<float>&) {
                        ++solves;
                        return false;  // the whole grid's solve, cut
                      },
                      [&](bool found) {
                        asked.push_back(found);
                        return found && othersFound;
                      }};
  auto timeline = [&] {
    return WindTimeline(k.altitude, k.valid, k.spec, k.weather, ModelParameters{}, cache, WindSolverOptions{}, nullptr, &part);
  };
  const size_t n = whole.stateCount();
  ASSERT_GE(n, 2u);
  const WindTimeline first = timeline();
  EXPECT_EQ(first.computedStates(), n);
  EXPECT_EQ(asked, std::vector<bool>(n, false));
  size_t entries = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    entries += e.path().filename().string().find("-cells-7-11-32-30") != std::string::npos;
  EXPECT_EQ(entries, n);
  asked.clear();
  const WindTimeline second = timeline();
  EXPECT_EQ(second.cachedStates(), n);
  EXPECT_EQ(second.computedStates(), 0u);
  EXPECT_EQ(asked, std::vector<bool>(n, true));
  EXPECT_EQ(solves, n);
  expectTheWholesCellsOnEveryDay(whole, second, part.cells);
  othersFound = false;  // another rank missed its part: this one solves with it
  const WindTimeline third = timeline();
  EXPECT_EQ(third.computedStates(), n);
  EXPECT_EQ(solves, 2 * n);
  expectTheWholesCellsOnEveryDay(whole, third, part.cells);
  std::filesystem::remove_all(dir);
}

TEST(WindTimeline, CacheReusedWhenInputsAreUnchanged) {
  DefaultTerrainOptions o;
  o.size = 40;
  GridSpec spec;
  const Grid<float> a = generateDefaultTerrain(o, &spec);
  const Grid<uint8_t> valid(40, 40, 1);
  const std::string dir = tempCacheDir();
  const PrecomputeCache cache(dir, true);
  const WindTimeline first(a, valid, spec, twoWinds(), ModelParameters{}, cache);
  EXPECT_EQ(first.computedStates(), 2u);
  const WindTimeline second(a, valid, spec, twoWinds(), ModelParameters{}, cache);
  EXPECT_EQ(second.cachedStates(), 2u);
  EXPECT_EQ(second.computedStates(), 0u);
  EXPECT_EQ(second.field(1).windEffectZM.values(), first.field(1).windEffectZM.values());
  ModelParameters other;
  other.windCapDecelerationMps2 = 0.5;  // a changed input: recomputed
  const WindTimeline third(a, valid, spec, twoWinds(), other, cache);
  EXPECT_EQ(third.computedStates(), 2u);
  // A damaged entry is ignored, not trusted.
  for (const auto& e : std::filesystem::directory_iterator(dir)) std::filesystem::resize_file(e.path(), 100);
  const WindTimeline fourth(a, valid, spec, twoWinds(), ModelParameters{}, cache);
  EXPECT_EQ(fourth.computedStates(), 2u);
  EXPECT_EQ(fourth.field(0).windEffectZM.values(), first.field(0).windEffectZM.values());
  const WindTimeline off(a, valid, spec, twoWinds(), ModelParameters{}, PrecomputeCache(dir, false));
  EXPECT_EQ(off.computedStates(), 2u);
  std::filesystem::remove_all(dir);
}
