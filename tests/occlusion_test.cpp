// Occlusion mode (Foldes & Benes 2007): the paper's own statements as tests, the ambient
// occlusion value against an analytic sky-view factor and the season's horizon sky term, the
// sun weights of Eqs. 2-3, meshes per vertex, and the mode through the whole bake.
#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <unistd.h>  // getpid

#include <OpenImageIO/imageio.h>

#include <cmath>
#include <iostream>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>

#include "bake_support.h"
#include "core/errors.h"
#include "core/mesh_normals.h"
#include "core/util.h"
#include "precompute/exposure.h"
#include "inputs/mesh.h"
#include "static_snow/occlusion.h"
#include "precompute/ray_scene.h"
#include "scene/scene.h"
#include "temp_dir.h"

namespace snow {
namespace {

namespace fs = std::filesystem;

struct OcclusionField {
  Grid<float> heights;
  Grid<uint8_t> valid;
  GridSpec spec;
};

// Heights f(x_m, y_m), metres east and south of the north-west corner.
template <class F>
OcclusionField field(int w, int h, double cell, F f) {
  OcclusionField t;
  t.spec.width = w, t.spec.height = h, t.spec.cellSizeXM = t.spec.cellSizeYM = cell;
  t.heights = Grid<float>(w, h, 0.f);
  t.valid = Grid<uint8_t>(w, h, 1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) t.heights(x, y) = static_cast<float>(f(x * cell, y * cell));
  return t;
}

OcclusionSnow run(const OcclusionField& t, const OcclusionSettings& s) {
  const RayScene scene(t.heights, t.spec);
  return computeOcclusionSnowOnTerrain(scene, t.heights, t.valid, t.spec, s);
}

size_t at(const OcclusionField& t, int x, int y) { return static_cast<size_t>(y) * t.spec.width + x; }

OcclusionSettings winter45() {
  OcclusionSettings s;
  s.latitudeDeg = 45.0;
  s.dayOfYear = 355;  // near the winter solstice: a low sun in the south
  return s;
}

TEST(Occlusion, FlatOpenPlaneGetsEquationOneEverywhere) {
  const OcclusionField t = field(48, 48, 10.0, [](double, double) { return 1000.0; });
  OcclusionSettings s = winter45();
  s.tauSun = 1.0;  // no dissipation: Eq. 1 alone
  const OcclusionSnow o = run(t, s);
  for (size_t k = 0; k < o.snowM.size(); ++k) {
    ASSERT_FLOAT_EQ(o.ambient[k], 1.f) << k;  // nothing above a plane
    ASSERT_NEAR(o.snowM[k], s.sMaxM * (s.tauAmbient - 1.0), 1e-6) << k;
  }
  // With the sun: it sees the whole plane all day (v = 1), which loses s_max (1 - tau_sun).
  s.tauSun = 0.75;
  const OcclusionSnow d = run(t, s);
  for (size_t k = 0; k < d.snowM.size(); ++k) {
    ASSERT_NEAR(d.sunVisibility[k], 1.0, 1e-6);
    ASSERT_NEAR(d.snowM[k], s.sMaxM * ((s.tauAmbient - 1.0) - (1.0 - s.tauSun)), 1e-6) << k;
  }
}

TEST(Occlusion, InclinedOpenPlaneScalesWithCosTheta) {
  const double slope = std::tan(30.0 * kPi / 180.0);
  const OcclusionField t = field(48, 48, 10.0, [&](double x, double) { return 1000.0 + slope * x; });
  OcclusionSettings s = winter45();
  s.tauSun = 1.0;
  const OcclusionSnow o = run(t, s);
  // Interior cells (the edge cells' one-sided normals are the same on a plane).
  for (int y = 1; y < 47; ++y)
    for (int x = 1; x < 47; ++x) {
      ASSERT_FLOAT_EQ(o.ambient[at(t, x, y)], 1.f);
      ASSERT_NEAR(o.snowM[at(t, x, y)], s.sMaxM * (s.tauAmbient - 1.0) * std::cos(30.0 * kPi / 180.0), 1e-5);
    }
}

// A flat plane at 1000 m with a square pit 60 m wide and 20 m deep in the middle.
OcclusionField pitField() {
  return field(64, 64, 5.0, [](double x, double y) {
    return std::abs(x - 160.0) < 30.0 && std::abs(y - 160.0) < 30.0 ? 980.0 : 1000.0;
  });
}

TEST(Occlusion, PitGetsMoreSnowThanTheOpenPlaneAroundIt) {
  const OcclusionField t = pitField();
  const OcclusionSettings s = winter45();
  const OcclusionSnow o = run(t, s);
  const size_t pit = at(t, 32, 32), open = at(t, 4, 60);
  EXPECT_LT(o.ambient[pit], 0.9f);
  EXPECT_FLOAT_EQ(o.ambient[open], 1.f);
  EXPECT_GT(o.accumulationM[pit], o.accumulationM[open] + 0.1);
  EXPECT_GT(o.snowM[pit], o.snowM[open] + 0.1);
  // A ditch: a long east-west trench 20 m wide, 10 m deep.
  const OcclusionField d = field(96, 48, 5.0, [](double, double y) { return std::abs(y - 120.0) < 10.0 ? 990.0 : 1000.0; });
  const OcclusionSnow od = run(d, s);
  EXPECT_GT(od.snowM[at(d, 48, 24)], od.snowM[at(d, 48, 4)] + 0.1);
}

TEST(Occlusion, PointsAtOrAboveTheThresholdGetNoSnow) {
  const OcclusionField t = pitField();
  OcclusionSettings s = winter45();
  s.tauAmbient = 0.9;
  s.tauSun = 1.0;
  const OcclusionSnow o = run(t, s);
  int above = 0, below = 0;
  for (size_t k = 0; k < o.snowM.size(); ++k) {
    if (o.ambient[k] >= 0.9f) {
      ++above;
      ASSERT_EQ(o.accumulationM[k], 0.f) << k;
      ASSERT_EQ(o.snowM[k], 0.f) << k;
    } else {
      ++below;
      ASSERT_GT(o.snowM[k], 0.f) << k << " a = " << o.ambient[k];
    }
  }
  EXPECT_GT(above, 1000);  // the open plane
  EXPECT_GT(below, 50);    // the pit
}

TEST(Occlusion, WallShadesTheSnowBehindItFromTheSun) {
  // An east-west wall 40 m high and 10 m thick across a plane, latitude 45 N in December: the
  // noon sun stands 21.6 deg high, so the wall's shadow reaches ~100 m north of it.
  const OcclusionField t = field(64, 96, 5.0, [](double, double y) { return std::abs(y - 240.0) <= 5.0 ? 1040.0 : 1000.0; });
  const OcclusionSettings s = winter45();
  const OcclusionSnow o = run(t, s);
  const size_t north = at(t, 32, 40), south = at(t, 32, 56);  // 35 m either side of the wall's middle
  EXPECT_LT(o.sunVisibility[north], 0.05f);
  EXPECT_GT(o.sunVisibility[south], 0.95f);
  // The wall hides the same sky on either side: same Eq. 1 snow; the sun takes it from the south.
  EXPECT_NEAR(o.ambient[north], o.ambient[south], 0.05);
  EXPECT_GT(o.snowM[north], o.snowM[south] + 0.15);
  EXPECT_EQ(o.dissipationM[north], 0.f);
  // Farther north than the shadow reaches, the snow is the open plane's again.
  const size_t far = at(t, 32, 2);
  EXPECT_GT(o.sunVisibility[far], 0.95f);
}

TEST(Occlusion, ThresholdsSweepMonotonically) {
  // The paper's Figure 3: more tau, more snow; the same for tau_sun (less dissipation).
  const OcclusionField t = field(64, 64, 20.0, [](double x, double y) {
    return 1500.0 + 300.0 * std::sin(x / 150.0) * std::cos(y / 200.0) + 120.0 * std::sin((x + 2 * y) / 60.0);
  });
  const RayScene scene(t.heights, t.spec);
  // Each threshold over increasing values: the snow never falls, per cell or in total.
  auto sweep = [&](double OcclusionSettings::*threshold, const char* name, std::initializer_list<double> values) {
    OcclusionSettings s = winter45();
    std::vector<float> previous;
    double previousTotal = -1.0;
    for (double value : values) {
      s.*threshold = value;
      const OcclusionSnow o = computeOcclusionSnowOnTerrain(scene, t.heights, t.valid, t.spec, s);
      const double total = std::accumulate(o.snowM.begin(), o.snowM.end(), 0.0);
      EXPECT_GT(total, previousTotal) << name << " " << value;
      for (size_t k = 0; k < previous.size(); ++k) ASSERT_GE(o.snowM[k], previous[k]) << name << " " << value << " cell " << k;
      previous = o.snowM;
      previousTotal = total;
    }
  };
  sweep(&OcclusionSettings::tauAmbient, "tau_ambient", {0.6, 0.8, 0.9, 1.0, 1.1, 1.3});
  sweep(&OcclusionSettings::tauSun, "tau_sun", {0.2, 0.5, 0.75, 0.9, 1.0});
}

TEST(Occlusion, AmbientOcclusionMatchesTheCanyonSkyViewFactor) {
  // The middle of a long trench's flat floor, walls H high and W apart: the sky-view factor of a
  // horizontal point at the centre of an infinite canyon is cos(atan(2H / W)) (Oke 1981).
  const double W = 100.0, H = 50.0, cell = 2.0;
  const OcclusionField t = field(600, 120, cell, [&](double, double y) { return std::abs(y - 120.0) < W / 2 ? 1000.0 : 1000.0 + H; });
  OcclusionSettings s = winter45();
  s.aoRays = 1024;
  const OcclusionSnow o = run(t, s);
  const double analytic = std::cos(std::atan(2.0 * H / W));
  double mean = 0.0;
  int n = 0;
  for (int x = 250; x < 350; ++x, ++n) mean += o.ambient[at(t, x, 60)];
  mean /= n;
  EXPECT_NEAR(mean, analytic, 0.01) << "analytic " << analytic;
  for (int x = 250; x < 350; ++x) EXPECT_NEAR(o.ambient[at(t, x, 60)], analytic, 0.05);

  // The same quantity from the season's sky term (horizon angles by bisection): I_sky = k pi a.
  const RayScene scene(t.heights, t.spec);
  const Grid<float> sky = computeSkyExposure(scene, t.valid, t.spec, 64, 12, 1.0);
  double skyMean = 0.0;
  for (int x = 250; x < 350; ++x) skyMean += sky(x, 60) / kPi;
  skyMean /= n;
  EXPECT_NEAR(skyMean, mean, 0.01);
}

TEST(Occlusion, SunTrajectoryWeightsFollowEquationsTwoAndThree) {
  // Eq. 2 at the zenith with the sun at the zenith is the zenith luminance itself.
  EXPECT_NEAR(clearSkyRelativeLuminance(0.0, 0.0, 0.0), 1.0, 1e-3);
  // Eq. 3: the sun's own point is 0 from the sun; the zenith is z0 from it.
  EXPECT_NEAR(skyAngleToSun(0.7, 0.7, kPi / 2), 0.0, 1e-6);
  EXPECT_NEAR(skyAngleToSun(0.7, 0.0, 0.3), 0.7, 1e-12);
  // The sky is brightest around the sun (circumsolar term).
  EXPECT_GT(clearSkyRelativeLuminance(0.7, 0.0, 0.7), clearSkyRelativeLuminance(0.7, 1.0, 0.7));
  for (double lat : {0.0, 45.0, 66.0}) {
    const auto sun = sunTrajectory(lat, 355, 10, 3.0);
    ASSERT_EQ(sun.size(), 10u) << lat;
    double total = 0.0;
    for (size_t k = 0; k < sun.size(); ++k) {
      EXPECT_GT(sun[k].elevationDeg, 0.0);
      EXPECT_GT(sun[k].weight, 0.0);
      total += sun[k].weight;
      // Symmetric about solar noon.
      EXPECT_NEAR(sun[k].weight, sun[sun.size() - 1 - k].weight, 1e-3);
    }
    EXPECT_NEAR(total, 1.0, 1e-12);
  }
  EXPECT_TRUE(sunTrajectory(80.0, 355, 10, 3.0).empty());  // polar night
  EXPECT_EQ(sunTrajectory(80.0, 172, 10, 3.0).size(), 10u);  // midnight sun: the whole day
}

TEST(Occlusion, SameResultsWhateverTheThreadCount) {
  const OcclusionField t = pitField();
  const OcclusionSettings s = winter45();
  OcclusionSnow one, two;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    one = run(t, s);
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    two = run(t, s);
  }
  EXPECT_EQ(one.ambient, two.ambient);
  EXPECT_EQ(one.sunVisibility, two.sunVisibility);
  EXPECT_EQ(one.snowM, two.snowM);
}

// A triangulated plane 200 m square with a pit 40 m square and 15 m deep, at 5 m spacing.
TriangleMesh pitMesh() {
  TriangleMesh m;
  const int n = 41;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const float x = 5.f * i, y = 5.f * j;
      const bool pit = std::abs(x - 100.f) < 20.f && std::abs(y - 100.f) < 20.f;
      m.positions.push_back({x, y, pit ? 85.f : 100.f});
    }
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const uint32_t a = j * n + i, b = a + 1, c = a + n, d = c + 1;
      m.triangles.push_back({a, b, d});
      m.triangles.push_back({a, d, c});
    }
  m.boundsMin = {0.f, 0.f, 85.f};
  m.boundsMax = {200.f, 200.f, 100.f};
  m.source = "pit mesh";
  return m;
}

TEST(Occlusion, MeshVerticesGetSnowPerVertex) {
  const TriangleMesh m = pitMesh();
  const Grid<float> none;
  const RayScene scene(none, GridSpec{}, {m});
  OcclusionSettings s = winter45();
  s.tauSun = 1.0;
  const OcclusionSnow o = computeOcclusionSnowOnMesh(scene, m, s);
  ASSERT_EQ(o.snowM.size(), m.positions.size());
  const size_t corner = 2 * 41 + 2, centre = 20 * 41 + 20;
  EXPECT_FLOAT_EQ(o.ambient[corner], 1.f);
  EXPECT_NEAR(o.snowM[corner], s.sMaxM * (s.tauAmbient - 1.0), 1e-6);
  EXPECT_LT(o.ambient[centre], 0.8f);
  EXPECT_GT(o.snowM[centre], o.snowM[corner] + 0.2);
  const auto normals = areaWeightedNormals(m.positions, m.triangles);
  EXPECT_NEAR(normals[corner][2], 1.0, 1e-6);
}

TEST(Occlusion, BakeOnAMeshWritesTheDisplacedMeshAndAllBakers) {
  // The pit mesh as an OBJ terrain: the raster layers, the VDB and the meshes all come out, and
  // the mesh baker's vertices are the input's raised by their own snow.
  const fs::path dir = test::uniqueTempDir("occlusion_mesh_input");
  const TriangleMesh m = pitMesh();
  {
    std::ofstream obj(dir / "pit.obj");
    for (const auto& p : m.positions) obj << "v " << p[0] << " " << p[1] << " " << p[2] << "\n";
    for (const auto& t : m.triangles) obj << "f " << t[0] + 1 << " " << t[1] + 1 << " " << t[2] + 1 << "\n";
  }
  const std::string text = "mode = \"occlusion\"\n[terrain]\nfile = \"" + (dir / "pit.obj").string() +
                           "\"\nformat = \"mesh\"\ncell_size_m = 5.0\n[site]\nlatitude_deg = 45.0\n[occlusion]\ntau_sun = 1.0\n"
                           "[outputs]\nlayers = [\"depth\", \"ambient_occlusion\", \"sun_visibility\", \"preview\"]\n"
                           "meshes = [\"ply\", \"glb\", \"obj\"]\nvdb = true\ndisplacement_size = [64, 64]\n";
  const test::Bake b = test::bakeSceneText("occlusion_mesh", text);
  for (const char* f : {"depth.exr", "ambient_occlusion.exr", "sun_visibility.exr", "preview.png", "snow.vdb", "displacement_depth.exr",
                        "snow_surface.ply", "snow_surface.glb", "snow_surface.obj", "snow_mesh.ply", "snow_mesh.glb", "snow_mesh.obj",
                        "manifest.json"})
    EXPECT_TRUE(fs::exists(b.out() / f)) << f;
  // Against the per-vertex snow computed directly on the mesh as the bake read it, vertex by
  // vertex matched on (x, y) (importers may renumber vertices).
  const TriangleMesh in = loadTriangleMesh((dir / "pit.obj").string(), UpAxis::Z);
  const TriangleMesh out = loadTriangleMesh((b.out() / "snow_mesh.ply").string(), UpAxis::Z);
  ASSERT_EQ(out.triangles.size(), m.triangles.size());
  ASSERT_EQ(out.positions.size(), in.positions.size());
  const Grid<float> none;
  const RayScene scene(none, GridSpec{}, {in});
  OcclusionSettings s;
  s.latitudeDeg = 45.0;
  s.tauSun = 1.0;
  const OcclusionSnow o = computeOcclusionSnowOnMesh(scene, in, s);
  std::map<std::pair<int, int>, float> snowAt;
  for (size_t k = 0; k < in.positions.size(); ++k)
    snowAt[{static_cast<int>(std::lround(in.positions[k][0])), static_cast<int>(std::lround(in.positions[k][1]))}] = in.positions[k][2] + o.snowM[k];
  double maxSnow = 0.0;
  for (const auto& p : out.positions) {
    const auto it = snowAt.find({static_cast<int>(std::lround(p[0])), static_cast<int>(std::lround(p[1]))});
    ASSERT_NE(it, snowAt.end());
    ASSERT_NEAR(p[2], it->second, 1e-4);
  }
  for (float v : o.snowM) maxSnow = std::max(maxSnow, double(v));
  EXPECT_GT(maxSnow, 0.5);  // the pit's bottom
  // glTF is y up: read back with y as the up axis, the same heights.
  const TriangleMesh glb = loadTriangleMesh((b.out() / "snow_mesh.glb").string(), UpAxis::Y);
  ASSERT_EQ(glb.positions.size(), m.positions.size());
  EXPECT_NEAR(glb.boundsMax[2], out.boundsMax[2], 1e-3);
  EXPECT_NEAR(glb.boundsMin[2], out.boundsMin[2], 1e-3);
  const std::string manifest = [&] {
    std::ifstream in(b.out() / "manifest.json");
    return std::string(std::istreambuf_iterator<char>(in), {});
  }();
  EXPECT_NE(manifest.find("\"mode\": \"occlusion\""), std::string::npos);
  EXPECT_NE(manifest.find("snow_mesh.glb"), std::string::npos);
}

TEST(Occlusion, TheMeshVerticesFollowTheNoSnowMaskAndSnowfallMultiplier) {
  // The pit mesh in occlusion mode with a no-snow mask over its western quarter and a snowfall
  // multiplier of 0.5 elsewhere: vertices over the mask stay where they were; the others rise by
  // half their snow (against the same bake without art direction).
  const fs::path dir = fs::temp_directory_path() / ("snowbake_occlusion_mesh_art_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const TriangleMesh m = pitMesh();
  {
    std::ofstream obj(dir / "pit.obj");
    for (const auto& p : m.positions) obj << "v " << p[0] << " " << p[1] << " " << p[2] << "\n";
    for (const auto& t : m.triangles) obj << "f " << t[0] + 1 << " " << t[1] + 1 << " " << t[2] + 1 << "\n";
    std::ofstream pgm(dir / "west.pgm", std::ios::binary);  // 40 x 40 cells of 5 m: mask the west 10 columns
    pgm << "P5\n40 40\n255\n";
    for (int y = 0; y < 40; ++y)
      for (int x = 0; x < 40; ++x) pgm.put(static_cast<char>(x < 10 ? 255 : 0));
    std::ofstream half(dir / "half.pgm", std::ios::binary);
    half << "P5\n40 40\n255\n";
    for (int i = 0; i < 1600; ++i) half.put(static_cast<char>(255));
  }
  const std::string base = "mode = \"occlusion\"\n[terrain]\nfile = \"" + (dir / "pit.obj").string() +
                           "\"\nformat = \"mesh\"\ncell_size_m = 5.0\n[site]\nlatitude_deg = 45.0\n[occlusion]\ntau_sun = 1.0\n";
  const std::string outputs = "[outputs]\nlayers = [\"depth\"]\nmeshes = [\"ply\"]\n";
  const test::Bake plain = test::bakeSceneText("occlusion_mesh_plain", base + outputs);
  const test::Bake art = test::bakeSceneText(
      "occlusion_mesh_art", base + "[multipliers]\nno_snow = \"" + (dir / "west.pgm").string() + "\"\nsnowfall = { file = \"" +
                                (dir / "half.pgm").string() + "\", range = [0.0, 0.5] }\n" + outputs);
  const TriangleMesh in = loadTriangleMesh((dir / "pit.obj").string(), UpAxis::Z);
  const TriangleMesh a = loadTriangleMesh((plain.out() / "snow_mesh.ply").string(), UpAxis::Z);
  const TriangleMesh b = loadTriangleMesh((art.out() / "snow_mesh.ply").string(), UpAxis::Z);
  std::map<std::pair<int, int>, float> bed, full;
  for (const auto& p : in.positions) bed[{static_cast<int>(std::lround(p[0])), static_cast<int>(std::lround(p[1]))}] = p[2];
  for (const auto& p : a.positions) full[{static_cast<int>(std::lround(p[0])), static_cast<int>(std::lround(p[1]))}] = p[2];
  int masked = 0, halved = 0;
  for (const auto& p : b.positions) {
    const std::pair<int, int> key{static_cast<int>(std::lround(p[0])), static_cast<int>(std::lround(p[1]))};
    const float z0 = bed.at(key), snow = full.at(key) - z0;
    if (p[0] < 49.0f) {  // cells 0..9 (x < 50 m); the vertex at x = 50 m reads cell 10
      ASSERT_NEAR(p[2], z0, 1e-4) << "snow on a no-snow vertex at x = " << p[0];
      ++masked;
    } else if (p[0] > 51.0f) {
      ASSERT_NEAR(p[2] - z0, 0.5f * snow, 1e-4) << "at x = " << p[0];
      halved += snow > 0.01f;
    }
  }
  EXPECT_GT(masked, 300);
  EXPECT_GT(halved, 1000);
  fs::remove_all(dir);
}

TEST(Occlusion, SceneFilesKeepEachModesLayersApart) {
  const std::string t = "[terrain]\nbuiltin = \"ridged\"\n";
  EXPECT_THROW(loadSceneText(t + "[outputs]\nlayers = [\"ambient_occlusion\"]\n", "season.toml", ""), InputError);
  EXPECT_THROW(loadSceneText("mode = \"occlusion\"\n" + t + "[outputs]\nlayers = [\"melt\"]\n", "occ.toml", ""), InputError);
  EXPECT_THROW(loadSceneText("mode = \"occlusion\"\n" + t + "[outputs]\nframes_days = [10]\n", "occ.toml", ""), InputError);
  EXPECT_THROW(loadSceneText("mode = \"occlusion\"\n" + t + "[occlusion]\nday = 500\n", "occ.toml", ""), InputError);
  EXPECT_THROW(loadSceneText("mode = \"fast\"\n" + t, "occ.toml", ""), InputError);
  const Scene s = loadSceneText("mode = \"occlusion\"\n" + t + "[occlusion]\ntau_ambient = 0.9\nsun_positions = 12\n", "occ.toml", "");
  EXPECT_EQ(s.mode, SceneMode::Occlusion);
  EXPECT_DOUBLE_EQ(s.occlusion.tauAmbient, 0.9);
  EXPECT_EQ(s.occlusion.sunPositions, 12);
}

TEST(Occlusion, FrontRangeOcclusionAndSeasonMapsDiffer) {
  const std::string dem = std::string(SNOWBAKE_SHARED_DATA_DIR) + "/dem/front_range_srtm3.asc";
  if (!fs::exists(dem)) GTEST_SKIP() << "shared data not found: ../shared/data/dem/front_range_srtm3.asc";
  const std::string common = "[terrain]\nfile = \"" + dem + "\"\n[season]\nstart_date = 2025-11-01\ndays = 60\n"
                             "[parameters]\navalanche_rate_per_km2_per_day = 0\n[outputs]\nlayers = [\"depth\"]\n";  // (no spontaneous avalanches: they take this season past 10 minutes)
  const test::Bake occ = test::bakeSceneText("fr_occlusion", "mode = \"occlusion\"\n" + common);
  const test::Bake season = test::bakeSceneText("fr_season", common);
  auto read = [](const fs::path& p) {
    auto in = OIIO::ImageInput::open(p.string());
    EXPECT_TRUE(in);
    std::vector<float> v(static_cast<size_t>(in->spec().width) * in->spec().height);
    in->read_image(0, 0, 0, 1, OIIO::TypeDesc::FLOAT, v.data());
    return v;
  };
  const auto a = read(occ.out() / "depth.exr"), b = read(season.out() / "depth.exr");
  ASSERT_EQ(a.size(), b.size());
  // Each map normalised by its own mean: where the snow lies relative to the average.
  const double ma = std::accumulate(a.begin(), a.end(), 0.0) / a.size(), mb = std::accumulate(b.begin(), b.end(), 0.0) / b.size();
  ASSERT_GT(ma, 0.0);
  ASSERT_GT(mb, 0.0);
  double diff = 0.0;
  for (size_t k = 0; k < a.size(); ++k) diff += std::abs(a[k] / ma - b[k] / mb);
  diff /= a.size();
  EXPECT_GT(diff, 0.2) << "mean |occlusion/mean - season/mean|";
  std::cout << "Front Range: occlusion mean depth " << ma << " m, season " << mb << " m, mean |difference| of the normalised maps "
            << diff << "\n";
}

}  // namespace
}  // namespace snow
