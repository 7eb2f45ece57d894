// Stress: 200 random terrains (cliffs, one-cell spikes, flat plateaus, NODATA holes, up to 4000 m
// of relief on 5 m cells) with parameters drawn across and beyond their documented ranges, through
// 500-day seasons with wind (and wind bedforms on a quarter of them). Nothing may turn NaN,
// infinite or negative, and the mass balance
// must hold to float rounding. Layers are float: a cell takes about 0.5 ulp of error per
// operation, and where a handful of cells hold all the snow through thousands of events those
// errors do not average out over the grid. The worst case here is a few 1e-6 of the total
// (printed); we assert 2e-5. Realistic seasons on real grids stay near 1e-8 (season tests, bench).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "core/cpu_backend.h"
#include "core/rng.h"
#include "core/bedform_runs.h"
#include "core/season.h"
#include "precompute/wind.h"
#include "precompute/wind_timeline.h"

using namespace snow;

namespace {

struct Draw {
  RandomKey key;
  uint64_t n = 0;
  double uniform(double lo, double hi) {
    const Philox4x32 r = key.draw(n++, 0, RngStream::Test);
    return lo + (hi - lo) * uniformOpenDouble(r.v[0], r.v[1]);
  }
  double logUniform(double lo, double hi) { return std::exp(uniform(std::log(lo), std::log(hi))); }
  int integer(int lo, int hi) { return std::min(hi, lo + static_cast<int>(uniform(0, hi - lo + 1))); }
};

SnowState randomTerrain(Draw& d, int index) {
  const int w = d.integer(12, 28), h = d.integer(12, 28);
  const double cell = index % 4 == 0 ? 5.0 : d.logUniform(1.0, 100.0);
  const double relief = index % 4 == 0 ? 4000.0 : d.uniform(0.0, 3000.0);
  SnowState s;
  GridSpec spec;
  spec.width = w;
  spec.height = h;
  spec.cellSizeXM = cell;
  spec.cellSizeYM = cell * d.uniform(0.7, 1.4);
  s.allocate(spec);
  const double fx = d.uniform(0.05, 0.5), fy = d.uniform(0.05, 0.5);
  const int cliffAt = d.integer(1, w - 2), spikeX = d.integer(0, w - 1), spikeY = d.integer(0, h - 1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      double z = 1000.0 + relief * 0.5 * (1.0 + std::sin(fx * x) * std::cos(fy * y));
      if (index % 3 == 0 && x >= cliffAt) z += relief * 0.5;                 // a cliff
      if (x == spikeX && y == spikeY) z += relief;                           // a one-cell spike
      if (index % 5 == 0 && x < w / 3 && y < h / 3) z = 1500.0;              // a flat plateau
      s.bedrockM(x, y) = static_cast<float>(z);
      if (index % 2 == 0 && std::abs(x - w / 2) + std::abs(y - h / 2) < std::min(w, h) / 5) s.validCell(x, y) = 0;  // a hole
    }
  return s;
}

}  // namespace

TEST(Stress, TwoHundredRandomTerrainsAndParameters) {
  Draw d{RandomKey{20261123}};
  int withWind = 0, withBedforms = 0;
  double worst = 0.0;
  for (int index = 0; index < 200; ++index) {
    SnowState s = randomTerrain(d, index);
    SeasonConfig c;
    c.days = 500;
    c.seed = static_cast<uint64_t>(index);
    ModelParameters& p = c.params;
    // Rates from a thousandth to ten times beyond the documented maxima; thresholds across ranges.
    p.snowfallRatePerDay = d.logUniform(1e-6, 1e-2);
    p.rainSnowLimitM = d.uniform(0.0, 4000.0);
    p.powderFromPrecipitation = d.logUniform(0.01, 1000.0);
    p.meltRateMPerDayPerC = d.logUniform(1e-4, 1.0);
    p.diffusionRatePerDay = d.logUniform(1e-3, 1e4);  // ten times the scene file's limit
    p.diffusionRestSlope = d.uniform(0.0, 3.0);
    p.windErosionRateMPerSPerDay = d.logUniform(1e-3, 1e3);
    p.instabilityByWarmthMPerDay = d.logUniform(1e-3, 1e5);
    p.stabilityByColdMPerDay = d.logUniform(1e-3, 1e5);
    p.windInstabilityPerMps2 = d.logUniform(1e-4, 100.0);
    // Event rates up to 3 a day (the paper's 2, and more); the diffusion's own substeps (up to
    // 256 an event) already take the largest rates far beyond what a scene file accepts.
    p.diffusionStepsPerDay = d.logUniform(0.05, 3.0);
    p.windTransportStepsPerDay = d.logUniform(0.05, 3.0);
    p.stateChangeStepsPerDay = d.logUniform(0.05, 3.0);
    p.snowfallStartsPerDay = d.logUniform(0.01, 2.0);
    WeatherKeyframe a, b;
    a.state.seaLevelTemperatureC = d.uniform(-30.0, 30.0);
    b.day = 500;
    b.state.seaLevelTemperatureC = d.uniform(-30.0, 30.0);
    c.weather.keyframes = {a, b};
    computeTemperatureBase(s, p);
    if (index % 3 != 2) {
      const WindField f = computeWindField(s.bedrockM, s.validCell, s.spec, WindState{d.uniform(0, 360), d.uniform(1, 40)}, p);
      s.windXMps = f.windXMps;
      s.windYMps = f.windYMps;
      s.windEffectZM = f.windEffectZM;
      s.windLoadingMps2 = windLoading(f, s.validCell, s.spec);
      c.windTransport = true;
      ++withWind;
    }
    // Wind bedforms on every fourth terrain (half of them inside a mask), parameters across and
    // beyond their ranges; the slab thickness capped where the repose angle would allow less
    // than one slab's step (the scene file refuses that).
    if (index % 4 == 1) {
      BedformParameters b;
      b.reposeAngleDeg = d.uniform(5.0, 70.0);
      b.slabM = std::min(d.logUniform(0.002, 0.5),
                         std::tan(b.reposeAngleDeg * 3.14159265358979 / 180.0) * std::min(s.spec.cellSizeXM, s.spec.cellSizeYM));
      b.hopLengthM = d.logUniform(0.05, 50.0);
      b.thresholdWindMps = d.uniform(0.0, 20.0);
      b.depositSnow = d.uniform(0.01, 1.0);
      b.depositBare = d.uniform(0.01, 1.0);
      b.shadowAngleDeg = d.uniform(2.0, 60.0);
      b.shadowLengthM = d.logUniform(0.1, 200.0);
      b.speedupLinear = d.uniform(0.0, 5.0);
      b.maxSlopeDeg = d.uniform(0.0, 80.0);
      b.sinteringPerDay = d.logUniform(1e-3, 10.0);
      b.roundsPerHour = d.logUniform(0.01, 0.2);
      c.bedforms = b;
      if (index % 8 == 1) {
        s.bedformMask.resize(s.spec.width, s.spec.height, 0);
        for (int y = 0; y < s.spec.height; ++y)
          for (int x = 0; x < s.spec.width; ++x) s.bedformMask(x, y) = (x + y) % 3 != 0;
      }
      ++withBedforms;
    }
    auto backend = createCpuBackend();
    const SeasonReport r = runSeason(*backend, s, c);
    SCOPED_TRACE("terrain " + std::to_string(index));
    for (const Grid<float>* g : {&s.compactedM, &s.stableM, &s.unstableM, &s.powderM, &s.windScourM, &s.windDepositM, &s.meltedM})
      for (size_t i = 0; i < g->size(); ++i) {
        ASSERT_TRUE(std::isfinite(g->values()[i]));
        ASSERT_GE(g->values()[i], 0.f);
        if (!s.validCell.values()[i] && g != &s.meltedM) {
          ASSERT_EQ(g->values()[i], 0.f) << "snow in a NODATA cell";
        }
      }
    ASSERT_TRUE(std::isfinite(r.final.totalM3()));
    if (c.bedforms) {
      EXPECT_TRUE(r.bedforms.atRest);
    }
    ASSERT_LT(r.massBalanceRelativeError(), 2e-5) << "added " << r.snowfallAddedM3 << " melted " << r.meltRemovedM3;
    worst = std::max(worst, r.massBalanceRelativeError());
  }
  EXPECT_GT(withWind, 120);
  EXPECT_EQ(withBedforms, 50);
  std::printf("[ measure ] 200 terrains x 500 days: worst relative mass-balance error %.2e\n", worst);
}
