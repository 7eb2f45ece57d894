#include "cache.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <ostream>

#include "core/atomic_file.h"
#include "core/hash.h"

namespace snow {

namespace fs = std::filesystem;

namespace {

// Version 2 added the payload length and its FNV-1a 64 checksum; version 1 files read as foreign.
constexpr char kMagic[16] = "SNOWBAKE-CACHE2";
constexpr const char* kForeign = "not a cache entry of this snowbake version";

struct EntryHeader {
  char magic[16];
  int32_t width, height, count, reserved;
  uint64_t payloadBytes;
  uint64_t checksum;  // FNV-1a 64 of the payload
};
static_assert(sizeof(EntryHeader) == 48, "the header is written as it lies in memory");

uint64_t gridBytes(int width, int height) { return static_cast<uint64_t>(width) * static_cast<uint64_t>(height) * sizeof(float); }

// Why a header cannot describe a file of `fileBytes` bytes; "" when it can.
std::string headerProblem(const EntryHeader& h, uint64_t fileBytes) {
  if (std::memcmp(h.magic, kMagic, sizeof kMagic) != 0) return kForeign;
  if (h.width <= 0 || h.height <= 0 || h.count <= 0 || h.payloadBytes != gridBytes(h.width, h.height) * static_cast<uint64_t>(h.count))
    return "header inconsistent with its grids";
  const uint64_t expected = sizeof(EntryHeader) + h.payloadBytes;
  if (fileBytes < expected) return "truncated: " + std::to_string(fileBytes) + " of " + std::to_string(expected) + " bytes";
  if (fileBytes > expected) return std::to_string(fileBytes) + " bytes where the header says " + std::to_string(expected);
  return "";
}

// Reads the header of an open entry; "" or why not.
std::string readHeader(std::ifstream& in, EntryHeader& h, uint64_t fileBytes) {
  if (fileBytes < sizeof h || !in.read(reinterpret_cast<char*>(&h), sizeof h))
    return "truncated: " + std::to_string(fileBytes) + " bytes, shorter than the header";
  return headerProblem(h, fileBytes);
}

// The entry is complete on disk under its unique temporary name before the rename makes it
// visible, and the rename reaches the disk before store() returns: a crash or a concurrent writer
// of the same key, on any node sharing the folder, leaves the old entry or a new whole one.
void writeEntryDurably(const std::string& finalPath, const EntryHeader& header, const std::vector<const Grid<float>*>& grids) {
  writeStreamAtomically(
      finalPath,
      [&](std::ostream& out) {
        out.write(reinterpret_cast<const char*>(&header), sizeof header);
        for (const Grid<float>* g : grids)
          out.write(reinterpret_cast<const char*>(g->data()), static_cast<std::streamsize>(g->size() * sizeof(float)));
      },
      Durability::Durable);
}

uint64_t fileSize(const std::string& path) {
  std::error_code ec;
  const uintmax_t n = fs::file_size(path, ec);
  return ec ? 0 : static_cast<uint64_t>(n);
}

}  // namespace

PrecomputeCache::PrecomputeCache(std::string directory, bool enabled, std::ostream* log)
    : directory_(std::move(directory)), enabled_(enabled && !directory_.empty()), log_(log) {}

std::string PrecomputeCache::defaultDirectory() {
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) return std::string(xdg) + "/snowbake";
  if (const char* home = std::getenv("HOME"); home && *home) return std::string(home) + "/.cache/snowbake";
  return "";
}

std::string PrecomputeCache::pathFor(const std::string& stage, const std::string& key) const {
  return (fs::path(directory_) / (stage + "-" + key + ".bin")).string();
}

bool PrecomputeCache::contains(const std::string& stage, const std::string& key) const {
  std::error_code ec;
  return enabled_ && std::filesystem::exists(pathFor(stage, key), ec);
}

bool PrecomputeCache::load(const std::string& stage, const std::string& key, int width, int height,
                           const std::vector<Grid<float>*>& grids) const {
  if (!enabled_) return false;
  const std::string path = pathFor(stage, key);
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;  // absent: the ordinary miss, nothing to say
  EntryHeader h{};
  std::string problem = readHeader(in, h, fileSize(path));
  if (problem.empty() && (h.width != width || h.height != height || h.count != static_cast<int32_t>(grids.size())))
    problem = "holds other grids than its key says";
  Fnv1a64 sum;
  for (size_t i = 0; problem.empty() && i < grids.size(); ++i) {
    grids[i]->resize(width, height);
    if (!in.read(reinterpret_cast<char*>(grids[i]->data()), static_cast<std::streamsize>(gridBytes(width, height))))
      problem = "truncated while reading";
    sum.add(grids[i]->data(), gridBytes(width, height));
  }
  if (problem.empty() && sum.value() != h.checksum) problem = "checksum mismatch";
  if (!problem.empty()) {
    if (log_ && problem == kForeign) *log_ << "  cache: " << path << " is " << problem << ": recomputing\n";
    else if (log_) *log_ << "  cache: " << path << " is damaged (" << problem << "): recomputing\n";
    return false;
  }
  ::utimensat(AT_FDCWD, path.c_str(), nullptr, 0);  // marks it as used now; best effort
  return true;
}

void PrecomputeCache::store(const std::string& stage, const std::string& key, const std::vector<const Grid<float>*>& grids) const {
  if (!enabled_ || grids.empty()) return;
  const std::string path = pathFor(stage, key);
  EntryHeader h{};
  std::memcpy(h.magic, kMagic, sizeof kMagic);
  h.width = grids[0]->width();
  h.height = grids[0]->height();
  h.count = static_cast<int32_t>(grids.size());
  Fnv1a64 sum;
  for (const Grid<float>* g : grids) sum.add(g->data(), g->size() * sizeof(float));
  h.payloadBytes = gridBytes(h.width, h.height) * grids.size();
  h.checksum = sum.value();
  try {
    fs::create_directories(directory_);
    writeEntryDurably(path, h, grids);
  } catch (const std::exception& e) {
    // A cache that cannot be written is no error: the bake goes on, and says so.
    if (log_) *log_ << "  cache: not stored (" << e.what() << ")\n";
  }
}

CacheEntryCheck PrecomputeCache::checkEntry(const std::string& path) {
  CacheEntryCheck check;
  std::ifstream in(path, std::ios::binary);
  if (!in) return check;
  check.present = true;
  EntryHeader h{};
  check.problem = readHeader(in, h, fileSize(path));
  if (!check.problem.empty()) return check;
  Fnv1a64 sum;
  std::vector<char> buffer(1 << 20);
  for (uint64_t left = h.payloadBytes; left > 0;) {
    const size_t n = static_cast<size_t>(std::min<uint64_t>(left, buffer.size()));
    if (!in.read(buffer.data(), static_cast<std::streamsize>(n))) {
      check.problem = "truncated while reading";
      return check;
    }
    sum.add(buffer.data(), n);
    left -= n;
  }
  if (sum.value() != h.checksum) check.problem = "checksum mismatch";
  check.valid = check.problem.empty();
  return check;
}

}  // namespace snow
