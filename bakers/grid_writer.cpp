#include "grid_writer.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <stdexcept>

#include "core/atomic_file.h"

namespace snow {

WrittenImage writeFloatImage(const std::string& base, const std::string& format, const Grid<float>& grid,
                             const std::string& channelName) {
  if (format != "exr" && format != "tiff") throw std::invalid_argument("unknown image format '" + format + "'");
  WrittenImage result;
  result.path = base + (format == "exr" ? ".exr" : ".tif");
  if (!grid.empty()) {
    const auto [lo, hi] = std::minmax_element(grid.values().begin(), grid.values().end());
    result.minValue = *lo;
    result.maxValue = *hi;
  }
  writeAtomically(result.path, [&](const std::string& temp) {
    auto out = OIIO::ImageOutput::create(temp);
    if (!out) throw std::runtime_error("cannot create an image writer for " + result.path + ": " + OIIO::geterror());
    OIIO::ImageSpec spec(grid.width(), grid.height(), 1, OIIO::TypeDesc::FLOAT);
    spec.channelnames = {channelName};
    spec.attribute("oiio:ColorSpace", "Linear");
    spec.attribute("compression", format == "exr" ? "zip" : "zip");
    // Fixed metadata only: no time stamps, so the same bake gives the same bytes.
    spec.attribute("Software", "snowbake");
    spec.attribute("DateTime", "");  // OIIO would stamp the current time (EXR capDate, TIFF DateTime)
    if (!out->open(temp, spec) || !out->write_image(OIIO::TypeDesc::FLOAT, grid.data()) || !out->close())
      throw std::runtime_error("cannot write " + result.path + ": " + out->geterror());
  });
  return result;
}

Grid<float> readFloatImage(const std::string& path) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) throw std::runtime_error("cannot open " + path + ": " + OIIO::geterror());
  const OIIO::ImageSpec& spec = in->spec();
  Grid<float> grid(spec.width, spec.height);
  std::vector<float> all(static_cast<size_t>(spec.width) * spec.height * spec.nchannels);
  if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, all.data()))
    throw std::runtime_error("cannot read " + path + ": " + in->geterror());
  for (size_t i = 0; i < grid.size(); ++i) grid.values()[i] = all[i * spec.nchannels];
  return grid;
}

}  // namespace snow
