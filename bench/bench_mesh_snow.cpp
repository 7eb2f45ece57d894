// `snowbake bench --stage meshsnow`: snow on a 500 000-triangle mesh (Fearing's model, mode =
// "mesh"): a 10 m x 10 m bumpy ground of 500 x 500 quads with boulders (closed boxes) and table
// slabs (overhangs) on it, the time of each stage, and the checks that are exact: the mass
// balance (sky = placed = kept + left the world) and the body's closure (every edge in two
// triangles).
#include <cmath>
#include <map>
#include <sstream>

#include "bakers/mesh_snow_body.h"
#include "bench_suite.h"
#include "static_snow/fallen_snow.h"

namespace snow {

namespace {

void addBox(TriangleMesh& m, float x0, float y0, float z0, float x1, float y1, float z1) {
  const uint32_t b = static_cast<uint32_t>(m.positions.size());
  for (float z : {z0, z1})
    for (const auto& [x, y] : {std::pair{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}) m.positions.push_back({x, y, z});
  const int q[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
  for (const auto& f : q) {
    m.triangles.push_back({b + f[0], b + f[1], b + f[2]});
    m.triangles.push_back({b + f[0], b + f[2], b + f[3]});
  }
}

}  // namespace

TriangleMesh meshSnowBenchScene(int quads) {
  TriangleMesh m;
  m.source = "bench: bumpy ground with boulders and tables";
  const float size = 10.f, h = size / quads;
  for (int j = 0; j <= quads; ++j)
    for (int i = 0; i <= quads; ++i) {
      const float x = i * h, y = j * h;
      m.positions.push_back({x, y, 0.15f * std::sin(1.3f * x) * std::cos(0.9f * y) + 0.05f * std::sin(7.f * x + 3.f * y)});
    }
  for (int j = 0; j < quads; ++j)
    for (int i = 0; i < quads; ++i) {
      const uint32_t a = static_cast<uint32_t>(j * (quads + 1) + i), b = a + 1, c = a + quads + 2, d = a + quads + 1;
      m.triangles.push_back({a, b, c});
      m.triangles.push_back({a, c, d});
    }
  for (int k = 0; k < 12; ++k) {
    const float x = 0.8f + 0.75f * k, y = 1.0f + 0.6f * static_cast<float>(k % 5);
    addBox(m, x, y, -0.2f, x + 0.4f, y + 0.3f, 0.3f + 0.05f * static_cast<float>(k % 3));  // boulders
  }
  for (int k = 0; k < 3; ++k) addBox(m, 1.f + 3.f * k, 6.5f, 0.6f, 2.4f + 3.f * k, 7.5f, 0.65f);  // table tops (overhangs)
  return m;
}

std::string meshSnowBench(const BenchOptions& o, std::ostream& log, int threads) {
  (void)o;
  const TriangleMesh mesh = meshSnowBenchScene(500);
  FallenSnowSettings ps;
  ps.depthM = 0.3;
  ps.siteSpacingM = 0.04;
  ps.flutterMeanM = 0.02;
  ps.flutterSigmaM = 0.01;
  ps.swirlHeightM = 0.05;
  const auto t0 = WallClock::now();
  FallenSnow snow = placeFallenSnow(mesh, ps);
  const double placeS = elapsedSeconds(t0);
  const auto t1 = WallClock::now();
  const FallenSnowStabilityReport st = stabilizeFallenSnow(mesh, snow, FallenSnowStability{});
  const double stableS = elapsedSeconds(t1);
  const auto t2 = WallClock::now();
  MeshSnowBodyOptions bo;
  bo.voxelSizeM = 0.02;
  const MeshSnowBody body = buildMeshSnowBody(snow, mesh, bo);
  const double bodyS = elapsedSeconds(t2);
  std::map<std::pair<uint32_t, uint32_t>, int> edges;
  for (const auto& t : body.mesh.triangles)
    for (int e = 0; e < 3; ++e) ++edges[{std::min(t[e], t[(e + 1) % 3]), std::max(t[e], t[(e + 1) % 3])}];
  size_t open = 0;
  for (const auto& [e, c] : edges) open += c != 2;
  const double total = placeS + stableS + bodyS;
  log << "  mesh snow: " << mesh.triangles.size() << " triangles, " << benchFormat("%.1f", total) << " s\n";
  std::ostringstream table;
  table << "Snow on a mesh (mode = \"mesh\"): a 10 m x 10 m bumpy ground of " << mesh.triangles.size()
        << " triangles with 12 boulders and 3 table tops, 0.3 m of snow, 4 cm sites, 2 cm flutter, 2 cm voxels; "
        << benchMachineDescription() << ", " << threads << " threads\n\n"
        << "| stage | seconds | what it did |\n|---|---|---|\n"
        << "| placement | " << benchFormat("%.2f", placeS) << " | " << snow.sites.size() << " sites (" << snow.refinedCells << " cells refined), "
        << snow.flakes << " flakes, " << snow.blocked << " blocked |\n"
        << "| stability | " << benchFormat("%.2f", stableS) << " | " << st.rounds << " rounds, " << st.passes << " passes"
        << (st.unconvergedRounds ? ", " + std::to_string(st.unconvergedRounds) + " at the pass limit" : std::string()) << ", "
        << benchFormat("%.3f", st.overEdgesM3) << " m^3 over edges |\n"
        << "| snow body | " << benchFormat("%.2f", bodyS) << " | " << body.snowVoxels << " voxels, " << body.mesh.triangles.size()
        << " triangles |\n"
        << "| **total** | **" << benchFormat("%.1f", total) << "** | target: under 120 s on 2 cores |\n\n"
        << "Exact checks: sky " << benchFormat("%.6f", snow.skyMassM3) << " m^3, placed " << benchFormat("%.6f", snow.placedM3)
        << " m^3, kept + left the world " << benchFormat("%.6f", st.finalM3 + st.leftTheWorldM3) << " m^3 (relative difference "
        << benchFormat("%.1e", std::abs(st.finalM3 + st.leftTheWorldM3 - snow.placedM3) / snow.placedM3) << "); body edges not in exactly two triangles: "
        << open << ".\n";
  return table.str();
}

}  // namespace snow
