// Powder diffusion step (paper §5.3), run as five colour passes of the §7.1 cross tiling
// (colour = (x + 2y) mod 5): a cell of the active colour moves powder only into its own cross
// (itself and its four neighbours), and crosses of one colour never overlap, so no two threads
// write the same cell and no atomics are needed.
//
// Each substep first computes every cell's outflows from the state at the substep's start
// (PowderFlowKernel, per cell, writing only its own cell), then gives them in the five colour
// passes (PowderGiveKernel). The outflows never see snow moved in the same substep, so the
// result does not depend on the order of the colour passes: otherwise snow moved right in pass c
// could move right again in pass c + 1, a directional bias that draws streaks.
//
// The paper shifts toward each 4-neighbour n the share m_d = dt * k_m * max(0, s_d - s_d0),
// s_d = (A(p) - A(n)) / |p - n|. Read literally, that threshold is anisotropic: a slope of 0.7
// along a diagonal has axis components of 0.49 and never moves at s_d0 = 0.5, while the same
// slope along an axis does, and powder runs in axis-aligned streaks. We threshold the slope's
// magnitude instead: with S = |(max(s_+x, s_-x), max(s_+y, s_-y))| (downhill components only),
// the share leaving p is dt * k_m * (L_d / dx_min) * max(0, S - s_d0), split among the downhill
// neighbours in proportion to s_d. On a slope along an axis this is exactly the paper's m_d.
// Read per cell, k_m would move powder k_m cells a day: 5 m at the paper's 10 m cells, 35 m at
// SRTM's 71 m. The factor L_d / dx turns it into a creep speed in world units, k_m * L_d metres a
// day per unit of excess slope, so a 2 m and a 10 m run move the same distance of snow per day.
// L_d = 400 m by default (200 m a day): loose powder sluffs off a steep face within a day or two
// and does not rest above its rest slope, as in the paper's results ("diffusion and avalanches
// clear steep slopes"); at the paper's 5 m a day the powder on a 300 m face outlasted the winter. Each cell pushes only outward (downhill): the uphill neighbour's own pass pushes toward
// it, which is the paper's incoming term. Two limits keep it stable:
//  - no single shift exceeds a fifth of the height difference, so even a cell shedding to all
//    four neighbours cannot end below them: no overshoot, no oscillation;
//  - the outflows are scaled so their sum never exceeds the snapshot P (the paper's rescaling:
//    no cell goes negative; a cell only gains snow before its own pass).
// A powder film thinner than diffusion_min_depth_m (1 mm) does not slide: a dusting sticks to
// rock, and the substeps skip whole 32 x 32 tiles where no cell holds powder above its rest
// slope (PowderActivityKernel), so the work follows the snow.
// Snow never enters NODATA cells or leaves the grid, so the step conserves mass exactly up to
// float rounding.
#pragma once
#include "../hd.h"
#include "../snow_state.h"

namespace snow {

struct PowderDiffusionArgs {
  float dtDays = 0.5f;           // time of this substep
  float diffusionRatePerDay = 0.5f;
  float restSlope = 0.5f;
  float diffusionLengthM = 400.f;  // L_d: creep speed k_m * L_d per unit of excess slope
  float minDepthM = 1e-3f;         // a powder film thinner than this does not slide
};

// Moves `amount` of snow from a source holding `remaining` into `receiver`, and returns what the
// source has left. Mass stays exact to rounding because the source gives what the receiver
// actually gained, (P_n + a) - P_n, which is exact in float: a share far below a deep receiver's
// last bit then stays at the source instead of vanishing (a bias that added up over long
// seasons). A gain that rounding makes larger than what the source still has is not made, so
// the source never goes negative and needs no clamp. `record`, if given, adds the gain.
SNOW_HD SNOW_INLINE float giveTo(float& receiver, float amount, float remaining, float* record) {
  const float before = receiver;
  const float after = before + amount;
  const float gained = after - before;
  if (!(gained > 0.f) || gained > remaining) return remaining;
  receiver = after;
  if (record) *record = *record + gained;
  return remaining - gained;
}

// The downhill slopes toward the four neighbours (drop / distance, 0 uphill) from a surface
// read through `surfaceAt(index)`, and the excess of the steepest-descent magnitude over the
// rest slope. Shared by the kernel and by the tile-activity scan, so a tile is skipped exactly
// when none of its cells would move powder.
struct PowderSlopes {
  float drop[4] = {0.f, 0.f, 0.f, 0.f};   // height above each downhill neighbour
  float slope[4] = {0.f, 0.f, 0.f, 0.f};  // s_d where positive (downhill)
  float excess = 0.f;
};

template <class SurfaceAt>
SNOW_HD SNOW_INLINE PowderSlopes powderSlopes(const SnowFieldsView& v, int x, int y, float restSlope, const SurfaceAt& surfaceAt) {
  PowderSlopes r;
  const float ap = surfaceAt(v.index(x, y));
  for (int d = 0; d < 4; ++d) {
    const int dx = d == 0 ? 1 : (d == 1 ? -1 : 0), dy = d == 2 ? 1 : (d == 3 ? -1 : 0);
    const int nx = x + dx, ny = y + dy;
    if (!v.isValid(nx, ny)) continue;
    // Times the reciprocal of the cell size, which the CPU's four-lane rows compute once a row
    // (powder_diffusion_rows.h) with the same result.
    const float perMetre = dx != 0 ? 1.f / v.cellSizeXM : 1.f / v.cellSizeYM;
    r.drop[d] = maxf(0.f, ap - surfaceAt(v.index(nx, ny)));
    r.slope[d] = r.drop[d] * perMetre;
  }
  // Steepest descent, one component per axis: an isotropic measure of the slope that also
  // sees a lone peak (where central differences would read zero).
  const float sx = maxf(r.slope[0], r.slope[1]), sy = maxf(r.slope[2], r.slope[3]);
  r.excess = sqrtf(sx * sx + sy * sy) - restSlope;
  return r;
}

// One thread per tile: is there a cell with powder above its rest slope? Reads the state the
// substep starts from, as the flow kernel does.
struct PowderActivityKernel {
  SnowFieldsView v;
  float restSlope;
  float minDepthM;
  SNOW_HD void operator()(int tx, int ty) const {
    const int x0 = tx * SnowFieldsView::kTileSize, y0 = ty * SnowFieldsView::kTileSize;
    const int x1 = minInt(x0 + SnowFieldsView::kTileSize, v.width), y1 = minInt(y0 + SnowFieldsView::kTileSize, v.height);
    uint8_t active = 0;
    const SnowFieldsView& view = v;
    for (int y = y0; y < y1 && !active; ++y)
      for (int x = x0; x < x1; ++x) {
        const int i = v.index(x, y);
        if (!v.valid[i] || !(v.powder[i] > minDepthM)) continue;
        if (powderSlopes(v, x, y, restSlope, [&view](int j) { return view.surface(j); }).excess > 0.f) {
          active = 1;
          break;
        }
      }
    v.tileActive[ty * v.tilesX() + tx] = active;
  }
};

// Runs `kernel` only on cells whose tile is flagged in `mask` (all cells when mask is null).
template <class K>
struct TileGated {
  K kernel;
  const uint8_t* mask;
  int tilesX;
  SNOW_HD void operator()(int x, int y) const {
    if (mask && !mask[(y >> SnowFieldsView::kTileShift) * tilesX + (x >> SnowFieldsView::kTileShift)]) return;
    kernel(x, y);
  }
};

// Copies A and P before the colour passes of a wind-transport step (per cell, no neighbour reads).
struct PowderSnapshotKernel {
  SnowFieldsView v;
  SNOW_HD void operator()(int x, int y) const {
    const int i = v.index(x, y);
    v.scratchSurface[i] = v.surface(i);
    v.scratchPowder[i] = v.powder[i];
  }
};

// Pass 1 of a substep, per cell (writes only its own cell): the outflows toward the four
// neighbours, from the state before any colour pass. Bit d of powderMoves[i] says whether
// powderFlow[4i + d] holds a share to give. Splitting the step this way lets the arithmetic run
// over contiguous rows (four cells at a time on the CPU, powder_diffusion_rows.h), and leaves
// the colour passes only the giving, which is what must follow the cross order.
struct PowderFlowKernel {
  SnowFieldsView v;
  PowderDiffusionArgs a;

  SNOW_HD void operator()(int x, int y) const {
    const int i = v.index(x, y);
    v.powderMoves[i] = 0;
    if (!v.valid[i]) return;
    if (v.bedformActive && v.bedformActive[i]) return;  // the bedform model's repose relaxation holds it
    const float powder = v.powder[i];
    if (!(powder > a.minDepthM)) return;
    const SnowFieldsView& view = v;
    const PowderSlopes s = powderSlopes(v, x, y, a.restSlope, [&view](int j) { return view.surface(j); });
    const float weightSum = s.slope[0] + s.slope[1] + s.slope[2] + s.slope[3];
    if (!(s.excess > 0.f) || !(weightSum > 0.f)) return;
    const float minCell = minf(v.cellSizeXM, v.cellSizeYM);
    const float shareTotal = a.dtDays * a.diffusionRatePerDay * (a.diffusionLengthM / minCell) * s.excess;
    // The share leaving toward d is (shareTotal * powder) * s_d / sum(s): one division a cell.
    const float perWeight = shareTotal * powder / weightSum;
    float out[4] = {0.f, 0.f, 0.f, 0.f};
    float total = 0.f;
    for (int d = 0; d < 4; ++d) {
      if (!(s.slope[d] > 0.f)) continue;
      out[d] = minf(perWeight * s.slope[d], 0.2f * s.drop[d]);
      total += out[d];
    }
    if (!(total > 0.f)) return;
    // When the outflows want more than the cell holds, they are scaled to all but a millionth
    // of it: the float sums of the shares then stay below the powder, so the source never
    // rounds below zero and needs no clamp (a clamp at zero adds a little snow each time, a
    // bias that adds up over a season).
    const bool empties = total >= powder;
    const float scale = empties ? powder / total * (1.f - 1e-6f) : 1.f;
    uint8_t moves = 0;
    for (int d = 0; d < 4; ++d) {
      if (!(out[d] > 0.f)) continue;
      v.powderFlow[4 * i + d] = out[d] * scale;
      moves = static_cast<uint8_t>(moves | (1u << d));
    }
    v.powderMoves[i] = moves;
  }
};

// Pass 2, one colour at a time: a cell of the colour gives its shares to its cross. The source
// gives from what it holds now (its own gains from earlier colours included), through giveTo.
struct PowderGiveKernel {
  SnowFieldsView v;

  SNOW_HD void operator()(int x, int y) const {
    const int i = v.index(x, y);
    const unsigned moves = v.powderMoves[i];
    if (!moves) return;
    float remaining = v.powder[i];
    for (int d = 0; d < 4; ++d) {
      if (!(moves & (1u << d))) continue;
      const int nx = x + (d == 0 ? 1 : (d == 1 ? -1 : 0)), ny = y + (d == 2 ? 1 : (d == 3 ? -1 : 0));
      remaining = giveTo(v.powder[v.index(nx, ny)], v.powderFlow[4 * i + d], remaining, nullptr);
    }
    v.powder[i] = remaining;
  }
};

// Substeps so that powder at a unit excess slope moves at most one cell per substep: the creep
// speed is then resolved up to the cap of 256 substeps. Stability does not depend on it (the
// shares are bounded by the powder there and by a fifth of each drop whatever the step).
SNOW_HD SNOW_INLINE int powderDiffusionSubsteps(float dtDays, float ratePerDay, float diffusionLengthM,
                                                float minCellSizeM) {
  const float perStep = dtDays * ratePerDay * diffusionLengthM / minCellSizeM;
  const float n = ceilf(perStep);
  return n < 1.f ? 1 : (n > 256.f ? 256 : static_cast<int>(n));
}

}  // namespace snow
