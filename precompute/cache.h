// The precompute cache: float grids stored under a key that hashes every input they depend on
// (terrain bytes, grid, parameters, state, solver settings), so an unchanged scene reuses them.
// A farm may share one folder: writers never leave a torn entry (a unique temporary file in the
// same folder, fsynced, renamed into place), and readers check each entry's checksum, so a
// damaged, truncated or foreign file is recomputed (and said so in the log), never trusted.
#pragma once
#include <iosfwd>
#include <string>
#include <vector>

#include "core/grid.h"
#include "core/grid_window.h"

namespace snow {

// What reading an entry found: ok, or why it cannot be used.
struct CacheEntryCheck {
  bool present = false;  // the file exists
  bool valid = false;    // its header, length and checksum are right
  std::string problem;   // why not, for the log ("truncated: 100 of 4152 bytes", ...)
};

// The key of a rank's part (its local grid's `cells`, across ranks) of the whole grid's entry
// `wholeKey`: an entry of its own, read by a later bake with the same ranks.
inline std::string partCacheKey(const std::string& wholeKey, const CellRect& cells) {
  return wholeKey + "-cells-" + std::to_string(cells.x0) + "-" + std::to_string(cells.y0) + "-" + std::to_string(cells.x1) + "-" +
         std::to_string(cells.y1);
}

class PrecomputeCache {
 public:
  // `directory` empty or `enabled` false: nothing is read or written. `log`, when given, hears
  // of every damaged entry that is recomputed.
  PrecomputeCache(std::string directory, bool enabled, std::ostream* log = nullptr);
  // The default folder: $XDG_CACHE_HOME/snowbake, else $HOME/.cache/snowbake, else "".
  static std::string defaultDirectory();

  bool enabled() const { return enabled_; }
  const std::string& directory() const { return directory_; }
  // Fills `grids` (all of size width x height) from the entry `key`; false when absent or
  // unusable (then the caller recomputes and stores). A hit marks the entry as just used (its
  // modification time), which `snowbake cache prune` reads as its age.
  bool load(const std::string& stage, const std::string& key, int width, int height, const std::vector<Grid<float>*>& grids) const;
  // Whether an entry `key` is stored (not whether it is usable: load checks that).
  bool contains(const std::string& stage, const std::string& key) const;
  void store(const std::string& stage, const std::string& key, const std::vector<const Grid<float>*>& grids) const;

  // Reads a whole entry file and checks it (header, length, checksum), without keeping it.
  static CacheEntryCheck checkEntry(const std::string& path);

 private:
  std::string pathFor(const std::string& stage, const std::string& key) const;
  std::string directory_;
  bool enabled_;
  std::ostream* log_;
};

}  // namespace snow
