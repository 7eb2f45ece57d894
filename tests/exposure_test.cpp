// Solar geometry and sun exposure against analytic cases.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "core/grid_window.h"
#include "core/util.h"
#include "precompute/exposure.h"
#include "precompute/horizon.h"
#include "precompute/solar.h"

using namespace snow;

namespace {

struct ExposureField {
  Grid<float> heights;
  Grid<uint8_t> valid;
  GridSpec spec;
};

ExposureField makeField(int w, int h, double cell, const std::function<double(double, double)>& z) {
  ExposureField f;
  f.spec.width = w;
  f.spec.height = h;
  f.spec.cellSizeXM = f.spec.cellSizeYM = cell;
  f.heights.resize(w, h);
  f.valid.resize(w, h, 1);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) f.heights(i, j) = static_cast<float>(z((i + 0.5) * cell, (h - j - 0.5) * cell));  // x east, y north
  return f;
}

// k_sun * sum over the day's sun positions of max(0, n . s) * dh, the analytic direct sun of an
// unshadowed plane with normal n.
double analyticDirect(const std::array<double, 3>& n, double lat, int doy, double step, double kSun) {
  double sum = 0.0;
  for (double hour = step / 2; hour < 24.0; hour += step) {
    const SunPosition s = sunPosition(lat, doy, hour);
    if (s.elevationDeg <= 0) continue;
    sum += std::max(0.0, n[0] * s.direction[0] + n[1] * s.direction[1] + n[2] * s.direction[2]) * step;
  }
  return kSun * sum;
}

}  // namespace

TEST(Solar, EquinoxNoonElevationIsNinetyMinusLatitude) {
  for (double lat : {0.0, 23.0, 46.5, 65.0, -33.9}) {
    const SunPosition s = sunPosition(lat, dayOfYear(2025, 3, 20), 12.0);
    EXPECT_NEAR(s.elevationDeg, 90.0 - std::abs(lat), 0.5) << lat;
    if (lat > 1) {
      EXPECT_NEAR(s.azimuthDeg, 180.0, 1e-6);  // due south at solar noon
    }
    if (lat < -1) {
      EXPECT_NEAR(std::fmod(s.azimuthDeg + 180.0, 360.0) - 180.0, 0.0, 1e-6);
    }
  }
}

TEST(Solar, SolsticesAndTheDayArc) {
  const SunPosition june = sunPosition(46.5, dayOfYear(2025, 6, 21), 12.0);
  const SunPosition december = sunPosition(46.5, dayOfYear(2025, 12, 21), 12.0);
  EXPECT_NEAR(june.elevationDeg, 90.0 - 46.5 + 23.44, 0.5);
  EXPECT_NEAR(december.elevationDeg, 90.0 - 46.5 - 23.44, 0.5);
  // Morning sun in the east, afternoon in the west, symmetric about noon.
  const SunPosition am = sunPosition(46.5, 80, 9.0), pm = sunPosition(46.5, 80, 15.0);
  EXPECT_LT(am.azimuthDeg, 180.0);
  EXPECT_GT(pm.azimuthDeg, 180.0);
  EXPECT_NEAR(am.elevationDeg, pm.elevationDeg, 0.1);  // the declination moves a little within the day
  EXPECT_LT(sunPosition(46.5, 80, 0.0).elevationDeg, 0.0);
  EXPECT_EQ(dayOfYear(2024, 3, 1), 61);  // leap year
  EXPECT_EQ(dayOfYear(2025, 12, 31), 365);
}

TEST(Exposure, FlatPlaneDirectIsTheAnalyticSumAndSkyIsKSkyPi) {
  const ExposureField f = makeField(24, 20, 10.0, [](double, double) { return 500.0; });
  const RayScene scene(f.heights, f.spec);
  ModelParameters p;
  for (int doy : {355, 80, 172}) {
    const Grid<float> sun = computeDirectSun(scene, f.heights, f.valid, f.spec, 46.5, doy, 0.5, p.directSunWeightHours);
    const double expected = analyticDirect({0, 0, 1}, 46.5, doy, 0.5, p.directSunWeightHours);
    for (float v : sun.values()) ASSERT_NEAR(v, expected, 1e-4 * expected) << doy;
  }
  // December and June differ: the season matters.
  EXPECT_LT(analyticDirect({0, 0, 1}, 46.5, 355, 0.5, 1.0), 0.5 * analyticDirect({0, 0, 1}, 46.5, 172, 0.5, 1.0));
  const Grid<float> sky = computeSkyExposure(scene, f.valid, f.spec, 16, 8, p.skyAmbientWeightHours);
  for (float v : sky.values()) ASSERT_NEAR(v, p.skyAmbientWeightHours * kPi, 1e-6);
  const Grid<float> ind = computeIndirectSun(Grid<float>(24, 20, 3.f), f.heights, f.valid, f.spec, 16, 8, 100.0, 1.0);
  for (float v : ind.values()) ASSERT_EQ(v, 0.f);  // an infinite flat plane sends nothing to itself
}

TEST(Exposure, TiltedPlanesTowardAndAwayFromTheSun) {
  const double tilt = 25.0 * kPi / 180.0;
  ModelParameters p;
  for (double sign : {1.0, -1.0}) {  // +1: facing south (toward the winter sun), -1: facing north
    // Height falls toward the south for a south-facing slope: z = -sign * tan(tilt) * (y - y0).
    const ExposureField f = makeField(30, 30, 10.0, [&](double, double y) { return 2000.0 + sign * std::tan(tilt) * (y - 150.0); });
    const RayScene scene(f.heights, f.spec);
    const Grid<float> sun = computeDirectSun(scene, f.heights, f.valid, f.spec, 46.5, 355, 0.25, p.directSunWeightHours);
    const std::array<double, 3> n{0.0, -sign * std::sin(tilt), std::cos(tilt)};
    const double expected = analyticDirect(n, 46.5, 355, 0.25, p.directSunWeightHours);
    // Interior cells (the plane's own edge cells have one-sided normals, equal here anyway).
    for (int j = 2; j < 28; ++j)
      for (int i = 2; i < 28; ++i) ASSERT_NEAR(sun(i, j), expected, 1e-3 * std::max(expected, 0.01)) << sign;
    if (sign > 0) EXPECT_GT(expected, 1.5 * analyticDirect({0, 0, 1}, 46.5, 355, 0.25, p.directSunWeightHours));
    else EXPECT_LT(expected, 0.3 * analyticDirect({0, 0, 1}, 46.5, 355, 0.25, p.directSunWeightHours));
  }
}

// A 40 m north-south wall (a plateau to the west) with the afternoon sun in the south-west: the
// ground east of the wall is shadowed to H |d_x| / d_z from the wall's top edge, +- one cell.
TEST(Exposure, WallCastsTheAnalyticShadow) {
  const double H = 40.0, cell = 1.0;
  const int w = 200, h = 300, edge = 60;  // cells i < edge are on the plateau
  ExposureField f = makeField(w, h, cell, [&](double x, double) { return x < edge * cell ? H : 0.0; });
  const RayScene scene(f.heights, f.spec);
  const SunPosition s = sunPosition(46.5, 80, 15.5);
  ASSERT_LT(s.direction[0], 0.0);  // the sun is to the west
  const std::array<float, 3> d{static_cast<float>(s.direction[0]), static_cast<float>(s.direction[1]), static_cast<float>(s.direction[2])};
  const double expected = H * std::abs(s.direction[0]) / s.direction[2];
  const int j = 40;  // near the north edge: the rays run south-west across the plateau
  int last = -1;
  for (int i = edge; i < w; ++i) {
    auto o = scene.cellPoint(i, j);
    o[2] += 1e-3f;
    if (scene.occluded(o, d, std::numeric_limits<float>::infinity())) last = i;
  }
  const double topEdgeX = (edge - 1 + 0.5) * cell, shadowEnd = (last + 0.5) * cell;
  EXPECT_NEAR(shadowEnd - topEdgeX, expected, 1.0 * cell) << "elevation " << s.elevationDeg << " deg";
}

// A V valley running north-south with side slopes s: from the floor the horizon in azimuth a is
// atan(s |sin a|). Bisection to 90 / 2^12 degrees; the floor is a grid line of vertices.
TEST(Exposure, VValleyHorizonAndSky) {
  const double s = 0.8, cell = 2.0;
  const int w = 101, h = 301;
  const ExposureField f = makeField(w, h, cell, [&](double x, double) { return 1000.0 + s * std::abs(x - 50.5 * cell); });
  const RayScene scene(f.heights, f.spec);
  std::vector<Grid<float>> horizons;
  const int azimuths = 16;
  const Grid<float> sky = computeSkyExposure(scene, f.valid, f.spec, azimuths, 12, 0.1, nullptr, &horizons);
  const int i = 50, j = h / 2;
  double expectedSky = 0.0;
  for (int k = 0; k < azimuths; ++k) {
    const double az = (k + 0.5) * 2.0 * kPi / azimuths;
    const double phi = std::atan(s * std::abs(std::sin(az)));
    // Azimuths close to the valley axis reach the grid's end before the wall: skip those.
    if (std::abs(std::sin(az)) > 0.3) {
      EXPECT_NEAR(horizons[k](i, j), phi * 180.0 / kPi, 0.05) << "azimuth " << az * 180 / kPi;
    }
    expectedSky += std::cos(phi) * std::cos(phi);
  }
  expectedSky *= 0.1 * kPi / azimuths;
  EXPECT_NEAR(sky(i, j), expectedSky, 0.01 * expectedSky);
}

// A conical pit: flat floor of radius R0, walls of slope s out to the rim at radius R, flat
// beyond. From the centre every azimuth's horizon is the rim, atan(s (R - R0) / R), and
// I_sky = k_sky pi cos^2 of it. Tolerance 0.5 degrees: the grid's triangles cut the circular rim.
TEST(Exposure, ConicalPitHorizonAndSky) {
  const double s = 1.0, cell = 1.0, r0 = 10.0, rim = 50.0;
  const int n = 121;
  const double c = 60.5 * cell;
  const ExposureField f = makeField(n, n, cell, [&](double x, double y) {
    const double r = std::hypot(x - c, y - c);
    return 500.0 + s * std::clamp(r - r0, 0.0, rim - r0);
  });
  const RayScene scene(f.heights, f.spec);
  std::vector<Grid<float>> horizons;
  const Grid<float> sky = computeSkyExposure(scene, f.valid, f.spec, 32, 12, 0.1, nullptr, &horizons);
  const double phi = std::atan(s * (rim - r0) / rim);
  for (const auto& hz : horizons) EXPECT_NEAR(hz(60, 60), phi * 180.0 / kPi, 0.5);
  const double expected = 0.1 * kPi * std::cos(phi) * std::cos(phi);
  EXPECT_NEAR(sky(60, 60), expected, 0.01 * expected);
}

TEST(Exposure, TiledGridGivesTheSameRays) {
  const ExposureField f = makeField(50, 37, 5.0, [](double x, double y) { return 100.0 + 20.0 * std::sin(x * 0.05) * std::cos(y * 0.07); });
  const RayScene whole(f.heights, f.spec), tiled(f.heights, f.spec, {}, 8);
  EXPECT_EQ(whole.tileCount(), 1);
  EXPECT_EQ(tiled.tileCount(), 7 * 6);  // tiles of 8 vertices share one: ceil(49 / 7) x ceil(36 / 7)
  const SunPosition s = sunPosition(46.5, 20, 10.0);
  const std::array<float, 3> d{static_cast<float>(s.direction[0]), static_cast<float>(s.direction[1]), static_cast<float>(s.direction[2])};
  int shadowed = 0;
  for (int j = 0; j < 37; ++j)
    for (int i = 0; i < 50; ++i) {
      auto o = whole.cellPoint(i, j);
      o[2] += 0.01f;
      const bool a = whole.occluded(o, d, 1e9f), b = tiled.occluded(o, d, 1e9f);
      ASSERT_EQ(a, b) << i << "," << j;
      shadowed += a;
    }
  EXPECT_GT(shadowed, 50);
}

TEST(Exposure, SeasonSamplesInterpolateBetweenDays) {
  const ExposureField f = makeField(16, 16, 10.0, [](double, double) { return 800.0; });
  const RayScene scene(f.heights, f.spec);
  ExposureSettings s;
  s.latitudeDeg = 46.5;
  s.startDayOfYear = 335;  // 1 December
  s.seasonDays = 120;
  s.horizonSweep = false;
  const Exposure e = computeExposure(&scene, f.heights, f.valid, f.spec, ModelParameters{}, s);
  ASSERT_EQ(e.days.size(), 5u);  // draft: every 30 days, plus the last day
  EXPECT_EQ(e.days[1].dayOfYear, 365);
  EXPECT_EQ(e.days[2].dayOfYear, 30);  // wraps into January
  const float d0 = e.days[0].sunHours(5, 5), d1 = e.days[1].sunHours(5, 5);
  EXPECT_NEAR(e.totalAt(15.0)(5, 5), e.skyHours(5, 5) + 0.5f * (d0 + d1), 1e-4f);
  EXPECT_GT(e.totalAt(120.0)(5, 5), e.totalAt(20.0)(5, 5));  // March is sunnier than December
}

// A rank's window of the exposure samples (a bake across ranks): every season day's total is the
// whole's cells, byte for byte, folded or not.
TEST(Exposure, AWindowGivesItsCellsOfTheWholeTotalOnEveryDay) {
  const ExposureField f = makeField(24, 20, 10.0, [](double x, double y) { return 800.0 + 3.0 * x + 40.0 * std::sin(y / 30.0); });
  ExposureSettings s;
  s.seasonDays = 120;
  Exposure whole = computeExposure(nullptr, f.heights, f.valid, f.spec, ModelParameters{}, s);
  for (bool folded : {false, true}) {
    if (folded) whole.foldIndirect();
    const Exposure window = whole.window(3, 5, 17, 9);
    for (double day : {0.0, 15.0, 61.0, 119.0})
      EXPECT_EQ(gridWindow(whole.totalAt(day), 3, 5, 17, 9), window.totalAt(day)) << day << (folded ? " folded" : "");
  }
}

// A rank's local grid computed alone (computeExposure with cells: the lines through them swept,
// or their rays alone traced by Embree, in the whole grid's packets, fewer rays than the whole
// grid's; the direct sun widened by the indirect radius) is the whole grid's computed and cut,
// bit for bit: sky, every sample day's direct and indirect sun, on rough relief with NODATA
// cells, for windows inside (their corners off the packets' 4 x 4 tiles), at each edge and
// corner, one cell wide, and the whole grid; with and without the indirect term, on a grid whose
// cells are not square.
TEST(Exposure, CellsComputedAloneAreTheWholeGridsCutBitForBit) {
  ExposureField f = makeField(61, 47, 10.0, [](double x, double y) {
    return 1500.0 + 300.0 * std::sin(x / 90.0) * std::cos(y / 70.0) + 0.4 * x + 40.0 * std::sin(0.37 * x + 0.23 * y);
  });
  f.spec.cellSizeYM = 12.5;
  for (int j = 18; j < 25; ++j)
    for (int i = 28; i < 34; ++i) f.valid(i, j) = 0;  // NODATA across window borders
  ExposureSettings s;
  s.seasonDays = 70;
  s.quality.indirectRadiusM = 60.0;  // several cells beyond a window's edge
  ModelParameters noIndirect;
  noIndirect.indirectSunWeightHours = 0.0;
  const RayScene rays(f.heights, f.spec);
  for (const bool sweep : {true, false}) {
    for (const ModelParameters& p : {ModelParameters{}, noIndirect}) {
      SCOPED_TRACE(std::string(sweep ? "horizon sweep" : "Embree rays") + (p.indirectSunWeightHours > 0.0 ? ", indirect" : ", no indirect"));
      s.horizonSweep = sweep;
      const RayScene* scene = sweep ? nullptr : &rays;
      const Exposure whole = computeExposure(scene, f.heights, f.valid, f.spec, p, s);
      for (const CellRect c : {CellRect{10, 8, 40, 30}, CellRect{0, 0, 25, 20}, CellRect{36, 27, 61, 47}, CellRect{0, 30, 61, 47},
                               CellRect{30, 0, 31, 47}, CellRect{0, 0, 61, 47}, CellRect{13, 7, 26, 22}}) {
        const Exposure part = computeExposure(scene, f.heights, f.valid, f.spec, p, s, c);
        if (!sweep && c != CellRect{0, 0, 61, 47}) {  // the rays of the cells (and of their packets) alone
          EXPECT_LT(part.timings.skyRays, whole.timings.skyRays);
          if (p.indirectSunWeightHours == 0.0) {
            EXPECT_LT(part.timings.sunRays, whole.timings.sunRays);
          }
        }
        ASSERT_EQ(part.days.size(), whole.days.size());
        ASSERT_TRUE(part.cells && *part.cells == c);
        EXPECT_EQ(gridWindow(whole.skyHours, c), part.skyHours) << c.x0 << "," << c.y0;
        for (size_t d = 0; d < whole.days.size(); ++d) {
          EXPECT_EQ(gridWindow(whole.days[d].sunHours, c), part.days[d].sunHours) << c.x0 << "," << c.y0 << " day " << d;
          EXPECT_EQ(gridWindow(whole.days[d].indirectHours, c), part.days[d].indirectHours) << c.x0 << "," << c.y0 << " day " << d;
        }
      }
    }
  }
}

// The indirect term's documented decision: senders are not tested for visibility; the cosines
// decide. Two slopes facing each other across a V valley light each other; a slope facing away
// from the receiver (the far side of a ridge, as seen from its crest) sends nothing.
TEST(Exposure, IndirectComesFromFacingSlopesAndNotFromBehind) {
  const double cell = 5.0;
  const int w = 81, h = 21;
  // A V valley along y, walls of slope 0.5: both walls face each other.
  const ExposureField v = makeField(w, h, cell, [&](double x, double) { return 1000.0 + 0.5 * std::abs(x - 40.5 * cell); });
  const Grid<float> lit(w, h, 4.f);
  const Grid<float> ind = computeIndirectSun(lit, v.heights, v.valid, v.spec, 32, 16, 200.0, 1.0);
  EXPECT_GT(ind(30, 10), 0.05f);  // on the west wall, lit by the east wall
  // A ridge (the V upside down): from the east side, the west side faces away.
  const ExposureField r = makeField(w, h, cell, [&](double x, double) { return 1000.0 - 0.5 * std::abs(x - 40.5 * cell); });
  const Grid<float> westOnly = [&] {
    Grid<float> g(w, h, 0.f);
    for (int j = 0; j < h; ++j)
      for (int i = 0; i < 40; ++i) g(i, j) = 4.f;
    return g;
  }();
  const Grid<float> behind = computeIndirectSun(westOnly, r.heights, r.valid, r.spec, 32, 16, 200.0, 1.0);
  EXPECT_EQ(behind(50, 10), 0.f);  // the lit west slope is behind the east slope's tangent plane
}

// A term whose weight is zero is not computed (no sky rays when k_sky = 0), and the zeros put in
// its place are the bytes computing it with that weight gives, on both paths.
TEST(Exposure, ATermOfZeroWeightIsSkippedAndIsTheBytesComputingItWouldGive) {
  const ExposureField f = makeField(24, 20, 10.0, [](double x, double y) { return 900.0 + 80.0 * std::sin(x / 60.0) * std::cos(y / 45.0); });
  const RayScene scene(f.heights, f.spec);
  auto same = [](const Grid<float>& a, const Grid<float>& b) {
    return a.size() == b.size() && std::equal(a.values().begin(), a.values().end(), b.values().begin(),
                                              [](float u, float v) { return std::memcmp(&u, &v, sizeof u) == 0; });
  };
  for (bool sweep : {true, false}) {
    ExposureSettings s;
    s.latitudeDeg = 46.5;
    s.startDayOfYear = 335;
    s.seasonDays = 60;
    s.horizonSweep = sweep;
    ModelParameters noSky, noSun;
    noSky.skyAmbientWeightHours = 0.0;
    noSun.directSunWeightHours = 0.0;
    const Exposure a = computeExposure(&scene, f.heights, f.valid, f.spec, noSky, s);
    const Exposure b = computeExposure(&scene, f.heights, f.valid, f.spec, noSun, s);
    const Exposure full = computeExposure(&scene, f.heights, f.valid, f.spec, ModelParameters{}, s);
    ASSERT_EQ(a.timings.skipped, std::vector<std::string>{"sky: sky_ambient_weight_hours = 0"}) << sweep;
    ASSERT_EQ(b.timings.skipped.size(), 2u) << sweep;  // the direct sun, and the indirect it scales
    EXPECT_TRUE(full.timings.skipped.empty());
    EXPECT_EQ(a.timings.skyRays, 0u);
    if (!sweep) {
      EXPECT_EQ(b.timings.sunRays, 0u);
    }
    const Grid<float> sky0 = sweep ? skyFromHorizons(computeHorizonsBySweep(f.heights, f.valid, f.spec, s.quality.azimuths), f.valid, 0.0)
                                   : computeSkyExposure(scene, f.valid, f.spec, s.quality.azimuths, s.quality.bisections, 0.0);
    EXPECT_TRUE(same(a.skyHours, sky0)) << sweep;
    EXPECT_TRUE(same(b.skyHours, full.skyHours)) << sweep;
    ASSERT_EQ(a.days.size(), full.days.size());
    ASSERT_EQ(b.days.size(), full.days.size());
    for (size_t d = 0; d < full.days.size(); ++d) {
      EXPECT_TRUE(same(a.days[d].sunHours, full.days[d].sunHours)) << sweep << " day " << d;  // only the sky was left out
      EXPECT_TRUE(same(a.days[d].indirectHours, full.days[d].indirectHours)) << sweep << " day " << d;
      const Grid<float> sun0 = computeDirectSun(scene, f.heights, f.valid, f.spec, s.latitudeDeg, full.days[d].dayOfYear, s.quality.hourStep, 0.0);
      EXPECT_TRUE(same(b.days[d].sunHours, sun0)) << sweep << " day " << d;
      const Grid<float> ind0 = computeIndirectSun(sun0, f.heights, f.valid, f.spec, s.quality.indirectDirections, s.quality.indirectRings,
                                                  s.quality.indirectRadiusM, 0.0);
      EXPECT_TRUE(same(b.days[d].indirectHours, ind0)) << sweep << " day " << d;
    }
  }
}
