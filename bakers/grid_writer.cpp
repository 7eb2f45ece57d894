#include "grid_writer.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <fstream>
#include <stdexcept>

#include "core/atomic_file.h"

namespace snow {

namespace {
// libpng tries all five row filters on every row by default, which at the fast deflate levels
// costs more than the deflate: at levels up to 3 the rows take the "sub" filter alone (measured
// on a 1024² season's layers: 25-55 % less time, files 0-10 % larger); higher levels keep
// libpng's adaptive choice, for the smallest files.
void setPngFilter(OIIO::ImageSpec& spec, int compressionLevel) {
  constexpr int kPngFilterSub = 0x10;  // PNG_FILTER_SUB
  if (compressionLevel <= 3) spec.attribute("png:filter", kPngFilterSub);
}
}  // namespace

// OpenEXR's zip with a level ("zip:N", honoured since OpenEXR 3.1.3), or none at level 0.
std::string exrCompressionName(int level) { return level <= 0 ? "none" : "zip:" + std::to_string(level > 9 ? 9 : level); }

WrittenImage writeFloatImage(const std::string& base, const std::string& format, const Grid<float>& grid,
                             const std::string& layerName, int compressionLevel) {
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
    // One greyscale channel "Y": what Blender, Nuke, Houdini and Terragen read from a
    // single-channel image (Blender ignores a channel named otherwise and loads zeros); the
    // layer's name goes into the metadata.
    spec.channelnames = {"Y"};
    spec.attribute("snowbake:layer", layerName);
    spec.attribute("ImageDescription", "snowbake layer: " + layerName);
    spec.attribute("oiio:ColorSpace", "Linear");
    spec.attribute("compression", format == "exr" ? exrCompressionName(compressionLevel) : "zip");
    // Fixed metadata only: no time stamps, so the same bake gives the same bytes.
    spec.attribute("Software", "snowbake");
    spec.attribute("DateTime", "");  // OIIO would stamp the current time (EXR capDate, TIFF DateTime)
    if (!out->open(temp, spec) || !out->write_image(OIIO::TypeDesc::FLOAT, grid.data()) || !out->close())
      throw std::runtime_error("cannot write " + result.path + ": " + out->geterror());
  });
  return result;
}

void writeRawFloat32(const std::string& path, const Grid<float>& grid) {
  static_assert(std::endian::native == std::endian::little, "r32 is written as the machine's floats");
  writeAtomically(path, [&](const std::string& temp) {
    std::ofstream out(temp, std::ios::binary);
    out.write(reinterpret_cast<const char*>(grid.data()), static_cast<std::streamsize>(grid.size() * sizeof(float)));
    if (!out) throw std::runtime_error("cannot write " + path);
  });
}

std::string encodingExtension(const std::string& encoding) {
  if (encoding == "png16") return ".16.png";
  if (encoding == "png8") return ".8.png";
  if (encoding == "r16") return ".r16";
  throw std::invalid_argument("unknown encoding '" + encoding + "'");
}

namespace {
// std::lround for v >= 0, without the library call: v - trunc(v) is exact in double. NaN gives 0
// (as lround's LONG_MIN did once cast to a pixel).
long roundHalfUp(double v) {
  if (!(v >= 0.0)) return 0;
  const long r = static_cast<long>(v);
  return r + (v - static_cast<double>(r) >= 0.5 ? 1 : 0);
}
}  // namespace

std::vector<uint16_t> quantisedPixels(const std::string& encoding, const Grid<float>& grid, const Grid<uint8_t>* valid, double lo,
                                      double hi, int nodataPixel) {
  encodingExtension(encoding);  // refuses an unknown encoding
  const double levels = encoding == "png8" ? 255.0 : 65535.0, span = hi - lo;
  const bool masked = valid && valid->width() == grid.width() && valid->height() == grid.height();
  std::vector<uint16_t> pixels(grid.size());
  for (size_t i = 0; i < grid.size(); ++i) {
    if (masked && !valid->values()[i]) pixels[i] = static_cast<uint16_t>(nodataPixel);
    else if (!(span > 0.0)) pixels[i] = 0;
    else pixels[i] = static_cast<uint16_t>(roundHalfUp(std::clamp((static_cast<double>(grid.values()[i]) - lo) / span, 0.0, 1.0) * levels));
  }
  return pixels;
}

void writeQuantisedPixels(const std::string& path, const std::string& encoding, int width, int height, const uint16_t* pixels,
                          int compressionLevel) {
  encodingExtension(encoding);
  const size_t n = static_cast<size_t>(width) * height;
  writeAtomically(path, [&](const std::string& temp) {
    if (encoding == "r16") {
      std::string bytes(n * 2, '\0');
      for (size_t i = 0; i < n; ++i) {
        bytes[2 * i] = static_cast<char>(pixels[i] & 0xff);
        bytes[2 * i + 1] = static_cast<char>(pixels[i] >> 8);
      }
      std::ofstream out(temp, std::ios::binary);
      out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
      if (!out) throw std::runtime_error("cannot write " + path);
      return;
    }
    const bool eight = encoding == "png8";
    auto out = OIIO::ImageOutput::create("png");
    if (!out) throw std::runtime_error("cannot create a PNG writer for " + path + ": " + OIIO::geterror());
    OIIO::ImageSpec spec(width, height, 1, eight ? OIIO::TypeDesc::UINT8 : OIIO::TypeDesc::UINT16);
    spec.attribute("oiio:ColorSpace", "Linear");
    spec.attribute("png:compressionLevel", compressionLevel);
    setPngFilter(spec, compressionLevel);
    spec.attribute("Software", "snowbake");
    spec.attribute("DateTime", "");
    std::vector<uint8_t> narrow(eight ? n : 0);
    for (size_t i = 0; i < narrow.size(); ++i) narrow[i] = static_cast<uint8_t>(pixels[i]);
    const bool ok = out->open(temp, spec) &&
                    (eight ? out->write_image(OIIO::TypeDesc::UINT8, narrow.data()) : out->write_image(OIIO::TypeDesc::UINT16, pixels)) &&
                    out->close();
    if (!ok) throw std::runtime_error("cannot write " + path + ": " + out->geterror());
  });
}

void writeQuantised(const std::string& path, const std::string& encoding, const Grid<float>& grid, const Grid<uint8_t>* valid,
                    double lo, double hi, int nodataPixel, int compressionLevel) {
  const std::vector<uint16_t> pixels = quantisedPixels(encoding, grid, valid, lo, hi, nodataPixel);
  writeQuantisedPixels(path, encoding, grid.width(), grid.height(), pixels.data(), compressionLevel);
}

WrittenImage writeNormalised(const std::string& base, const std::string& encoding, const Grid<float>& grid, int compressionLevel) {
  WrittenImage result;
  result.path = base + encodingExtension(encoding);
  if (!grid.empty()) {
    const auto [lo, hi] = std::minmax_element(grid.values().begin(), grid.values().end());
    result.minValue = *lo;
    result.maxValue = *hi;
  }
  writeQuantised(result.path, encoding, grid, nullptr, result.minValue, result.maxValue, 0, compressionLevel);
  return result;
}

std::string normalisedFormat(const std::string& encoding, int width, int height) {
  // min and max: the file's mapping (the manifest's range: its lo and hi); NODATA cells are pixel 0.
  const std::string mapping = ": value = min + (max - min) * p / " + std::string(encoding == "png8" ? "255" : "65535");
  if (encoding == "png16") return "PNG, 1 channel uint16, linear" + mapping;
  if (encoding == "png8") return "PNG, 1 channel uint8, linear" + mapping;
  return "raw uint16 little-endian, " + std::to_string(width) + " x " + std::to_string(height) + ", row 0 north, no header" + mapping;
}

Grid<float> resampleBilinear(const Grid<float>& g, int width, int height) {
  return resampleBilinear(g, ResampleWindow{CellRect{0, 0, g.width(), g.height()}, g.width(), g.height(), CellRect{0, 0, width, height}, width, height});
}

Grid<float> resampleValid(const Grid<float>& g, const Grid<uint8_t>& valid, int width, int height, Grid<uint8_t>& validOut) {
  return resampleValid(g, valid,
                       ResampleWindow{CellRect{0, 0, g.width(), g.height()}, g.width(), g.height(), CellRect{0, 0, width, height}, width, height},
                       validOut);
}

namespace {
// Pixel x's position in the grid's cells (cell centres at integers), as both resamplers take it.
double sourceCoordinate(int x, int cells, int pixels) { return (x + 0.5) * cells / pixels - 0.5; }
}  // namespace

Grid<float> resampleBilinear(const Grid<float>& held, const ResampleWindow& w) {
  Grid<float> out(w.to.width(), w.to.height(), 0.f);
  const int sw = w.fromWidth, sh = w.fromHeight;
  auto at = [&](int i, int j) { return static_cast<double>(held(i - w.from.x0, j - w.from.y0)); };
  for (int y = w.to.y0; y < w.to.y1; ++y)
    for (int x = w.to.x0; x < w.to.x1; ++x)
      out(x - w.to.x0, y - w.to.y0) = static_cast<float>(sampleBilinearClamped(sw, sh, sourceCoordinate(x, sw, w.width), sourceCoordinate(y, sh, w.height), at));
  return out;
}

Grid<float> resampleValid(const Grid<float>& held, const Grid<uint8_t>& heldValid, const ResampleWindow& w, Grid<uint8_t>& validOut) {
  Grid<float> out(w.to.width(), w.to.height(), 0.f);
  validOut = Grid<uint8_t>(w.to.width(), w.to.height(), 0);
  const int sw = w.fromWidth, sh = w.fromHeight;
  auto g = [&](int i, int j) { return held(i - w.from.x0, j - w.from.y0); };
  auto valid = [&](int i, int j) { return heldValid(i - w.from.x0, j - w.from.y0); };
  for (int y = w.to.y0; y < w.to.y1; ++y)
    for (int x = w.to.x0; x < w.to.x1; ++x) {
      const double fx = sourceCoordinate(x, sw, w.width), fy = sourceCoordinate(y, sh, w.height);
      const int nx = std::clamp(static_cast<int>(std::lround(fx)), 0, sw - 1), ny = std::clamp(static_cast<int>(std::lround(fy)), 0, sh - 1);
      if (!valid(nx, ny)) continue;
      const int x0 = static_cast<int>(std::floor(fx)), y0 = static_cast<int>(std::floor(fy));
      const double tx = fx - x0, ty = fy - y0;
      double sum = 0, weight = 0;
      for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i) {
          const int cx = std::clamp(x0 + i, 0, sw - 1), cy = std::clamp(y0 + j, 0, sh - 1);
          const double wt = (i ? tx : 1 - tx) * (j ? ty : 1 - ty);
          if (valid(cx, cy)) sum += wt * g(cx, cy), weight += wt;
        }
      validOut(x - w.to.x0, y - w.to.y0) = 1;
      out(x - w.to.x0, y - w.to.y0) = static_cast<float>(weight > 0 ? sum / weight : g(nx, ny));
    }
  return out;
}

std::pair<int, int> cellsReadBy(int firstPixel, int lastPixel, int pixels, int cells) {
  if (lastPixel <= firstPixel) return {0, 0};
  // c grows with the pixel. resampleValid reads floor(c) and floor(c) + 1 (and the nearest, one of
  // them), each clamped to the grid; resampleBilinear clamps c first, then reads its floor and the
  // next cell, even at a weight of 0 (a pixel before the first cell's centre reads cells 0 and 1).
  const int lo = std::clamp(static_cast<int>(std::floor(sourceCoordinate(firstPixel, cells, pixels))), 0, cells - 1);
  const int last = std::clamp(static_cast<int>(std::floor(sourceCoordinate(lastPixel - 1, cells, pixels))), 0, cells - 1);
  return {lo, std::min(last + 1, cells - 1) + 1};
}

CellRect cellsReadBy(const CellRect& pixels, int width, int height, int cellsWide, int cellsHigh) {
  if (pixels.empty()) return CellRect{};
  const auto [x0, x1] = cellsReadBy(pixels.x0, pixels.x1, width, cellsWide);
  const auto [y0, y1] = cellsReadBy(pixels.y0, pixels.y1, height, cellsHigh);
  return CellRect{x0, y0, x1, y1};
}

void writeMultiChannelExr(const std::string& path, const std::vector<std::string>& names, const std::vector<const Grid<float>*>& grids,
                          int compressionLevel) {
  if (grids.empty()) return;
  const int w = grids[0]->width(), h = grids[0]->height(), n = static_cast<int>(grids.size());
  std::vector<float> interleaved(static_cast<size_t>(w) * h * n);
  for (int c = 0; c < n; ++c)
    for (size_t i = 0; i < grids[c]->size(); ++i) interleaved[i * n + c] = grids[c]->values()[i];
  writeAtomically(path, [&](const std::string& temp) {
    auto out = OIIO::ImageOutput::create(path);
    if (!out) throw std::runtime_error("cannot create an EXR writer for " + path + ": " + OIIO::geterror());
    OIIO::ImageSpec spec(w, h, n, OIIO::TypeDesc::FLOAT);
    // "<layer>.Y": each layer an EXR layer with one greyscale channel, which Blender reads as
    // render passes named after the layers (the compositor's Image node), Nuke as layers and
    // Houdini as planes. A bare "<layer>" channel name is ignored by Blender.
    spec.channelnames.clear();
    for (const auto& n : names) spec.channelnames.push_back(n + ".Y");
    spec.alpha_channel = -1;
    spec.attribute("oiio:ColorSpace", "Linear");
    spec.attribute("compression", exrCompressionName(compressionLevel));
    spec.attribute("Software", "snowbake");
    spec.attribute("DateTime", "");
    if (!out->open(temp, spec) || !out->write_image(OIIO::TypeDesc::FLOAT, interleaved.data()) || !out->close())
      throw std::runtime_error("cannot write " + path + ": " + out->geterror());
  });
}

void writeRgbPng(const std::string& path, int width, int height, const std::vector<uint8_t>& rgb, int compressionLevel) {
  writePng8(path, width, height, 3, rgb, compressionLevel);
}

void writePng8(const std::string& path, int width, int height, int channels, const std::vector<uint8_t>& pixels, int compressionLevel) {
  writeAtomically(path, [&](const std::string& temp) {
    auto out = OIIO::ImageOutput::create("png");
    if (!out) throw std::runtime_error("cannot create a PNG writer for " + path + ": " + OIIO::geterror());
    OIIO::ImageSpec spec(width, height, channels, OIIO::TypeDesc::UINT8);
    if (channels == 4) spec.alpha_channel = -1, spec.attribute("oiio:UnassociatedAlpha", 1);  // weights, not colour with alpha
    spec.attribute("png:compressionLevel", compressionLevel);
    setPngFilter(spec, compressionLevel);
    spec.attribute("Software", "snowbake");
    spec.attribute("DateTime", "");
    if (!out->open(temp, spec) || !out->write_image(OIIO::TypeDesc::UINT8, pixels.data()) || !out->close())
      throw std::runtime_error("cannot write " + path + ": " + out->geterror());
  });
}

namespace {
// Lambert term of the surface under a light from `toLight` (unit vector x east, y north, z up),
// from central differences; `at(x, y)` clamps at the edges. Not clamped to [0, 1].
template <class SurfaceAt>
double lambert(const SurfaceAt& at, int x, int y, double dx, double dy, const double toLight[3]) {
  const double gx = (at(x + 1, y) - at(x - 1, y)) / (2 * dx), gNorth = (at(x, y - 1) - at(x, y + 1)) / (2 * dy);
  const double n = std::sqrt(gx * gx + gNorth * gNorth + 1.0);
  return (-gx * toLight[0] - gNorth * toLight[1] + toLight[2]) / n;
}
}  // namespace

std::vector<uint8_t> avalanchePreviewRgb(const Grid<float>& a, const Grid<uint8_t>& valid, const Grid<float>& scour,
                                         const Grid<float>& deposit, double dx, double dy) {
  const int w = a.width(), h = a.height();
  std::vector<uint8_t> rgb(static_cast<size_t>(w) * h * 3, 0);
  const double fromNorthWest[3] = {-0.5, 0.5, 0.7071};  // 45 degrees up
  auto at = [&](int x, int y) { return static_cast<double>(a(std::clamp(x, 0, w - 1), std::clamp(y, 0, h - 1))); };
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (!valid(x, y)) continue;
      const double shade = std::clamp(lambert(at, x, y, dx, dy, fromNorthWest), 0.0, 1.0);
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

AltitudeRange bedrockRange(const SnowState& s) {
  AltitudeRange r;
  for (size_t i = 0; i < s.bedrockM.size(); ++i)
    if (s.validCell.values()[i]) r.lo = std::min(r.lo, s.bedrockM.values()[i]), r.hi = std::max(r.hi, s.bedrockM.values()[i]);
  return r;
}

std::vector<uint8_t> snowPreviewRgb(const SnowState& s, const double sun[3], const AltitudeRange& altitudes) {
  const int w = s.spec.width, h = s.spec.height;
  std::vector<uint8_t> rgb(static_cast<size_t>(w) * h * 3, 0);
  const float lo = altitudes.lo, hi = altitudes.hi;
  auto surface = [&](int x, int y) {
    x = std::clamp(x, 0, w - 1), y = std::clamp(y, 0, h - 1);
    return static_cast<double>(s.bedrockM(x, y)) + s.depthM(x, y);
  };
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (!s.validCell(x, y)) continue;
      const double lit = std::max(0.0, lambert(surface, x, y, s.spec.cellSizeXM, s.spec.cellSizeYM, sun));
      const double light = 0.35 + 0.75 * lit;
      double c[3];
      const double depth = s.depthM(x, y);
      if (depth > 0.01) {
        const double* tint;
        static const double powder[3] = {1.0, 1.0, 1.0}, unstable[3] = {0.85, 0.92, 1.0}, stable[3] = {0.97, 0.95, 0.88},
                            compacted[3] = {0.78, 0.78, 0.80};
        tint = s.powderM(x, y) > 0.005f ? powder : s.unstableM(x, y) > 0.005f ? unstable : s.stableM(x, y) > 0.005f ? stable : compacted;
        for (int k = 0; k < 3; ++k) c[k] = tint[k] * 0.92;
      } else {
        const double t = hi > lo ? (s.bedrockM(x, y) - lo) / (hi - lo) : 0.0;
        static const double low[3] = {0.30, 0.45, 0.22}, mid[3] = {0.45, 0.36, 0.25}, top[3] = {0.55, 0.53, 0.50};
        for (int k = 0; k < 3; ++k) c[k] = t < 0.5 ? low[k] + (mid[k] - low[k]) * t * 2 : mid[k] + (top[k] - mid[k]) * (t - 0.5) * 2;
      }
      uint8_t* p = &rgb[(static_cast<size_t>(y) * w + x) * 3];
      for (int k = 0; k < 3; ++k) {
        const double linear = std::clamp(c[k] * light, 0.0, 1.0);
        const double srgb = linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1 / 2.4) - 0.055;
        p[k] = static_cast<uint8_t>(std::lround(255 * srgb));
      }
    }
  return rgb;
}

std::vector<uint8_t> contactSheetRgb(const std::vector<std::vector<uint8_t>>& images, int w, int h, int columns, int& sw, int& sh) {
  const int gap = 4, n = static_cast<int>(images.size());
  columns = std::max(1, std::min(columns, n));
  const int rows = (n + columns - 1) / columns;
  sw = columns * w + (columns + 1) * gap;
  sh = rows * h + (rows + 1) * gap;
  std::vector<uint8_t> sheet(static_cast<size_t>(sw) * sh * 3, 96);
  for (int k = 0; k < n; ++k) {
    const int ox = gap + (k % columns) * (w + gap), oy = gap + (k / columns) * (h + gap);
    for (int y = 0; y < h; ++y)
      std::copy_n(&images[k][static_cast<size_t>(y) * w * 3], static_cast<size_t>(w) * 3, &sheet[(static_cast<size_t>(oy + y) * sw + ox) * 3]);
  }
  return sheet;
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
