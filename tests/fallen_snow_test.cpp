// Snow on any mesh, placement stage (precompute/fallen_snow.h): the thesis's own checks that
// placement alone must pass (Fearing 2000, digest §6.3): a flat open plane holds exactly the
// requested depth and mass; with zero flutter an opaque overhang keeps the ground under it bare,
// with a sharp edge at its vertical projection; with flutter some snow reaches under it and the
// total mass is unchanged; downward faces keep nothing. (The thinner top edge the thesis shows
// is not asserted: placement alone gives the roof's last 10 cm 0.312 m against 0.298 m inside,
// 32 flakes a site -- printed below; to revisit with the stability stage, which sheds edge snow.)
#include <tbb/global_control.h>

#include <gtest/gtest.h>

#include "precompute/fallen_snow.h"

namespace snow {
namespace {

// A horizontal rectangle at height z as two triangles, facing up (or down).
void addQuad(TriangleMesh& m, float x0, float y0, float x1, float y1, float z, bool up) {
  const uint32_t base = static_cast<uint32_t>(m.positions.size());
  m.positions.push_back({x0, y0, z});
  m.positions.push_back({x1, y0, z});
  m.positions.push_back({x1, y1, z});
  m.positions.push_back({x0, y1, z});
  if (up) {
    m.triangles.push_back({base, base + 1, base + 2});
    m.triangles.push_back({base, base + 2, base + 3});
  } else {
    m.triangles.push_back({base, base + 2, base + 1});
    m.triangles.push_back({base, base + 3, base + 2});
  }
}
// A vertical wall along x = const (or y = const) between two heights.
void addWallX(TriangleMesh& m, float x, float y0, float y1, float z0, float z1) {
  const uint32_t b = static_cast<uint32_t>(m.positions.size());
  m.positions.push_back({x, y0, z0});
  m.positions.push_back({x, y1, z0});
  m.positions.push_back({x, y1, z1});
  m.positions.push_back({x, y0, z1});
  m.triangles.push_back({b, b + 1, b + 2});
  m.triangles.push_back({b, b + 2, b + 3});
}

// The ground (2 x 2 m at z = 0) and a roof slab over x in [0, 1] (top at 0.5 m, bottom 0.45 m,
// its open edge at x = 1 closed by a wall).
TriangleMesh overhang() {
  TriangleMesh m;
  m.source = "overhang";
  addQuad(m, 0, 0, 2, 2, 0.f, true);
  addQuad(m, 0, 0, 1, 2, 0.5f, true);
  addQuad(m, 0, 0, 1, 2, 0.45f, false);
  addWallX(m, 1.f, 0.f, 2.f, 0.45f, 0.5f);
  return m;
}

double meanDepth(const FallenSnow& f, float zMin, float zMax, float xMin, float xMax) {
  double sum = 0;
  int n = 0;
  for (const SnowSite& s : f.sites)
    if (s.position[2] >= zMin && s.position[2] <= zMax && s.position[0] >= xMin && s.position[0] < xMax) sum += s.depthM, ++n;
  return n ? sum / n : -1.0;
}

TEST(FallenSnow, AnOpenPlaneHoldsExactlyTheRequestedDepthAndMass) {
  TriangleMesh plane;
  plane.source = "plane";
  addQuad(plane, 0, 0, 2, 2, 1.f, true);
  FallenSnowSettings s;
  s.depthM = 0.3;
  for (double flutter : {0.0, 0.03}) {
    s.flutterMeanM = flutter;
    s.flutterSigmaM = flutter / 3.0;
    const FallenSnow f = placeFallenSnow(plane, s);
    EXPECT_EQ(f.emptyBuckets, 0);
    EXPECT_NEAR(f.skyMassM3, 0.3 * 4.0, 1e-12);
    EXPECT_NEAR(f.placedM3, 0.3 * 4.0, 1e-9);
    if (flutter == 0.0) {
      ASSERT_EQ(f.sites.size(), 40u * 40u);  // one site a lattice cell, diagonal points counted once
      EXPECT_EQ(f.refinedCells, 0);          // the same coverage everywhere
      EXPECT_EQ(f.blocked, 0);
      for (const SnowSite& site : f.sites) ASSERT_NEAR(site.depthM, 0.3, 1e-6);
    }
  }
}

TEST(FallenSnow, WithoutFlutterAnOverhangKeepsTheGroundUnderItBareWithASharpEdge) {
  const TriangleMesh m = overhang();
  FallenSnowSettings s;
  s.depthM = 0.3;
  const FallenSnow f = placeFallenSnow(m, s);
  double under = 0, open = 0, top = 0;  // footprint areas, m^2
  float lastBare = -1.f, firstFull = 3.f;
  for (const SnowSite& site : f.sites) {
    ASSERT_GT(m.triangles.size(), site.face);
    const bool ground = site.position[2] < 0.01f;
    if (ground && site.position[0] < 1.f) {
      ASSERT_EQ(site.depthM, 0.f) << "snow under the overhang at x = " << site.position[0];
      under += site.footprintM2;
      lastBare = std::max(lastBare, site.position[0]);
    } else {
      ASSERT_NEAR(site.depthM, 0.3, 1e-6) << "at (" << site.position[0] << ", " << site.position[2] << ")";
      (ground ? open : top) += site.footprintM2;
      if (ground) firstFull = std::min(firstFull, site.position[0]);
    }
  }
  EXPECT_NEAR(under, 2.0, 1e-6);
  EXPECT_NEAR(open, 2.0, 1e-6);
  EXPECT_NEAR(top, 2.0, 1e-6);
  // The adaptive sampling split the cells along the shadow's edge (the 40 columns on either side),
  // so the edge is resolved at half the spacing: bare at x = 0.9875, full at 1.0125.
  EXPECT_EQ(f.refinedCells, 2 * 40);
  EXPECT_FLOAT_EQ(lastBare, 0.9875f);
  EXPECT_FLOAT_EQ(firstFull, 1.0125f);
  // And the roof's snow is the snow the ground under it lacks.
  EXPECT_NEAR(f.placedM3, 0.3 * 4.0, 1e-9);
}

TEST(FallenSnow, WithFlutterSomeSnowReachesUnderTheOverhangAndTheMassIsUnchanged) {
  const TriangleMesh m = overhang();
  FallenSnowSettings s;
  s.depthM = 0.3;
  s.flutterMeanM = 0.04;  // Fearing Fig. 7.22: 1-7 cm
  s.flutterSigmaM = 0.01;
  s.swirlHeightM = 0.05;
  s.flakesPerSite = 32;
  const FallenSnow f = placeFallenSnow(m, s);
  const double underEdge = meanDepth(f, -1.f, 0.01f, 0.8f, 1.0f);    // ground, the last 20 cm under the roof
  const double underDeep = meanDepth(f, -1.f, 0.01f, 0.0f, 0.5f);    // ground, deep under it
  const double topEdge = meanDepth(f, 0.49f, 0.51f, 0.9f, 1.0f);     // roof top, its last 10 cm
  const double topInner = meanDepth(f, 0.49f, 0.51f, 0.2f, 0.6f);
  const double open = meanDepth(f, -1.f, 0.01f, 1.3f, 1.7f);
  std::cout << "under the edge " << underEdge << " m, deep under " << underDeep << " m, roof edge " << topEdge << " m, roof "
            << topInner << " m, open ground " << open << " m\n";
  EXPECT_GT(underEdge, 0.01);
  EXPECT_LT(underDeep, underEdge);
  EXPECT_NEAR(topInner, 0.3, 0.03);
  EXPECT_NEAR(open, 0.3, 0.03);
  EXPECT_EQ(f.emptyBuckets, 0);
  EXPECT_GT(f.refinedCells, 0);
  EXPECT_NEAR(f.placedM3, 0.3 * 4.0, 1e-9);  // mass unchanged
}

TEST(FallenSnow, DownwardAndVerticalFacesKeepNothingAndThreadsDoNotMatter) {
  // A 0.5 m box (top, bottom and two vertical sides) floating 0.3 m above the ground: sites only
  // on upward faces.
  TriangleMesh m;
  m.source = "box";
  addQuad(m, 0, 0, 2, 2, 0.f, true);
  addQuad(m, 0.75f, 0.75f, 1.25f, 1.25f, 0.8f, true);
  addQuad(m, 0.75f, 0.75f, 1.25f, 1.25f, 0.3f, false);
  addWallX(m, 0.75f, 0.75f, 1.25f, 0.3f, 0.8f);
  addWallX(m, 1.25f, 0.75f, 1.25f, 0.3f, 0.8f);
  FallenSnowSettings s;
  s.flutterMeanM = 0.03;
  s.flutterSigmaM = 0.01;
  auto run = [&](int threads) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    return placeFallenSnow(m, s);
  };
  const FallenSnow one = run(1), two = run(2);
  ASSERT_EQ(one.sites.size(), two.sites.size());
  for (size_t i = 0; i < one.sites.size(); ++i) {
    ASSERT_EQ(one.sites[i].depthM, two.sites[i].depthM);
    const auto& t = m.triangles[one.sites[i].face];
    const auto& a = m.positions[t[0]];
    const auto& b = m.positions[t[1]];
    const auto& c = m.positions[t[2]];
    const double nz = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    ASSERT_GT(nz, 0.0) << "a site on a face that does not look up";
  }
  EXPECT_NEAR(one.placedM3, 0.3 * 4.0, 1e-9);
}

}  // namespace
}  // namespace snow
