// Stage 1: the scene, with the command line's overrides.
#include <filesystem>
#include <optional>

#include "core/errors.h"
#include "stages.h"

namespace snow {

Scene resolveScene(const BakeOptions& options) {
  if (options.terrainFile) {
    std::error_code ec;
    if (!std::filesystem::exists(*options.terrainFile, ec))
      throw InputError(*options.terrainFile + ": terrain file does not exist (--terrain)");
  }
  // --terrain replaces the scene's whole [terrain] table; --set terrain.KEY still applies to it.
  Scene scene = loadScene(options.scene, options.sets, options.terrainFile);
  if (options.seed) scene.seed = *options.seed;
  if (options.threads) scene.threads = *options.threads;
  if (options.backend) {
    const std::optional<BackendChoice> backend = enumFromName<BackendChoice>(*options.backend);
    if (!backend) throw InputError("--backend " + *options.backend + ": must be cpu, cuda or auto");
    scene.backend = *backend;
  }
  if (scene.threads < 0) throw InputError("--threads " + std::to_string(scene.threads) + ": must be 0 (all cores) or more");
  return scene;
}

}  // namespace snow
