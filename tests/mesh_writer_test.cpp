// Meshes: the adaptive triangulation's error bound and conformity, the closed snow body, tiles,
// and every format read back by assimp (an independent reader) through the project's mesh loader.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <algorithm>
#include <map>

#include "bakers/mesh_tiles.h"
#include "bakers/mesh_writer.h"
#include "bakers/rtin.h"
#include "bake_support.h"
#include "core/default_terrain.h"
#include "inputs/mesh.h"
#include "temp_dir.h"

namespace snow {
namespace {

namespace fs = std::filesystem;

struct Surface {
  GridSpec spec;
  Grid<float> bedrock, depth, surface;
  Grid<uint8_t> valid;
};

// The embedded range, `w` x `h` at 20 m, with snow deeper in the west, none in the east third,
// and optionally a NODATA hole.
Surface makeSurface(int w, int h, bool hole) {
  DefaultTerrainOptions o;
  o.size = std::max(w, h);
  o.cellSizeM = 20.0;
  const Terrain t = makeBuiltinTerrain(o);
  Surface s;
  s.spec.width = w, s.spec.height = h, s.spec.cellSizeXM = s.spec.cellSizeYM = 20.0;
  s.bedrock = Grid<float>(w, h, 0.f), s.depth = Grid<float>(w, h, 0.f), s.surface = Grid<float>(w, h, 0.f);
  s.valid = Grid<uint8_t>(w, h, 1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      s.bedrock(x, y) = t.heightsM(x, y);
      s.depth(x, y) = x < 2 * w / 3 ? static_cast<float>(1.5 + std::sin(0.2 * x) * std::cos(0.15 * y)) : 0.f;
      if (hole && std::hypot(x - w / 2.0, y - h / 2.0) < 6.0) s.valid(x, y) = 0;
      s.surface(x, y) = s.bedrock(x, y) + s.depth(x, y);
    }
  return s;
}

using EdgeCounts = std::map<std::pair<uint32_t, uint32_t>, int>;
EdgeCounts countEdges(const std::vector<std::array<uint32_t, 3>>& triangles) {
  EdgeCounts e;
  for (const auto& t : triangles)
    for (int k = 0; k < 3; ++k) ++e[{std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3])}];
  return e;
}

TEST(AdaptiveMesh, VerticalErrorStaysWithinTheBoundAndTrianglesFallAsItGrows) {
  const Surface s = makeSurface(150, 97, true);  // neither square nor 2^k + 1, with a hole
  size_t previous = SIZE_MAX;
  for (double bound : {0.0, 0.05, 0.5, 2.0, 10.0}) {
    const RtinMesh m = buildRtin({&s.surface}, s.valid, bound);
    const double err = rtinMaxVerticalError(m, s.surface);
    EXPECT_LE(err, bound + 1e-4) << "bound " << bound;
    EXPECT_LT(m.triangles.size(), previous) << "bound " << bound;
    previous = m.triangles.size();
    // Every triangle inside the grid and on valid points.
    for (const auto& t : m.triangles)
      for (uint32_t p : t) ASSERT_TRUE(m.x(p) < 150 && m.y(p) < 97 && s.valid(m.x(p), m.y(p)));
  }
  // A plane: two triangles, error 0.
  Grid<float> plane(129, 129, 0.f);
  for (int y = 0; y < 129; ++y)
    for (int x = 0; x < 129; ++x) plane(x, y) = 3.f * x - 2.f * y;
  EXPECT_EQ(buildRtin({&plane}, Grid<uint8_t>(129, 129, 1), 0.0).triangles.size(), 2u);
}

TEST(AdaptiveMesh, IsConformingAndCoversTheValidGrid) {
  const Surface s = makeSurface(150, 97, true);
  const RtinMesh m = buildRtin({&s.surface}, s.valid, 0.5);
  const MeshData mesh = surfaceMesh(m, s.surface, s.spec);
  // Interior edges are shared by two triangles; an edge used once lies on the grid's edge or next
  // to NODATA (no T-junction cracks).
  for (const auto& [edge, count] : countEdges(mesh.triangles)) {
    ASSERT_LE(count, 2);
    if (count == 2) continue;
    for (uint32_t v : {edge.first, edge.second}) {
      const int x = static_cast<int>(std::lround(mesh.positions[v][0] / 20.0 - 0.5));
      const int y = 96 - static_cast<int>(std::lround(mesh.positions[v][1] / 20.0 - 0.5));
      bool rim = x == 0 || y == 0 || x == 149 || y == 96;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) rim = rim || !s.valid(std::clamp(x + dx, 0, 149), std::clamp(y + dy, 0, 96));
      ASSERT_TRUE(rim) << "edge used once inside the grid at (" << x << ", " << y << ")";
    }
  }
  // Area covered: the valid cells' area less a ring around the hole.
  double area = 0.0;
  for (const auto& t : mesh.triangles) {
    const auto &a = mesh.positions[t[0]], &b = mesh.positions[t[1]], &c = mesh.positions[t[2]];
    const double cross = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
    ASSERT_GT(cross, 0.0);  // counter-clockwise from above: normals up
    area += cross / 2;
  }
  EXPECT_NEAR(area, 149.0 * 96.0 * 400.0, 0.02 * 149.0 * 96.0 * 400.0);
}

TEST(AdaptiveMesh, SnowBodyIsWatertightAndHoldsTheSnowVolume) {
  const Surface s = makeSurface(150, 97, true);
  const RtinMesh m = buildRtin({&s.surface, &s.bedrock}, s.valid, 0.05);
  const MeshData body = snowBodyMesh(m, s.bedrock, s.depth, s.valid, s.spec);
  ASSERT_FALSE(body.triangles.empty());
  // Written and read back by assimp: every edge shared by exactly two triangles.
  const fs::path dir = test::uniqueTempDir("mesh_body_test");
  for (const std::string format : {"ply", "glb", "obj", "fbx"}) {
    const std::string path = (dir / ("body." + format)).string();
    writeMesh(path, format, body);
    const TriangleMesh back = loadTriangleMesh(path, format == "ply" ? UpAxis::Z : UpAxis::Y);
    ASSERT_EQ(back.triangles.size(), body.triangles.size()) << format;
    int bad = 0;
    for (const auto& [edge, count] : countEdges(back.triangles)) bad += count != 2;
    EXPECT_EQ(bad, 0) << format << ": edges not shared by exactly two triangles";
    // Volume by the divergence theorem against the snow on the grid (the trapezoid rule over the
    // cells the triangulation covers, within the error bound).
    double volume = 0.0;
    for (const auto& t : back.triangles) {
      const auto &a = back.positions[t[0]], &b = back.positions[t[1]], &c = back.positions[t[2]];
      volume += (double(a[0]) * (double(b[1]) * c[2] - double(b[2]) * c[1]) - double(a[1]) * (double(b[0]) * c[2] - double(b[2]) * c[0]) +
                 double(a[2]) * (double(b[0]) * c[1] - double(b[1]) * c[0])) / 6.0;
    }
    double snow = 0.0;
    for (int y = 0; y < 97; ++y)
      for (int x = 0; x < 150; ++x) snow += s.valid(x, y) ? s.depth(x, y) * 400.0 : 0.0;
    EXPECT_NEAR(volume, snow, 0.03 * snow) << format;
  }
}

// Tiles cut along their borders: every vertex inside its tile, the projected area kept, and the
// edges on a shared border the same in both tiles bit for bit (no cracks, no T-junctions).
TEST(AdaptiveMesh, TilesAreCutAlongTheBorderAndMeetWithoutCracks) {
  const Surface s = makeSurface(150, 97, false);
  const RtinMesh m = buildRtin({&s.surface}, s.valid, 0.5);
  const MeshData mesh = surfaceMesh(m, s.surface, s.spec);
  const auto tiles = cutIntoTiles(mesh, s.spec, 64);
  ASSERT_EQ(tiles.size(), 6u);  // 3 columns x 2 rows of 64 cells
  const double t = 64 * 20.0, top = 97 * 20.0;
  auto area = [](const MeshData& d) {
    double a = 0;
    for (const auto& tri : d.triangles) {
      const auto &p = d.positions[tri[0]], &q = d.positions[tri[1]], &r = d.positions[tri[2]];
      a += 0.5 * ((static_cast<double>(q[0]) - p[0]) * (r[1] - p[1]) - (static_cast<double>(r[0]) - p[0]) * (q[1] - p[1]));
    }
    return a;
  };
  double tiled = 0;
  using Edge = std::pair<std::array<float, 3>, std::array<float, 3>>;
  std::map<std::pair<int, int>, std::vector<Edge>> westEdges, northEdges;  // each tile's edges on its west and north border
  std::map<std::pair<int, int>, std::vector<Edge>> eastEdges, southEdges;
  for (const auto& tile : tiles) {
    const double x0 = tile.column * t, x1 = x0 + t, y1 = top - tile.row * t, y0 = y1 - t;
    for (const auto& p : tile.mesh.positions) {
      ASSERT_GE(p[0], static_cast<float>(x0));
      ASSERT_LE(p[0], static_cast<float>(x1));
      ASSERT_GE(p[1], static_cast<float>(y0));
      ASSERT_LE(p[1], static_cast<float>(y1));
    }
    const double a = area(tile.mesh);
    EXPECT_GT(a, 0.0);
    tiled += a;
    for (const auto& [e, count] : countEdges(tile.mesh.triangles)) {
      if (count != 1) continue;  // inner edges are shared by two triangles
      auto p = tile.mesh.positions[e.first], q = tile.mesh.positions[e.second];
      if (q < p) std::swap(p, q);
      const Edge edge{p, q};
      const std::pair<int, int> at{tile.column, tile.row};
      if (p[0] == static_cast<float>(x0) && q[0] == p[0]) westEdges[at].push_back(edge);
      if (p[0] == static_cast<float>(x1) && q[0] == p[0]) eastEdges[at].push_back(edge);
      if (p[1] == static_cast<float>(y1) && q[1] == p[1]) northEdges[at].push_back(edge);
      if (p[1] == static_cast<float>(y0) && q[1] == p[1]) southEdges[at].push_back(edge);
    }
  }
  EXPECT_NEAR(tiled, area(mesh), 1e-9 * area(mesh));
  int borders = 0;
  for (auto& [at, edges] : eastEdges) {
    auto west = westEdges[{at.first + 1, at.second}];
    if (west.empty()) continue;  // the grid's east edge
    std::sort(edges.begin(), edges.end()), std::sort(west.begin(), west.end());
    EXPECT_EQ(edges, west) << "tile " << at.first << ", " << at.second;
    ++borders;
  }
  for (auto& [at, edges] : southEdges) {
    auto north = northEdges[{at.first, at.second + 1}];
    if (north.empty()) continue;
    std::sort(edges.begin(), edges.end()), std::sort(north.begin(), north.end());
    EXPECT_EQ(edges, north) << "tile " << at.first << ", " << at.second;
    ++borders;
  }
  EXPECT_EQ(borders, 2 * 2 + 3);  // 2 vertical borders in 2 rows, 1 horizontal in 3 columns
}

TEST(AdaptiveMesh, SurfaceMeshHeightsAndUvsLineUpWithTheGrid) {
  const Surface s = makeSurface(64, 48, false);
  const RtinMesh m = buildRtin({&s.surface}, s.valid, 0.2);
  const MeshData mesh = surfaceMesh(m, s.surface, s.spec);
  const fs::path dir = test::uniqueTempDir("mesh_surface_test");
  const std::string path = (dir / "surface.glb").string();
  writeMesh(path, "glb", mesh);
  const TriangleMesh back = loadTriangleMesh(path, UpAxis::Y);  // glTF is y up
  ASSERT_EQ(back.positions.size(), mesh.positions.size());
  for (const auto& p : back.positions) {
    const int x = static_cast<int>(std::lround(p[0] / 20.0 - 0.5)), y = 47 - static_cast<int>(std::lround(p[1] / 20.0 - 0.5));
    ASSERT_NEAR(p[0], (x + 0.5) * 20.0, 1e-3);
    ASSERT_NEAR(p[2], s.surface(x, y), 1e-3);
  }
  for (size_t k = 0; k < mesh.positions.size(); ++k) {
    EXPECT_NEAR(mesh.uvs[k][0], mesh.positions[k][0] / (64 * 20.0), 1e-6);
    EXPECT_NEAR(mesh.uvs[k][1], mesh.positions[k][1] / (48 * 20.0), 1e-6);
  }
}

// writeSurfaceMeshes reads the mesh as it writes it (no mesh arrays): the same bytes as the mesh
// built by surfaceMesh and written by writeMesh, in every format, with a hole in the grid.
TEST(AdaptiveMesh, SurfaceWrittenAsItIsReadIsTheSameBytesAsTheBuiltMesh) {
  const Surface s = makeSurface(150, 97, true);
  const RtinMesh m = buildRtin({&s.surface}, s.valid, 0.2);
  const MeshData mesh = surfaceMesh(m, s.surface, s.spec);
  const fs::path dir = test::uniqueTempDir("mesh_surface_stream_test");
  std::vector<std::pair<std::string, std::string>> streamed;
  for (const std::string format : {"ply", "glb", "obj", "fbx"}) {
    writeMesh((dir / ("built." + format)).string(), format, mesh);
    streamed.push_back({(dir / ("streamed." + format)).string(), format});
  }
  const MeshCounts counts = writeSurfaceMeshes(streamed, m, s.surface, s.spec);
  EXPECT_EQ(counts.vertices, mesh.positions.size());
  EXPECT_EQ(counts.triangles, mesh.triangles.size());
  auto bytes = [](const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  for (const std::string format : {"ply", "glb", "obj", "fbx"}) {
    const std::string built = bytes(dir / ("built." + format));
    EXPECT_GT(built.size(), 1000u) << format;
    EXPECT_TRUE(built == bytes(dir / ("streamed." + format))) << format;
  }
}

TEST(AdaptiveMesh, BakeWritesTheRequestedPartsFormatsAndTiles) {
  const std::string text =
      "[terrain]\nbuiltin = \"ridged\"\nsize = 96\ncell_size_m = 20\n[season]\ndays = 20\n[[events]]\ntype = \"snowfall\"\nday = 2\n"
      "duration_days = 3\n[outputs]\nlayers = [\"depth\"]\nmeshes = [\"glb\", \"fbx\"]\nmesh_parts = [\"surface\", \"body\"]\n"
      "mesh_max_error_m = 0.5\nmesh_tile_size_m = 1000\n";
  const test::Bake b = test::bakeSceneText("mesh_parts", text);
  for (const char* f : {"snow_body.glb", "snow_body.fbx", "snow_surface_x0_y0.glb", "snow_surface_x1_y1.fbx"})
    EXPECT_TRUE(fs::exists(b.out() / f)) << f;
  EXPECT_FALSE(fs::exists(b.out() / "snow_surface.glb"));  // tiled instead
  EXPECT_FALSE(fs::exists(b.out() / "snow_body.ply"));      // not asked
}

}  // namespace
}  // namespace snow
