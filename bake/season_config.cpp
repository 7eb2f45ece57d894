// What the season runs: the scene's days, weather and events, art direction's edits and masked
// events, and the ski-track texture and route map when the outputs ask for them.
#include <algorithm>
#include <array>

#include "core/bedform_runs.h"
#include "core/errors.h"
#include "core/format.h"
#include "stages.h"

namespace snow {
namespace {

// A user event's point (metres from the north-west corner, or the DEM's own projected
// coordinates) as a valid cell.
std::array<int, 2> eventCell(const Scene& scene, const Terrain& terrain, const Scene::AvalancheEvent& a,
                             const std::string& what, const std::string& point) {
  const std::string where = scene.sourceName + ":" + std::to_string(a.line) + ": events: " + what + " on day " + fixed(a.day, 1);
  const TerrainInfo& ti = terrain.info;
  double xM = a.xM, yM = a.yM;
  if (a.mapCoordinates) {
    if (ti.coordinateSystem.rfind("geographic", 0) == 0)
      throw InputError(where + ": map_position needs a DEM in projected metres; this one is " + ti.coordinateSystem + " (use position_m)");
    xM = a.xM - ti.spec.originX;
    yM = ti.spec.originY - a.yM;
  }
  const double fx = xM / ti.spec.cellSizeXM, fy = yM / ti.spec.cellSizeYM;
  if (!(fx >= 0.0 && fy >= 0.0 && fx < ti.spec.width && fy < ti.spec.height))
    throw InputError(where + ": the " + point + " (" + fixed(xM, 1) + " m east, " + fixed(yM, 1) +
                     " m south of the north-west corner) is outside the terrain (" + fixed(ti.spec.width * ti.spec.cellSizeXM, 1) + " x " +
                     fixed(ti.spec.height * ti.spec.cellSizeYM, 1) + " m)");
  const int x = static_cast<int>(fx), y = static_cast<int>(fy);
  if (!terrain.valid(x, y)) throw InputError(where + ": the " + point + " falls on a NODATA cell");
  return {x, y};
}

}  // namespace

SeasonConfig makeSeasonConfig(const Scene& scene, const BakeTerrain& terrain, const ArtDirectionPlan& art,
                              const Precomputed& pre, const std::vector<std::string>& layers, SeasonOutputs& outputs, std::ostream& log) {
  SeasonConfig config;
  config.days = scene.days;
  config.seed = scene.seed;
  config.params = scene.params;
  config.weather = scene.weather;
  config.userSnowfalls = scene.userSnowfalls;
  config.avalancheMaps = scene.outputs.avalancheMaps;
  config.avalancheFrameIntervalS = scene.outputs.avalancheFrameIntervalS;
  config.edits = art.edits;
  config.userAvalanches = art.avalanches;  // masked releases
  config.userSkiers = art.skiers;          // skiers from start masks
  for (const Scene::AvalancheEvent& a : scene.userAvalanches) {
    if (a.mask) continue;
    const auto c = eventCell(scene, terrain.terrain, a, "avalanche", "rupture point");
    config.userAvalanches.push_back({a.day, c[0], c[1], false, nullptr});
  }
  for (const Scene::AvalancheEvent& a : scene.userSkiers) {
    if (a.mask) continue;
    const auto c = eventCell(scene, terrain.terrain, a, "skier", "start point");
    config.userSkiers.push_back({a.day, c[0], c[1], a.count, nullptr});
  }
  const uint8_t needs = layersNeeds(layers);
  // The whole terrain's (the state's terrain fields' bytes; a rank may hold its local grid alone).
  const Terrain& t = terrain.terrain;
  if (needs & kNeedsRouteMap) outputs.routeMap = routeMap(t.heightsM, t.valid, t.info.spec);
  if (needs & kNeedsSkiTracks) {
    outputs.skiTracks.emplace(t.info.spec, scene.outputs.skiTrackFactor);
    config.skiTracks = &*outputs.skiTracks;
  }
  config.frameDays = scene.outputs.frameDays;
  config.recordFields = recordFieldsToKeep(layersRecords(layers), scene.outputs.avalancheMaps);
  config.windTransport = pre.wind->hasWind();
  if (scene.bedforms.enabled) {
    config.bedforms = scene.bedforms.params;
    if (!config.windTransport) log << "bedforms: the scene has no wind; only the cohesion of the snow will change\n";
  }
  config.updateStaticFields = dailyStaticFill(pre, scene.params);
  return config;
}

std::function<void(int, SnowState&)> dailyStaticFill(const Precomputed& pre, const ModelParameters& params) {
  // The wind changes with several keyframe states, or calm keyframes among windy ones.
  const bool windChanges = pre.wind && pre.wind->varies();
  if (!pre.exposure && !windChanges) return {};
  return [&pre, params, windChanges](int day, SnowState& s) {
    if (pre.exposure) pre.temperatureForDay(day, s, params);
    if (windChanges) pre.windForDay(day, s);
  };
}

void checkBedformsSuitTheGrid(const Scene& scene, const GridSpec& spec) {
  if (!scene.bedforms.enabled || scene.mode == SceneMode::Occlusion) return;
  const std::string problem = validateBedformParameters(scene.bedforms.params, spec);
  if (problem.empty()) return;
  // The problem starts with its key ("bedforms.periodic: ...", "bedforms.slab_m = ..."): its line.
  throw InputError(scene.keyLocation(problem.substr(0, problem.find_first_of(" :"))) + ": " + problem);
}

}  // namespace snow
