// The manifest of a grid bake (season or occlusion mode), assembled from what each stage made.
#pragma once
#include <string>
#include <vector>

#include "core/season.h"
#include "manifest.h"
#include "scene/scene.h"
#include "inputs/terrain_loader.h"

namespace snow {

struct BakeManifestInputs {
  const Scene* scene = nullptr;
  const Terrain* terrain = nullptr;
  double latitudeDeg = 0.0;
  std::string programVersion;
  std::string backendName;
  ManifestOcclusion occlusion;              // occlusion mode's settings
  const SeasonReport* report = nullptr;     // the season's (or occlusion mode's) report
  std::vector<ManifestRaster> artRasters;   // art direction's rasters
  std::vector<ManifestEdit> edits;          // its edits (volumes filled from the report here)
  std::vector<ManifestFile> files;          // every file written, in order
  std::vector<std::string> commandLine;     // argv, empty from a library
  std::string terrainHash;                  // terrainHashOf, taken before the terrain's heights were freed; empty: taken here
};

Manifest assembleBakeManifest(const BakeManifestInputs& in);
// The manifest's terrain hash: a builtin terrain's heights', else its file's.
std::string terrainHashOf(const Scene& scene, const Terrain& terrain);

}  // namespace snow
