// The grid modes: mode = "season" (the paper's season) and mode = "occlusion" (Foldes & Benes'
// static cover in place of the season). Stages: terrain -> inputs and art direction ->
// precompute -> season (or occlusion) -> outputs -> manifest.
#include <tbb/global_control.h>

#include <algorithm>
#include <filesystem>
#include <iomanip>
#include <optional>

#include "across_ranks.h"
#include "bake_stage.h"
#include "bakers/bake_manifest.h"
#include "core/atomic_file.h"
#include "core/cpu_backend.h"
#include "core/errors.h"
#include "core/format.h"
#include "memory_model.h"
#include "modes.h"
#include "progress.h"
#include "stages.h"

namespace snow {

namespace fs = std::filesystem;

std::vector<std::string> layersToWrite(const Scene& scene, const TerrainInfo& ti) {
  std::vector<std::string> layers = scene.outputs.layers;
  if (ti.nodataCells > 0 && std::find(layers.begin(), layers.end(), "valid_mask") == layers.end()) layers.push_back("valid_mask");
  return layers;
}

GeoFrame geoFrameOf(const TerrainInfo& ti) {
  GeoFrame g;
  g.georeferenced = ti.georeferenced;
  g.crsWkt = ti.crsWkt;
  g.originX = ti.spec.originX, g.originY = ti.spec.originY;
  g.cellX = ti.georeferenced ? ti.geoCellX : ti.spec.cellSizeXM;
  g.cellY = ti.georeferenced ? ti.geoCellY : ti.spec.cellSizeYM;
  g.gridWidth = ti.spec.width, g.gridHeight = ti.spec.height;
  return g;
}

namespace {

// The memory model's prediction for the grid, logged; refused above the budget before any work.
// One process's prediction against the budget; across ranks, this machine's ranks' together
// (`predictOn`: one process's prediction on another grid, a rank's local one).
void refuseAboveTheBudget(const Scene& scene, const GridSpec& spec, const MemoryPrediction& prediction, double budget,
                          const std::function<MemoryPrediction(const Scene&, const GridSpec&)>& predictOn, std::ostream* log) {
  const std::optional<RanksMemory> ranks = ranksMemory(scene, spec, prediction, predictOn);
  if (!ranks) return refuseAboveBudget(scene, prediction, budget);
  refuseRanksAboveBudget(scene, prediction, *ranks, budget);
  constexpr double kMiB = 1024.0 * 1024.0;
  if (log)
    *log << "memory: across " << ranks->ranks << " ranks, rank 0 about " << fixed(ranks->rankZeroBytes / kMiB, 0) << " MiB, each other about "
         << fixed(ranks->otherBytes / kMiB, 0) << " MiB; the " << ranks->ranksHere << " on this machine about "
         << fixed(ranks->hereBytes() / kMiB, 0) << " MiB together\n";
}

GridMemoryPlan checkGridMemory(const Scene& scene, const BakeTerrain& terrain, FrameTiming timing, double budget, std::ostream& log) {
  const GridSpec& spec = terrain.info().spec;
  refuseBeyondTheModel(scene, spec);
  const size_t triangles = triangleCount(terrain.occluders);
  const SnowReach reach = terrainSnowReach(scene, terrain);
  const GridMemoryPlan plan = planGridMemory(scene, spec, triangles, reach, budget, timing);
  refuseAboveTheBudget(scene, spec, plan.prediction, budget,
                       [&](const Scene& onRank, const GridSpec& local) { return planGridMemory(onRank, local, triangles, reach, budget, timing).prediction; },
                       &log);
  log << "memory: " << plan.prediction.summary() << "; budget " << fixed(budget / (1024.0 * 1024.0), 0) << " MiB\n";
  if (plan.askedBytes > 0)
    log << "frames: written " << (plan.timing == FrameTiming::Paused ? "while the season waits" : "after the season, from copies held through it")
        << " (as run.frame_writing asks the bake would need " << fixed(plan.askedBytes / (1024.0 * 1024.0), 0) << " MiB)\n";
  return plan;
}

}  // namespace

void checkBuiltinMemory(const Scene& scene, FrameTiming timing, double budget) {
  const TerrainSource& t = scene.terrain;
  if (!t.builtin || t.cropM || t.resampleCellSizeM || t.resampleSize) return;
  const DefaultTerrainOptions& b = t.builtinOptions;
  GridSpec spec;
  spec.width = spec.height = b.size;
  spec.cellSizeXM = spec.cellSizeYM = b.cellSizeM;
  refuseBeyondTheModel(scene, spec);
  const SnowReach reach = builtinSnowReach(b, scene.params.rainSnowLimitM);
  refuseAboveTheBudget(scene, spec, planGridMemory(scene, spec, 0, reach, budget, timing).prediction, budget,
                       [&](const Scene& onRank, const GridSpec& local) { return planGridMemory(onRank, local, 0, reach, budget, timing).prediction; },
                       nullptr);
}

size_t triangleCount(const std::vector<TriangleMesh>& meshes) {
  size_t n = 0;
  for (const auto& m : meshes) n += m.triangles.size();
  return n;
}

SnowReach terrainSnowReach(const Scene& scene, const BakeTerrain& terrain) {
  return snowReachOf(terrain.terrain.heightsM, terrain.terrain.valid, scene.params.rainSnowLimitM);
}

void reportFilesWritten(const std::vector<std::string>& paths, const char* stage) {
  for (const std::string& path : paths) {
    std::error_code ec;
    const auto bytes = fs::file_size(path, ec);
    progress().event(stage, "file", {{"path", jsonText(path)}, {"bytes", ec ? "null" : std::to_string(bytes)}});
  }
}

std::string resolvedScenePath(const std::string& outDir) { return (fs::path(outDir) / "scene.resolved.toml").string(); }
std::string manifestPath(const std::string& outDir) { return (fs::path(outDir) / "manifest.json").string(); }

std::string writeResolvedScene(const Scene& scene, const std::string& outDir) {
  const std::string path = resolvedScenePath(outDir);
  writeTextAtomically(path, resolvedSceneToml(scene));
  currentSink().files.push_back(
      {.path = "scene.resolved.toml", .content = "the resolved scene: every key, defaults and --set overrides included, paths absolute", .format = "TOML"});
  currentSink().paths.push_back(path);
  return path;
}

void createOutputFolder(const std::string& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw InputError(dir + ": cannot create the output folder: " + ec.message());
}

namespace {

// What the stages after the precompute share, made in runGridBake's order (across ranks, the
// state may be the rank's local grid).
struct GridBake {
  const Scene& scene;
  const BakeOptions& options;
  BakeTerrain& terrain;
  SnowState& state;
  Precomputed& pre;
  const std::vector<std::string>& layers;
  uint8_t needs;
  std::ostream& log;
};

// Where every file comes from: the scene, the precompute, the occlusion or season results (filled
// as those stages run) and the terrain's frame; "file" events as each file is written, a frame's
// during the season and the rest in the outputs stage.
OutputSources outputSourcesOf(const GridBake& b, const OcclusionResult& occlusion, const SeasonOutputs& seasonOutputs) {
  OutputSources sources{.scene = &b.scene,
                        .outDir = b.options.outDir,
                        .latitudeDeg = b.terrain.latitudeDeg,
                        .layers = b.layers,
                        .wind = &*b.pre.wind,
                        .exposure = b.pre.exposure ? &*b.pre.exposure : nullptr,
                        .occlusion = &occlusion.grids,
                        .routeMap = &seasonOutputs.routeMap,
                        .skiTrackFactor = b.scene.outputs.skiTrackFactor,
                        .occluders = &b.terrain.occluders,
                        .geo = geoFrameOf(b.terrain.info())};
  sources.fileWritten = [](const std::string& path, double day) { reportFilesWritten({path}, day >= 0.0 ? "season" : "outputs"); };
  return sources;
}

// The season on `backend`, its frames written by `writer` as frame_writing and the memory plan
// say, then what no writer reads freed: the backend, the state's static fields, and the sun's
// samples unless a layer reads the sun.
SeasonReport runTheSeason(const GridBake& b, const ArtDirectionPlan& art, FrameTiming planned, bool tilesOnRanks, int threads,
                          std::unique_ptr<SnowBackend> backend, OutputWriter& writer, SeasonOutputs& seasonOutputs) {
  SeasonConfig config = makeSeasonConfig(b.scene, b.terrain, art, b.pre, b.layers, seasonOutputs, b.log);
  seasonOutputs.routeMap = theRanksWindow(std::move(seasonOutputs.routeMap), b.scene, b.terrain.info().spec);
  // Ranks writing their tiles exchange as they write (each layer's range), from the main thread
  // alone and all at once: every rank writes its frames in place, whatever timing its own memory
  // plan chose (the same files).
  const FrameTiming timing = tilesOnRanks ? FrameTiming::Paused : planned;
  FrameWriter frames(writer, seasonOutputs.skiTracks ? &*seasonOutputs.skiTracks : nullptr, threads, timing);
  config.lendFrames = frames.lendsFrames();
  config.spillFolder = b.options.outDir;
  SeasonReport report = bakingAcrossRanks()
                                  ? runSeasonAcrossRanks(b.scene, b.terrain, std::move(backend), b.state, b.pre, b.needs, config, frames, b.log)
                                  : runSeasonStage(b.scene, *backend, b.state, config, frames, b.log);
  backend.reset();  // its copies of the state and its scratch, freed before the outputs
  b.state.releaseFields([](FieldRole r) { return r == FieldRole::Static; });
  if (b.pre.exposure && !(b.needs & kNeedsSun)) b.pre.exposure->release();
  frames.writeHeld();  // the frames held through the season (FrameTiming::AfterSeason)
  return report;
}

// The outputs of the season's end (or of the occlusion), the contact sheet and each avalanche's
// maps (of the whole grid; each rank its tiles where the ranks write their tiles).
void writeEndOfBake(const GridBake& b, OutputWriter& writer, const OcclusionResult& occlusion, const SeasonOutputs& seasonOutputs,
                    const SeasonReport& report) {
  writer.setSnowMesh(occlusion.snowMesh ? &*occlusion.snowMesh : nullptr);
  writer.writeDay(b.state, -1.0, seasonOutputs.skiTracks ? &seasonOutputs.skiTracks->depth() : nullptr);
  writer.writeSeasonEncodings();
  writer.writeContactSheet();
  writer.writeAvalancheMaps(report.avalanches, b.terrain.info().spec);
}

// The manifest of every file written (`files`, the resolved scene's and its own added), with the
// measured memory against `memory`'s prediction.
void writeGridManifest(const GridBake& b, const ArtDirectionPlan& art, const OcclusionResult& occlusion, const SeasonReport& report,
                       const OutputSink& files, const MemoryPrediction& memory, const std::string& terrainHash, BakeResult& result) {
  Manifest manifest = assembleBakeManifest({&b.scene, &b.terrain.terrain, b.terrain.latitudeDeg, programVersion(), result.backendName,
                                            occlusion.manifest, &report, art.rasters, art.editRecords, files.files,
                                            b.options.commandLine, terrainHash});
  manifest.memoryJson =
      measuredMemoryBreakdown(memory, static_cast<double>(b.terrain.info().spec.cellCount()), "cell", b.options.verbose, b.log);
  result.files = files.paths;
  writeTextAtomically(manifestPath(b.options.outDir), manifestToJson(manifest));
  result.files.push_back(manifestPath(b.options.outDir));
  reportFilesWritten({result.files.end() - 2, result.files.end()});  // the resolved scene and the manifest (the rest as written)
}

}  // namespace

BakeResult runGridBake(const Scene& scene, const BakeOptions& options, int threads, std::ostream& log, WallClock::time_point tStart) {
  // The budget as the bake starts: the terrain read after it is among the model's owners (and
  // across ranks, the other ranks' terrains on this machine too).
  const double budget = memoryBudgetBytes(scene);
  checkBuiltinMemory(scene, options.frames, budget);
  std::optional<BakeStage> stage(std::in_place, "terrain");
  progress().stage("terrain", 0.0);
  BakeTerrain terrain = loadBakeTerrain(scene, log);  // across ranks, the ranks but 0 free its grids for the season
  const GridMemoryPlan memoryPlan = checkGridMemory(scene, terrain, options.frames, budget, log);
  checkRanksSuitTheGrid(scene, terrain.info().spec);
  progress().stage("terrain", 1.0);
  const bool occlusionMode = scene.mode == SceneMode::Occlusion;
  if (occlusionMode) log << "mode: occlusion (Foldes & Benes 2007): no season\n";

  // Painted rasters first: a bad mask fails before any precompute runs; so do bedform parameters
  // that do not suit the grid.
  stage.emplace("inputs and art direction");
  const GridSpec& wholeSpec = terrain.info().spec;
  const std::vector<std::string> layers = layersToWrite(scene, terrain.info());
  const uint8_t needs = layersNeeds(layers);
  const PrecomputeParts parts = rankPrecomputeParts(scene, wholeSpec, needs);
  const CellRect cells = initialStateCells(scene, wholeSpec, parts);  // across ranks, maybe the rank's local grid alone
  SnowState state = initialState(terrain, cells);
  const ArtDirectionPlan art = prepareArtDirection(scene, terrain.terrain, cells, state, log);
  checkBedformsSuitTheGrid(scene, wholeSpec);
  const PrecomputeCache cache(options.cacheDir.value_or(PrecomputeCache::defaultDirectory()), options.useCache, &log);
  stage.emplace("precompute");
  Precomputed pre = runPrecompute(scene, terrain, state, cache, parts, log);
  // A constant wind's fields are the state's copy from here on, unless a layer reads the wind
  // (across ranks with parts, each rank's local state's: runSeasonAcrossRanks).
  if (!pre.wind->varies() && !(needs & kNeedsWind) && !pre.partsOnRanks) pre.wind->releaseFields();
  const GridBake bake{scene, options, terrain, state, pre, layers, needs, log};

  // Across ranks, each rank's season runs on the CPU (acrossRanksRefusal refuses run.backend = "cuda").
  std::unique_ptr<SnowBackend> backend = occlusionMode ? nullptr : bakingAcrossRanks() ? createCpuBackend() : chooseBackend(scene.backend, log);
  BakeResult result;
  result.backendName = backend ? backend->name() : "cpu (Embree ray queries; occlusion mode has no season kernels)";
  if (bakingAcrossRanks()) log << "backend: " << result.backendName << " on each rank\n";
  // Across ranks, rank 0 gathers the whole grid and writes every file, or each rank writes the tiles
  // that start in its subdomain and rank 0 the whole files, one at a time.
  const bool tilesOnRanks = ranksWriteTheirTiles(scene, wholeSpec);
  if (writesOutputs() || tilesOnRanks) createOutputFolder(options.outDir);
  // Where every rank writes its tiles, rank 0 too frees the terrain's heights for the season.
  const std::string terrainHash = tilesOnRanks && writesOutputs() ? terrainHashOf(scene, terrain.terrain) : std::string();

  OutputSink files;  // every file written, in order: the manifest's list
  const SinkScope filesScope(files);
  OcclusionResult occlusion;
  SeasonOutputs seasonOutputs;
  OutputSources sources = outputSourcesOf(bake, occlusion, seasonOutputs);
  Precomputed tilesPre;  // across ranks on the replica: the local grid's cells of the precompute the layers read
  shareTheRanksTiles(sources, scene, wholeSpec, pre, tilesPre);
  OutputWriter writer(sources, log);
  if (occlusionMode) {
    stage.emplace("occlusion");
    progress().stage("occlusion", 0.0);
    runOcclusion(scene, terrain, state, occlusion, log);
    progress().stage("occlusion", 1.0);
    result.season = occlusion.report;
  } else {
    stage.emplace("season");
    result.season = runTheSeason(bake, art, memoryPlan.timing, tilesOnRanks, threads, std::move(backend), writer, seasonOutputs);
  }
  if (!writesOutputs() && !tilesOnRanks) return result;  // rank 0 writes a bake across ranks

  stage.emplace("outputs");
  const auto t0 = WallClock::now();
  progress().stage("outputs", 0.0);
  writeEndOfBake(bake, writer, occlusion, seasonOutputs, result.season);
  if (tilesOnRanks) {  // each rank wrote its tiles; rank 0 lists every rank's
    mergeTheRanksFiles(files);
    if (!writesOutputs()) return result;
  }
  writeResolvedScene(scene, options.outDir);
  progress().stage("outputs", 1.0);
  stage.emplace("manifest");  // the outputs stage's memory noted: every owner has had its peak
  progress().stage("manifest", 0.0);
  writeGridManifest(bake, art, occlusion, result.season, files, memoryPlan.prediction, terrainHash, result);
  progress().stage("manifest", 1.0);
  log << writer.occluderNotes();
  log << "outputs: " << result.files.size() << " files in " << options.outDir << " (" << fixed(elapsedSeconds(t0), 2) << " s)\n";
  for (const auto& [kind, seconds] : files.seconds) log << "  " << std::left << std::setw(36) << kind << std::right << fixed(seconds, 2) << " s\n";
  log << "total: " << fixed(elapsedSeconds(tStart), 2) << " s\n";
  return result;
}

}  // namespace snow
