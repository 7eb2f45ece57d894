// The bake behind `snowbake bake` and `snowbake demo`: scene -> terrain -> inputs and art
// direction -> precompute -> season -> outputs -> manifest (bake.cpp lists the stages, one file
// each in this folder). Throws InputError for bad input (exit status 2) and other exceptions for
// failures (exit status 1).
#pragma once
#include <cstdint>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "bake/frame_timing.h"
#include "core/season.h"
#include "inputs/terrain_loader.h"

namespace snow {

class ProgressSink;

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
  // --verbose: the memory breakdown (the model's groups against the measured peak) in the log.
  bool verbose = false;
  // When frame days' outputs are written (frame_timing.h): beside the season unless only writing
  // them after it fits the memory budget; the same files whichever.
  FrameTiming frames = FrameTiming::Auto;
  // Where stages report progress and events (progress.h); null: the human bar on the log.
  ProgressSink* progressSink = nullptr;
  std::vector<std::string> commandLine;  // recorded in the manifest (argv of `snowbake bake`)
};

struct BakeResult {
  std::vector<std::string> files;  // paths written, manifest last
  SeasonReport season;
  std::string backendName;
};

BakeResult runBake(const BakeOptions& options, std::ostream& log);

const char* programVersion();

}  // namespace snow
