// planBake: the bake's own steps up to the first that does work (scene, terrain, memory model),
// then the output writers in plan mode over every day the bake writes.
#include "plan.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>

#include "core/errors.h"
#include "core/format.h"
#include "modes.h"
#include "progress.h"
#include "stages.h"

namespace snow {

namespace fs = std::filesystem;

namespace {

// Rough: the rates are tools/plan-vs-bake.sh's bakes on this 2-core machine under load (2 us a
// cell-day, 0.1 ms an occlusion cell, 1.5 ms a launch site); avalanches can make a season far
// slower than its cells and days say.
std::string timeClassOf(double work, double secondsPerUnit) {
  const double s = work * secondsPerUnit;
  return s < 10 ? "seconds" : s < 60 ? "tens of seconds" : s < 3600 ? "minutes" : "hours";
}

std::vector<PlannedStage> gridStages(const Scene& scene, const BakeTerrain& terrain, const BakeOptions& options) {
  const bool occlusion = scene.mode == SceneMode::Occlusion;
  const TerrainInfo& ti = terrain.info();
  std::vector<PlannedStage> st;
  st.push_back({"terrain", true, ti.source + " (" + ti.format + "), " + std::to_string(ti.spec.width) + " x " + std::to_string(ti.spec.height) +
                                     " cells, " + std::to_string(ti.nodataCells) + " NODATA"});
  st.push_back({"inputs and art direction", true, "the painted rasters the scene names, if any"});
  if (const StageDecision sun = sunExposureDecision(scene); !sun.runs)
    st.push_back({"sun exposure", false, sun.why});
  else {
    const PrecomputeCache cache(options.cacheDir.value_or(PrecomputeCache::defaultDirectory()), options.useCache);
    const ExposureSettings es = exposureSettings(scene, terrain);
    const bool cached = cache.contains("exposure", exposureCacheKey(terrain.terrain.heightsM, terrain.terrain.valid, ti.spec, terrain.occluders,
                                                                    scene.params, es));
    std::string why = std::string(cached ? "cached" : "computed") + " (" + es.quality.name + ", " + (es.horizonSweep ? "horizon sweep" : "Embree") + ")";
    for (const std::string& term : exposureTermsFor(scene.params).skipped) why += "; skipped " + term;
    st.push_back({"sun exposure", true, why});
  }
  const StageDecision wind = windDecision(scene);
  st.push_back({"wind", wind.runs, wind.runs ? "computed or from the cache, per wind state" : wind.why});
  if (occlusion) {
    st.push_back({"season", false, "occlusion mode"});
    st.push_back({"occlusion", true, "Foldes & Benes' static cover"});
  } else {
    st.push_back({"season", true, fixed(scene.days, 0) + " days, backend " + std::string(enumName(scene.backend))});
    st.push_back({"frames", !scene.outputs.frameDays.empty(), std::to_string(scene.outputs.frameDays.size()) + " frame day(s) (outputs.frames_days)"});
  }
  st.push_back({"outputs", true, "the season's end"});
  st.push_back({"manifest", true, "manifest.json, last"});
  return st;
}

void planGrid(const Scene& scene, const BakeOptions& options, BakePlan& plan) {
  plan.budgetBytes = memoryBudgetBytes(scene);  // as the bake would start
  checkBuiltinMemory(scene, options.frames, plan.budgetBytes);
  const BakeTerrain terrain = loadBakeTerrain(scene, *std::make_unique<std::ostringstream>());
  const GridSpec& spec = terrain.info().spec;
  refuseBeyondTheModel(scene, spec);
  plan.memory = planGridMemory(scene, spec, triangleCount(terrain.occluders), terrainSnowReach(scene, terrain), plan.budgetBytes, options.frames)
                    .prediction;
  refuseAboveBudget(scene, plan.memory, plan.budgetBytes);
  const bool occlusion = scene.mode == SceneMode::Occlusion;
  checkBedformsSuitTheGrid(scene, spec);
  plan.width = spec.width, plan.height = spec.height;
  plan.stages = gridStages(scene, terrain, options);

  OutputSink sink;
  {
    const SinkScope scope(sink);
    OutputSources src{.scene = &scene,
                      .outDir = options.outDir,
                      .latitudeDeg = terrain.latitudeDeg,
                      .layers = layersToWrite(scene, terrain.info()),
                      .skiTrackFactor = scene.outputs.skiTrackFactor,
                      .occluders = &terrain.occluders,
                      .geo = geoFrameOf(terrain.info()),
                      .plan = true};
    src.planSnowMesh = occlusion && occlusionWritesSnowMesh(scene, terrain.info());
    src.planNodata = terrain.info().nodataCells > 0;
    std::ostringstream quiet;
    OutputWriter writer(src, quiet);
    SnowState shape;  // the spec alone: plan mode reads no value
    shape.spec = spec;
    if (!occlusion)
      for (double day : scene.outputs.frameDays)
        if (frameDayInSeason(day, scene.days)) writer.writeDay(shape, day, nullptr);
    writer.writeDay(shape, -1.0, nullptr);
    writer.writeSeasonEncodings();
    writer.writeContactSheet();
    writer.planAvalancheMaps();
  }
  plan.files = sink.planned;
  plan.files.push_back({resolvedScenePath(options.outDir), "TOML", "the resolved scene"});
  plan.files.push_back({manifestPath(options.outDir), "JSON", "the manifest"});
  plan.work = occlusion ? static_cast<double>(spec.cellCount()) : static_cast<double>(spec.cellCount()) * scene.days;
  plan.timeClass = timeClassOf(plan.work, occlusion ? 1e-4 : 2e-6);
}

void planMesh(const Scene& scene, const BakeOptions& options, BakePlan& plan) {
  const TriangleMesh mesh = loadTriangleMesh(scene.terrain.file, scene.terrain.upAxis);
  float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (const auto& p : mesh.positions)
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
  const double extent[3] = {hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]};
  plan.triangles = mesh.triangles.size();
  plan.memory = predictMeshBake(scene, mesh.triangles.size(), extent);
  plan.budgetBytes = memoryBudgetBytes(scene);
  refuseAboveBudget(scene, plan.memory, plan.budgetBytes);
  plan.stages = {{"terrain", true, mesh.source + ": " + std::to_string(mesh.triangles.size()) + " triangles"},
                 {"placement", true, "Fearing's snow on the mesh"},
                 {"stability", true, "Fearing's stability passes"},
                 {"season", false, "mode = \"mesh\" has no season"},
                 {"outputs", true, "the snow body"},
                 {"manifest", true, "manifest.json, last"}};
  plan.files = planMeshBakeFiles(scene, options.outDir);
  // The launch sites of the lattice over the footprint: what placement and stability cost.
  const double spacing = scene.meshSnow.placement.siteSpacingM;
  plan.work = extent[0] * extent[1] / (spacing * spacing);
  plan.timeClass = timeClassOf(plan.work, 1.5e-3);
}

}  // namespace

BakePlan planBake(const BakeOptions& given) {
  BakeOptions options = given;
  options.outDir = fs::absolute(given.outDir).string();  // the files' paths absolute, listed relative to it
  const Scene scene = resolveScene(options);
  BakePlan plan;
  plan.scene = scene.sourceName;
  plan.sceneName = scene.name;
  plan.mode = enumName(scene.mode);
  plan.outDir = options.outDir;
  plan.days = scene.days;
  if (scene.mode == SceneMode::Mesh)
    planMesh(scene, options, plan);
  else
    planGrid(scene, options, plan);
  return plan;
}

std::string planToJson(const BakePlan& p) {
  std::ostringstream o;
  o << "{\n  \"scene\": " << jsonText(p.scene) << ",\n  \"name\": " << jsonText(p.sceneName) << ",\n  \"mode\": " << jsonText(p.mode)
    << ",\n  \"out\": " << jsonText(p.outDir) << ",\n  \"grid\": [" << p.width << ", " << p.height << "],\n  \"triangles\": " << p.triangles
    << ",\n  \"days\": " << jsonNumber(p.days) << ",\n  \"stages\": [";
  for (size_t i = 0; i < p.stages.size(); ++i)
    o << (i ? "," : "") << "\n    {\"name\": " << jsonText(p.stages[i].name) << ", \"runs\": " << (p.stages[i].runs ? "true" : "false")
      << ", \"why\": " << jsonText(p.stages[i].why) << "}";
  o << "\n  ],\n  \"files\": [";
  for (size_t i = 0; i < p.files.size(); ++i) {
    const PlannedFile& f = p.files[i];
    o << (i ? "," : "") << "\n    {\"path\": " << jsonText(fs::relative(f.path, p.outDir).string()) << ", \"format\": " << jsonText(f.format)
      << ", \"content\": " << jsonText(f.content) << ", \"data_bytes\": " << jsonNumber(f.dataBytes)
      << ", \"exact_bytes\": " << (f.exactBytes ? "true" : "false") << ", \"condition\": " << jsonText(f.condition);
    if (!f.note.empty()) o << ", \"note\": " << jsonText(f.note);
    o << "}";
  }
  o << "\n  ],\n  \"memory\": {\"peak_bytes\": " << jsonNumber(p.memory.peakBytes()) << ", \"peak_phase\": " << jsonText(p.memory.peakPhase().name)
    << ", \"library_bytes\": " << jsonNumber(p.memory.libraryBytes) << ", \"budget_bytes\": " << jsonNumber(p.budgetBytes)
    << ", \"summary\": " << jsonText(p.memory.summary()) << "},\n  \"time_class\": " << jsonText(p.timeClass)
    << ",\n  \"work\": " << jsonNumber(p.work) << "\n}\n";
  return o.str();
}

void printPlan(const BakePlan& p, std::ostream& out) {
  out << "plan: " << p.scene << " (" << p.sceneName << "), mode " << p.mode;
  if (p.width > 0) out << ", " << p.width << " x " << p.height << " cells, " << fixed(p.days, 0) << " days";
  if (p.triangles > 0) out << ", " << p.triangles << " triangles";
  out << "\nstages:\n";
  for (const PlannedStage& s : p.stages) out << "  " << (s.runs ? "run  " : "skip ") << s.name << ": " << s.why << "\n";
  double bytes = 0;
  size_t conditional = 0;
  for (const PlannedFile& f : p.files) bytes += f.dataBytes, conditional += !f.condition.empty();
  out << "files: " << p.files.size() << " in " << p.outDir << " (" << conditional << " depending on the snow; "
      << fixed(bytes / (1024.0 * 1024.0), 1) << " MiB of pixel data before compression)\n";
  for (const PlannedFile& f : p.files) {
    out << "  " << fs::relative(f.path, p.outDir).string();
    if (f.dataBytes > 0) out << "  " << (f.exactBytes ? "" : "~") << static_cast<long long>(f.dataBytes) << " B";
    out << "  " << f.format.substr(0, f.format.find(','));
    if (!f.condition.empty()) out << "  (" << f.condition << ")";
    if (!f.note.empty()) out << "  [" << f.note << "]";
    out << "\n";
  }
  out << "memory: " << p.memory.summary() << "; budget " << fixed(p.budgetBytes / (1024.0 * 1024.0), 0) << " MiB\n";
  out << "time: " << p.timeClass << " (rough, from " << fixed(p.work, 0) << (p.mode == "mesh" ? " launch sites" : p.mode == "occlusion" ? " cells" : " cell-days")
      << ")\n";
}

}  // namespace snow
