// The horizon-sweep fast path against the Embree path it replaces for pure height fields.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "core/default_terrain.h"
#include "precompute/exposure.h"
#include "precompute/horizon.h"
#include "inputs/terrain_loader.h"

using namespace snow;

namespace {

struct Agreement {
  double horizonMeanAbsDeg = 0, horizonP99Deg = 0, skyRelL1 = 0, sunRelL1 = 0;
};

Agreement compare(const Terrain& t, int azimuths, int doy, double lat) {
  const RayScene scene(t.heightsM, t.info.spec);
  std::vector<Grid<float>> embreeHorizons;
  const Grid<float> skyE = computeSkyExposure(scene, t.valid, t.info.spec, azimuths, 12, 0.1, nullptr, &embreeHorizons);
  const auto sweep = computeHorizonsBySweep(t.heightsM, t.valid, t.info.spec, azimuths);
  const Grid<float> skyF = skyFromHorizons(sweep, t.valid, 0.1);
  const Grid<float> sunE = computeDirectSun(scene, t.heightsM, t.valid, t.info.spec, lat, doy, 0.5, 0.9);
  const auto sweepFine = computeHorizonsBySweep(t.heightsM, t.valid, t.info.spec, 4 * azimuths);
  const Grid<float> sunF = directSunFromHorizons(sweepFine, t.heightsM, t.valid, t.info.spec, lat, doy, 0.5, 0.9);
  Agreement a;
  std::vector<double> diffs;
  double skyDiff = 0, skySum = 0, sunDiff = 0, sunSum = 0;
  for (size_t i = 0; i < t.heightsM.size(); ++i) {
    if (!t.valid.values()[i]) continue;
    for (int k = 0; k < azimuths; ++k) diffs.push_back(std::abs(embreeHorizons[k].values()[i] - sweep[k].values()[i]));
    skyDiff += std::abs(skyE.values()[i] - skyF.values()[i]);
    skySum += skyE.values()[i];
    sunDiff += std::abs(sunE.values()[i] - sunF.values()[i]);
    sunSum += sunE.values()[i];
  }
  double sum = 0;
  for (double d : diffs) sum += d;
  std::sort(diffs.begin(), diffs.end());
  a.horizonMeanAbsDeg = sum / diffs.size();
  a.horizonP99Deg = diffs[static_cast<size_t>(0.99 * (diffs.size() - 1))];
  a.skyRelL1 = skyDiff / skySum;
  a.sunRelL1 = sunDiff / sunSum;
  return a;
}

}  // namespace

TEST(HorizonSweep, VValleyHorizons) {
  GridSpec spec;
  spec.width = 61;
  spec.height = 81;
  spec.cellSizeXM = spec.cellSizeYM = 2.0;
  Grid<float> z(61, 81);
  for (int j = 0; j < 81; ++j)
    for (int i = 0; i < 61; ++i) z(i, j) = static_cast<float>(100.0 + 0.5 * std::abs((i - 30) * 2.0));
  const Grid<uint8_t> valid(61, 81, 1);
  const auto hz = computeHorizonsBySweep(z, valid, spec, 16);
  for (int k = 0; k < 16; ++k) {
    const double az = (k + 0.5) * 2.0 * M_PI / 16;
    if (std::abs(std::sin(az)) < 0.3) continue;  // along the valley the grid ends first
    // The floor is a crease: the two lines around the centre sample the walls half a cell up,
    // so the interpolated horizon is a little low there (0.22 degrees here).
    EXPECT_NEAR(hz[k](30, 40), std::atan(0.5 * std::abs(std::sin(az))) * 180.0 / M_PI, 0.3) << k;
  }
}

// The agreement the fast path is used under: on the real Tyrol DEM (5 m, NODATA outline) and
// the rough embedded range (16 sky azimuths, as production quality), the sky term within 2 % and the day's direct sun within
// 2.5 % (relative L1 over the valid cells) of the Embree path, with the fast path's shadows from
// 4x the sky's azimuths as computeExposure uses them.
TEST(HorizonSweep, AgreesWithEmbreeOnRealAndBuiltinTerrain) {
  const std::string dem = std::string(SNOWBAKE_SHARED_DATA_DIR) + "/dem/tyrol_avaWog_5m.asc";
  std::vector<std::pair<std::string, Terrain>> cases;
  DefaultTerrainOptions o;
  o.size = 192;
  o.cellSizeM = 20.0;
  cases.push_back({"builtin 192^2 at 20 m", makeBuiltinTerrain(o)});
  if (std::filesystem::exists(dem)) {
    TerrainSource src;
    src.file = dem;
    cases.push_back({"tyrol_avaWog_5m.asc", loadTerrain(src)});
  } else {
    std::printf("[ skipped ] %s not found\n", dem.c_str());
  }
  for (const auto& [name, t] : cases) {
    const Agreement a = compare(t, 16, 20, 47.2);
    std::printf("[ measure ] %s: horizon mean |diff| %.3f deg, p99 %.2f deg; sky rel. L1 %.4f; direct sun rel. L1 %.4f\n",
                name.c_str(), a.horizonMeanAbsDeg, a.horizonP99Deg, a.skyRelL1, a.sunRelL1);
    EXPECT_LT(a.skyRelL1, 0.02) << name;
    EXPECT_LT(a.sunRelL1, 0.025) << name;
  }
}

// The shadows swept one azimuth at a time (two grids held, a bit a sun position) give the bytes of
// every azimuth held at once, for several days, with NODATA cells.
TEST(HorizonSweep, SunForDaysSweptOneAzimuthAtATimeIsTheSameBytesAsAllHorizonsHeld) {
  DefaultTerrainOptions o;
  o.size = 96;
  o.cellSizeM = 30.0;
  Terrain t = makeBuiltinTerrain(o);
  for (int j = 10; j < 20; ++j)
    for (int i = 40; i < 60; ++i) t.valid(i, j) = 0;
  const std::vector<int> days{335, 355, 20, 50};
  const auto horizons = computeHorizonsBySweep(t.heightsM, t.valid, t.info.spec, 32);
  const std::vector<Grid<float>> swept = directSunForDaysBySweep(t.heightsM, t.valid, t.info.spec, 32, 46.5, days, 1.0, 0.9);
  ASSERT_EQ(swept.size(), days.size());
  double lit = 0;
  for (size_t d = 0; d < days.size(); ++d) {
    const Grid<float> held = directSunFromHorizons(horizons, t.heightsM, t.valid, t.info.spec, 46.5, days[d], 1.0, 0.9);
    EXPECT_EQ(swept[d].values(), held.values()) << "day of year " << days[d];
    for (float v : held.values()) lit += v;
  }
  EXPECT_GT(lit, 0.0);  // the sun shone: the comparison is not of zeros
}
