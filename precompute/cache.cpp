#include "cache.h"

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "core/atomic_file.h"

namespace snow {

namespace {
constexpr char kMagic[16] = "SNOWBAKE-CACHE1";
}

PrecomputeCache::PrecomputeCache(std::string directory, bool enabled)
    : directory_(std::move(directory)), enabled_(enabled && !directory_.empty()) {}

std::string PrecomputeCache::defaultDirectory() {
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) return std::string(xdg) + "/snowbake";
  if (const char* home = std::getenv("HOME"); home && *home) return std::string(home) + "/.cache/snowbake";
  return "";
}

std::string PrecomputeCache::pathFor(const std::string& stage, const std::string& key) const {
  return (std::filesystem::path(directory_) / (stage + "-" + key + ".bin")).string();
}

bool PrecomputeCache::contains(const std::string& stage, const std::string& key) const {
  std::error_code ec;
  return enabled_ && std::filesystem::exists(pathFor(stage, key), ec);
}

bool PrecomputeCache::load(const std::string& stage, const std::string& key, int width, int height,
                           const std::vector<Grid<float>*>& grids) const {
  if (!enabled_) return false;
  std::ifstream in(pathFor(stage, key), std::ios::binary);
  if (!in) return false;
  char magic[16];
  int32_t header[3];
  if (!in.read(magic, 16) || std::memcmp(magic, kMagic, 16) != 0) return false;
  if (!in.read(reinterpret_cast<char*>(header), sizeof header)) return false;
  if (header[0] != width || header[1] != height || header[2] != static_cast<int32_t>(grids.size())) return false;
  for (Grid<float>* g : grids) {
    g->resize(width, height);
    if (!in.read(reinterpret_cast<char*>(g->data()), static_cast<std::streamsize>(g->size() * sizeof(float)))) return false;
  }
  return in.peek() == std::char_traits<char>::eof();
}

void PrecomputeCache::store(const std::string& stage, const std::string& key, const std::vector<const Grid<float>*>& grids) const {
  if (!enabled_ || grids.empty()) return;
  std::error_code ec;
  std::filesystem::create_directories(directory_, ec);
  if (ec) return;  // a cache that cannot be written is no error: the bake goes on
  std::string bytes(kMagic, 16);
  const int32_t header[3] = {grids[0]->width(), grids[0]->height(), static_cast<int32_t>(grids.size())};
  bytes.append(reinterpret_cast<const char*>(header), sizeof header);
  for (const Grid<float>* g : grids) bytes.append(reinterpret_cast<const char*>(g->data()), g->size() * sizeof(float));
  try {
    writeTextAtomically(pathFor(stage, key), bytes);
  } catch (const std::exception&) {
  }
}

}  // namespace snow
