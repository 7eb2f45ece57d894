// Looking after a (shared) precompute cache folder: `snowbake cache prune` keeps it within an age
// and a size, `snowbake cache check` reads every entry. Only files named as cache entries are
// touched, so a cache folder pointed at the wrong place loses nothing else.
#pragma once
#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace snow {

struct CachePruneOptions {
  std::string directory;
  std::optional<double> olderThanDays;  // remove entries not used for longer than this
  std::optional<double> maxSizeGb;      // then the least recently used until the rest fit (1 GB = 10^9 bytes)
  bool dryRun = false;                  // list, remove nothing
};

struct CachePruneReport {
  std::vector<std::string> removed;  // paths, in the order they were (or would be) removed
  uint64_t removedBytes = 0;
  size_t keptEntries = 0;
  uint64_t keptBytes = 0;
};

// A writer's temporary file older than this is left over from a killed bake (a live one is
// renamed within seconds) and is removed whatever the options.
constexpr double kStaleTemporaryDays = 1.0;

// Throws InputError for options that make no sense (negative, neither given, no folder).
CachePruneReport pruneCache(const CachePruneOptions& options, std::chrono::system_clock::time_point now);

struct CacheEntryStatus {
  std::string path;
  std::string problem;  // "" when valid
};

// Every entry of the folder, by name, each read whole and its checksum checked.
std::vector<CacheEntryStatus> checkCacheFolder(const std::string& directory);

// True for a name the cache writes (STAGE-KEY.bin), false for its temporary files and anything else.
bool isCacheEntryName(const std::string& fileName);

}  // namespace snow
