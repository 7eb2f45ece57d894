// Powder diffusion step (paper §5.3), run as five colour passes of the §7.1 cross tiling
// (colour = (x + 2y) mod 5): a cell of the active colour moves powder only into its own cross
// (itself and its four neighbours), and crosses of one colour never overlap, so no two threads
// write the same cell and no atomics are needed.
//
// Each substep first snapshots the surface A and the powder P (PowderSnapshotKernel). Every
// cell's outflows are computed from the snapshot alone, so the result does not depend on the
// order of the colour passes: without it, snow moved right in pass c could move right again in
// pass c + 1 of the same substep, a directional bias that draws streaks.
//
// The paper shifts toward each 4-neighbour n the share m_d = dt * k_m * max(0, s_d - s_d0),
// s_d = (A(p) - A(n)) / |p - n|. Read literally, that threshold is anisotropic: a slope of 0.7
// along a diagonal has axis components of 0.49 and never moves at s_d0 = 0.5, while the same
// slope along an axis does, and powder runs in axis-aligned streaks. We threshold the slope's
// magnitude instead: with S = |(max(s_+x, s_-x), max(s_+y, s_-y))| (downhill components only),
// the share leaving p is dt * k_m * (L_ref / dx_min) * max(0, S - s_d0), split among the downhill
// neighbours in proportion to s_d. On a slope along an axis this is exactly the paper's m_d.
// The paper sets k_m per event at 10 m cells; the factor L_ref / dx (L_ref = 10 m by default)
// turns it into a creep speed so that a 2 m and a 10 m run move the same distance of snow per
// day. Each cell pushes only outward (downhill): the uphill neighbour's own pass pushes toward
// it, which is the paper's incoming term. Two limits keep it stable:
//  - no single shift exceeds a fifth of the height difference, so even a cell shedding to all
//    four neighbours cannot end below them: no overshoot, no oscillation;
//  - the outflows are scaled so their sum never exceeds the snapshot P (the paper's rescaling:
//    no cell goes negative; a cell only gains snow before its own pass).
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
  float referenceCellSizeM = 10.f;
  int colour = 0;                // which of the five colour passes
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

// Copies A and P before the colour passes of a substep (per cell, no neighbour reads).
struct PowderSnapshotKernel {
  SnowFieldsView v;
  SNOW_HD void operator()(int x, int y) const {
    const int i = v.index(x, y);
    v.scratchSurface[i] = v.surface(i);
    v.scratchPowder[i] = v.powder[i];
  }
};

struct PowderDiffusionKernel {
  SnowFieldsView v;
  PowderDiffusionArgs a;

  SNOW_HD void operator()(int x, int y) const {
    const int i = v.index(x, y);
    if (!v.valid[i]) return;
    const float powder = v.scratchPowder[i];
    if (!(powder > 0.f)) return;
    const float ap = v.scratchSurface[i];
    const int dxs[4] = {1, -1, 0, 0};
    const int dys[4] = {0, 0, 1, -1};
    float drop[4] = {0.f, 0.f, 0.f, 0.f};   // height above each downhill neighbour
    float slope[4] = {0.f, 0.f, 0.f, 0.f};  // s_d where positive (downhill)
    for (int d = 0; d < 4; ++d) {
      const int nx = x + dxs[d], ny = y + dys[d];
      if (!v.isValid(nx, ny)) continue;
      const float dist = dxs[d] != 0 ? v.cellSizeXM : v.cellSizeYM;
      drop[d] = maxf(0.f, ap - v.scratchSurface[v.index(nx, ny)]);
      slope[d] = drop[d] / dist;
    }
    // Steepest descent, one component per axis: an isotropic measure of the slope that also
    // sees a lone peak (where central differences would read zero).
    const float sx = maxf(slope[0], slope[1]), sy = maxf(slope[2], slope[3]);
    const float steepest = sqrtf(sx * sx + sy * sy);
    const float excess = steepest - a.restSlope;
    const float weightSum = slope[0] + slope[1] + slope[2] + slope[3];
    if (!(excess > 0.f) || !(weightSum > 0.f)) return;
    const float minCell = minf(v.cellSizeXM, v.cellSizeYM);
    const float shareTotal = a.dtDays * a.diffusionRatePerDay * (a.referenceCellSizeM / minCell) * excess;
    float out[4] = {0.f, 0.f, 0.f, 0.f};
    float total = 0.f;
    for (int d = 0; d < 4; ++d) {
      if (!(slope[d] > 0.f)) continue;
      out[d] = minf(shareTotal * powder * (slope[d] / weightSum), 0.2f * drop[d]);
      total += out[d];
    }
    if (!(total > 0.f)) return;
    // When the outflows want more than the cell holds, they are scaled to all but a millionth
    // of it: the float sums of the shares then stay below the powder, so the source never
    // rounds below zero and needs no clamp (a clamp at zero adds a little snow each time, a
    // bias that adds up over a season).
    const bool empties = total >= powder;
    const float scale = empties ? powder / total * (1.f - 1e-6f) : 1.f;
    float remaining = v.powder[i];
    for (int d = 0; d < 4; ++d) {
      if (!(out[d] > 0.f)) continue;
      remaining = giveTo(v.powder[v.index(x + dxs[d], y + dys[d])], out[d] * scale, remaining, nullptr);
    }
    v.powder[i] = remaining;
  }
};

// Substeps so that a unit excess slope never moves more than a quarter of a cell's powder per
// direction in one pass: the step is stable for any event length and cell size.
SNOW_HD SNOW_INLINE int powderDiffusionSubsteps(float dtDays, float ratePerDay, float referenceCellSizeM,
                                                float minCellSizeM) {
  const float perStep = dtDays * ratePerDay * referenceCellSizeM / minCellSizeM;
  const float n = ceilf(perStep / 0.25f);
  return n < 1.f ? 1 : (n > 256.f ? 256 : static_cast<int>(n));
}

}  // namespace snow
