// Float grids as single-channel 32-bit float images (OpenEXR or TIFF), linear values in the
// grid's own unit (metres for snow layers), row 0 at the north edge.
#pragma once
#include <string>

#include "core/grid.h"

namespace snow {

struct WrittenImage {
  std::string path;
  float minValue = 0.f, maxValue = 0.f;
};

// `format` is "exr" or "tiff"; the file gets that extension. Written atomically.
WrittenImage writeFloatImage(const std::string& pathWithoutExtension, const std::string& format, const Grid<float>& grid,
                             const std::string& channelName);

// Reads one channel of a float image back (for tests and `snowbake info`).
Grid<float> readFloatImage(const std::string& path);

}  // namespace snow
