// OutputWriter's engine maps: the Unity RGBA splat map (the engine weights, summing to 255 in
// 8 bits) and the tangent-space normal map of the snow surface, both at the output size
// (outputs.resize, or the tiles' own) and tiled like every raster.
#include <algorithm>
#include <array>
#include <cmath>

#include "grid_writer.h"
#include "output_writer.h"

namespace snow {

namespace {
// Weights (summing to 1) as bytes summing to exactly 255: each floored, the rest given one by one
// to the largest remainders (ties to the lower channel), so no pixel is off by the rounding.
std::array<uint8_t, 3> bytesSummingTo255(const std::array<double, 3>& w) {
  std::array<uint8_t, 3> q{};
  std::array<double, 3> rest{};
  int sum = 0;
  for (int k = 0; k < 3; ++k) {
    const double v = std::clamp(w[k], 0.0, 1.0) * 255.0;
    q[k] = static_cast<uint8_t>(std::floor(v)), rest[k] = v - q[k], sum += q[k];
  }
  while (sum < 255) {
    const int k = static_cast<int>(std::max_element(rest.begin(), rest.end()) - rest.begin());
    ++q[k], rest[k] = -1.0, ++sum;
  }
  while (sum > 255) {  // weights summing past 1 by float error
    const int k = static_cast<int>(std::max_element(q.begin(), q.end()) - q.begin());
    --q[k], --sum;
  }
  return q;
}
}  // namespace

OutputWriter::Resampled OutputWriter::atSetSize(const RasterSet& set, const Grid<float>& g, const Grid<uint8_t>& valid, int marginPx) const {
  if (!set.resized()) return {g, valid, windowOf(g.width(), g.height())};
  return resampled(set.tiles, set.resizeWidth, set.resizeHeight, g, &valid, marginPx);
}

constexpr const char* kSplatFormat = "PNG, 4 channels uint8, linear weights: R snow, G rock, B ground, A 0; R + G + B = 255";

void OutputWriter::writeSplatMap(const Day& d, const RasterSet& set, const LayerInfo& layer) {
  const auto& out = scene_.outputs;
  if (src_.plan)
    return writeRgbRaster(set, baseOf(d), d.day, layer.name, set.resized() ? set.resizeWidth : d.s.spec.width,
                          set.resized() ? set.resizeHeight : d.s.spec.height, {}, layer.content, layer.unit, 4, kSplatFormat);
  LayerInputs in{&d.s, &scene_.params, &out};
  std::array<Grid<float>, 3> cells;
  const char* names[3] = {"weight_snow", "weight_rock", "weight_ground"};
  for (int k = 0; k < 3; ++k) cells[k] = findLayer(names[k])->compute(in);
  // At the set's size: resampled over one mask, or the weights themselves (moved, not copied).
  ResampledLayers r;
  if (set.resized()) {
    r = resampled(set.tiles, set.resizeWidth, set.resizeHeight, {&cells[0], &cells[1], &cells[2]}, &d.s.validCell);
  } else {
    for (Grid<float>& c : cells) r.pixels.push_back(std::move(c));
    r.valid = d.s.validCell, r.window = windowOf(d.s.spec.width, d.s.spec.height);
  }
  const std::vector<Grid<float>>& w = r.pixels;
  const Grid<uint8_t>& valid = r.valid;
  const ImageWindow& window = r.window;
  std::vector<uint8_t> rgba(valid.size() * 4, 0);
  for (size_t i = 0; i < valid.size(); ++i) {
    // NODATA: all ground, so the channels sum to 255 everywhere.
    const std::array<double, 3> weights = valid.values()[i] ? std::array<double, 3>{w[0].values()[i], w[1].values()[i], w[2].values()[i]}
                                                            : std::array<double, 3>{0.0, 0.0, 1.0};
    const auto q = bytesSummingTo255(weights);
    std::copy(q.begin(), q.end(), &rgba[i * 4]);
  }
  writeRgbRaster(set, baseOf(d), d.day, layer.name, window.width, window.height, rgba, layer.content, layer.unit, 4, kSplatFormat, &window);
}

void OutputWriter::writeNormalMap(const Day& d, const RasterSet& set, const LayerInfo& layer) {
  const auto& out = scene_.outputs;
  const std::string format = "PNG, 3 channels uint8, linear (not sRGB): n = 2 p / 255 - 1, tangent space (u east, v north), " + out.normalMapConvention;
  if (src_.plan)
    return writeRgbRaster(set, baseOf(d), d.day, layer.name, set.resized() ? set.resizeWidth : d.s.spec.width,
                          set.resized() ? set.resizeHeight : d.s.spec.height, {}, layer.content, layer.unit, 3, format);
  // With a pixel more around a resampled window's tiles, for their edge pixels' neighbours; a
  // pixel of the window's own edge, clamped there, lies in no tile the rank writes unless it is
  // the image's edge, clamped alike in the whole image.
  const Resampled r = atSetSize(set, findLayer("surface")->compute(LayerInputs{&d.s}), d.s.validCell, 1);
  const Grid<float>& surface = r.pixels;
  const Grid<uint8_t>& valid = r.valid;
  const int w = surface.width(), h = surface.height();
  const ImageWindow cells = windowOf(d.s.spec.width, d.s.spec.height);  // the whole grid's size
  const double dx = d.s.spec.cellSizeXM * cells.width / r.window.width, dy = d.s.spec.cellSizeYM * cells.height / r.window.height;
  const double green = out.normalMapConvention == "directx" ? -1.0 : 1.0;
  auto at = [&](int x, int y, int cx, int cy) {  // NODATA and the edge: the centre's height (flat)
    x = std::clamp(x, 0, w - 1), y = std::clamp(y, 0, h - 1);
    return valid(x, y) ? surface(x, y) : surface(cx, cy);
  };
  std::vector<uint8_t> rgb(static_cast<size_t>(w) * h * 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      // Tangent space of a height field with u east, v north: n = (-dz/dx, -dz/dnorth, 1) normalised.
      const double gx = (at(x + 1, y, x, y) - at(x - 1, y, x, y)) / (2 * dx), gNorth = (at(x, y - 1, x, y) - at(x, y + 1, x, y)) / (2 * dy);
      const double n = std::sqrt(gx * gx + gNorth * gNorth + 1.0);
      const double v[3] = {-gx / n, green * -gNorth / n, 1.0 / n};
      uint8_t* p = &rgb[(static_cast<size_t>(y) * w + x) * 3];
      for (int k = 0; k < 3; ++k) p[k] = static_cast<uint8_t>(std::lround(127.5 + 127.5 * v[k]));
    }
  writeRgbRaster(set, baseOf(d), d.day, layer.name, r.window.width, r.window.height, rgb, layer.content, layer.unit, 3, format, &r.window);
}

}  // namespace snow
