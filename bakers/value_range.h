// How a layer's quantised encodings (png16, png8, r16) map its values to pixels: [outputs.ranges]
// or the layer kind's default. p = round((v - lo) / (hi - lo) * (2^bits - 1)), clamped to the
// pixel range; NODATA cells are left out of every range and written as pixel 0 (kNodataPixel).
#pragma once
#include <algorithm>
#include <limits>
#include <string>

#include "core/grid.h"
#include "scene/layers.h"
#include "scene/scene.h"

namespace snow {

constexpr int kNodataPixel = 0;

struct ValueMapping {
  RangeMode mode = RangeMode::Own;
  double lo = 0.0, hi = 0.0;
};

// The scene's range for `layer`, else its kind's default: [0, 1] for layers in unit 1 (masks and
// fractions, so 1 is full weight in an engine), "season" for the others (frames do not flicker).
LayerRange rangeOf(const OutputRequest& outputs, const LayerInfo& layer);
const char* rangeModeName(RangeMode m);

// A range of values seen so far (empty until the first).
struct SeenRange {
  double lo = std::numeric_limits<double>::infinity(), hi = -std::numeric_limits<double>::infinity();
  bool empty() const { return lo > hi; }
  // Widens to the valid cells of `grid` (all cells when `valid` is null or of another size).
  void widen(const Grid<float>& grid, const Grid<uint8_t>* valid);
  void widen(const SeenRange& o) { lo = std::min(lo, o.lo), hi = std::max(hi, o.hi); }
  // The mapping over this range ({0, 0} when empty: every pixel 0).
  ValueMapping mapping(RangeMode mode) const { return empty() ? ValueMapping{mode, 0.0, 0.0} : ValueMapping{mode, lo, hi}; }
};

}  // namespace snow
