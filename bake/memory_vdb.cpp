// The VDB term of the memory model (memory_vdb.h).
#include "memory_vdb.h"

#include <algorithm>
#include <cmath>

#include "bakers/vdb_writer.h"

namespace snow {

namespace {

// Snow assumed in a column where the scene's snow cannot be estimated (occlusion mode's cover,
// initial snow, edits, a painted snowfall multiplier, a terrain not yet known): 3 m everywhere.
constexpr double kVdbDepthM = 3.0;
// Measured: the VDB writer's peak per leaf slot (columns / 64 x leaf layers). The level set built
// whole, every column snowed: heaptrack, occlusion mode at 1024², 207 MB over 32768 slots. The
// level set it returns: the default preset at 2048² (20 days, a day-10 frame) built in tiles of
// 256 columns, 264 MiB against 539 MiB built whole (VmHWM against the same bake without a VDB).
constexpr double kVdbBytesPerLeafSlot = 6400.0, kVdbLevelSetBytesPerLeafSlot = 3050.0;

// The share of the whole construction's transient one tile of the level set holds
// (vdb_level_set.h): its columns with their halo over the grid's, each way at most 1.
double levelSetTileShare(double columnsI, double columnsJ) {
  const double tile = VdbOptions{}.levelSetTileColumns + 2.0 * levelSetHaloColumns(kSnowLevelSetHalfWidth);
  return std::min(1.0, tile / std::max(1.0, columnsI)) * std::min(1.0, tile / std::max(1.0, columnsJ));
}

double overlapDays(const std::vector<SnowfallPeriod>& periods, double day) {
  double d = 0;
  for (const auto& w : periods) d += std::max(0.0, std::min(w.endDay, day) - std::max(w.startDay, 0.0));
  return d;
}

// The snow cannot be estimated from the snowfall alone.
bool snowBeyondTheSnowfall(const Scene& s) {
  if (s.mode == SceneMode::Occlusion || !s.edits.empty() || s.multipliers.snowfall) return true;
  for (const auto& l : s.initialSnow)
    if (l.kind != InitialSnowLayer::Kind::None) return true;
  return false;
}

}  // namespace

SnowReach snowReachOf(const Grid<float>& heightsM, const Grid<uint8_t>& valid, double limit) {
  SnowReach r;
  r.known = true;
  double n = 0, excess = 0;
  const auto& h = heightsM.values();
  const auto& v = valid.values();
  for (size_t i = 0; i < h.size(); ++i)
    if (v[i] && h[i] > limit) ++n, excess += h[i] - limit;
  r.share = h.empty() ? 0.0 : n / static_cast<double>(h.size());
  r.meanExcessM = n > 0 ? excess / n : 0.0;
  return r;
}

SnowReach builtinSnowReach(const DefaultTerrainOptions& terrain, double limit) {
  DefaultTerrainOptions coarse = terrain;
  coarse.size = std::min(terrain.size, 256);
  coarse.cellSizeM = terrain.cellSizeM * terrain.size / coarse.size;
  const Grid<float> h = generateDefaultTerrain(coarse);
  return snowReachOf(h, Grid<uint8_t>(h.width(), h.height(), 1), limit);
}

double expectedSnowfallDays(const Scene& s, double day) {
  double d = overlapDays(s.userSnowfalls, day);
  if (!s.weather.snowfallPeriods.empty()) return d + overlapDays(s.weather.snowfallPeriods, day);
  const double a = s.params.snowfallStartsPerDay, b = 1.0 / s.params.snowfallMeanDurationDays;
  if (!(a > 0.0) || day <= 0.0) return d;
  const double k = a + b;
  return d + a / k * (day - (1.0 - std::exp(-k * day)) / k);
}

double vdbWriterBytes(const Scene& s, const GridSpec& spec, const SnowReach& reach, double day) {
  if (!s.outputs.vdb) return 0;
  const double vs = vdbVoxelSizeM(s.outputs.vdbVoxelSizeM, spec);
  const double columns = (spec.width * spec.cellSizeXM / vs) * (spec.height * spec.cellSizeYM / vs);
  double share = 1.0, depth = kVdbDepthM, occupied = 1.0;
  if (reach.known && !snowBeyondTheSnowfall(s)) {
    double intensity = s.weather.keyframes.empty() ? 1.0 : 0.0;
    for (const auto& k : s.weather.keyframes) intensity = std::max(intensity, k.state.snowfallIntensity);
    share = reach.share;
    depth = s.params.snowfallRatePerDay * intensity * reach.meanExcessM * expectedSnowfallDays(s, day);
    if (!(depth > 0.0)) return 0;
    // A column holds a voxel with probability depth / voxel; a leaf's 8 x 8 columns, if any does.
    occupied = 1.0 - std::pow(1.0 - std::min(1.0, depth / vs), 64.0);
  }
  const double leafLayers = std::ceil(depth / vs / 8.0) + 1.0;
  const double tileShare = levelSetTileShare(spec.width * spec.cellSizeXM / vs, spec.height * spec.cellSizeYM / vs);
  const double bytesPerSlot = kVdbLevelSetBytesPerLeafSlot + (kVdbBytesPerLeafSlot - kVdbLevelSetBytesPerLeafSlot) * tileShare;
  return columns / 64.0 * share * occupied * leafLayers * bytesPerSlot;
}

}  // namespace snow
