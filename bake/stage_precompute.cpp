// Stage 4: the precompute, once per terrain: sun exposure (direct, sky, indirect) and the wind
// timeline (each wind state's field and wind-effect surface), both through the cache.
#include "core/errors.h"
#include "core/format.h"
#include "core/hash.h"
#include "precompute/ray_scene.h"
#include "progress.h"
#include "stages.h"

namespace snow {
namespace {

// Sun exposure, from the cache when every input is unchanged. On a rank's local grid (`cells`),
// its own entry: the key of the whole grid's and the cells.
Exposure loadOrComputeExposure(const Terrain& terrain, const std::vector<TriangleMesh>& occluders, const ModelParameters& p,
                               const ExposureSettings& es, const PrecomputeCache& cache, const std::optional<CellRect>& cells,
                               std::ostream& log) {
  const GridSpec& spec = terrain.info.spec;
  std::string key = exposureCacheKey(terrain.heightsM, terrain.valid, spec, occluders, p, es);
  if (cells) key = partCacheKey(key, *cells);
  const CellRect extent = cells.value_or(CellRect::whole(spec));
  // The sample days are fixed by the settings: list them, then fill the grids from the cache.
  Exposure e;
  e.days = exposureSampleDays(es);
  std::vector<Grid<float>*> grids{&e.skyHours};
  for (auto& d : e.days) grids.push_back(&d.sunHours), grids.push_back(&d.indirectHours);
  if (cache.load("exposure", key, extent.width(), extent.height(), grids)) {
    e.cells = cells;
    log << "  sun exposure: from the cache" << (cells ? " (each rank its local grid's)" : "") << "\n";
    progress().event("precompute", "exposure", {{"status", jsonText("cached")}});
    return e;
  }
  std::unique_ptr<RayScene> scene;
  if (!es.horizonSweep) scene = std::make_unique<RayScene>(terrain.heightsM, spec, occluders);
  e = computeExposure(scene.get(), terrain.heightsM, terrain.valid, spec, p, es, cells);
  if (cells) log << "  sun exposure: each rank its local grid (rank 0's " << cells->width() << " x " << cells->height() << " cells)\n";
  const ExposureTimings& t = e.timings;
  if (es.horizonSweep)
    log << "  sun exposure (horizon sweep): horizons " << fixed(t.horizonSeconds, 2) << " s, direct " << fixed(t.sunSeconds, 2)
        << " s, sky " << fixed(t.skySeconds, 2) << " s, indirect " << fixed(t.indirectSeconds, 2) << " s\n";
  else
    log << "  sun exposure (Embree rays): direct " << fixed(t.sunSeconds, 2) << " s (" << t.sunRays << " rays), sky "
        << fixed(t.skySeconds, 2) << " s (" << t.skyRays << " rays), indirect " << fixed(t.indirectSeconds, 2) << " s\n";
  for (const std::string& term : t.skipped) log << "  sun exposure: " << term << ": skipped\n";
  std::vector<const Grid<float>*> out{&e.skyHours};
  for (const auto& d : e.days) out.push_back(&d.sunHours), out.push_back(&d.indirectHours);
  cache.store("exposure", key, out);
  progress().event("precompute", "exposure", {{"status", jsonText("computed")}});
  return e;
}

void precomputeExposure(const Scene& scene, const BakeTerrain& terrain, const PrecomputeCache& cache, const PrecomputeParts& parts,
                        Precomputed& pre, std::ostream& log) {
  const auto t0 = WallClock::now();
  const ExposureSettings es = exposureSettings(scene, terrain);
  if (scene.sunMethod == SunMethod::Horizon && !terrain.occluders.empty())
    throw InputError(scene.sourceName + ": precompute.sun_method = \"horizon\" cannot see occluder meshes; use \"embree\" or \"auto\"");
  const bool shared = parts.exposureShare.has_value();
  pre.exposure = loadOrComputeExposure(terrain.terrain, terrain.occluders, scene.params, es, cache, shared ? parts.exposureShare : parts.exposure, log);
  pre.exposure->foldIndirect();  // the season and the layers read I_sun + I_ind only
  if (shared) {
    pre.exposure = parts.wholeExposure(*pre.exposure);
    log << "  sun exposure: the ranks' local grids' gathered whole on every rank (the season's replica reads it)\n";
  }
  log << "precompute: sun exposure (" << es.quality.name << ", " << (es.horizonSweep ? "horizon sweep" : "Embree") << ", "
      << pre.exposure->days.size() << " sample days) (" << fixed(elapsedSeconds(t0), 2) << " s)\n";
}

}  // namespace

ExposureSettings exposureSettings(const Scene& scene, const BakeTerrain& terrain) {
  ExposureSettings es;
  es.quality = sunQuality(scene.sunQuality);
  es.latitudeDeg = terrain.latitudeDeg;
  es.startDayOfYear = scene.startDayOfYear();
  es.seasonDays = scene.days;
  // The fast path where it is valid (a pure height field) unless the scene asks for rays.
  es.horizonSweep = scene.sunMethod == SunMethod::Horizon || (scene.sunMethod == SunMethod::Auto && terrain.occluders.empty());
  return es;
}

std::string exposureCacheKey(const Grid<float>& bedrockM, const Grid<uint8_t>& valid, const GridSpec& spec,
                             const std::vector<TriangleMesh>& occluders, const ModelParameters& p, const ExposureSettings& es) {
  Fnv1a64 h;
  h.add("exposure-v2");
  h.add(es.horizonSweep ? "horizon-sweep" : "embree");
  h.add(bedrockM.data(), bedrockM.size() * sizeof(float));
  h.add(valid.data(), valid.size());
  const double numbers[] = {static_cast<double>(spec.width), static_cast<double>(spec.height), spec.cellSizeXM,
                            spec.cellSizeYM, es.latitudeDeg, static_cast<double>(es.startDayOfYear), es.seasonDays,
                            p.directSunWeightHours, p.skyAmbientWeightHours, p.indirectSunWeightHours};
  h.add(numbers, sizeof numbers);
  h.add(es.quality.name);
  for (const auto& m : occluders) {
    h.add(m.positions.data(), m.positions.size() * sizeof(m.positions[0]));
    h.add(m.triangles.data(), m.triangles.size() * sizeof(m.triangles[0]));
  }
  return h.hex();
}

void Precomputed::temperatureForDay(int day, SnowState& s, const ModelParameters& params) const {
  if (exposure) s.exposureHours = exposure->totalAt(day);
  else if (s.exposureHours.size() != s.spec.cellCount()) s.exposureHours.resize(s.spec.width, s.spec.height, 0.f);  // no sun: none
  computeTemperatureBase(s, params);
}

void Precomputed::windForDay(int day, SnowState& s) const {
  WindFieldsAtDay f = wind->at(day);
  s.windXMps = std::move(f.windXMps);
  s.windYMps = std::move(f.windYMps);
  s.windEffectZM = std::move(f.windEffectZM);
  s.windLoadingMps2 = std::move(f.windLoadingMps2);
}

Precomputed Precomputed::window(int x0, int y0, int width, int height) const {
  Precomputed out;
  if (exposure) out.exposure = exposure->window(x0, y0, width, height);
  if (wind) out.wind = wind->window(x0, y0, width, height);
  return out;
}

StageDecision sunExposureDecision(const Scene& scene) {
  if (scene.mode == SceneMode::Occlusion) return {false, "occlusion mode"};
  if (!scene.sunExposure) return {false, "precompute.sun = false"};
  return {};
}

StageDecision windDecision(const Scene& scene) {
  if (scene.mode == SceneMode::Occlusion) return {false, "occlusion mode"};
  if (!scene.weather.hasWind()) return {false, "no wind in the season"};
  return {};
}

Precomputed runPrecompute(const Scene& scene, const BakeTerrain& terrain, SnowState& state, const PrecomputeCache& cache,
                          const PrecomputeParts& parts, std::ostream& log) {
  progress().stage("precompute", 0.0);
  Precomputed pre;
  pre.partsOnRanks = parts.any();
  const bool occlusionMode = scene.mode == SceneMode::Occlusion;
  const StageDecision sun = sunExposureDecision(scene), windStage = windDecision(scene);
  if (sun.runs)
    precomputeExposure(scene, terrain, cache, parts, pre, log);
  else if (occlusionMode)
    log << "precompute: sun exposure and wind not needed in occlusion mode: skipped\n";
  else
    log << "precompute: sun exposure off (precompute.sun = false): temperature from altitude alone\n";
  if (!sun.runs) progress().event("precompute", "exposure", {{"status", jsonText("skipped")}, {"why", jsonText(sun.why)}});
  if (!pre.partsOnRanks) pre.temperatureForDay(0, state, scene.params);
  const auto t0 = WallClock::now();
  const WeatherTimeline calm;
  const Terrain& t = terrain.terrain;  // the state's terrain fields' bytes, which a rank may hold in part
  const WindPart* windPart = parts.wind ? &*parts.wind : parts.windShare ? &*parts.windShare : nullptr;
  pre.wind.emplace(t.heightsM, t.valid, t.info.spec, occlusionMode ? calm : scene.weather, scene.params, cache, WindSolverOptions{}, &log,
                   windPart);
  if (parts.windShare) {
    pre.wind = parts.wholeWind(*pre.wind, t.heightsM);
    if (windStage.runs) log << "  wind: the ranks' local grids' gathered whole on every rank (the season's replica reads it)\n";
  }
  const WindTimeline& wind = *pre.wind;
  if (windStage.runs)
    progress().event("precompute", "wind", {{"status", jsonText(wind.computedStates() ? "computed" : "cached")},
                                            {"computed", std::to_string(wind.computedStates())}, {"cached", std::to_string(wind.cachedStates())}});
  else
    progress().event("precompute", "wind", {{"status", jsonText("skipped")}, {"why", jsonText(windStage.why)}});
  if (occlusionMode) {
  } else if (windStage.runs) {
    log << "precompute: wind, " << wind.stateCount() << " state" << (wind.stateCount() == 1 ? "" : "s") << " (" << wind.computedStates()
        << " computed, " << wind.cachedStates() << " from the cache"
        << (windPart ? ", each rank its local grid's" : "") << (cache.enabled() ? " " + cache.directory() : std::string(", cache off"))
        << ") (" << fixed(elapsedSeconds(t0), 2) << " s)\n";
  } else {
    log << "precompute: no wind in the season: wind field skipped\n";
  }
  if (!pre.partsOnRanks) pre.windForDay(0, state);
  progress().stage("precompute", 1.0);
  return pre;
}

}  // namespace snow
