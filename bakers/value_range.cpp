#include "value_range.h"

#include <algorithm>

namespace snow {

LayerRange rangeOf(const OutputRequest& outputs, const LayerInfo& layer) {
  const auto it = outputs.ranges.find(layer.name);
  if (it != outputs.ranges.end()) return it->second;
  LayerRange r;
  if (std::string(layer.unit) == "1") r.mode = RangeMode::Fixed, r.lo = 0.0, r.hi = 1.0;
  else r.mode = RangeMode::Season;
  return r;
}

const char* rangeModeName(RangeMode m) { return m == RangeMode::Own ? "own" : m == RangeMode::Season ? "season" : "fixed"; }

void SeenRange::widen(const Grid<float>& g, const Grid<uint8_t>* valid) {
  const bool masked = valid && valid->width() == g.width() && valid->height() == g.height();
  for (size_t i = 0; i < g.size(); ++i) {
    if (masked && !valid->values()[i]) continue;
    const double v = g.values()[i];
    lo = std::min(lo, v), hi = std::max(hi, v);
  }
}

}  // namespace snow
