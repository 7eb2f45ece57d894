// The bake's modes, each a driver over the stages (stages.h); bake.cpp picks one by scene.mode.
#pragma once
#include <ostream>
#include <string>

#include "memory_vdb.h"
#include "stages.h"

namespace snow {

// The output folder (and its parents), or an InputError naming it.
void createOutputFolder(const std::string& dir);
// One "file" progress event per path written (its size in bytes).
void reportFilesWritten(const std::vector<std::string>& paths, const char* stage = "outputs");
// DIR/scene.resolved.toml (scene.h, resolvedSceneToml), listed in the current output sink; its path.
std::string writeResolvedScene(const Scene& scene, const std::string& outDir);
std::string resolvedScenePath(const std::string& outDir);
std::string manifestPath(const std::string& outDir);  // DIR/manifest.json, written last
// The grid modes' pieces `snowbake plan` shares (mode_grid.cpp): the layers written (the scene's,
// and valid_mask where the terrain has NODATA cells), the rasters' georeference, a builtin
// terrain's memory refused before it is made, the occluders' triangles, where snow can fall on
// the terrain (the memory model's VDB term).
std::vector<std::string> layersToWrite(const Scene& scene, const TerrainInfo& ti);
GeoFrame geoFrameOf(const TerrainInfo& ti);
void checkBuiltinMemory(const Scene& scene, FrameTiming timing, double budgetBytes);
size_t triangleCount(const std::vector<TriangleMesh>& meshes);
SnowReach terrainSnowReach(const Scene& scene, const BakeTerrain& terrain);
// mode = "season" and mode = "occlusion" (mode_grid.cpp).
BakeResult runGridBake(const Scene& scene, const BakeOptions& options, int threads, std::ostream& log, WallClock::time_point tStart);
// mode = "mesh" (mode_mesh.cpp): Fearing's snow on the mesh itself, no grid and no season.
BakeResult runMeshBake(const Scene& scene, const BakeOptions& options, std::ostream& log, WallClock::time_point tStart);
// The files runMeshBake writes, by the same names (snowbake plan).
std::vector<PlannedFile> planMeshBakeFiles(const Scene& scene, const std::string& outDir);

}  // namespace snow
