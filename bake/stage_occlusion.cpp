// mode = "occlusion" (Foldes & Benes 2007, static_snow/occlusion.h): ambient occlusion and the
// day's sun trajectory give a static snow cover, in place of the season.
#include <algorithm>
#include <cmath>
#include <iomanip>

#include "core/format.h"
#include "static_snow/occlusion.h"
#include "precompute/ray_scene.h"
#include "stages.h"

namespace snow {

bool occlusionWritesSnowMesh(const Scene& scene, const TerrainInfo& terrain) { return terrain.format == "mesh" && !scene.outputs.meshes.empty(); }

namespace {

// The season day of the sun trajectory: occlusion.day, or the season's middle.
double occlusionSunDay(const Scene& scene) { return scene.occlusion.day.value_or(scene.days / 2.0); }

OcclusionSettings occlusionSettings(const Scene& scene, double latitudeDeg) {
  const OcclusionParameters& op = scene.occlusion;
  OcclusionSettings os;
  os.sMaxM = op.sMaxM;
  os.tauAmbient = op.tauAmbient;
  os.tauSun = op.tauSun;
  os.sunPositions = op.sunPositions;
  os.aoRays = op.aoRays > 0 ? op.aoRays : occlusionRaysForQuality(scene.sunQuality);
  os.aoRadiusM = op.aoRadiusM;
  os.latitudeDeg = latitudeDeg;
  os.turbidity = op.turbidity;
  os.dayOfYear = std::fmod(scene.startDayOfYear() - 1 + occlusionSunDay(scene), 365.0) + 1.0;
  return os;
}

// Snow per vertex of the input mesh itself (the paper's irregular mesh), raised along z. The
// scene's art direction applies as on the grid: the snowfall multiplier scales a vertex's snow and
// the no-snow mask clears it, read at the grid cell under the vertex (the grid covers the mesh:
// x east from its origin, rows south from it).
TriangleMesh snowOnInputMesh(const Scene& scene, const BakeTerrain& terrain, const SnowState& state, const OcclusionSettings& os,
                             std::ostream& log) {
  const auto tm = WallClock::now();
  TriangleMesh mesh = loadTriangleMesh(scene.terrain.file, scene.terrain.upAxis);
  std::vector<TriangleMesh> meshes = terrain.occluders;
  meshes.insert(meshes.begin(), mesh);
  const Grid<float> none;
  const RayScene meshRays(none, GridSpec{}, meshes);
  const OcclusionSnow mo = computeOcclusionSnowOnMesh(meshRays, mesh, os);
  const bool factor = state.snowfallFactor.size() == state.stableM.size(), bare = state.noSnow.size() == state.stableM.size();
  double volume = 0.0;
  for (size_t k = 0; k < mesh.positions.size(); ++k) {
    float snow = mo.snowM[k];
    if (factor || bare) {
      const auto& q = mesh.positions[k];
      const int i = std::clamp(static_cast<int>(std::floor((q[0] - state.spec.originX) / state.spec.cellSizeXM)), 0, state.spec.width - 1);
      const int j = std::clamp(static_cast<int>(std::floor((state.spec.originY - q[1]) / state.spec.cellSizeYM)), 0, state.spec.height - 1);
      if (factor) snow *= state.snowfallFactor(i, j);
      if (bare && state.noSnow(i, j)) snow = 0.f;
    }
    mesh.positions[k][2] += snow, volume += snow;
  }
  log << "occlusion: mesh " << mesh.source << ", " << mesh.positions.size() << " vertices, " << mesh.triangles.size()
      << " triangles: " << fixed(elapsedSeconds(tm), 2) << " s (mean snow " << fixed(volume / std::max<size_t>(1, mesh.positions.size()), 3)
      << " m per vertex)\n";
  return mesh;
}

}  // namespace

void runOcclusion(const Scene& scene, const BakeTerrain& terrain, SnowState& state, OcclusionResult& result, std::ostream& log) {
  const OcclusionSettings os = occlusionSettings(scene, terrain.latitudeDeg);
  const double sunDay = occlusionSunDay(scene);
  const auto tOcc = WallClock::now();
  const RayScene rays(state.bedrockM, state.spec, terrain.occluders);
  const double buildSeconds = elapsedSeconds(tOcc);
  const OcclusionSnow o = computeOcclusionSnowOnTerrain(rays, state.bedrockM, state.validCell, state.spec, os);
  auto asGrid = [&](const std::vector<float>& v) {
    Grid<float> g(state.spec.width, state.spec.height, 0.f);
    std::copy(v.begin(), v.end(), g.data());
    return g;
  };
  result.grids = {asGrid(o.ambient), asGrid(o.sunVisibility), asGrid(o.accumulationM), asGrid(o.dissipationM)};
  // The static cover is settled snow: the stable layer; the scene's snowfall multiplier (a sky
  // mask) scales it and its no-snow mask clears it.
  state.stableM = asGrid(o.snowM);
  for (size_t i = 0; i < state.stableM.size(); ++i) {
    float& d = state.stableM.values()[i];
    if (state.snowfallFactor.size() == state.stableM.size()) d *= state.snowfallFactor.values()[i];
    if (state.noSnow.size() == state.stableM.size() && state.noSnow.values()[i]) d = 0.f;
  }
  log << "occlusion: Embree scene " << fixed(buildSeconds, 2) << " s; ambient occlusion " << os.aoRays << " rays/cell, "
      << fixed(o.aoSeconds, 2) << " s (" << fixed(o.aoRayCount / std::max(o.aoSeconds, 1e-9) / 1e6, 1) << " M rays/s); sun "
      << o.sun.size() << " positions on day " << fixed(os.dayOfYear, 0) << " of the year, " << fixed(o.sunSeconds, 2) << " s\n";
  if (o.sun.empty()) log << "  the sun stays below the horizon on that day (polar night): no dissipation\n";
  result.manifest = {os.sMaxM, os.tauAmbient, os.tauSun, os.aoRadiusM, sunDay, os.dayOfYear, os.turbidity, os.aoRays, {}, ""};
  for (const SunSample& x : o.sun) result.manifest.sunHoursAndWeights.push_back({x.solarHour, x.weight});
  if (occlusionWritesSnowMesh(scene, terrain.info())) {
    result.snowMesh = snowOnInputMesh(scene, terrain, state, os, log);
    result.manifest.meshSource = result.snowMesh->source;
  }
  for (size_t i = 0; i < state.stableM.size(); ++i) result.report.final.stableM3 += state.stableM.values()[i] * state.spec.cellAreaM2();
  result.report.seconds = elapsedSeconds(tOcc);
  log << "occlusion: " << std::scientific << std::setprecision(4) << result.report.final.totalM3() << std::defaultfloat << " m^3 of snow ("
      << fixed(result.report.seconds, 2) << " s)\n";
}

}  // namespace snow
