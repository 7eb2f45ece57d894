// mode = "mesh": Fearing's snow on the mesh itself (docs/models/snow-on-meshes.md): placement,
// stability, the snow body as meshes and a VDB, and a manifest.
#include <filesystem>
#include <optional>

#include "bakers/manifest.h"
#include "bakers/output_sink.h"
#include "bakers/mesh_snow_body.h"
#include "bakers/mesh_writer.h"
#include "core/atomic_file.h"
#include "core/format.h"
#include "core/hash.h"
#include "bake_stage.h"
#include "memory_model.h"
#include "modes.h"
#include "progress.h"
#include "static_snow/fallen_snow.h"

namespace snow {

namespace fs = std::filesystem;

namespace {

constexpr const char* kMeshVdbName = "snow.vdb";
std::string meshBodyName(const std::string& format) { return "snow_body." + format; }

MeshSnowManifest meshManifest(const Scene& scene, const TriangleMesh& mesh, const float lo[3], const float hi[3],
                              const FallenSnowSettings& placement, const FallenSnowStability& stability, const FallenSnow& snow,
                              const FallenSnowStabilityReport& st, const MeshSnowBody& body) {
  MeshSnowManifest m;
  m.programVersion = programVersion();
  m.sceneSource = scene.sourceName;
  m.sceneName = scene.name;
  m.sceneHash = Fnv1a64().add(scene.canonicalToml).hex();
  m.meshSource = mesh.source;
  m.meshHash = hashFileFnv1a64(scene.terrain.file);
  m.triangles = mesh.triangles.size();
  for (int k = 0; k < 3; ++k) m.boundsMin[k] = lo[k], m.boundsMax[k] = hi[k];
  m.seed = scene.seed;
  m.placement = placement;
  m.stability = stability;
  m.sites = snow.sites.size();
  m.skyM3 = snow.skyMassM3;
  m.placedM3 = snow.placedM3;
  m.stabilityReport = st;
  m.voxelSizeM = body.voxelSizeM;
  m.bodyTriangles = body.mesh.triangles.size();
  return m;
}

// The "terrain" stage: the mesh, its bounds, and the memory model's prediction refused above the
// budget before any work.
struct MeshTerrain {
  TriangleMesh mesh;
  float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  MemoryPrediction memory{};
};

MeshTerrain loadMeshTerrain(const Scene& scene, std::ostream& log) {
  const auto t0 = WallClock::now();
  progress().stage("terrain", 0.0);
  MeshTerrain t{.mesh = loadTriangleMesh(scene.terrain.file, scene.terrain.upAxis)};
  for (const auto& p : t.mesh.positions)
    for (int k = 0; k < 3; ++k) t.lo[k] = std::min(t.lo[k], p[k]), t.hi[k] = std::max(t.hi[k], p[k]);
  log << "mode: mesh (Fearing 2000: snow on the mesh itself; no grid, no season)\n";
  const double extent[3] = {t.hi[0] - t.lo[0], t.hi[1] - t.lo[1], t.hi[2] - t.lo[2]};
  t.memory = predictMeshBake(scene, t.mesh.triangles.size(), extent);
  const double budget = memoryBudgetBytes(scene);
  refuseAboveBudget(scene, t.memory, budget);
  log << "memory: " << t.memory.summary() << "; budget " << fixed(budget / (1024.0 * 1024.0), 0) << " MiB\n";
  log << "mesh: " << t.mesh.source << ": " << t.mesh.triangles.size() << " triangles, " << fixed(extent[0], 2) << " x " << fixed(extent[1], 2)
      << " x " << fixed(extent[2], 2) << " m (" << fixed(elapsedSeconds(t0), 2) << " s)\n";
  progress().stage("terrain", 1.0);
  return t;
}

// The "placement" stage: the sky's flakes placed on the mesh (Fearing's sites).
FallenSnow placeSnowOnMesh(const TriangleMesh& mesh, const FallenSnowSettings& placement, std::ostream& log) {
  progress().stage("placement", 0.0);
  const auto t0 = WallClock::now();
  FallenSnow snow = placeFallenSnow(mesh, placement);
  log << "placement: " << snow.sites.size() << " sites (" << snow.refinedCells << " cells refined), " << snow.flakes << " flakes ("
      << snow.blocked << " blocked, " << snow.leftTheWorld << " left the world), sky " << fixed(snow.skyMassM3, 4) << " m^3, placed "
      << fixed(snow.placedM3, 4) << " m^3 (" << fixed(elapsedSeconds(t0), 2) << " s)\n";
  progress().stage("placement", 1.0);
  return snow;
}

// The "stability" stage: snow too steep for its sites moved on until it rests.
FallenSnowStabilityReport stabilizeSnowOnMesh(const TriangleMesh& mesh, FallenSnow& snow, const FallenSnowStability& stability, std::ostream& log) {
  progress().stage("stability", 0.0);
  const auto t0 = WallClock::now();
  const FallenSnowStabilityReport st = stabilizeFallenSnow(mesh, snow, stability);
  log << "stability: " << st.rounds << " rounds, " << st.passes << " passes"
      << (st.unconvergedRounds ? " (" + std::to_string(st.unconvergedRounds) + " rounds hit the pass limit)" : std::string()) << ", "
      << fixed(st.overEdgesM3, 4) << " m^3 over edges, " << fixed(st.leftTheWorldM3, 4) << " m^3 left the world, " << fixed(st.finalM3, 4)
      << " m^3 kept (" << fixed(elapsedSeconds(t0), 2) << " s)\n";
  progress().stage("stability", 1.0);
  return st;
}

// The snow body's files listed in `manifest` and `result`: the VDB (written with the body, where
// `vdbPath` is set), each mesh format, and the resolved scene.
void writeSnowBodyFiles(const Scene& scene, const BakeOptions& options, const MeshSnowBody& body, const std::string& vdbPath,
                        MeshSnowManifest& manifest, BakeResult& result) {
  if (!vdbPath.empty()) {
    manifest.files.push_back({kMeshVdbName,
                              "the snow body: snow_sdf (level set, metres) and density (fog volume, kg/m^3 of " +
                                  fixed(scene.meshSnow.body.densityKgPerM3, 0) + " inside)",
                              "m; kg/m^3", "OpenVDB"});
    result.files.push_back(vdbPath);
  }
  for (const std::string& format : scene.outputs.meshes) {
    const std::string name = meshBodyName(format);
    const std::string path = (fs::path(options.outDir) / name).string();
    writeMesh(path, format, body.mesh);
    manifest.files.push_back({name, "the snow body, closed, in the input mesh's frame", "m", meshFormatDescription(format)});
    result.files.push_back(path);
  }
  OutputSink resolved;
  const SinkScope scope(resolved);
  result.files.push_back(writeResolvedScene(scene, options.outDir));
  manifest.files.push_back({"scene.resolved.toml", resolved.files[0].content, "", "TOML"});
}

}  // namespace

BakeResult runMeshBake(const Scene& scene, const BakeOptions& options, std::ostream& log, WallClock::time_point tStart) {
  BakeResult result;
  result.backendName = "cpu (Embree ray queries, TBB)";
  std::optional<BakeStage> stage(std::in_place, "mesh");
  const MeshTerrain terrain = loadMeshTerrain(scene, log);
  FallenSnowSettings placement = scene.meshSnow.placement;
  placement.seed = scene.seed;
  stage.emplace("placement");
  FallenSnow snow = placeSnowOnMesh(terrain.mesh, placement, log);
  FallenSnowStability stability = scene.meshSnow.stability;
  stability.seed = scene.seed;
  stage.emplace("stability");
  const FallenSnowStabilityReport st = stabilizeSnowOnMesh(terrain.mesh, snow, stability, log);

  progress().stage("outputs", 0.0);
  const auto t0 = WallClock::now();
  createOutputFolder(options.outDir);
  const std::string vdbPath = scene.outputs.vdb ? (fs::path(options.outDir) / kMeshVdbName).string() : std::string();
  stage.emplace("snow body");
  const MeshSnowBody body = buildMeshSnowBody(snow, terrain.mesh, scene.meshSnow.body, vdbPath);
  log << "snow body: " << body.snowVoxels << " voxels of " << fixed(body.voxelSizeM, 4) << " m, " << body.mesh.triangles.size()
      << " triangles (" << fixed(body.seconds, 2) << " s)\n";
  MeshSnowManifest manifest = meshManifest(scene, terrain.mesh, terrain.lo, terrain.hi, placement, stability, snow, st, body);
  writeSnowBodyFiles(scene, options, body, vdbPath, manifest, result);
  manifest.commandLine = options.commandLine;
  progress().stage("outputs", 1.0);
  stage.emplace("manifest");  // the snow body's and the files' memory noted
  progress().stage("manifest", 0.0);
  manifest.memoryJson = measuredMemoryBreakdown(terrain.memory, static_cast<double>(snow.sites.size()), "site", options.verbose, log);
  writeTextAtomically(manifestPath(options.outDir), meshSnowManifestToJson(manifest));
  result.files.push_back(manifestPath(options.outDir));
  reportFilesWritten(result.files);
  progress().stage("manifest", 1.0);
  log << "outputs: " << result.files.size() << " files in " << options.outDir << " (" << fixed(elapsedSeconds(t0), 2) << " s)\n";
  log << "total: " << fixed(elapsedSeconds(tStart), 2) << " s\n";
  return result;
}

std::vector<PlannedFile> planMeshBakeFiles(const Scene& scene, const std::string& outDir) {
  std::vector<PlannedFile> files;
  if (scene.outputs.vdb)
    files.push_back({.path = (fs::path(outDir) / kMeshVdbName).string(), .format = "OpenVDB", .content = "the snow body: snow_sdf (level set) and density (fog)"});
  for (const std::string& format : scene.outputs.meshes)
    files.push_back({.path = (fs::path(outDir) / meshBodyName(format)).string(), .format = meshFormatDescription(format), .content = "the snow body, closed"});
  files.push_back({.path = resolvedScenePath(outDir), .format = "TOML", .content = "the resolved scene"});
  files.push_back({.path = manifestPath(outDir), .format = "JSON", .content = "the manifest"});
  return files;
}

}  // namespace snow
