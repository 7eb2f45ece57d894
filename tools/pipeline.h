// The bake pipeline behind `snowbake bake` and `snowbake demo`: scene -> terrain -> precompute ->
// season -> outputs. Throws InputError for bad input (exit status 2) and other exceptions for
// failures (exit status 1).
#pragma once
#include <cstdint>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "core/season.h"
#include "precompute/terrain_loader.h"

namespace snow {

struct BakeOptions {
  std::string scene = "preset:default";  // a path, or preset:NAME
  std::optional<std::string> terrainFile;  // --terrain: replaces the scene's terrain
  std::string outDir = "snowbake-out";
  std::optional<uint64_t> seed;
  std::optional<int> threads;              // 0 = all cores
  std::optional<std::string> backend;      // cpu | cuda | auto
  std::vector<std::string> sets;           // --set KEY=VALUE
  bool progress = true;
  std::optional<std::string> cacheDir;     // precompute cache folder (default: PrecomputeCache::defaultDirectory())
  bool useCache = true;                    // --no-cache: neither read nor write it
  // Frame days' outputs written on their own thread while the season goes on (false: in place,
  // the season waiting; the same files, for tests and timing comparisons).
  bool framesBesideSeason = true;
};

struct BakeResult {
  std::vector<std::string> files;  // paths written, manifest last
  SeasonReport season;
  std::string backendName;
};

BakeResult runBake(const BakeOptions& options, std::ostream& log);

// `snowbake info`: what snowbake understood of a terrain: a DEM file, builtin:ridged, or a scene
// (file or preset:NAME, with --set overrides) whose [terrain] says how to read its file.
std::string describeTerrain(const std::string& source, bool json, const std::vector<std::string>& sets = {});

const char* programVersion();

}  // namespace snow
