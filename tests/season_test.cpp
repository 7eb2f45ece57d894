#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <string>

#include "core/cpu_backend.h"
#include "core/default_terrain.h"
#include "core/season.h"
#include "precompute/wind.h"
#include "precompute/wind_timeline.h"
#include "test_support.h"

using namespace snow;

namespace {

SnowState terrainState(int size, double cell) {
  DefaultTerrainOptions o;
  o.size = size;
  o.cellSizeM = cell;
  SnowState s;
  GridSpec spec;
  Grid<float> h = generateDefaultTerrain(o, &spec);
  s.allocate(spec);
  s.bedrockM = h;
  return s;
}

SeasonConfig winter(double days, double t0) {
  SeasonConfig c;
  c.days = days;
  c.seed = 4;
  c.params.rainSnowLimitM = 1200.0;
  WeatherKeyframe k;
  k.state.seaLevelTemperatureC = t0;
  c.weather.keyframes = {k};
  return c;
}

void expectPhysical(const SnowState& s) {
  for (const Grid<float>* g : {&s.compactedM, &s.stableM, &s.unstableM, &s.powderM})
    for (float v : g->values()) {
      ASSERT_TRUE(std::isfinite(v));
      ASSERT_GE(v, 0.f);
    }
}

}  // namespace

TEST(Season, MassBalanceHoldsOverAWinter) {
  SnowState s = terrainState(96, 20.0);
  SeasonConfig c = winter(120, 12.0);  // warm enough to melt the low slopes
  computeTemperatureBase(s, c.params);
  auto backend = createCpuBackend();
  const SeasonReport r = runSeason(*backend, s, c);
  EXPECT_GT(r.snowfallAddedM3, 0.0);
  EXPECT_GT(r.meltRemovedM3, 0.0);
  EXPECT_LT(r.massBalanceRelativeError(), 1e-6);
  expectPhysical(s);
  // The report's final total is the state's.
  double total = 0.0;
  for (int y = 0; y < 96; ++y)
    for (int x = 0; x < 96; ++x) total += s.depthM(x, y);
  EXPECT_NEAR(r.final.totalM3(), total * 400.0, 1e-6 * r.final.totalM3());
}

TEST(Season, MeltKernelsSkippedWhenTheWarmestCellIsBelowFreezing) {
  SnowState s = terrainState(48, 20.0);
  SeasonConfig c = winter(40, -5.0);  // every cell below 0 degC
  computeTemperatureBase(s, c.params);
  auto backend = createCpuBackend();
  const SeasonReport r = runSeason(*backend, s, c);
  const auto& melt = r.phenomena[1];
  ASSERT_EQ(melt.name, "melt");
  EXPECT_GT(melt.steps, 40u);
  EXPECT_EQ(melt.skippedSteps, melt.steps + 1);  // every step, and the catch-up at the season's end
  EXPECT_EQ(r.meltRemovedM3, 0.0);
}

// A phenomenon whose rate is zero is not run: each of its steps counted skipped, the log's reason
// naming the key (snowfall's too where the weather's intensity is zero). Skipping keeps the bytes: each kernel at a rate of zero, run on a rough state
// with snow in every layer, wind and wind loading, leaves every field as it was.
TEST(Season, PhenomenaOfZeroRateAreSkippedNamingTheKeyAndTheirKernelsWouldChangeNothing) {
  ModelParameters p;
  p.meltRateMPerDayPerC = 0.0;
  p.instabilityByWarmthMPerDay = p.stabilityByColdMPerDay = 0.0;
  p.windInstabilityPerMps2 = 0.0;
  p.diffusionRatePerDay = 0.0;
  p.windErosionRateMPerSPerDay = 0.0;
  SnowState rough = test::makeRoughState(64, 48, 7);
  auto backend = createCpuBackend();
  backend->upload(rough);
  WeatherState warm;
  warm.seaLevelTemperatureC = 25.0;  // above T_0melt and T_warm on every cell
  p.snowfallRatePerDay = 0.0;
  backend->snowfall(makeSnowfallArgs(p, 0.5, warm));
  backend->melt(makeMeltArgs(p, 0.5, warm));
  backend->stabilityChange(makeStabilityArgs(p, 0.5, warm));
  backend->powderDiffusion(makePowderDiffusionArgs(p, 0.5));
  backend->windTransport(makeWindTransportArgs(p, 0.5));
  SnowState after = rough;
  backend->download(after);
  test::expectSameBytes(rough, after);

  SnowState s = terrainState(48, 20.0);
  SeasonConfig c = winter(20, 8.0);
  c.params.meltRateMPerDayPerC = c.params.diffusionRatePerDay = c.params.windErosionRateMPerSPerDay = 0.0;
  c.params.instabilityByWarmthMPerDay = c.params.stabilityByColdMPerDay = c.params.windInstabilityPerMps2 = 0.0;
  c.windTransport = true;
  computeTemperatureBase(s, c.params);
  const SeasonReport r = runSeason(*backend, s, c);
  const std::map<std::string, std::string> keys = {{"melt", "melt_rate_m_per_day_per_c = 0"},
                                                   {"stability", "instability_by_warmth_m_per_day = stability_by_cold_m_per_day = 0"},
                                                   {"powder diffusion", "diffusion_rate_per_day = 0"},
                                                   {"wind transport", "wind_erosion_rate_m_per_s_per_day = 0"}};
  size_t seen = 0;
  for (const PhenomenonReport& ph : r.phenomena) {
    const auto k = keys.find(ph.name);
    if (k == keys.end()) continue;
    ++seen;
    EXPECT_GT(ph.steps, 20u) << ph.name;
    EXPECT_EQ(ph.skippedSteps, ph.steps + 1) << ph.name;  // every step, and the catch-up at the season's end
    EXPECT_NE(ph.skippedWhy.find(k->second), std::string::npos) << ph.name << ": " << ph.skippedWhy;
    EXPECT_EQ(ph.seconds, 0.0) << ph.name;
  }
  EXPECT_EQ(seen, keys.size());
  EXPECT_EQ(r.meltRemovedM3, 0.0);
  EXPECT_GT(r.snowfallAddedM3, 0.0);

  // No snowfall: its steps skipped, by the rate or by the weather's intensity.
  for (const bool byWeather : {false, true}) {
    SeasonConfig dry = winter(20, 8.0);
    if (byWeather) dry.weather.keyframes[0].state.snowfallIntensity = 0.0;
    else dry.params.snowfallRatePerDay = 0.0;
    SnowState bare = terrainState(48, 20.0);
    computeTemperatureBase(bare, dry.params);
    const SeasonReport d = runSeason(*backend, bare, dry);
    ASSERT_EQ(d.phenomena[0].name, "snowfall");
    EXPECT_GT(d.phenomena[0].steps, 0u);
    // Every step and stop skipped, and the catch-up of a storm still falling at the season's end.
    const uint64_t steps = d.phenomena[0].steps + d.phenomena[0].stops;
    EXPECT_GE(d.phenomena[0].skippedSteps, steps) << byWeather;
    EXPECT_LE(d.phenomena[0].skippedSteps, steps + 1) << byWeather;
    EXPECT_NE(d.phenomena[0].skippedWhy.find(byWeather ? "snowfall_intensity = 0" : "snowfall_rate_per_day = 0"), std::string::npos);
    EXPECT_EQ(d.snowfallAddedM3, 0.0);
  }
}

TEST(Season, SameSeedSameStateOtherSeedOtherState) {
  auto run = [](uint64_t seed) {
    SnowState s = terrainState(48, 20.0);
    SeasonConfig c = winter(60, 4.0);
    c.seed = seed;
    computeTemperatureBase(s, c.params);
    auto backend = createCpuBackend();
    runSeason(*backend, s, c);
    return s.powderM.values();
  };
  EXPECT_EQ(run(3), run(3));
  EXPECT_NE(run(3), run(8));
}

TEST(Season, FramesArriveAtTheirDaysAndFixedSnowfallPeriodsAreHonoured) {
  SnowState s = terrainState(32, 20.0);
  SeasonConfig c = winter(30, -3.0);
  c.weather.snowfallPeriods = {{5.0, 8.0}};
  c.frameDays = {4.0, 20.0};
  computeTemperatureBase(s, c.params);
  auto backend = createCpuBackend();
  std::vector<double> frameDays, frameSnow;
  const SeasonReport r = runSeason(*backend, s, c, {}, [&](double day, const SnowState& f) {
    frameDays.push_back(day);
    double t = 0;
    for (int y = 0; y < 32; ++y)
      for (int x = 0; x < 32; ++x) t += f.depthM(x, y);
    frameSnow.push_back(t);
  });
  EXPECT_EQ(frameDays, (std::vector<double>{4.0, 20.0}));
  EXPECT_EQ(frameSnow[0], 0.0);  // before the only snowfall period
  EXPECT_GT(frameSnow[1], 0.0);
  EXPECT_EQ(r.phenomena[0].starts, 1u);
  EXPECT_EQ(r.phenomena[0].stops, 1u);
}

// A small stress sweep (the 200-terrain sweep is stress_test.cpp): rough terrains
// with holes, cell sizes from 1 m to 100 m, warm and cold, long events. Never NaN or negative,
// mass balance holds.
TEST(Season, StressRoughTerrainsStayPhysical) {
  for (uint64_t seed = 0; seed < 12; ++seed) {
    const double cell = seed % 3 == 0 ? 1.0 : (seed % 3 == 1 ? 10.0 : 100.0);
    SnowState s = test::makeRoughState(40 + static_cast<int>(seed), 33, seed, cell, cell * 1.3);
    SeasonConfig c = winter(200, seed % 2 ? 15.0 : -2.0);
    c.seed = seed;
    c.params.snowfallRatePerDay = 1e-3 * static_cast<double>(seed + 1);
    c.params.diffusionRatePerDay = 5.0 * static_cast<double>(seed);
    c.params.diffusionStepsPerDay = 0.2;  // 5-day diffusion events: the kernel must substep
    computeTemperatureBase(s, c.params);
    auto backend = createCpuBackend();
    const SeasonReport r = runSeason(*backend, s, c);
    SCOPED_TRACE(seed);
    expectPhysical(s);
    EXPECT_LT(r.massBalanceRelativeError(), 1e-6);
  }
}

TEST(Weather, InterpolatesKeyframesAndWindDirectionTheShortWay) {
  WeatherTimeline t;
  WeatherKeyframe a, b;
  a.day = 0;
  a.state.seaLevelTemperatureC = 0;
  a.state.windDirectionDeg = 350;
  b.day = 10;
  b.state.seaLevelTemperatureC = 10;
  b.state.windDirectionDeg = 10;
  t.keyframes = {a, b};
  EXPECT_DOUBLE_EQ(t.at(5).seaLevelTemperatureC, 5.0);
  EXPECT_NEAR(t.at(5).windDirectionDeg, 0.0, 1e-9);
  EXPECT_DOUBLE_EQ(t.at(-3).seaLevelTemperatureC, 0.0);
  EXPECT_DOUBLE_EQ(t.at(30).seaLevelTemperatureC, 10.0);
}

TEST(DefaultTerrain, DeterministicAndInRange) {
  DefaultTerrainOptions o;
  o.size = 64;
  const Grid<float> a = generateDefaultTerrain(o), b = generateDefaultTerrain(o);
  EXPECT_EQ(a.values(), b.values());
  float lo = 1e9f, hi = -1e9f;
  for (float v : a.values()) lo = std::min(lo, v), hi = std::max(hi, v);
  EXPECT_FLOAT_EQ(lo, 900.f);
  EXPECT_FLOAT_EQ(hi, 3100.f);
  o.seed = 7;
  EXPECT_NE(generateDefaultTerrain(o).values(), a.values());
}

namespace {
// The range with a westerly wind field and its wind-effect surface.
SnowState windyRange(int size, double cell, double speed) {
  SnowState s = terrainState(size, cell);
  ModelParameters p;
  const WindField f = computeWindField(s.bedrockM, s.validCell, s.spec, WindState{270.0, speed}, p);
  s.windXMps = f.windXMps;
  s.windYMps = f.windYMps;
  s.windEffectZM = f.windEffectZM;
  s.windLoadingMps2 = windLoading(f, s.validCell, s.spec);
  return s;
}
}  // namespace

TEST(Season, WindScoursRidgesLoadsLeesAndConservesMass) {
  SnowState s = windyRange(96, 20.0, 10.0);
  SeasonConfig c = winter(60, -4.0);
  c.windTransport = true;
  computeTemperatureBase(s, c.params);
  auto backend = createCpuBackend();
  const SeasonReport r = runSeason(*backend, s, c);
  double scour = 0, deposit = 0;
  for (size_t i = 0; i < s.windScourM.size(); ++i) scour += s.windScourM.values()[i], deposit += s.windDepositM.values()[i];
  EXPECT_GT(scour, 1.0) << "the wind should move snow on this range";
  EXPECT_NEAR(deposit, scour, 1e-4 * scour);  // every scoured metre lands somewhere
  EXPECT_LT(r.massBalanceRelativeError(), 1e-6);
  expectPhysical(s);
  // Scour only where the surface is exposed (not in the wind shadow).
  for (size_t i = 0; i < s.windScourM.size(); ++i)
    if (s.windEffectZM.values()[i] - s.bedrockM.values()[i] > 30.f) {
      ASSERT_EQ(s.windScourM.values()[i], 0.f);
    }
  // Ridges scoured, lees loaded: the scour sits on the higher ground, the deposit in the shadow
  // (weighted by metres moved: the mean altitude and shadow depth of each).
  double scourZ = 0, depositZ = 0, scourShadow = 0, depositShadow = 0;
  for (size_t i = 0; i < s.windScourM.size(); ++i) {
    const double shadow = s.windEffectZM.values()[i] - s.bedrockM.values()[i];
    scourZ += s.windScourM.values()[i] * s.bedrockM.values()[i], depositZ += s.windDepositM.values()[i] * s.bedrockM.values()[i];
    scourShadow += s.windScourM.values()[i] * shadow, depositShadow += s.windDepositM.values()[i] * shadow;
  }
  std::printf("[ measure ] scour at %.1f m mean altitude, %.2f m mean shadow; deposit at %.1f m, %.2f m\n", scourZ / scour, scourShadow / scour,
              depositZ / deposit, depositShadow / deposit);
  EXPECT_GT(scourZ / scour, depositZ / deposit);
  EXPECT_GT(depositShadow / deposit, scourShadow / scour);
}

// The record fields are written by the kernels only where the season keeps them
// (SeasonConfig::recordFields): leaving any of them out changes no byte of the snow, of the
// records kept, or of a frame, and frees the others in the state and its frames.
// Frames written while the season waits (SeasonConfig::lendFrames: the backend's scratch, the
// avalanche runner's snapshot and the skiers' storage freed, the backend's fields lent to the
// host's state) are the bytes of frames copied from a season that goes on, and so is the season
// after them; a frame whose instant falls inside an avalanche is set aside on disk and written
// once it has settled, with the same bytes.
TEST(Season, FramesLentWhileTheSeasonWaitsAreTheBytesOfFramesCopied) {
  struct Run {
    SnowState end;
    std::vector<std::pair<double, SnowState>> frames;
    SeasonReport report;
  };
  auto run = [](bool lend, const std::vector<double>& frameDays) {
    Run r;
    r.end = windyRange(64, 20.0, 10.0);
    SeasonConfig c = winter(40, 10.0);
    c.windTransport = true;
    c.params.avalancheRatePerKm2PerDay = 20.0;
    c.params.skiersPerHour = 4.0;
    c.userAvalanches = {{25.0, 0, 0, false, std::make_shared<std::vector<uint8_t>>(64 * 64, uint8_t{1})}};
    c.userSkiers = {{25.0, 30, 6, 12, nullptr}};  // skiing while it runs
    c.frameDays = frameDays;
    c.recordFields = fieldBit(SnowField::meltedM) | fieldBit(SnowField::avalancheDepositM);
    c.lendFrames = lend;
    computeTemperatureBase(r.end, c.params);
    auto backend = createCpuBackend();
    r.report = runSeason(*backend, r.end, c, {}, [&](double day, const SnowState& f) { r.frames.emplace_back(day, f); });
    return r;
  };
  // Two frames 0.2 s and 0.9 s into an avalanche released over the whole terrain on day 25.
  const std::vector<double> days = {10.0, 25.0 + 2e-6, 25.0 + 1e-5, 30.0};
  const Run copied = run(false, days), lent = run(true, days);
  ASSERT_GT(copied.report.avalanches.size(), 2u);
  ASSERT_GT(copied.report.skiers.size(), 10u);
  EXPECT_EQ(copied.report.framesSetAside, 0);
  EXPECT_EQ(lent.report.framesSetAside, 2) << "the day-25 avalanche was no longer in motion at its frames' instants";
  EXPECT_EQ(lent.report.avalanches.size(), copied.report.avalanches.size());
  EXPECT_EQ(lent.report.skiers.size(), copied.report.skiers.size());
  ASSERT_EQ(lent.frames.size(), 4u);
  ASSERT_EQ(copied.frames.size(), 4u);
  for (size_t k = 0; k <= lent.frames.size(); ++k) {
    const SnowState& a = k < lent.frames.size() ? lent.frames[k].second : lent.end;
    const SnowState& b = k < copied.frames.size() ? copied.frames[k].second : copied.end;
    if (k < lent.frames.size()) {
      EXPECT_EQ(lent.frames[k].first, copied.frames[k].first);
    }
#define SNOW_COMPARE(member, view, Element, role, access, fill) \
  EXPECT_TRUE(a.member.values() == b.member.values()) << #member << " of " << (k < lent.frames.size() ? "frame " + std::to_string(k) : "the end");
    SNOW_STATE_FIELDS(SNOW_COMPARE)
#undef SNOW_COMPARE
  }
  double moving = 0;
  for (uint8_t m : lent.frames[1].second.snowMoving.values()) moving += m;
  EXPECT_GT(moving, 0.0) << "the frame inside the avalanche holds snow in motion";
}

TEST(Season, RecordFieldsLeftOutChangeNoByteOfTheSnowOrOfTheRecordsKept) {
  struct Run {
    SnowState end, frame;
    size_t avalanches = 0;
  };
  auto run = [](SnowFieldSet kept) {
    Run r;
    r.end = windyRange(64, 20.0, 10.0);
    SeasonConfig c = winter(40, 10.0);  // melt on the low slopes
    c.windTransport = true;
    c.params.avalancheRatePerKm2PerDay = 20.0;
    c.userAvalanches = {{5.0, 20, 30, false, nullptr}, {25.0, 40, 12, false, nullptr}};
    c.frameDays = {30.0};
    c.recordFields = kept;
    computeTemperatureBase(r.end, c.params);
    auto backend = createCpuBackend();
    const SeasonReport report = runSeason(*backend, r.end, c, {}, [&](double, const SnowState& f) { r.frame = f; });
    r.avalanches = report.avalanches.size();
    return r;
  };
  const Run whole = run(kAllRecordFields);
  ASSERT_GT(whole.avalanches, 2u);
  double melted = 0, scoured = 0, avalancheScoured = 0, peak = 0;
  for (size_t i = 0; i < whole.end.meltedM.size(); ++i)
    melted += whole.end.meltedM.values()[i], scoured += whole.end.windScourM.values()[i],
        avalancheScoured += whole.end.avalancheScourM.values()[i], peak = std::max<double>(peak, whole.end.avalancheSeasonPeakSpeedMps.values()[i]);
  ASSERT_GT(melted, 0.0);
  ASSERT_GT(scoured, 0.0);
  ASSERT_GT(avalancheScoured, 0.0);
  ASSERT_GT(peak, 0.0);
  const auto bit = [](SnowField f) { return fieldBit(f); };
  const SnowFieldSet peaks = bit(SnowField::avalanchePeakThicknessM) | bit(SnowField::avalanchePeakSpeedMps);
  for (SnowFieldSet kept : {SnowFieldSet(0), bit(SnowField::meltedM), bit(SnowField::windScourM),
                            bit(SnowField::avalancheDepositM) | bit(SnowField::windDepositM), peaks | bit(SnowField::avalancheSeasonPeakSpeedMps)}) {
    const Run lean = run(kept);
    EXPECT_EQ(lean.avalanches, whole.avalanches);
    for (const auto* pair : {&lean.end, &lean.frame}) {
      const SnowState& a = *pair;
      const SnowState& b = pair == &lean.end ? whole.end : whole.frame;
#define SNOW_COMPARE(member, view, Element, role, access, fill)                                                         \
  if (FieldRole::role == FieldRole::Evolved) {                                                                         \
    EXPECT_TRUE(a.member.values() == b.member.values()) << #member << " kept " << kept;                                \
  } else if (FieldRole::role == FieldRole::Record && (kept & bit(SnowField::member))) {                                \
    EXPECT_TRUE(a.member.values() == b.member.values()) << #member << " kept " << kept;                                \
  } else if (FieldRole::role == FieldRole::Record) {                                                                   \
    EXPECT_EQ(a.member.size(), 0u) << #member << " kept " << kept;                                                     \
  }
      SNOW_STATE_FIELDS(SNOW_COMPARE)
#undef SNOW_COMPARE
    }
  }
}
