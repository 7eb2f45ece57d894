// A painted raster as a scene names it (art direction: masks, multipliers, depth rasters): the
// file and how its values map to 0..1. Reading and placing it is inputs/raster_input.h.
#pragma once
#include <array>
#include <optional>
#include <string>

namespace snow {

struct RasterRef {
  std::string name;  // the [masks] entry it came from, or empty for a file given in place
  std::string file;  // resolved path
  std::optional<std::array<double, 2>> values;  // the file's values that mean 0 and 1
  std::optional<std::array<double, 2>> range;   // what 0 and 1 become
  bool invert = false;
  std::string declaredAt;  // "scene.toml:12: multipliers.snowfall", for messages
  std::string label() const { return name.empty() ? file : name + " (" + file + ")"; }
};

}  // namespace snow
