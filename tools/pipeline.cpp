#include "pipeline.h"

#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <fstream>
#include <iomanip>
#include <map>
#include <memory>
#include <optional>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "core/atomic_file.h"
#include "bakers/grid_writer.h"
#include "bakers/manifest.h"
#include "bakers/mesh_snow_body.h"
#include "bakers/mesh_writer.h"
#include "bakers/rtin.h"
#include "bakers/vdb_writer.h"
#include "precompute/solar.h"
#include "core/cpu_backend.h"
#include "core/errors.h"
#include "core/hash.h"
#include "cuda/cuda_backend.h"
#include "precompute/mesh.h"
#include "precompute/scene.h"
#include "precompute/exposure.h"
#include "precompute/fallen_snow.h"
#include "precompute/occlusion.h"
#include "precompute/ray_scene.h"
#include "precompute/wind_timeline.h"
#include "art_direction.h"
#include "progress.h"

#ifndef SNOWBAKE_VERSION
#define SNOWBAKE_VERSION "0.0.0"
#endif

namespace snow {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

const char* programVersion() { return SNOWBAKE_VERSION; }

namespace {

double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

std::string fixed(double v, int digits) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(digits) << v;
  return o.str();
}

// What a layer name in [outputs].layers means, and its grid.
Grid<float> layerGrid(const SnowState& s, const std::string& name) {
  // NODATA cells are written as zero; the valid_mask layer says which they are.
  Grid<float> g(s.spec.width, s.spec.height, 0.f);
  for (int y = 0; y < s.spec.height; ++y)
    for (int x = 0; x < s.spec.width; ++x) {
      if (!s.validCell(x, y)) continue;
      float v = 0.f;
      if (name == "compacted") v = s.compactedM(x, y);
      else if (name == "wind_scour") v = s.windScourM(x, y);
      else if (name == "wind_deposit") v = s.windDepositM(x, y);
      else if (name == "melt") v = s.meltedM(x, y);
      else if (name == "avalanche_scour") v = s.avalancheScourM(x, y);
      else if (name == "avalanche_deposit") v = s.avalancheDepositM(x, y);
      else if (name == "stable") v = s.stableM(x, y);
      else if (name == "unstable") v = s.unstableM(x, y);
      else if (name == "powder") v = s.powderM(x, y);
      else if (name == "bedrock") v = s.bedrockM(x, y);
      else if (name == "depth") v = s.depthM(x, y);
      else if (name == "surface") v = s.bedrockM(x, y) + s.depthM(x, y);
      else if (name == "valid_mask") v = 1.f;
      else if (name == "bedform_cohesion") v = s.bedformCohesion.size() == s.spec.cellCount() ? s.bedformCohesion(x, y) : 0.f;
      g(x, y) = v;
    }
  return g;
}

// The layers drawn from the precomputed wind fields (scour and deposit are season records).
bool isWindLayer(const std::string& name) {
  return name == "wind_speed" || name == "wind_direction" || name == "wind_shadow_depth" || name == "wind_shadow_mask";
}

// Wind layers for the day of an output, from the precomputed fields.
Grid<float> windLayerGrid(const SnowState& s, const WindTimeline& wind, double day, const std::string& name, double shadowToleranceM) {
  const WindFieldsAtDay f = wind.at(day);
  Grid<float> g(s.spec.width, s.spec.height, 0.f);
  for (int y = 0; y < s.spec.height; ++y)
    for (int x = 0; x < s.spec.width; ++x) {
      if (!s.validCell(x, y)) continue;
      const double wx = f.windXMps(x, y), wy = f.windYMps(x, y), depth = f.windEffectZM(x, y) - s.bedrockM(x, y);
      if (name == "wind_speed") g(x, y) = static_cast<float>(std::hypot(wx, wy));
      else if (name == "wind_direction") g(x, y) = wx == 0 && wy == 0 ? 0.f : static_cast<float>(std::fmod(std::atan2(-wx, wy) * 180.0 / M_PI + 360.0, 360.0));
      else if (name == "wind_shadow_depth") g(x, y) = static_cast<float>(std::max(0.0, depth));
      else if (name == "wind_shadow_mask") g(x, y) = depth > shadowToleranceM ? 1.f : 0.f;
    }
  return g;
}

std::string layerUnit(const std::string& name) {
  if (name == "valid_mask" || name == "bedform_cohesion" || name == "wind_shadow_mask" || name == "ambient_occlusion" || name == "sun_visibility") return "1";
  if (name == "sun_exposure") return "h";
  if (name == "temperature") return "degC";
  if (name == "wind_speed") return "m/s";
  if (name == "wind_direction") return "deg";
  return "m";
}

std::string layerContent(const std::string& name) {
  if (name == "wind_scour") return "snow removed by wind transport since the season start (m)";
  if (name == "wind_deposit") return "snow deposited by wind transport since the season start (m)";
  if (name == "melt") return "snow melted since the season start (m)";
  if (name == "bedform_cohesion") return "wind bedforms: cohesion of the loose snow, 0 loose .. 1 bonded; wind lifts it above threshold / (1 - cohesion)";
  if (name == "avalanche_scour") return "snow taken away by avalanches since the season start, net per avalanche (m)";
  if (name == "avalanche_deposit") return "snow left by avalanches since the season start, net per avalanche (m)";
  if (name == "sun_exposure") return "sun exposure I = I_sun + I_sky + I_ind, hours of equivalent direct sun per day (§4.1)";
  if (name == "temperature") return "air temperature at the surface, T = T0 + k_t A + k_i I (§4.1)";
  if (name == "wind_speed") return "wind speed |W| (venturi and terrain redirection, Eq. 2)";
  if (name == "wind_direction") return "direction the wind blows from, degrees clockwise from north";
  if (name == "wind_shadow_depth") return "wind shadow depth W_z - A (height of the wind-effect surface above the ground)";
  if (name == "wind_shadow_mask") return "1 where the wind-effect surface is more than wind_shadow_tolerance_m above the ground (wind shadow)";
  if (name == "depth") return "total snow depth C+S+U+P";
  if (name == "ski_tracks") return "ski tracks: depth of the grooves below the snow surface (subtract from the surface), faded by snow since";
  if (name == "ski_route_map") return "skiers' route map: length of the longest strictly descending path from the cell (m)";
  if (name == "ambient_occlusion")
    return "ambient occlusion value a (Foldes & Benes Eq. 1): cosine-weighted fraction of the hemisphere open to the sky, 1 = unoccluded";
  if (name == "sun_visibility") return "sun visibility v: luminance-weighted fraction of the day's sun trajectory that sees the point";
  if (name == "occlusion_accumulation") return "snow placed by ambient occlusion, s_max max(0, tau_ambient - a) cos(theta) (Eq. 1)";
  if (name == "occlusion_dissipation") return "snow the sun dissipates, s_max max(0, v - tau_sun) cos(theta)";
  if (name == "bedrock") return "terrain altitude B";
  if (name == "surface") return "snow-surface altitude B+C+S+U+P";
  if (name == "valid_mask") return "1 where the terrain has data, 0 at NODATA cells (written as 0 in every layer)";
  return "snow layer: " + name;
}

// Sun exposure, from the cache when every input is unchanged.
Exposure loadOrComputeExposure(const SnowState& state, const std::vector<TriangleMesh>& occluders, const ModelParameters& p,
                               const ExposureSettings& es, const PrecomputeCache& cache, std::ostream& log) {
  Fnv1a64 h;
  h.add("exposure-v2");
  h.add(es.horizonSweep ? "horizon-sweep" : "embree");
  h.add(state.bedrockM.data(), state.bedrockM.size() * sizeof(float));
  h.add(state.validCell.data(), state.validCell.size());
  const double numbers[] = {static_cast<double>(state.spec.width), static_cast<double>(state.spec.height), state.spec.cellSizeXM,
                            state.spec.cellSizeYM, es.latitudeDeg, static_cast<double>(es.startDayOfYear), es.seasonDays,
                            p.directSunWeightHours, p.skyAmbientWeightHours, p.indirectSunWeightHours};
  h.add(numbers, sizeof numbers);
  h.add(es.quality.name);
  for (const auto& m : occluders) {
    h.add(m.positions.data(), m.positions.size() * sizeof(m.positions[0]));
    h.add(m.triangles.data(), m.triangles.size() * sizeof(m.triangles[0]));
  }
  const std::string key = h.hex();
  // The sample days are fixed by the settings: list them, then fill the grids from the cache.
  Exposure e;
  e.days = exposureSampleDays(es);
  std::vector<Grid<float>*> grids{&e.skyHours};
  for (auto& d : e.days) grids.push_back(&d.sunHours), grids.push_back(&d.indirectHours);
  if (cache.load("exposure", key, state.spec.width, state.spec.height, grids)) {
    log << "  sun exposure: from the cache\n";
    return e;
  }
  std::unique_ptr<RayScene> scene;
  if (!es.horizonSweep) scene = std::make_unique<RayScene>(state.bedrockM, state.spec, occluders);
  e = computeExposure(scene.get(), state.bedrockM, state.validCell, state.spec, p, es);
  if (es.horizonSweep)
    log << "  sun exposure (horizon sweep): horizons " << fixed(e.timings.horizonSeconds, 2) << " s, direct "
        << fixed(e.timings.sunSeconds, 2) << " s, sky " << fixed(e.timings.skySeconds, 2) << " s, indirect "
        << fixed(e.timings.indirectSeconds, 2) << " s\n";
  else
    log << "  sun exposure (Embree rays): direct " << fixed(e.timings.sunSeconds, 2) << " s (" << e.timings.sunRays << " rays), sky "
        << fixed(e.timings.skySeconds, 2) << " s (" << e.timings.skyRays << " rays), indirect " << fixed(e.timings.indirectSeconds, 2)
        << " s\n";
  std::vector<const Grid<float>*> out{&e.skyHours};
  for (const auto& d : e.days) out.push_back(&d.sunHours), out.push_back(&d.indirectHours);
  cache.store("exposure", key, out);
  return e;
}

std::unique_ptr<SnowBackend> chooseBackend(const std::string& wanted, std::ostream& log) {
  if (wanted == "cpu") return createCpuBackend();
  const cuda::DeviceInfo device = cuda::probeDevice();
  if (wanted == "cuda") {
    if (!device.available) throw InputError("--backend cuda: no usable CUDA device: " + device.reason);
    return cuda::createCudaBackend();
  }
  if (device.available) {
    log << "backend: cuda (auto: " << device.description << ")\n";
    return cuda::createCudaBackend();
  }
  log << "backend: cpu (auto: " << device.reason << ")\n";
  return createCpuBackend();
}

}  // namespace

// Where listed output files go while a group of writers runs on its own thread: the manifest
// entries, paths and per-format seconds of that group, merged in a fixed order afterwards so the
// manifest is the same whatever ran first.
struct OutputSink {
  std::vector<ManifestFile> files;
  std::vector<std::string> paths;
  std::map<std::string, double> seconds;
  Clock::time_point last = Clock::now();
};
thread_local OutputSink* tlSink = nullptr;
struct SinkScope {
  OutputSink* previous;
  explicit SinkScope(OutputSink& sink) : previous(tlSink) {
    tlSink = &sink;
    sink.last = Clock::now();
  }
  ~SinkScope() { tlSink = previous; }
  SinkScope(const SinkScope&) = delete;
  SinkScope& operator=(const SinkScope&) = delete;
};

namespace {

// mode = "mesh": Fearing's snow on the mesh itself (README "Snow on meshes"): placement,
// stability, the snow body as meshes and a VDB, and a manifest.
BakeResult runMeshBake(const Scene& scene, const BakeOptions& options, std::ostream& log, Clock::time_point tStart) {
  BakeResult result;
  result.backendName = "cpu (Embree ray queries, TBB)";
  auto t0 = Clock::now();
  const TriangleMesh mesh = loadTriangleMesh(scene.terrain.file, scene.terrain.upAxis);
  float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (const auto& p : mesh.positions)
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
  log << "mode: mesh (Fearing 2000: snow on the mesh itself; no grid, no season)\n";
  log << "mesh: " << mesh.source << ": " << mesh.triangles.size() << " triangles, " << fixed(hi[0] - lo[0], 2) << " x "
      << fixed(hi[1] - lo[1], 2) << " x " << fixed(hi[2] - lo[2], 2) << " m (" << fixed(since(t0), 2) << " s)\n";
  t0 = Clock::now();
  FallenSnowSettings placement = scene.meshSnow.placement;
  placement.seed = scene.seed;
  FallenSnow snow = placeFallenSnow(mesh, placement);
  log << "placement: " << snow.sites.size() << " sites (" << snow.refinedCells << " cells refined), " << snow.flakes << " flakes ("
      << snow.blocked << " blocked, " << snow.leftTheWorld << " left the world), sky " << fixed(snow.skyMassM3, 4) << " m^3, placed "
      << fixed(snow.placedM3, 4) << " m^3 (" << fixed(since(t0), 2) << " s)\n";
  t0 = Clock::now();
  FallenSnowStability stability = scene.meshSnow.stability;
  stability.seed = scene.seed;
  const FallenSnowStabilityReport st = stabilizeFallenSnow(mesh, snow, stability);
  log << "stability: " << st.rounds << " rounds, " << st.passes << " passes" << (st.unconvergedRounds ? " (" + std::to_string(st.unconvergedRounds) + " rounds hit the pass limit)" : std::string())
      << ", " << fixed(st.overEdgesM3, 4) << " m^3 over edges, " << fixed(st.leftTheWorldM3, 4) << " m^3 left the world, "
      << fixed(st.finalM3, 4) << " m^3 kept (" << fixed(since(t0), 2) << " s)\n";
  t0 = Clock::now();
  std::error_code ec;
  fs::create_directories(options.outDir, ec);
  if (ec) throw InputError(options.outDir + ": cannot create the output folder: " + ec.message());
  const MeshSnowBodyOptions& bo = scene.meshSnow.body;
  const std::string vdbPath = scene.outputs.vdb ? (fs::path(options.outDir) / "snow.vdb").string() : std::string();
  const MeshSnowBody body = buildMeshSnowBody(snow, mesh, bo, vdbPath);
  log << "snow body: " << body.snowVoxels << " voxels of " << fixed(body.voxelSizeM, 4) << " m, " << body.mesh.triangles.size()
      << " triangles (" << fixed(body.seconds, 2) << " s)\n";
  MeshSnowManifest manifest;
  manifest.programVersion = programVersion();
  manifest.sceneSource = scene.sourceName;
  manifest.sceneName = scene.name;
  manifest.sceneHash = Fnv1a64().add(scene.canonicalToml).hex();
  manifest.meshSource = mesh.source;
  manifest.meshHash = hashFileFnv1a64(scene.terrain.file);
  manifest.triangles = mesh.triangles.size();
  for (int k = 0; k < 3; ++k) manifest.boundsMin[k] = lo[k], manifest.boundsMax[k] = hi[k];
  manifest.seed = scene.seed;
  manifest.placement = placement;
  manifest.stability = stability;
  manifest.sites = snow.sites.size();
  manifest.skyM3 = snow.skyMassM3;
  manifest.placedM3 = snow.placedM3;
  manifest.stabilityReport = st;
  manifest.voxelSizeM = body.voxelSizeM;
  manifest.bodyTriangles = body.mesh.triangles.size();
  if (!vdbPath.empty()) {
    manifest.files.push_back({"snow.vdb", "the snow body: snow_sdf (level set, metres) and density (fog volume, kg/m^3 of " +
                                              fixed(bo.densityKgPerM3, 0) + " inside)",
                              "m; kg/m^3", "OpenVDB"});
    result.files.push_back(vdbPath);
  }
  for (const std::string& format : scene.outputs.meshes) {
    const std::string name = "snow_body." + format;
    const std::string path = (fs::path(options.outDir) / name).string();
    writeMesh(path, format, body.mesh);
    manifest.files.push_back({name, "the snow body, closed, in the input mesh's frame", "m", meshFormatDescription(format)});
    result.files.push_back(path);
  }
  const std::string manifestPath = (fs::path(options.outDir) / "manifest.json").string();
  writeTextAtomically(manifestPath, meshSnowManifestToJson(manifest));
  result.files.push_back(manifestPath);
  log << "outputs: " << result.files.size() << " files in " << options.outDir << " (" << fixed(since(t0), 2) << " s)\n";
  log << "total: " << fixed(since(tStart), 2) << " s\n";
  return result;
}

}  // namespace

BakeResult runBake(const BakeOptions& options, std::ostream& log) {
  const auto tStart = Clock::now();
  // 1. Scene
  Scene scene = loadScene(options.scene, options.sets);
  if (options.terrainFile) {
    std::error_code ec;
    if (!fs::exists(*options.terrainFile, ec)) throw InputError(*options.terrainFile + ": terrain file does not exist (--terrain)");
    // The scene's reading options (cell size, height range, resampling...) still apply.
    scene.terrain.builtin = false;
    scene.terrain.file = *options.terrainFile;
    scene.terrain.declaredAt = "--terrain";
  }
  if (options.seed) scene.seed = *options.seed;
  if (options.threads) scene.threads = *options.threads;
  if (options.backend) scene.backend = *options.backend;
  if (scene.backend != "cpu" && scene.backend != "cuda" && scene.backend != "auto")
    throw InputError("--backend " + scene.backend + ": must be cpu, cuda or auto");
  if (scene.threads < 0) throw InputError("--threads " + std::to_string(scene.threads) + ": must be 0 (all cores) or more");
  const int threads = scene.threads > 0 ? scene.threads : tbb::info::default_concurrency();
  tbb::global_control threadLimit(tbb::global_control::max_allowed_parallelism, static_cast<size_t>(threads));
  log << "snowbake " << programVersion() << ": scene " << scene.sourceName << " (" << scene.name << "), seed " << scene.seed
      << ", " << threads << " thread" << (threads == 1 ? "" : "s") << "\n";
  if (scene.mode == "mesh") return runMeshBake(scene, options, log, tStart);

  // 2. Terrain
  auto t0 = Clock::now();
  Terrain terrain = loadTerrain(scene.terrain);
  const TerrainInfo& ti = terrain.info;
  log << "terrain: " << ti.source << " (" << ti.format << "): " << ti.spec.width << " x " << ti.spec.height << " cells of "
      << fixed(ti.spec.cellSizeXM, 2) << " x " << fixed(ti.spec.cellSizeYM, 2) << " m, " << fixed(ti.minElevationM, 0) << "-"
      << fixed(ti.maxElevationM, 0) << " m, " << ti.nodataCells << " NODATA cells"
      << (ti.filledCells ? ", " + std::to_string(ti.filledCells) + " filled" : std::string()) << ", " << ti.coordinateSystem << " ("
      << fixed(since(t0), 2) << " s)\n";
  if (!ti.resampling.empty()) log << "  resampled: " << ti.resampling << "\n";
  std::vector<TriangleMesh> occluders;
  if (!scene.occluders.empty()) {
    t0 = Clock::now();
    occluders = loadOccluders(scene.occluders);
    size_t triangles = 0;
    for (const auto& mesh : occluders) triangles += mesh.triangles.size();
    log << "occluders: " << scene.occluders.size() << " meshes, " << triangles << " triangles (" << fixed(since(t0), 2)
        << " s); they shade the sun exposure\n";
  }
  const double latitude = scene.latitudeDeg ? *scene.latitudeDeg : (ti.latitudeKnown ? ti.centreLatitudeDeg : 45.0);
  if (!scene.latitudeDeg)
    log << "site: latitude " << fixed(latitude, 3) << " deg " << (ti.latitudeKnown ? "(from the DEM)" : "(default; set site.latitude_deg)") << "\n";

  const bool occlusionMode = scene.mode == "occlusion";
  if (occlusionMode) log << "mode: occlusion (Foldes & Benes 2007): no season\n";

  // 3. Precompute
  t0 = Clock::now();
  SnowState state;
  state.allocate(ti.spec);
  state.bedrockM = terrain.heightsM;
  state.validCell = terrain.valid;
  // Painted rasters first: a bad mask fails before any precompute runs; so do bedform
  // parameters that do not suit the grid.
  const ArtDirectionPlan art = prepareArtDirection(scene, ti, state, log);
  if (scene.bedforms.enabled && !occlusionMode)
    if (const std::string problem = validateBedformParameters(scene.bedforms.params, state.spec); !problem.empty())
      throw InputError(scene.sourceName + ": " + problem);
  const PrecomputeCache cache(options.cacheDir.value_or(PrecomputeCache::defaultDirectory()), options.useCache);
  std::optional<Exposure> exposure;
  if (occlusionMode) {
    log << "precompute: sun exposure and wind not needed in occlusion mode: skipped\n";
  } else if (scene.sunExposure) {
    ExposureSettings es;
    es.quality = sunQuality(scene.sunQuality);
    es.latitudeDeg = latitude;
    es.startDayOfYear = scene.startDayOfYear();
    es.seasonDays = scene.days;
    // The fast path where it is valid (a pure height field) unless the scene asks for rays.
    es.horizonSweep = scene.sunMethod == "horizon" || (scene.sunMethod == "auto" && occluders.empty());
    if (scene.sunMethod == "horizon" && !occluders.empty())
      throw InputError(scene.sourceName + ": precompute.sun_method = \"horizon\" cannot see occluder meshes; use \"embree\" or \"auto\"");
    exposure = loadOrComputeExposure(state, occluders, scene.params, es, cache, log);
    log << "precompute: sun exposure (" << es.quality.name << ", " << (es.horizonSweep ? "horizon sweep" : "Embree") << ", " << exposure->days.size() << " sample days) ("
        << fixed(since(t0), 2) << " s)\n";
  } else {
    log << "precompute: sun exposure off (precompute.sun = false): temperature from altitude alone\n";
  }
  // T = T0 + k_t A + k_i I (§4.1), the exposure of each season day interpolated between samples.
  auto temperatureForDay = [&](int day, SnowState& s) {
    if (exposure) s.exposureHours = exposure->totalAt(day);
    computeTemperatureBase(s, scene.params);
  };
  temperatureForDay(0, state);
  t0 = Clock::now();
  const WeatherTimeline calm;
  const WindTimeline wind(state.bedrockM, state.validCell, state.spec, occlusionMode ? calm : scene.weather, scene.params, cache,
                          WindSolverOptions{}, &log);
  if (occlusionMode) {
  } else if (wind.hasWind()) {
    log << "precompute: wind, " << wind.stateCount() << " state" << (wind.stateCount() == 1 ? "" : "s") << " ("
        << wind.computedStates() << " computed, " << wind.cachedStates() << " from the cache"
        << (cache.enabled() ? " " + cache.directory() : std::string(", cache off")) << ") (" << fixed(since(t0), 2) << " s)\n";
  } else {
    log << "precompute: no wind in the season: wind field skipped\n";
  }
  // The wind of a day (calm: no wind, W_z on the ground); refreshed daily when it changes through
  // the season (several keyframe states, or calm keyframes among windy ones).
  auto windForDay = [&](int day, SnowState& s) {
    WindFieldsAtDay f = wind.at(day);
    s.windXMps = std::move(f.windXMps);
    s.windYMps = std::move(f.windYMps);
    s.windEffectZM = std::move(f.windEffectZM);
    s.windLoadingMps2 = std::move(f.windLoadingMps2);
  };
  windForDay(0, state);
  const bool windChanges = wind.varies();

  // 4. Season
  std::unique_ptr<SnowBackend> backend = occlusionMode ? nullptr : chooseBackend(scene.backend, log);
  const std::string backendName = backend ? backend->name() : "cpu (Embree ray queries; occlusion mode has no season kernels)";
  std::error_code ec;
  fs::create_directories(options.outDir, ec);
  if (ec) throw InputError(options.outDir + ": cannot create the output folder: " + ec.message());

  Manifest manifest;
  BakeResult result;
  std::vector<std::string> layers = scene.outputs.layers;
  if (ti.nodataCells > 0 && std::find(layers.begin(), layers.end(), "valid_mask") == layers.end()) layers.push_back("valid_mask");
  std::map<std::string, Grid<float>> occlusionLayers;  // mode = "occlusion": a, v, accumulation, dissipation
  std::optional<SkiTracks> skiTracks;                   // the ski-track texture, when asked for
  Grid<float> routeMapGrid;                             // the skiers' route map, when there are skiers
  std::optional<TriangleMesh> snowMesh;                 // occlusion mode on a mesh terrain: the input mesh, snow on its vertices
  std::vector<std::vector<uint8_t>> previews;  // for the contact sheet, in the order written
  int previewWidth = 0, previewHeight = 0;
  // Every file written is listed, in order, in the current writer group's sink (tlSink): here
  // the bake's own, `outputs`, which becomes the manifest's file list and the result's; groups
  // that run on other threads list into their own and are merged in a fixed order. Time per kind
  // of output (by format): the time since the group's previous listing, which is the time to
  // compute and write this one.
  OutputSink outputs;
  const SinkScope outputScope(outputs);
  auto addSeconds = [&](const std::string& kind, double seconds) {
    tlSink->seconds[kind] += seconds;
    tlSink->last = Clock::now();
  };
  auto listFile = [&](const std::string& path, const std::string& content, const std::string& unit, const std::string& format,
                      double day, float minValue, float maxValue) {
    addSeconds(format.substr(0, format.find(',')), since(tlSink->last));
    ManifestFile f;
    f.path = fs::relative(path, options.outDir).string();
    f.content = content;
    f.unit = unit;
    f.format = format;
    f.day = day;
    f.minValue = minValue;
    f.maxValue = maxValue;
    tlSink->files.push_back(f);
    tlSink->paths.push_back(path);
  };
  auto mergeInto = [](OutputSink& into, const OutputSink& from) {
    into.files.insert(into.files.end(), from.files.begin(), from.files.end());
    into.paths.insert(into.paths.end(), from.paths.begin(), from.paths.end());
    for (const auto& [kind, seconds] : from.seconds) into.seconds[kind] += seconds;
    into.last = Clock::now();
  };
  // A written float image (EXR or TIFF, as the scene asks).
  const std::string exrCompression = exrCompressionName(scene.outputs.compressionLevel);
  const std::string floatImageFormat = scene.outputs.format == "exr" ? "OpenEXR, 1 channel float32 (" + exrCompression + "), linear"
                                                                      : "TIFF, 1 channel float32 (zip), linear";
  auto listImage = [&](const WrittenImage& img, const std::string& content, const std::string& unit, double day) {
    listFile(img.path, content, unit, floatImageFormat, day, img.minValue, img.maxValue);
  };
  const std::string rgbPngFormat = "PNG, 3 channels uint8, sRGB";
  std::string occluderNotes;  // snow on the occluders, logged once the output writers are done
  // `skiDepth`: the ski-track texture to write for that day (a frame written beside the season
  // gets a copy: the season goes on stamping the live one); null when there is none.
  auto writeLayers = [&](const SnowState& s, double day, const Grid<float>* skiDepth) {
    OutputSink& parent = *tlSink;
    const bool frame = day >= 0.0;
    if (frame) fs::create_directories(fs::path(options.outDir) / "frames");
    // Where an output of this day goes, less its extension: DIR/STEM at the season's end,
    // DIR/frames/STEM.DDDD on a frame day (zero-padded, so DCC tools read the frames as a sequence).
    std::string dayTag;
    if (frame) {
      std::ostringstream o;
      o << "." << std::setw(4) << std::setfill('0') << static_cast<long>(std::lround(day));
      dayTag = o.str();
    }
    auto outputBase = [&](const std::string& stem) { return (fs::path(options.outDir) / (frame ? "frames" : "") / (stem + dayTag)).string(); };
    auto writeVdb = [&] {
      if (scene.outputs.vdb) {
        VdbOptions vo;
        vo.voxelSizeM = scene.outputs.vdbVoxelSizeM > 0.0 ? scene.outputs.vdbVoxelSizeM : std::min(s.spec.cellSizeXM, s.spec.cellSizeYM);
        const std::string path = outputBase("snow") + ".vdb";
        const VdbSummary v = writeSnowVdb(path, s, vo);
        listFile(path, "snow body: snow_sdf (level set), density (fog, 1 in snow), compacted/stable/unstable/powder (fog, kg/m^3: " +
                    fixed(vo.compactedKgPerM3, 0) + "/" + fixed(vo.stableKgPerM3, 0) + "/" + fixed(vo.unstableKgPerM3, 0) + "/" +
                    fixed(vo.powderKgPerM3, 0) + "); " + std::to_string(v.snowVoxels) + " snow voxels; x east, y north from the south-west corner, z altitude",
                 "m (voxel size " + fixed(vo.voxelSizeM, 3) + ")", "OpenVDB", day, 0.f, 0.f);
      }
    };
    auto writeMeshes = [&] {
      if (scene.meshSnow.onOccluders && !frame) {
        // Snow on the [[occluders]] (Fearing, as mode = "mesh"), as deep on open flat ground as
        // the terrain's snow around each mesh: the mean depth of the valid cells in a ring two
        // cells wide round its footprint. Sites below the terrain's snow surface are buried in
        // it (their snow is the terrain's) and left bare.
        for (size_t k = 0; k < occluders.size(); ++k) {
          const TriangleMesh& mesh = occluders[k];
          float lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
          for (const auto& p : mesh.positions)
            for (int a = 0; a < 2; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
          const double dx = s.spec.cellSizeXM, dy = s.spec.cellSizeYM, H = s.spec.height;
          double sum = 0;
          long ring = 0;
          // Only the rows and columns near the footprint (a cell's centre is at ((col + 1/2) dx,
          // (H - row - 1/2) dy)).
          const int col0 = std::max(0, static_cast<int>(std::floor(lo[0] / dx)) - 3), col1 = std::min(s.spec.width - 1, static_cast<int>(hi[0] / dx) + 3);
          const int row0 = std::max(0, static_cast<int>(std::floor(H - hi[1] / dy)) - 3), row1 = std::min(s.spec.height - 1, static_cast<int>(H - lo[1] / dy) + 3);
          for (int row = row0; row <= row1; ++row)
            for (int col = col0; col <= col1; ++col) {
              const double x = (col + 0.5) * dx, y = (H - row - 0.5) * dy;
              const bool near = x > lo[0] - 2 * dx && x < hi[0] + 2 * dx && y > lo[1] - 2 * dy && y < hi[1] + 2 * dy;
              const bool under = x >= lo[0] && x <= hi[0] && y >= lo[1] && y <= hi[1];
              if (near && !under && s.validCell(col, row)) sum += s.depthM(col, row), ++ring;
            }
          FallenSnowSettings ps = scene.meshSnow.placement;
          ps.seed = scene.seed + k;
          ps.depthM = ring > 0 ? sum / ring : 0.0;
          const std::string name = "occluder_" + std::to_string(k) + "_snow";
          if (!(ps.depthM > 0.0)) {
            occluderNotes += "  " + name + ": no snow on the terrain round " + mesh.source + ": no snow body written\n";
            continue;
          }
          auto tm = Clock::now();
          FallenSnow snow = placeFallenSnow(mesh, ps);
          double buriedM3 = 0;
          for (SnowSite& site : snow.sites) {
            const int col = std::clamp(static_cast<int>(site.position[0] / dx), 0, s.spec.width - 1);
            const int row = std::clamp(static_cast<int>(H - 1 - site.position[1] / dy), 0, s.spec.height - 1);
            if (site.position[2] < s.bedrockM(col, row) + s.depthM(col, row)) buriedM3 += site.depthM * site.footprintM2, site.depthM = 0.f;
          }
          FallenSnowStability ss = scene.meshSnow.stability;
          ss.seed = scene.seed + k;
          const FallenSnowStabilityReport st = stabilizeFallenSnow(mesh, snow, ss);
          const MeshSnowBody body = buildMeshSnowBody(snow, mesh, scene.meshSnow.body);
          addSeconds("snow on the occluders", since(tm));
          // (Logged after the writers join: this runs beside the layers' thread.)
          occluderNotes += "  " + name + ": " + mesh.source + ", " + fixed(ps.depthM, 3) + " m as on the terrain round it (" +
                           std::to_string(ring) + " cells), " + std::to_string(snow.sites.size()) + " sites, " + fixed(snow.placedM3, 3) +
                           " m^3 placed (" + fixed(buriedM3, 3) + " in the terrain's snow), " + fixed(st.finalM3, 3) + " m^3 kept, " +
                           std::to_string(body.mesh.triangles.size()) + " triangles\n";
          for (const std::string& format : scene.outputs.meshes) {
            const std::string path = outputBase(name) + "." + format;
            writeMesh(path, format, body.mesh);
            listFile(path, "snow body on the occluder " + mesh.source + " (Fearing: placement and stability, " + fixed(ps.depthM, 3) +
                               " m as on the terrain round it; the terrain's frame)",
                     "m", meshFormatDescription(format), day, 0.f, 0.f);
          }
        }
      }
      if (!scene.outputs.meshes.empty()) {
        // One adaptive triangulation for every part asked (rtin.h), within the vertical error bound
        // of the surface (and of the bedrock, the body's bottom).
        const auto& parts = scene.outputs.meshParts;
        const bool body = std::find(parts.begin(), parts.end(), "body") != parts.end();
        const Grid<float> surface = layerGrid(s, "surface");
        std::vector<const Grid<float>*> fields{&surface};
        if (body) fields.push_back(&s.bedrockM);
        const auto tTri = Clock::now();
        const RtinMesh triangulation = buildRtin(fields, s.validCell, scene.outputs.meshMaxErrorM);
        addSeconds("mesh triangulation (adaptive)", since(tTri));
        const std::string frameNote = " (adaptive triangulation, vertical error at most " + fixed(scene.outputs.meshMaxErrorM, 3) +
                                      " m at every grid point; x east, y north from the south-west corner; UVs line up with the maps)";
        auto writeAll = [&](const std::string& stem, const MeshData& mesh, const std::string& what) {
          for (const std::string& format : scene.outputs.meshes) {
            const std::string path = outputBase(stem) + "." + format;
            writeMesh(path, format, mesh);
            listFile(path, what + ", " + std::to_string(mesh.positions.size()) + " vertices, " + std::to_string(mesh.triangles.size()) +
                               " triangles" + frameNote,
                     "m", meshFormatDescription(format), day, 0.f, 0.f);
          }
        };
        // Each part (the surface, the body) on its own task into its own sink, merged in the
        // parts' order.
        auto writePart = [&](const std::string& part) {
          if (part == "surface") {
            auto tm = Clock::now();
            const MeshData mesh = surfaceMesh(triangulation, surface, s.spec);
            addSeconds("mesh building", since(tm));
            const int tileCells = scene.outputs.meshTileSizeM > 0.0
                                      ? std::max(1, static_cast<int>(std::lround(scene.outputs.meshTileSizeM / s.spec.cellSizeXM)))
                                      : 0;
            if (tileCells == 0 || tileCells >= std::max(s.spec.width, s.spec.height)) {
              writeAll("snow_surface", mesh, "snow surface B+C+S+U+P");
            } else {
              for (const MeshTile& t : splitIntoTiles(mesh, s.spec, tileCells))
                writeAll("snow_surface_x" + std::to_string(t.column) + "_y" + std::to_string(t.row), t.mesh,
                         "snow surface B+C+S+U+P, tile column " + std::to_string(t.column) + " (from the west), row " +
                             std::to_string(t.row) + " (from the north) of " + std::to_string(tileCells) + " x " +
                             std::to_string(tileCells) + " cells");
            }
          } else {
            auto tm = Clock::now();
            const MeshData mesh = snowBodyMesh(triangulation, s.bedrockM, layerGrid(s, "depth"), s.validCell, s.spec);
            addSeconds("mesh building", since(tm));
            if (mesh.triangles.empty()) {
              log << "  snow_body" << dayTag << ": no snow, no mesh written\n";
              return;
            }
            writeAll("snow_body", mesh, "the snow body alone, closed (top on the snow surface, bottom on the bedrock, walls at the grid's edge)");
          }
        };
        std::vector<OutputSink> partSinks(parts.size());
        tbb::task_group partGroup;
        for (size_t k = 0; k < parts.size(); ++k)
          partGroup.run([&, k] {
            SinkScope scope(partSinks[k]);
            writePart(parts[k]);
          });
        partGroup.wait();
        for (const OutputSink& partSink : partSinks) mergeInto(*tlSink, partSink);
        if (snowMesh && !frame)
          for (const std::string& format : scene.outputs.meshes) {
            const std::string meshPath = (fs::path(options.outDir) / ("snow_mesh." + format)).string();
            writeMesh(meshPath, format, MeshData{snowMesh->positions, {}, {}, snowMesh->triangles});
            listFile(meshPath,
                     "the input mesh " + snowMesh->source + " with its vertices raised by their snow depth (occlusion mode, per vertex; " +
                         std::to_string(snowMesh->positions.size()) + " vertices, " + std::to_string(snowMesh->triangles.size()) +
                         " triangles), in the input's own coordinates",
                     "m", meshFormatDescription(format), day, 0.f, 0.f);
          }
      }
    };
    // The VDB and the meshes (the larger writers) run beside the layers as tasks of their own;
    // each group lists its files into its own sink, merged below in a fixed order.
    OutputSink layerSink, vdbSink, meshSink;
    tbb::task_group group;
    group.run([&] {
      SinkScope scope(vdbSink);
      writeVdb();
    });
    group.run([&] {
      SinkScope scope(meshSink);
      writeMeshes();
    });
    std::exception_ptr layerError;
    try {
      SinkScope scope(layerSink);
      std::vector<std::string> channelNames;
      std::vector<Grid<float>> channels;
      for (const auto& layer : layers) {
        if (frame && layer == "valid_mask") continue;
        const std::string base = outputBase(layer);
        const double outputDay = frame ? day : scene.days;
        if (layer == "preview") {
          // The sun at solar noon of the output's day at the site, or low in the south in a polar night.
          SunPosition sun = sunPosition(latitude, scene.startDayOfYear() + outputDay, 12.0);
          double direction[3] = {sun.direction[0], sun.direction[1], sun.direction[2]};
          if (sun.elevationDeg < 5.0) direction[0] = 0.0, direction[1] = latitude >= 0 ? -0.966 : 0.966, direction[2] = 0.259;
          const std::vector<uint8_t> rgb = snowPreviewRgb(s, direction);
          const std::string path = base + ".png";
          writeRgbPng(path, s.spec.width, s.spec.height, rgb, scene.outputs.compressionLevel);
          listFile(path,
                   "preview: shaded relief of the snow-covered terrain, sun at solar noon of the day; snow by top layer (powder white, "
                   "unstable pale blue, stable cream, compacted grey)",
                   "sRGB", rgbPngFormat, day, 0.f, 255.f);
          // Every preview, subsampled to at most 512 pixels across, for the season's contact sheet.
          const int stride = std::max(1, (std::max(s.spec.width, s.spec.height) + 511) / 512);
          const int tw = (s.spec.width + stride - 1) / stride, th = (s.spec.height + stride - 1) / stride;
          std::vector<uint8_t> thumb(static_cast<size_t>(tw) * th * 3);
          for (int y = 0; y < th; ++y)
            for (int x = 0; x < tw; ++x)
              std::copy_n(&rgb[(static_cast<size_t>(y * stride) * s.spec.width + x * stride) * 3], 3, &thumb[(static_cast<size_t>(y) * tw + x) * 3]);
          previews.push_back(std::move(thumb));
          previewWidth = tw, previewHeight = th;
          continue;
        }
        if (layer == "avalanche_preview") {
          const Grid<float> surface = layerGrid(s, "surface");
          const std::string path = base + ".png";
          writeRgbPng(path, s.spec.width, s.spec.height,
                      avalanchePreviewRgb(surface, s.validCell, s.avalancheScourM, s.avalancheDepositM, s.spec.cellSizeXM, s.spec.cellSizeYM),
                      scene.outputs.compressionLevel);
          listFile(path, "preview: shaded snow surface, avalanche scour red (full at 1 m), deposit blue (full at 2 m)", "sRGB", rgbPngFormat,
                   day, 0.f, 255.f);
          continue;
        }
        Grid<float> grid;
        std::string content = layerContent(layer);
        if (layer == "ski_tracks") {
          // The finer texture: its own size, listed with each file.
          content += " (" + std::to_string(skiTracks->factor()) + " x " + std::to_string(skiTracks->factor()) + " texels per cell)";
          grid = *skiDepth;
        } else if (layer == "ski_route_map") {
          grid = routeMapGrid.empty() ? Grid<float>(s.spec.width, s.spec.height, 0.f) : routeMapGrid;
        } else if (occlusionLayers.count(layer)) {
          grid = occlusionLayers.at(layer);
        } else if (isWindLayer(layer)) {
          grid = windLayerGrid(s, wind, outputDay, layer, scene.params.windShadowToleranceM);
        } else if (layer == "sun_exposure" || layer == "temperature") {
          // I of the output's day, and T = T0 + k_t A + k_i I.
          const Grid<float> sun = exposure ? exposure->totalAt(outputDay) : Grid<float>(s.spec.width, s.spec.height, 0.f);
          const double t0c = scene.weather.at(outputDay).seaLevelTemperatureC;
          grid = Grid<float>(s.spec.width, s.spec.height, 0.f);
          for (size_t i = 0; i < grid.size(); ++i) {
            if (!s.validCell.values()[i]) continue;
            const float base = temperatureBaseC(scene.params, s.bedrockM.values()[i], sun.values()[i]);
            grid.values()[i] = layer == "sun_exposure" ? sun.values()[i] : static_cast<float>(t0c + base);
          }
        } else {
          grid = layerGrid(s, layer);
        }
        const bool ownSize = grid.width() != s.spec.width || grid.height() != s.spec.height;
        auto sized = [&] {
          if (ownSize) tlSink->files.back().width = grid.width(), tlSink->files.back().height = grid.height();
        };
        listImage(writeFloatImage(base, scene.outputs.format, grid, layer, scene.outputs.compressionLevel), content, layerUnit(layer), day);
        sized();
        for (const std::string& encoding : scene.outputs.encodings) {
          const WrittenImage img = writeNormalised(base, encoding, grid, scene.outputs.compressionLevel);
          listFile(img.path, content, layerUnit(layer), normalisedFormat(encoding, grid.width(), grid.height()), day, img.minValue,
                   img.maxValue);
          sized();
        }
        if (scene.outputs.multichannelExr && !ownSize) {
          channelNames.push_back(layer);
          channels.push_back(std::move(grid));
        }
      }
      if (scene.outputs.displacementWidth > 0) {
        // Displacement maps at the requested resolution: snow depth (for a displacement modifier on
        // the terrain) and the snow surface's height, bilinear from the grid.
        for (const std::string what : {"depth", "surface"}) {
          const Grid<float> g = resampleBilinear(layerGrid(s, what), scene.outputs.displacementWidth, scene.outputs.displacementHeight);
          listImage(writeFloatImage(outputBase(std::string("displacement_") + what), scene.outputs.format, g, what, scene.outputs.compressionLevel),
                    layerContent(what) + ", resampled (bilinear) to " + std::to_string(g.width()) + " x " + std::to_string(g.height()) +
                        " over the same extent",
                    "m", day);
        }
      }
      if (!channels.empty()) {
        const std::string path = outputBase("layers") + ".exr";
        std::vector<const Grid<float>*> grids;
        for (const auto& g : channels) grids.push_back(&g);
        writeMultiChannelExr(path, channelNames, grids, scene.outputs.compressionLevel);
        std::string names;
        for (const auto& n : channelNames) names += (names.empty() ? "" : ", ") + n;
        listFile(path, "all layers as named channels: " + names, "per channel, as the single-layer files",
                 "OpenEXR, " + std::to_string(channels.size()) + " channels float32 (" + exrCompression + "), linear", day, 0.f, 0.f);
      }
    } catch (...) {
      layerError = std::current_exception();
    }
    group.wait();  // rethrows the VDB and mesh writers' error
    if (layerError) std::rethrow_exception(layerError);
    mergeInto(parent, layerSink);
    mergeInto(parent, vdbSink);
    mergeInto(parent, meshSink);
  };

  SeasonReport report;
  ManifestOcclusion manifestOcclusion;
  if (occlusionMode) {
    // Foldes & Benes 2007 (precompute/occlusion.h): ambient occlusion and the day's sun trajectory.
    const OcclusionParameters& op = scene.occlusion;
    OcclusionSettings os;
    os.sMaxM = op.sMaxM;
    os.tauAmbient = op.tauAmbient;
    os.tauSun = op.tauSun;
    os.sunPositions = op.sunPositions;
    os.aoRays = op.aoRays > 0 ? op.aoRays : occlusionRaysForQuality(scene.sunQuality);
    os.aoRadiusM = op.aoRadiusM;
    os.latitudeDeg = latitude;
    os.turbidity = op.turbidity;
    const double sunDay = op.day.value_or(scene.days / 2.0);
    os.dayOfYear = std::fmod(scene.startDayOfYear() - 1 + sunDay, 365.0) + 1.0;
    const auto tOcc = Clock::now();
    const RayScene rays(state.bedrockM, state.spec, occluders);
    const double buildSeconds = since(tOcc);
    const OcclusionSnow o = computeOcclusionSnowOnTerrain(rays, state.bedrockM, state.validCell, state.spec, os);
    auto asGrid = [&](const std::vector<float>& v) {
      Grid<float> g(state.spec.width, state.spec.height, 0.f);
      std::copy(v.begin(), v.end(), g.data());
      return g;
    };
    occlusionLayers["ambient_occlusion"] = asGrid(o.ambient);
    occlusionLayers["sun_visibility"] = asGrid(o.sunVisibility);
    occlusionLayers["occlusion_accumulation"] = asGrid(o.accumulationM);
    occlusionLayers["occlusion_dissipation"] = asGrid(o.dissipationM);
    // The static cover is settled snow: the stable layer; the scene's snowfall multiplier (a
    // sky mask) scales it and its no-snow mask clears it.
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
    manifestOcclusion = {os.sMaxM, os.tauAmbient, os.tauSun, os.aoRadiusM, sunDay, os.dayOfYear, os.turbidity, os.aoRays, {}, ""};
    for (const SunSample& x : o.sun) manifestOcclusion.sunHoursAndWeights.push_back({x.solarHour, x.weight});
    if (ti.format == "mesh" && !scene.outputs.meshes.empty()) {
      // Snow per vertex of the input mesh itself (the paper's irregular mesh), raised along z.
      const auto tm = Clock::now();
      TriangleMesh mesh = loadTriangleMesh(scene.terrain.file, scene.terrain.upAxis);
      std::vector<TriangleMesh> meshes = occluders;
      meshes.insert(meshes.begin(), mesh);
      const Grid<float> none;
      const RayScene meshRays(none, GridSpec{}, meshes);
      const OcclusionSnow mo = computeOcclusionSnowOnMesh(meshRays, mesh, os);
      // The scene's art direction, as on the grid: the snowfall multiplier scales a vertex's snow
      // and the no-snow mask clears it, read at the grid cell under the vertex (the grid covers
      // the mesh: x east from its origin, rows south from it).
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
          << " triangles: " << fixed(since(tm), 2) << " s (mean snow " << fixed(volume / std::max<size_t>(1, mesh.positions.size()), 3)
          << " m per vertex)\n";
      manifestOcclusion.meshSource = mesh.source;
      snowMesh = std::move(mesh);
    }
    for (size_t i = 0; i < state.stableM.size(); ++i) report.final.stableM3 += state.stableM.values()[i] * state.spec.cellAreaM2();
    report.seconds = since(tOcc);
    log << "occlusion: " << std::scientific << std::setprecision(4) << report.final.totalM3() << std::defaultfloat << " m^3 of snow ("
        << fixed(report.seconds, 2) << " s)\n";
  } else {
    SeasonConfig config;
    config.days = scene.days;
    config.seed = scene.seed;
    config.params = scene.params;
    config.weather = scene.weather;
    config.userSnowfalls = scene.userSnowfalls;
    config.avalancheMaps = scene.outputs.avalancheMaps;
    config.avalancheFrameIntervalS = scene.outputs.avalancheFrameIntervalS;
    // A user event's point (metres from the north-west corner, or the DEM's own projected
    // coordinates) as a valid cell.
    auto eventCell = [&](const Scene::AvalancheEvent& a, const std::string& what, const std::string& point) {
      const std::string where = scene.sourceName + ":" + std::to_string(a.line) + ": events: " + what + " on day " + fixed(a.day, 1);
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
                         " m south of the north-west corner) is outside the terrain (" + fixed(ti.spec.width * ti.spec.cellSizeXM, 1) +
                         " x " + fixed(ti.spec.height * ti.spec.cellSizeYM, 1) + " m)");
      const int x = static_cast<int>(fx), y = static_cast<int>(fy);
      if (!state.validCell(x, y)) throw InputError(where + ": the " + point + " falls on a NODATA cell");
      return std::array<int, 2>{x, y};
    };
    config.edits = art.edits;
    config.userAvalanches = art.avalanches;  // masked releases
    config.userSkiers = art.skiers;          // skiers from start masks
    for (const Scene::AvalancheEvent& a : scene.userAvalanches) {
      if (a.mask) continue;
      const auto c = eventCell(a, "avalanche", "rupture point");
      config.userAvalanches.push_back({a.day, c[0], c[1], false, nullptr});
    }
    for (const Scene::AvalancheEvent& a : scene.userSkiers) {
      if (a.mask) continue;
      const auto c = eventCell(a, "skier", "start point");
      config.userSkiers.push_back({a.day, c[0], c[1], a.count, nullptr});
    }
    if (std::find(layers.begin(), layers.end(), "ski_route_map") != layers.end())
      routeMapGrid = routeMap(state.bedrockM, state.validCell, state.spec);
    if (std::find(layers.begin(), layers.end(), "ski_tracks") != layers.end()) {
      skiTracks.emplace(state.spec, scene.outputs.skiTrackFactor);
      config.skiTracks = &*skiTracks;
    }
    config.frameDays = scene.outputs.frameDays;
    config.windTransport = wind.hasWind();
    if (scene.bedforms.enabled) {
      config.bedforms = scene.bedforms.params;
      if (!config.windTransport) log << "bedforms: the scene has no wind; only the cohesion of the snow will change\n";
    }
    if (exposure || windChanges)
      config.updateStaticFields = [&](int day, SnowState& s) {
        if (exposure) temperatureForDay(day, s);
        if (windChanges) windForDay(day, s);
      };
    ProgressBar bar(log, "season", stderrIsTerminal() && &log == &std::cerr, options.progress);
    // A frame day's outputs are written on a thread of their own from a copy of the state while
    // the season goes on (one frame in flight; the next frame, or the season's end, waits for
    // it), in a task arena of their own so that the season's parallel loops never run a writer's
    // task. Each frame lists its files into its own sink, merged in frame order: the same files
    // and manifest as writing them in place.
    tbb::task_arena writerArena(std::max(1, threads));  // outlives the writer (declared first)
    struct FrameWriter {
      std::thread thread;
      SnowState state;
      Grid<float> skiDepth;
      OutputSink sink;
      std::exception_ptr error;
      ~FrameWriter() {
        if (thread.joinable()) thread.join();  // the season threw: let the writer finish first
      }
    } frameWriter;
    auto joinFrame = [&] {
      if (!frameWriter.thread.joinable()) return;
      frameWriter.thread.join();
      if (frameWriter.error) std::rethrow_exception(frameWriter.error);
      mergeInto(*tlSink, frameWriter.sink);
      frameWriter.sink = OutputSink();
    };
    auto writeFrame = [&](double day, const SnowState& s) {
      if (!options.framesBesideSeason) return writeLayers(s, day, skiTracks ? &skiTracks->depth() : nullptr);
      joinFrame();
      frameWriter.state = s;
      if (skiTracks) frameWriter.skiDepth = skiTracks->depth();
      frameWriter.thread = std::thread([&, day] {
        try {
          SinkScope scope(frameWriter.sink);
          writerArena.execute([&] { writeLayers(frameWriter.state, day, skiTracks ? &frameWriter.skiDepth : nullptr); });
        } catch (...) {
          frameWriter.error = std::current_exception();
        }
      });
    };
    SeasonReport seasonReport = runSeason(*backend, state, config, [&](double f) { bar.update(f); }, writeFrame);
    joinFrame();
    bar.finish();
    report = std::move(seasonReport);
    log << "season: " << fixed(scene.days, 0) << " days, " << report.events << " events on " << backend->name() << " ("
        << fixed(report.seconds, 2) << " s)\n";
    for (const auto& p : report.phenomena)
      log << "  " << std::left << std::setw(24) << p.name << std::right << std::setw(6) << p.steps << " steps"
          << (p.skippedSteps ? " (" + std::to_string(p.skippedSteps) + " skipped)" : std::string()) << "  " << fixed(p.seconds, 3)
          << " s\n";
    for (const AvalancheRecord& a : report.avalanches) {
      log << "  avalanche day " << fixed(a.day, 2) << " at cell (" << a.ruptureX << ", " << a.ruptureY << ")" << (a.user ? " (user)" : "");
      if (!a.released) {
        log << ": not released, " << a.why << "\n";
        continue;
      }
      log << ": " << a.releaseCells << " cells released (" << fixed(a.releasedM3, 0) << " m^3), runout " << fixed(a.runoutM, 0)
          << " m, fall " << fixed(a.fallHeightM, 0) << " m, " << a.steps << " steps of " << fixed(scene.params.avalancheStepS, 2)
          << " s, " << fixed(a.secondsPerStep() * 1e3, 3) << " ms a step; " << a.why << "\n";
    }
    for (const EditRecord& e : report.edits)
      log << "  " << e.label << ": " << std::scientific << std::setprecision(4) << e.volumeM3 << std::defaultfloat << " m^3\n";
    if (report.noSnowRemovedM3 > 0.0)
      log << "  no-snow mask: " << std::scientific << std::setprecision(4) << report.noSnowRemovedM3 << std::defaultfloat
          << " m^3 of initial snow removed\n";
    if (report.avalancheTries > 0) log << "  spontaneous avalanche tries: " << report.avalancheTries << "\n";
    if (config.bedforms)
      log << "  wind bedforms: " << report.bedforms.domainCells << " cells, " << report.bedforms.rounds << " rounds, "
          << report.bedforms.slabsEroded << " slabs lifted, " << report.bedforms.slabsAvalanched << " slab moves by avalanching, "
          << report.bedforms.calmSteps << " calm hours; " << (report.bedforms.atRest ? "at rest (within the repose angle)" : "NOT at rest after the relaxation cap") << "\n";
    if (!report.skiers.empty()) {
      int users = 0, triggered = 0, skied = 0;
      double length = 0.0;
      for (const SkierRecord& k : report.skiers) {
        users += k.user, triggered += k.triggered, skied += k.cells > 0;
        length += k.lengthM;
      }
      log << "  skiers: " << report.skiers.size() << " (" << users << " from the scene), " << skied << " skied, "
          << fixed(length / 1000.0, 1) << " km in all, " << triggered << " set off an avalanche\n";
      for (const SkierRecord& k : report.skiers)
        if (k.user)
          log << "  skier day " << fixed(k.day, 2) << " from cell (" << k.startX << ", " << k.startY << "): " << k.cells << " cells, "
              << fixed(k.lengthM, 0) << " m, drop " << fixed(k.dropM, 0) << " m; " << k.why << "\n";
    }
    log << "  snow: " << std::scientific << std::setprecision(4) << report.final.totalM3() << " m^3 (added "
        << report.snowfallAddedM3 << ", melted " << report.meltRemovedM3 << "), mass balance error " << report.massBalanceRelativeError()
        << std::defaultfloat << "\n";
  }

  // 5. Outputs
  t0 = Clock::now();
  writeLayers(state, -1.0, skiTracks ? &skiTracks->depth() : nullptr);
  if (previews.size() > 1) {
    int sw = 0, sh = 0;
    const int columns = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(previews.size()))));
    const std::vector<uint8_t> sheet = contactSheetRgb(previews, previewWidth, previewHeight, columns, sw, sh);
    const std::string path = (fs::path(options.outDir) / "contact_sheet.png").string();
    writeRgbPng(path, sw, sh, sheet, scene.outputs.compressionLevel);
    listFile(path,
             "contact sheet of the season: the previews of the frame days in order, then the season's end, " + std::to_string(columns) +
                 " to a row",
             "sRGB", rgbPngFormat, -1.0, 0.f, 255.f);
  }
  // Each avalanche's own maps and frames (outputs.avalanche_maps, outputs.avalanche_frame_interval_s),
  // full-size so they line up with the layers: avalanches/NNN_<map>, avalanches/NNN/depth.FFFF.
  int avalancheNumber = 0;
  for (const AvalancheRecord& a : report.avalanches) {
    if (!a.released) continue;
    ++avalancheNumber;
    if (!a.maps) continue;
    std::ostringstream stem;
    stem << "avalanches/" << std::setw(3) << std::setfill('0') << avalancheNumber;
    auto write = [&](const std::string& rel, Grid<float> full, const GridCrop& c, const std::string& content, const std::string& unit,
                     double day) {
      for (int y = 0; y < c.grid.height(); ++y)
        for (int x = 0; x < c.grid.width(); ++x) full(c.x0 + x, c.y0 + y) = c.grid(x, y);
      fs::create_directories((fs::path(options.outDir) / rel).parent_path());
      listImage(writeFloatImage((fs::path(options.outDir) / rel).string(), scene.outputs.format, full, "value", scene.outputs.compressionLevel), content, unit,
                day);
    };
    const Grid<float> zero(state.spec.width, state.spec.height, 0.f);
    const std::string which = "avalanche " + std::to_string(avalancheNumber) + " (day " + fixed(a.day, 2) + ")";
    write(stem.str() + "_release", zero, a.maps->release, which + ": release zone (1 released, 0 not)", "1", a.day);
    write(stem.str() + "_scour", zero, a.maps->scour, which + ": snow taken away, net (m)", "m", a.day);
    write(stem.str() + "_deposit", zero, a.maps->deposit, which + ": snow left, net (m)", "m", a.day);
    for (size_t k = 0; k < a.maps->frames.size(); ++k) {
      std::ostringstream rel;
      rel << stem.str() << "/depth." << std::setw(4) << std::setfill('0') << k;
      const auto& [seconds, c] = a.maps->frames[k];
      write(rel.str(), a.maps->depthAtRelease, c,
            which + ": snow depth C+S+U+P at " + fixed(seconds, 2) + " s after the release (m)", "m", a.day + seconds / 86400.0);
    }
  }
  manifest.programVersion = programVersion();
  manifest.sceneSource = scene.sourceName;
  manifest.sceneName = scene.name;
  manifest.sceneHash = Fnv1a64().add(scene.canonicalToml).hex();
  manifest.terrainSource = ti.source;
  manifest.terrainHash = scene.terrain.builtin ? Fnv1a64().add(terrain.heightsM.data(), terrain.heightsM.size() * sizeof(float)).hex()
                                               : hashFileFnv1a64(scene.terrain.file);
  manifest.coordinateSystem = ti.coordinateSystem;
  manifest.seed = scene.seed;
  manifest.backend = backendName;
  manifest.mode = scene.mode;
  for (const ParameterInfo& info : parameterTable()) manifest.parameters.push_back({info.key, scene.params.*(info.member)});
  manifest.occlusion = manifestOcclusion;
  manifest.grid = ti.spec;
  manifest.latitudeDeg = latitude;
  manifest.seasonDays = scene.days;
  {
    std::ostringstream d;
    d << std::setfill('0') << std::setw(4) << scene.startYear << "-" << std::setw(2) << scene.startMonth << "-" << std::setw(2)
      << scene.startDay;
    manifest.seasonStartDate = d.str();
  }
  for (const AvalancheRecord& a : report.avalanches)
    manifest.avalanches.push_back({a.day, a.ruptureX, a.ruptureY, a.user, a.released, a.why, a.releaseCells, a.footprintCells,
                                   a.steps, a.releasedM3, a.depositM3, a.runoutM, a.fallHeightM, a.simulatedS});
  for (const SkierRecord& k : report.skiers)
    manifest.skiers.push_back({k.day, k.startX, k.startY, k.user, k.cells, k.lengthM, k.dropM, k.triggered, k.why});
  manifest.artRasters = art.rasters;
  manifest.edits = art.editRecords;
  for (ManifestEdit& e : manifest.edits)
    for (const EditRecord& r : report.edits)
      if (r.label == e.label) e.volumeM3 = r.volumeM3;
  manifest.editsNetM3 = report.editsNetM3;
  manifest.noSnowRemovedM3 = report.noSnowRemovedM3;
  manifest.events = report.events;
  manifest.snowfallAddedM3 = report.snowfallAddedM3;
  manifest.meltRemovedM3 = report.meltRemovedM3;
  manifest.initialSnowM3 = report.initial.totalM3();
  manifest.finalSnowM3 = report.final.totalM3();
  for (const auto& p : report.phenomena) manifest.phenomena.push_back({p.name, p.starts, p.steps, p.stops, p.skippedSteps});
  manifest.files = outputs.files;
  result.files = outputs.paths;
  const std::string manifestPath = (fs::path(options.outDir) / "manifest.json").string();
  writeTextAtomically(manifestPath, manifestToJson(manifest));
  result.files.push_back(manifestPath);
  log << occluderNotes;
  log << "outputs: " << result.files.size() << " files in " << options.outDir << " (" << fixed(since(t0), 2) << " s)\n";
  for (const auto& [kind, seconds] : outputs.seconds) log << "  " << std::left << std::setw(36) << kind << std::right << fixed(seconds, 2) << " s\n";
  log << "total: " << fixed(since(tStart), 2) << " s\n";
  result.season = report;
  result.backendName = backendName;
  return result;
}

std::string describeTerrain(const std::string& source, bool json, const std::vector<std::string>& sets) {
  // A scene (file or preset) describes the terrain with its reading options; anything else is a
  // terrain file read with the defaults.
  std::string ext = fs::path(source).extension().string();
  Terrain t;
  if (source == "builtin:ridged") {
    t = makeBuiltinTerrain(DefaultTerrainOptions{});
  } else if (source.rfind("preset:", 0) == 0 || ext == ".toml") {
    t = loadTerrain(loadScene(source, sets).terrain);
  } else {
    if (!sets.empty()) throw InputError("--set applies to scene files; " + source + " is a terrain file");
    TerrainSource src;
    src.file = source;
    std::error_code ec;
    if (!fs::exists(source, ec)) throw InputError(source + ": terrain file does not exist");
    const std::string format = detectTerrainFormat(src);
    if (format != "dem")
      throw InputError(source + ": a " + format + " file needs its cell size (and height mapping) from a scene: run "
                       "`snowbake info SCENE.toml` with a scene whose [terrain] names it");
    t = loadTerrain(src);
  }
  const TerrainInfo& i = t.info;
  if (json) {
    nlohmann::ordered_json j;
    j["source"] = i.source;
    j["format"] = i.format;
    j["driver"] = i.driver;
    j["width"] = i.spec.width;
    j["height"] = i.spec.height;
    j["cell_size_x_m"] = i.spec.cellSizeXM;
    j["cell_size_y_m"] = i.spec.cellSizeYM;
    j["native_cell_size_x"] = i.nativeCellSizeX;
    j["native_cell_size_y"] = i.nativeCellSizeY;
    j["native_unit"] = i.nativeUnit;
    j["min_elevation_m"] = i.minElevationM;
    j["max_elevation_m"] = i.maxElevationM;
    j["native_width"] = i.nativeWidth;
    j["native_height"] = i.nativeHeight;
    j["nodata_cells"] = i.nodataCells;
    j["filled_cells"] = i.filledCells;
    j["height_mapping"] = i.heightMapping;
    j["resampling"] = i.resampling;
    j["coordinate_system"] = i.coordinateSystem;
    j["coordinate_decision"] = i.coordinateDecision;
    if (i.latitudeKnown) j["centre_latitude_deg"] = i.centreLatitudeDeg; else j["centre_latitude_deg"] = nullptr;
    return j.dump(2) + "\n";
  }
  std::ostringstream o;
  o << i.source << "\n"
    << "  format:            " << i.format << " (" << i.driver << ")\n"
    << "  grid:              " << i.spec.width << " x " << i.spec.height << " cells\n"
    << "  cell size:         " << fixed(i.spec.cellSizeXM, 3) << " m (x) x " << fixed(i.spec.cellSizeYM, 3) << " m (y)"
    << "  [native " << i.nativeCellSizeX << " x " << i.nativeCellSizeY << " " << i.nativeUnit << "]\n"
    << "  elevation:         " << fixed(i.minElevationM, 1) << " to " << fixed(i.maxElevationM, 1) << " m\n"
    << "  NODATA cells:      " << i.nodataCells << (i.filledCells ? " (" + std::to_string(i.filledCells) + " filled)" : std::string())
    << "\n"
    << "  coordinate system: " << i.coordinateSystem << "\n"
    << "  decided by:        " << i.coordinateDecision << "\n";
  if (i.latitudeKnown) o << "  centre latitude:   " << fixed(i.centreLatitudeDeg, 4) << " deg\n";
  if (!i.heightMapping.empty()) o << "  heights:           " << i.heightMapping << "\n";
  if (!i.resampling.empty()) o << "  resampled:         " << i.resampling << "\n";
  return o.str();
}

}  // namespace snow
