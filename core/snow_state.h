// The layered snow model of the paper's §3.1 and §5: bedrock B and, on top of it, compacted C,
// stable S, unstable U and powdery P snow (each a depth in metres of snow), the avalanche
// "snow moving" flag, and the static fields that precompute fills once per terrain.
#pragma once
#include <cstdint>
#include <string>

#include "grid.h"
#include "hd.h"

namespace snow {

enum class SnowLayer : int { Compacted = 0, Stable = 1, Unstable = 2, Powder = 3 };
constexpr int kSnowLayerCount = 4;
inline const char* snowLayerName(SnowLayer l) {
  switch (l) {
    case SnowLayer::Compacted: return "compacted";
    case SnowLayer::Stable: return "stable";
    case SnowLayer::Unstable: return "unstable";
    case SnowLayer::Powder: return "powder";
  }
  return "?";
}

// Host-side state of one terrain: what the season evolves and what the bakers read.
struct SnowState {
  GridSpec spec;
  Grid<float> bedrockM;        // B: terrain altitude (metres above sea level)
  Grid<float> compactedM;      // C
  Grid<float> stableM;         // S
  Grid<float> unstableM;       // U
  Grid<float> powderM;         // P
  Grid<uint8_t> snowMoving;    // avalanche flag (§6.1): 1 where unstable snow is in motion
  Grid<uint8_t> validCell;     // 1 = simulated terrain, 0 = NODATA (no snow ever enters or leaves)
  // Static fields (precompute/): constant over the season for one wind and sun state.
  Grid<float> exposureHours;     // I = I_sun + I_sky + I_ind (hours of equivalent direct sun per day)
  Grid<float> temperatureBaseC;  // k_t*A + k_i*I: add the day's sea-level temperature T0 to get T
  Grid<float> windXMps;          // wind field W (east component)
  Grid<float> windYMps;          // wind field W (south component, +y = rows downward)
  Grid<float> windEffectZM;      // wind-effect surface altitude W_z
  Grid<float> windLoadingMps2;   // max(0, W . grad W_sz): where wind loading destabilises snow
  // Records for the bakers, accumulated over the season (metres of snow).
  Grid<float> windScourM;        // removed by wind transport
  Grid<float> windDepositM;      // deposited by wind transport
  Grid<float> meltedM;           // removed by melt
  Grid<float> avalancheScourM;   // taken away by avalanches (net per avalanche)
  Grid<float> avalancheDepositM; // left by avalanches (net per avalanche)
  // Art direction (the scene's [multipliers], mapped from painted rasters): per-cell factors on
  // a phenomenon; an empty grid means 1 everywhere. noSnow: 1 where snow is never allowed
  // (roads, buildings, rivers): the season treats those cells as outside the snow domain.
  Grid<float> snowfallFactor;
  Grid<float> meltFactor;
  Grid<float> windErosionFactor;
  Grid<float> avalancheReleaseFactor;  // host only: spontaneous release probability
  Grid<float> skierSpawnFactor;        // host only: where automatic skiers start
  Grid<uint8_t> noSnow;
  // Wind bedforms (kernels/bedform.h): 1 where the slab-saltation model runs (empty: everywhere),
  // and the snow's cohesion there (0 loose .. 1 bonded; filled by download once bedforms ran).
  Grid<uint8_t> bedformMask;
  Grid<float> bedformCohesion;

  // Allocates every field for `s`, snow layers zero, all cells valid, static fields zero.
  void allocate(const GridSpec& s) {
    spec = s;
    const int w = s.width, h = s.height;
    bedrockM.resize(w, h, 0.f);
    compactedM.resize(w, h, 0.f);
    stableM.resize(w, h, 0.f);
    unstableM.resize(w, h, 0.f);
    powderM.resize(w, h, 0.f);
    snowMoving.resize(w, h, 0);
    validCell.resize(w, h, 1);
    exposureHours.resize(w, h, 0.f);
    temperatureBaseC.resize(w, h, 0.f);
    windXMps.resize(w, h, 0.f);
    windYMps.resize(w, h, 0.f);
    windEffectZM.resize(w, h, 0.f);
    windLoadingMps2.resize(w, h, 0.f);
    windScourM.resize(w, h, 0.f);
    windDepositM.resize(w, h, 0.f);
    meltedM.resize(w, h, 0.f);
    avalancheScourM.resize(w, h, 0.f);
    avalancheDepositM.resize(w, h, 0.f);
  }
  Grid<float>& layer(SnowLayer l) {
    switch (l) {
      case SnowLayer::Compacted: return compactedM;
      case SnowLayer::Stable: return stableM;
      case SnowLayer::Unstable: return unstableM;
      case SnowLayer::Powder: return powderM;
    }
    return powderM;
  }
  const Grid<float>& layer(SnowLayer l) const { return const_cast<SnowState*>(this)->layer(l); }
  float depthM(int x, int y) const { return compactedM(x, y) + stableM(x, y) + unstableM(x, y) + powderM(x, y); }
  // C + S + U + P of every cell (NODATA cells included, as stored).
  Grid<float> depthGrid() const {
    Grid<float> d(spec.width, spec.height, 0.f);
    for (int y = 0; y < spec.height; ++y)
      for (int x = 0; x < spec.width; ++x) d(x, y) = depthM(x, y);
    return d;
  }
};

// What kernels see: plain pointers into the backend's storage (host or device memory).
struct SnowFieldsView {
  int width = 0;
  int height = 0;
  float cellSizeXM = 1.f;
  float cellSizeYM = 1.f;
  float* bedrock = nullptr;
  float* compacted = nullptr;
  float* stable = nullptr;
  float* unstable = nullptr;
  float* powder = nullptr;
  uint8_t* moving = nullptr;
  const uint8_t* valid = nullptr;
  const float* exposure = nullptr;
  const float* temperatureBase = nullptr;
  const float* windX = nullptr;
  const float* windY = nullptr;
  const float* windEffectZ = nullptr;
  const float* windLoading = nullptr;
  float* windScour = nullptr;
  float* windDeposit = nullptr;
  float* melted = nullptr;
  // Art-direction factors (null: 1 everywhere) and a per-cell weight for timeline edits.
  const float* snowfallFactor = nullptr;
  const float* meltFactor = nullptr;
  const float* windErosionFactor = nullptr;
  const float* editWeight = nullptr;
  // The wind bedforms' domain at their last step (null: no bedforms yet): the layered wind
  // transport and powder diffusion leave these cells to the slab model (its saltation and repose).
  const uint8_t* bedformActive = nullptr;
  float* delta = nullptr;  // per-cell scratch: snow volume changed by the last step (for the mass ledger)
  // Per-cell scratch: |grad A| of the snow surface, taken before a per-cell pass that changes A,
  // so the pass never reads a neighbour that another thread is writing.
  float* surfaceSlope = nullptr;
  // Per-cell scratch for transport: wind transport's snapshot of A and P before its colour
  // passes; powder diffusion's surface below the powder in scratchSurface; the avalanche's
  // outflow scales in scratchPowder.
  float* scratchSurface = nullptr;
  float* scratchPowder = nullptr;
  // Powder diffusion's shares of a substep: five per cell (toward +x, -x, +y, -y, and what the
  // cell keeps; powder_diffusion.h).
  float* powderFlow = nullptr;
  // Avalanches: four signed pipe flows per cell (m^3/s), U + P at release, the records, and four
  // floats per row of statistics for the host.
  float* flows = nullptr;
  float* avalancheBefore = nullptr;
  double* avalancheU = nullptr;  // during an avalanche: U in double (the float layer is its rounding)
  float* avalancheScour = nullptr;
  float* avalancheDeposit = nullptr;
  float* rowStats = nullptr;

  SNOW_HD SNOW_INLINE bool inside(int x, int y) const { return x >= 0 && y >= 0 && x < width && y < height; }
  SNOW_HD SNOW_INLINE int index(int x, int y) const { return y * width + x; }
  SNOW_HD SNOW_INLINE bool isValid(int x, int y) const { return inside(x, y) && valid[index(x, y)] != 0; }
  SNOW_HD SNOW_INLINE float snowDepth(int i) const { return compacted[i] + stable[i] + unstable[i] + powder[i]; }
  // A = B + C + S + U + P: the snow-surface altitude used at run time.
  SNOW_HD SNOW_INLINE float surface(int i) const { return bedrock[i] + snowDepth(i); }
};

}  // namespace snow
