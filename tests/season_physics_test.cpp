// The season as a whole: resolution independence and physical sense on a real DEM.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "bakers/grid_writer.h"
#include "core/cpu_backend.h"
#include "core/reference_scenario.h"
#include "precompute/wind.h"
#include "precompute/wind_timeline.h"
#include "bake_support.h"
#include "bake/bake.h"

using namespace snow;
namespace fs = std::filesystem;

namespace {

struct SeasonOutcome {
  double volumeM3 = 0, coveredM2 = 0;
};

// The embedded range over 5.12 km at a given grid size, a 60-day winter with two fixed storms,
// wind from the west, powder diffusion, melt and stability: everything the season has.
SeasonOutcome winterAt(int size) {
  SnowState s = referenceRangeState(size, 5120.0);
  SeasonConfig c = referenceWinter(60);
  c.weather.keyframes[0].state.seaLevelTemperatureC = 8.0;
  c.weather.keyframes[1].state.seaLevelTemperatureC = 12.0;
  c.weather.snowfallPeriods = {{5.0, 9.0}, {30.0, 33.0}};
  const WindField f = computeWindField(s.bedrockM, s.validCell, s.spec, WindState{270.0, 8.0}, c.params);
  s.windXMps = f.windXMps;
  s.windYMps = f.windYMps;
  s.windEffectZM = f.windEffectZM;
  s.windLoadingMps2 = windLoading(f, s.validCell, s.spec);
  c.windTransport = true;
  computeTemperatureBase(s, c.params);
  auto backend = createCpuBackend();
  runSeason(*backend, s, c);
  SeasonOutcome o;
  const double area = s.spec.cellAreaM2();
  for (int y = 0; y < s.spec.height; ++y)
    for (int x = 0; x < s.spec.width; ++x) {
      o.volumeM3 += s.depthM(x, y) * area;
      if (s.depthM(x, y) > 0.01f) o.coveredM2 += area;
    }
  return o;
}

}  // namespace

// The same terrain at 20 m and 10 m cells: total snow volume within 5 %.
TEST(SeasonPhysics, TwentyAndTenMetreRunsHoldTheSameSnow) {
  const SeasonOutcome coarse = winterAt(256), fine = winterAt(512);
  std::printf("[ measure ] 20 m: %.4e m^3, %.4e m^2 covered; 10 m: %.4e m^3, %.4e m^2 covered\n", coarse.volumeM3, coarse.coveredM2,
              fine.volumeM3, fine.coveredM2);
  EXPECT_NEAR(fine.volumeM3 / coarse.volumeM3, 1.0, 0.05);
}

// The same real DEM at two cell sizes (Tyrol, native 5 m and resampled to 10 m), a 60-day winter
// with storms, wind, melt and powder diffusion: total snow volume and snow-covered fraction
// (depth > 1 cm) within 5 %. Spontaneous avalanches are left out: their sites are drawn a cell at
// a time, so the two grids run different avalanches (with them, the covered fractions measured
// 0.454 and 0.431, 5.3 % apart, on 2026-12-02). (The embedded range is not used for the area: its ridged noise has
// crests that no grid resolves, so it gets steeper as cells shrink, from 85.4 % of cells above
// the powder's rest slope at 20 m to 87.0 % at 10 m over 2.56 km, and the covered area, which is
// mostly the gentle rest, follows the terrain rather than the model.)
namespace {
struct TyrolOutcome {
  double volumeM3 = 0, coveredFraction = 0;
};
TyrolOutcome tyrolWinter(const std::string& dem, const std::string& resample) {
  std::ostringstream text;
  text << "[terrain]\nfile = \"" << dem << "\"\n" << resample << "[season]\nstart_date = 2025-12-01\ndays = 60\n"
       << "[[weather.keyframe]]\nday = 0\nsea_level_temperature_c = 12.0\nwind_direction_deg = 300\nwind_speed_mps = 8\n"
       << "[[weather.keyframe]]\nday = 60\nsea_level_temperature_c = 16.0\nwind_direction_deg = 300\nwind_speed_mps = 8\n"
       << "[[weather.snowfall]]\nstart_day = 5\nend_day = 9\n[[weather.snowfall]]\nstart_day = 30\nend_day = 33\n"
       << "[parameters]\nrain_snow_limit_m = 1300\navalanche_rate_per_km2_per_day = 0\n[outputs]\nlayers = [\"depth\", \"valid_mask\"]\n";
  const test::Bake bake = test::bakeSceneText("tyrol_resolution_test", text.str());
  const fs::path dir = bake.dir;
  const BakeResult& result = bake.result;
  const Grid<float> depth = readFloatImage((dir / "out" / "depth.exr").string());
  const Grid<float> valid = readFloatImage((dir / "out" / "valid_mask.exr").string());
  double covered = 0, cells = 0;
  for (size_t i = 0; i < depth.size(); ++i)
    if (valid.values()[i] > 0.5f) {
      cells += 1;
      covered += depth.values()[i] > 0.01f;
    }
  fs::remove_all(dir);
  return {result.season.final.totalM3(), covered / cells};
}
}  // namespace

TEST(SeasonPhysics, RealDemAtFiveAndTenMetresHoldsAndCoversTheSame) {
  const std::string dem = std::string(SNOWBAKE_SHARED_DATA_DIR) + "/dem/tyrol_avaWog_5m.asc";
  if (!fs::exists(dem)) GTEST_SKIP() << "shared data not found: ../shared/data/dem/tyrol_avaWog_5m.asc";
  const TyrolOutcome fine = tyrolWinter(dem, ""), coarse = tyrolWinter(dem, "resample_cell_size_m = 10\n");
  std::printf("[ measure ] Tyrol 5 m: %.4e m^3, %.4f covered; 10 m: %.4e m^3, %.4f covered\n", fine.volumeM3,
              fine.coveredFraction, coarse.volumeM3, coarse.coveredFraction);
  ASSERT_GT(coarse.coveredFraction, 0.2);  // a partial cover, so the comparison means something
  ASSERT_LT(coarse.coveredFraction, 0.95);
  EXPECT_NEAR(fine.volumeM3 / coarse.volumeM3, 1.0, 0.05);
  EXPECT_NEAR(fine.coveredFraction / coarse.coveredFraction, 1.0, 0.05);
}

namespace {
struct FrontRange {
  double bandMean[6] = {0}, bandCount[6] = {0};
  double north = 0, northN = 0, south = 0, southN = 0, steepPowder = 0, steepN = 0, gentlePowder = 0, gentleN = 0, creepPowder = 0, creepN = 0;
  bool available = false;
};

// Mid-winter on the Front Range (SRTM, 71 m x 92 m cells), warm enough that snow near 2600 m
// melts on sunny slopes; five fixed storms, the last ending six days before the end.
FrontRange frontRangeWinter() {
  FrontRange r;
  const std::string dem = std::string(SNOWBAKE_SHARED_DATA_DIR) + "/dem/front_range_srtm3.asc";
  if (!fs::exists(dem)) return r;
  r.available = true;
  std::ostringstream text;
  text << "[terrain]\nfile = \"" << dem << "\"\n[season]\nstart_date = 2025-11-01\ndays = 75\n"
       << "[[weather.keyframe]]\nday = 0\nsea_level_temperature_c = 26.0\nwind_direction_deg = 280\nwind_speed_mps = 6\n"
       << "[[weather.snowfall]]\nstart_day = 8\nend_day = 11\n[[weather.snowfall]]\nstart_day = 22\nend_day = 26\n"
       << "[[weather.snowfall]]\nstart_day = 40\nend_day = 43\n[[weather.snowfall]]\nstart_day = 55\nend_day = 59\n"
       << "[[weather.snowfall]]\nstart_day = 66\nend_day = 69\n"
       // No spontaneous avalanches: this is about snowfall, melt and powder; at the paper's rate this
       // DEM's season runs hundreds of them (over 10 minutes on 2 cores).
       << "[parameters]\nrain_snow_limit_m = 2300\navalanche_rate_per_km2_per_day = 0\n[outputs]\nlayers = [\"depth\", \"powder\", \"bedrock\"]\n";
  const fs::path dir = test::bakeSceneText("front_range_test", text.str()).dir;
  const Grid<float> depth = readFloatImage((dir / "out" / "depth.exr").string());
  const Grid<float> powder = readFloatImage((dir / "out" / "powder.exr").string());
  const Grid<float> bed = readFloatImage((dir / "out" / "bedrock.exr").string());
  const int w = depth.width(), h = depth.height();
  const double dx = 71.0, dy = 92.5;
  // Altitude bands of 300 m from 2600 m; aspect from central differences (north = row - 1).
  double bandSum[6] = {0};
  double* bandCount = r.bandCount;
  double &north = r.north, &northN = r.northN, &south = r.south, &southN = r.southN;
  double &steepPowder = r.steepPowder, &steepN = r.steepN, &gentlePowder = r.gentlePowder, &gentleN = r.gentleN;
  for (int y = 1; y < h - 1; ++y)
    for (int x = 1; x < w - 1; ++x) {
      const double z = bed(x, y);
      const double gx = (bed(x + 1, y) - bed(x - 1, y)) / (2 * dx), gNorth = (bed(x, y - 1) - bed(x, y + 1)) / (2 * dy);
      const double slope = std::hypot(gx, gNorth);
      const int band = static_cast<int>((z - 2600.0) / 300.0);
      if (z >= 2600.0 && band < 6) bandSum[band] += depth(x, y), bandCount[band] += 1;
      if (z > 2500.0 && z < 2900.0 && slope > 0.2 && slope < 0.6) {
        // Downhill toward the north (the slope faces north) when the height rises southward.
        if (-gNorth / slope > 0.8) north += depth(x, y), northN += 1;
        if (gNorth / slope > 0.8) south += depth(x, y), southN += 1;
      }
      // The slope of the snow surface A = B + depth, measured as the diffusion kernel does:
      // the steepest drop toward a 4-neighbour on each axis. Rest slope s_d0 = 0.5.
      auto surf = [&](int xx, int yy) { return double(bed(xx, yy)) + depth(xx, yy); };
      const double a = surf(x, y);
      const double sx = std::max({0.0, a - surf(x + 1, y), a - surf(x - 1, y)}) / dx;
      const double sy = std::max({0.0, a - surf(x, y + 1), a - surf(x, y - 1)}) / dy;
      const double surfaceSlope = std::hypot(sx, sy);
      if (surfaceSlope > 1.0) steepPowder += powder(x, y), steepN += 1;
      if (surfaceSlope > 0.75 && surfaceSlope <= 1.0) r.creepPowder += powder(x, y), r.creepN += 1;
      if (surfaceSlope <= 0.5) gentlePowder += powder(x, y), gentleN += 1;
    }
  std::printf("[ measure ] mean depth by 300 m band from 2600 m:");
  for (int b = 0; b < 6; ++b)
    if (bandCount[b] > 0) std::printf(" %.2f", bandSum[b] / bandCount[b]);
  std::printf("\n[ measure ] 2500-2900 m, slopes 0.2-0.6: north-facing %.3f m (%g cells), south-facing %.3f m (%g cells)\n",
              north / northN, northN, south / southN, southN);
  std::printf("[ measure ] powder where the snow surface slope is > 1: %.4f m (%g cells); 0.75-1: %.4f m (%g cells); <= 0.5: %.4f m (%g cells)\n",
              steepPowder / steepN, steepN, r.creepPowder / r.creepN, r.creepN, gentlePowder / gentleN, gentleN);
  for (int b = 0; b < 6; ++b) r.bandMean[b] = bandCount[b] > 0 ? bandSum[b] / bandCount[b] : 0.0;
  fs::remove_all(dir);
  return r;
}
}  // namespace

// Depth rises with altitude above the snow line; at equal altitude north-facing slopes keep
// more snow than south-facing ones.
TEST(SeasonPhysics, FrontRangeDepthFollowsAltitudeAndAspect) {
  const FrontRange r = frontRangeWinter();
  if (!r.available) GTEST_SKIP() << "shared data not found: ../shared/data/dem/front_range_srtm3.asc";
  for (int b = 1; b < 5; ++b) {
    ASSERT_GT(r.bandCount[b - 1], 200) << b - 1;  // every band is well sampled on this DEM
    ASSERT_GT(r.bandCount[b], 200) << b;
    EXPECT_GT(r.bandMean[b], r.bandMean[b - 1]) << b;
  }
  ASSERT_GT(r.northN, 100);
  ASSERT_GT(r.southN, 100);
  EXPECT_GT(r.north / r.northN, 1.2 * r.south / r.southN);
}

// Powder does not rest on slopes steeper than its rest slope (s_d0 = 0.5): six days after the
// last storm, snow surface steeper than 2 s_d0 holds a small fraction of the powder that rests on
// slopes at or below s_d0. The slope is the snow surface's (powder fills gullies on steep rock
// until its own surface is at rest, as it should), measured with the kernel's steepest-descent
// components. Powder creeps at a speed proportional to its excess slope, so just above s_d0 it is
// still on its way: measured 0.005 m above 2 s_d0, 0.022 m at 1.5-2 s_d0, 0.054 m at rest.
TEST(SeasonPhysics, FrontRangePowderLeavesSteepSlopes) {
  const FrontRange r = frontRangeWinter();
  if (!r.available) GTEST_SKIP() << "shared data not found: ../shared/data/dem/front_range_srtm3.asc";
  ASSERT_GT(r.steepN, 1000);
  EXPECT_LT(r.creepPowder / r.creepN, 0.5 * r.gentlePowder / r.gentleN);
  ASSERT_GT(r.gentleN, 1000);
  EXPECT_GT(r.gentlePowder / r.gentleN, 0.01);
  EXPECT_LT(r.steepPowder / r.steepN, 0.2 * r.gentlePowder / r.gentleN);
}
