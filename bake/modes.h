// The bake's modes, each a driver over the stages (stages.h); bake.cpp picks one by scene.mode.
#pragma once
#include <ostream>
#include <string>

#include "stages.h"

namespace snow {

// The output folder (and its parents), or an InputError naming it.
void createOutputFolder(const std::string& dir);
// One "file" progress event per path written (its size in bytes).
void reportFilesWritten(const std::vector<std::string>& paths);
// DIR/scene.resolved.toml (scene.h, resolvedSceneToml), listed in the current output sink; its path.
std::string writeResolvedScene(const Scene& scene, const std::string& outDir);
// mode = "season" and mode = "occlusion" (mode_grid.cpp).
BakeResult runGridBake(const Scene& scene, const BakeOptions& options, int threads, std::ostream& log, WallClock::time_point tStart);
// mode = "mesh" (mode_mesh.cpp): Fearing's snow on the mesh itself, no grid and no season.
BakeResult runMeshBake(const Scene& scene, const BakeOptions& options, std::ostream& log, WallClock::time_point tStart);

}  // namespace snow
