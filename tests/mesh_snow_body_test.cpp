// The snow body of snow on a mesh (bakers/mesh_snow_body.h): a closed mesh, a level set whose
// zero crossing sits on the input surface (no gap) and at the snow top within a voxel, and a VDB
// read back by OpenVDB: the body must be watertight and sit on the input mesh without gaps larger
// than one voxel.
#include <gtest/gtest.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>

#include <filesystem>
#include <fstream>
#include <map>

#include "bakers/mesh_snow_body.h"
#include "static_snow/fallen_snow.h"

namespace snow {
namespace {

void quad(TriangleMesh& m, std::array<float, 3> a, std::array<float, 3> b, std::array<float, 3> c, std::array<float, 3> d) {
  const uint32_t base = static_cast<uint32_t>(m.positions.size());
  for (const auto& p : {a, b, c, d}) m.positions.push_back(p);
  m.triangles.push_back({base, base + 1, base + 2});
  m.triangles.push_back({base, base + 2, base + 3});
}

// The ground, a roof slab (an overhang: top, underside and its open edge), and a 30 degree wedge.
TriangleMesh scene() {
  TriangleMesh m;
  m.source = "overhang and ramp";
  quad(m, {0, 0, 0}, {3, 0, 0}, {3, 2, 0}, {0, 2, 0});
  quad(m, {0, 0, 0.5f}, {1, 0, 0.5f}, {1, 2, 0.5f}, {0, 2, 0.5f});        // roof top
  quad(m, {0, 0, 0.45f}, {0, 2, 0.45f}, {1, 2, 0.45f}, {1, 0, 0.45f});    // roof underside
  quad(m, {1, 0, 0.45f}, {1, 2, 0.45f}, {1, 2, 0.5f}, {1, 0, 0.5f});      // its open edge
  const float rise = 0.5f * std::tan(30.f * 3.14159265f / 180.f);
  quad(m, {2, 0, 0}, {2.5f, 0, rise}, {2.5f, 2, rise}, {2, 2, 0});        // ramp: a closed wedge
  quad(m, {2.5f, 0, rise}, {2.5f, 0, 0}, {2.5f, 2, 0}, {2.5f, 2, rise});
  for (float y : {0.f, 2.f}) {
    const uint32_t b = static_cast<uint32_t>(m.positions.size());
    m.positions.push_back({2, y, 0});
    m.positions.push_back({2.5f, y, 0});
    m.positions.push_back({2.5f, y, rise});
    m.triangles.push_back({b, b + 1, b + 2});
  }
  return m;
}

TEST(MeshSnowBody, IsWatertightAndSitsOnTheSurfaceWithoutGaps) {
  const TriangleMesh m = scene();
  FallenSnowSettings s;
  s.depthM = 0.3;
  s.flutterMeanM = 0.03;
  s.flutterSigmaM = 0.01;
  s.siteSpacingM = 0.05;
  FallenSnow f = placeFallenSnow(m, s);
  stabilizeFallenSnow(m, f, FallenSnowStability{});
  const std::string dir = ::testing::TempDir() + "/mesh_snow_body";
  std::filesystem::create_directories(dir);
  MeshSnowBodyOptions o;
  o.voxelSizeM = 0.025;
  const MeshSnowBody body = buildMeshSnowBody(f, m, o, dir + "/snow.vdb");
  ASSERT_GT(body.mesh.triangles.size(), 1000u);

  // Watertight: every edge in exactly two triangles, once each way (consistent winding).
  std::map<std::pair<uint32_t, uint32_t>, int> edges;
  for (const auto& t : body.mesh.triangles)
    for (int e = 0; e < 3; ++e) ++edges[{t[e], t[(e + 1) % 3]}];
  size_t bad = 0;
  for (const auto& [e, count] : edges) bad += count != 1 || edges.count({e.second, e.first}) == 0 || edges.at({e.second, e.first}) != 1;
  EXPECT_EQ(bad, 0u);
  // Outward: the enclosed volume is positive, the voxels' (the smoothing takes a little off
  // corners), and more than the sites' snow (the columns reach a voxel into the surface).
  double volume = 0;
  for (const auto& t : body.mesh.triangles) {
    const auto &a = body.mesh.positions[t[0]], &b = body.mesh.positions[t[1]], &c = body.mesh.positions[t[2]];
    volume += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0])) / 6.0;
  }
  const double voxels = static_cast<double>(body.snowVoxels) * std::pow(o.voxelSizeM, 3);
  std::printf("[ measure ] snow body: %zu triangles, %.4f m^3 enclosed, %zu voxels = %.4f m^3, the sites' snow %.4f m^3, %.2f s\n",
              body.mesh.triangles.size(), volume, body.snowVoxels, voxels, body.columnsM3, body.seconds);
  EXPECT_NEAR(volume, voxels, 0.05 * voxels);
  EXPECT_GT(volume, body.columnsM3);

  // The VDB read back: grids, classes, voxel size; the zero crossing on the surface and the top.
  openvdb::initialize();
  openvdb::io::File file(dir + "/snow.vdb");
  file.open();
  openvdb::FloatGrid::Ptr sdf = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("snow_sdf"));
  openvdb::FloatGrid::Ptr fog = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("density"));
  file.close();
  ASSERT_TRUE(sdf && fog);
  EXPECT_EQ(sdf->getGridClass(), openvdb::GRID_LEVEL_SET);
  EXPECT_EQ(fog->getGridClass(), openvdb::GRID_FOG_VOLUME);
  EXPECT_NEAR(sdf->voxelSize()[0], 0.025, 1e-9);
  const openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> at(*sdf);
  const double vx = o.voxelSizeM;
  int checked = 0, gaps = 0, topsOff = 0;
  for (const SnowSite& site : f.sites) {
    // Sites well inside the snow (their footprint holds at least 4 voxels of it), away from the
    // roof's edge and the wedge's back wall (where the ground's snow meets the snow above).
    if (site.depthM < 4 * vx || site.position[0] < 0.1f || site.position[1] < 0.1f || site.position[1] > 1.9f ||
        std::abs(site.position[0] - 1.f) < 0.15f || std::abs(site.position[0] - 2.5f) < 0.1f || site.position[0] > 2.9f)
      continue;
    ++checked;
    const double x = site.position[0], y = site.position[1], zb = site.position[2], top = zb + site.depthM;
    // The snow's distance from the surface point under the site: at most a voxel (no larger gap).
    if (!(at.wsSample(openvdb::Vec3d(x, y, zb)) < vx)) ++gaps;
    // The top within a voxel.
    const bool inside = at.wsSample(openvdb::Vec3d(x, y, top - vx)) < 0.f, outside = at.wsSample(openvdb::Vec3d(x, y, top + vx)) > 0.f;
    if (!inside || !outside) ++topsOff;
  }
  std::printf("[ measure ] %d sites checked: %d with the snow more than a voxel from the surface under them, %d with the top off by "
              "more than a voxel\n",
              checked, gaps, topsOff);
  EXPECT_GT(checked, 500);
  EXPECT_EQ(gaps, 0);
  EXPECT_EQ(topsOff, 0);
}

TEST(MeshSnowBody, TheVdbIsTheSameBytesTwice) {
  const TriangleMesh m = scene();
  FallenSnowSettings s;
  s.siteSpacingM = 0.1;
  FallenSnow f = placeFallenSnow(m, s);
  stabilizeFallenSnow(m, f, FallenSnowStability{});
  const std::string dir = ::testing::TempDir() + "/mesh_snow_body_twice";
  std::filesystem::create_directories(dir);
  buildMeshSnowBody(f, m, MeshSnowBodyOptions{}, dir + "/a.vdb");
  buildMeshSnowBody(f, m, MeshSnowBodyOptions{}, dir + "/b.vdb");
  auto bytes = [](const std::string& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  EXPECT_EQ(bytes(dir + "/a.vdb"), bytes(dir + "/b.vdb"));
}

}  // namespace
}  // namespace snow

#include "core/errors.h"
#include "tests/bake_support.h"
#include <nlohmann/json.hpp>

namespace snow {
namespace {

// A 2 m ground with a 0.5 m block on it, as OBJ (z up).
std::string writeBlockObj() {
  const auto dir = test::uniqueTempDir("mesh_mode");
  const std::string path = (dir / "block.obj").string();
  std::ofstream o(path);
  o << "v 0 0 0\nv 2 0 0\nv 2 2 0\nv 0 2 0\n"                         // ground 1-4
    << "v 0.7 0.7 0.5\nv 1.3 0.7 0.5\nv 1.3 1.3 0.5\nv 0.7 1.3 0.5\n"  // block top 5-8
    << "v 0.7 0.7 0\nv 1.3 0.7 0\nv 1.3 1.3 0\nv 0.7 1.3 0\n"          // block bottom 9-12
    << "f 1 2 3\nf 1 3 4\nf 5 6 7\nf 5 7 8\n"
    << "f 9 10 6\nf 9 6 5\nf 10 11 7\nf 10 7 6\nf 11 12 8\nf 11 8 7\nf 12 9 5\nf 12 5 8\n";
  return path;
}

TEST(MeshSnowBake, ModeMeshWritesTheSnowBodyAndAManifest) {
  const std::string obj = writeBlockObj();
  const test::Bake b = test::bakeSceneText("mesh_mode", "mode = \"mesh\"\n[terrain]\nfile = \"" + obj +
                                                            "\"\n[mesh_snow]\ndepth_m = 0.3\nsite_spacing_m = 0.05\nflutter_mean_m = 0.02\n"
                                                            "flutter_sigma_m = 0.01\n[outputs]\nmeshes = [\"glb\", \"ply\"]\nvdb = true\n");
  for (const char* f : {"snow_body.glb", "snow_body.ply", "snow.vdb", "manifest.json"})
    EXPECT_GT(std::filesystem::file_size(b.out() / f), 1000u) << f;
  const auto m = nlohmann::json::parse(std::ifstream(b.out() / "manifest.json"));
  EXPECT_EQ(m["run"]["mode"], "mesh");
  EXPECT_EQ(m["mesh"]["triangles"], 12);
  const double placed = m["mass_balance_m3"]["placed"], kept = m["mass_balance_m3"]["kept"], lost = m["mass_balance_m3"]["left_the_world"];
  EXPECT_NEAR(placed, 0.3 * 4.0, 1e-9);
  EXPECT_NEAR(kept + lost, placed, 1e-9 * placed);
  EXPECT_GT(m["run"]["stability"]["buried_sites"].get<int>(), 0);  // the ground under the block
  EXPECT_EQ(m["files"].size(), 4u);  // the body twice, the VDB and scene.resolved.toml
}

TEST(MeshSnowBake, ModeMeshRefusesWhatItCannotMake) {
  const std::string obj = writeBlockObj();
  auto bake = [&](const std::string& extra) {
    return test::bakeSceneText("mesh_mode_bad", "mode = \"mesh\"\n[terrain]\nfile = \"" + obj + "\"\n" + extra);
  };
  EXPECT_THROW(bake("[outputs]\nmeshes = [\"glb\"]\nlayers = [\"depth\"]\n"), InputError);
  EXPECT_THROW(bake("[outputs]\nformat = \"exr\"\n"), InputError);  // nothing to write
  EXPECT_THROW(test::bakeSceneText("mesh_mode_bad", "[mesh_snow]\ndepth_m = 0.3\n[terrain]\nbuiltin = \"ridged\"\nsize = 64\n"), InputError);
  EXPECT_THROW(test::bakeSceneText("mesh_mode_bad", "mode = \"mesh\"\n[terrain]\nbuiltin = \"ridged\"\n[outputs]\nvdb = true\n"), InputError);
}

}  // namespace
}  // namespace snow

namespace snow {
namespace {

// Snow on a season's [[occluders]]: a 20 m box held high over the builtin range gets a snow body
// whose top stands the terrain's snow depth round it above the box (the same snowfall).
TEST(MeshSnowBake, OccludersOnATerrainGetSnowAsDeepAsTheTerrainRoundThem) {
  const auto dir = test::uniqueTempDir("occluder_snow");
  const std::string obj = (dir / "box.obj").string();
  {
    TriangleMesh m;
    std::ofstream o(obj);
    const float x0 = 300, y0 = 300, x1 = 320, y1 = 320, z0 = 3990, z1 = 4000;
    for (float z : {z0, z1})
      for (const auto& [x, y] : {std::pair{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}) o << "v " << x << " " << y << " " << z << "\n";
    o << "f 1 4 3\nf 1 3 2\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n";
  }
  const test::Bake b = test::bakeSceneText(
      "occluder_snow", "[terrain]\nbuiltin = \"ridged\"\nsize = 64\ncell_size_m = 10\n[season]\ndays = 10\n"
                       "[[weather.keyframe]]\nday = 0\nsea_level_temperature_c = -5\n[[weather.snowfall]]\nstart_day = 0\nend_day = 4\n"
                       "[[occluders]]\nfile = \"" + obj + "\"\n[mesh_snow]\nsite_spacing_m = 0.5\nvoxel_size_m = 0.05\n[precompute]\nsun = false\n"
                       "[outputs]\nlayers = [\"depth\"]\nmeshes = [\"obj\"]\n");
  const auto m = nlohmann::json::parse(std::ifstream(b.out() / "manifest.json"));
  std::string content;
  for (const auto& f : m["files"])
    if (f["path"] == "occluder_0_snow.obj") content = f["content"];
  ASSERT_FALSE(content.empty());
  const double depth = std::stod(content.substr(content.find(", ") + 2));
  // The body's highest point (OBJ is y-up: y is the altitude).
  double top = -1e9;
  std::ifstream in(b.out() / "occluder_0_snow.obj");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("v ", 0) == 0) {
      std::istringstream l(line.substr(2));
      double x, y, z;
      l >> x >> y >> z;
      top = std::max(top, y);
    }
  std::printf("[ measure ] terrain snow round the box %.3f m; the snow body's top %.3f m above the box\n", depth, top - 4000.0);
  EXPECT_GT(depth, 0.05);
  EXPECT_NEAR(top - 4000.0, depth, 0.05 * depth + 0.05);  // a voxel is 0.05 m
}

}  // namespace
}  // namespace snow
