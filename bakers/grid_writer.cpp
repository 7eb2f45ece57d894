#include "grid_writer.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
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

void writeRgbPng(const std::string& path, int width, int height, const std::vector<uint8_t>& rgb) {
  writeAtomically(path, [&](const std::string& temp) {
    auto out = OIIO::ImageOutput::create("png");
    if (!out) throw std::runtime_error("cannot create a PNG writer for " + path + ": " + OIIO::geterror());
    OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
    spec.attribute("Software", "snowbake");
    spec.attribute("DateTime", "");
    if (!out->open(temp, spec) || !out->write_image(OIIO::TypeDesc::UINT8, rgb.data()) || !out->close())
      throw std::runtime_error("cannot write " + path + ": " + out->geterror());
  });
}

std::vector<uint8_t> avalanchePreviewRgb(const Grid<float>& a, const Grid<uint8_t>& valid, const Grid<float>& scour,
                                         const Grid<float>& deposit, double dx, double dy) {
  const int w = a.width(), h = a.height();
  std::vector<uint8_t> rgb(static_cast<size_t>(w) * h * 3, 0);
  const double lx = -0.5, ly = -0.5, lz = 0.7071;  // light from the north-west, 45 degrees up
  auto at = [&](int x, int y) { return static_cast<double>(a(std::clamp(x, 0, w - 1), std::clamp(y, 0, h - 1))); };
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (!valid(x, y)) continue;
      const double gx = (at(x + 1, y) - at(x - 1, y)) / (2 * dx), gy = (at(x, y + 1) - at(x, y - 1)) / (2 * dy);
      const double n = std::sqrt(gx * gx + gy * gy + 1.0);
      const double shade = std::clamp((-gx * lx - gy * ly + lz) / n, 0.0, 1.0);
      double r = 0.25 + 0.7 * shade, g = r, b = r;
      const double s = std::clamp(scour(x, y) / 1.0, 0.0, 1.0), d = std::clamp(deposit(x, y) / 2.0, 0.0, 1.0);
      r = r * (1 - s) + 0.9 * s, g = g * (1 - s) + 0.15 * s, b = b * (1 - s) + 0.1 * s;
      r = r * (1 - d) + 0.1 * d, g = g * (1 - d) + 0.35 * d, b = b * (1 - d) + 0.95 * d;
      uint8_t* p = &rgb[(static_cast<size_t>(y) * w + x) * 3];
      p[0] = static_cast<uint8_t>(std::lround(255 * r));
      p[1] = static_cast<uint8_t>(std::lround(255 * g));
      p[2] = static_cast<uint8_t>(std::lround(255 * b));
    }
  return rgb;
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
