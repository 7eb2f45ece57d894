#include "cache_folder.h"

#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <regex>

#include "core/atomic_file.h"
#include "core/errors.h"
#include "precompute/cache.h"

namespace snow {

namespace fs = std::filesystem;

namespace {

struct CacheFile {
  std::string path;
  uint64_t bytes;
  double ageDays;  // since its last use (a hit renews the modification time)
};

double ageDays(const std::string& path, std::chrono::system_clock::time_point now) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return 0.0;
  const double mtime = static_cast<double>(st.st_mtim.tv_sec) + 1e-9 * static_cast<double>(st.st_mtim.tv_nsec);
  const double nowSeconds = std::chrono::duration<double>(now.time_since_epoch()).count();
  return (nowSeconds - mtime) / 86400.0;
}

// An entry's temporary: core/atomic_file's name for it, ".<stage>-<key>.tmp-<host>-<pid>-<nonce>.bin",
// or the earlier cache writer's, ".<stage>-<key>.bin.tmp-<host>-<pid>-<nonce>", which a killed
// writer of an older snowbake may have left.
bool isTemporaryEntryName(const std::string& name) {
  static const std::regex entryStem(R"(\.[a-z]+-[0-9a-f]{16}\.tmp-.+\.bin)");
  static const std::regex earlier(R"(\.[a-z]+-[0-9a-f]{16}\.bin\.tmp-.+)");
  return (isTemporaryFileName(name) && std::regex_match(name, entryStem)) || std::regex_match(name, earlier);
}

void checkOptions(const CachePruneOptions& o) {
  if (o.directory.empty()) throw InputError("cache prune: no cache folder (give --cache-dir; neither $XDG_CACHE_HOME nor $HOME is set)");
  if (!o.olderThanDays && !o.maxSizeGb) throw InputError("cache prune: give --older-than-days, --max-size-gb or both");
  if (o.olderThanDays && !(*o.olderThanDays >= 0.0 && std::isfinite(*o.olderThanDays)))
    throw InputError("cache prune: --older-than-days must be a number of days >= 0");
  if (o.maxSizeGb && !(*o.maxSizeGb >= 0.0 && std::isfinite(*o.maxSizeGb)))
    throw InputError("cache prune: --max-size-gb must be a number of GB >= 0");
}

}  // namespace

bool isCacheEntryName(const std::string& fileName) {
  static const std::regex entry(R"([a-z]+-[0-9a-f]{16}\.bin)");
  return std::regex_match(fileName, entry);
}

CachePruneReport pruneCache(const CachePruneOptions& o, std::chrono::system_clock::time_point now) {
  checkOptions(o);
  CachePruneReport report;
  std::error_code ec;
  if (!fs::is_directory(o.directory, ec)) return report;  // no cache yet: nothing to prune
  std::vector<CacheFile> entries;
  auto remove = [&](const CacheFile& f) {
    if (!o.dryRun) fs::remove(f.path, ec);  // a file another pruner removed first is no error
    report.removed.push_back(f.path);
    report.removedBytes += f.bytes;
  };
  for (const auto& e : fs::directory_iterator(o.directory, ec)) {
    if (!e.is_regular_file(ec)) continue;
    const std::string name = e.path().filename().string();
    const CacheFile f{e.path().string(), static_cast<uint64_t>(e.file_size(ec)), ageDays(e.path().string(), now)};
    if (isTemporaryEntryName(name) && f.ageDays > kStaleTemporaryDays) remove(f);
    if (isCacheEntryName(name)) entries.push_back(f);
  }
  // Least recently used first; ties by name, so two pruners at once agree.
  std::sort(entries.begin(), entries.end(), [](const CacheFile& a, const CacheFile& b) {
    return a.ageDays != b.ageDays ? a.ageDays > b.ageDays : a.path < b.path;
  });
  uint64_t total = 0;
  for (const CacheFile& f : entries) total += f.bytes;
  const uint64_t maxBytes = o.maxSizeGb ? static_cast<uint64_t>(std::llround(*o.maxSizeGb * 1e9)) : 0;
  for (const CacheFile& f : entries) {
    const bool tooOld = o.olderThanDays && f.ageDays > *o.olderThanDays;
    const bool tooBig = o.maxSizeGb && total > maxBytes;
    if (tooOld || tooBig) {
      remove(f);
      total -= f.bytes;
    } else {
      ++report.keptEntries;
      report.keptBytes += f.bytes;
    }
  }
  return report;
}

std::vector<CacheEntryStatus> checkCacheFolder(const std::string& directory) {
  std::vector<CacheEntryStatus> entries;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(directory, ec))
    if (e.is_regular_file(ec) && isCacheEntryName(e.path().filename().string()))
      entries.push_back({e.path().string(), PrecomputeCache::checkEntry(e.path().string()).problem});
  std::sort(entries.begin(), entries.end(), [](const CacheEntryStatus& a, const CacheEntryStatus& b) { return a.path < b.path; });
  return entries;
}

}  // namespace snow
