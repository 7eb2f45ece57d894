// The precompute cache: float grids stored under a key that hashes every input they depend on
// (terrain bytes, grid, parameters, state, solver settings), so an unchanged scene reuses them.
// Files are written atomically; a damaged or foreign file is ignored (recomputed), never trusted.
#pragma once
#include <string>
#include <vector>

#include "core/grid.h"

namespace snow {

class PrecomputeCache {
 public:
  // `directory` empty or `enabled` false: nothing is read or written.
  PrecomputeCache(std::string directory, bool enabled);
  // The default folder: $XDG_CACHE_HOME/snowbake, else $HOME/.cache/snowbake, else "".
  static std::string defaultDirectory();

  bool enabled() const { return enabled_; }
  const std::string& directory() const { return directory_; }
  // Fills `grids` (all of size width x height) from the entry `key`; false when absent or unusable.
  bool load(const std::string& stage, const std::string& key, int width, int height, const std::vector<Grid<float>*>& grids) const;
  // Whether an entry `key` is stored (not whether it is usable: load checks that).
  bool contains(const std::string& stage, const std::string& key) const;
  void store(const std::string& stage, const std::string& key, const std::vector<const Grid<float>*>& grids) const;

 private:
  std::string pathFor(const std::string& stage, const std::string& key) const;
  std::string directory_;
  bool enabled_;
};

}  // namespace snow
