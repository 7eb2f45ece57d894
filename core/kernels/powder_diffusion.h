// Powder diffusion step (paper §5.3), run as five colour passes of the §7.1 cross tiling
// (colour = (x + 2y) mod 5): a cell of the active colour moves powder only into its own cross
// (itself and its four neighbours), and crosses of one colour never overlap, so no two threads
// write the same cell and no atomics are needed.
//
// For each 4-neighbour n of p, the slope s_d = (A(p) - A(n)) / |p - n| and the share of p's
// powder shifted toward n is m_d = dt * k_m * (L_ref / |p - n|) * max(0, s_d - s_d0).
// The paper sets k_m per event at 10 m cells; the factor L_ref / |p - n| (L_ref = 10 m by
// default) turns it into a creep speed so that a 2 m and a 10 m run move the same distance of
// snow per day. Each cell pushes only outward (downhill): the uphill neighbour's own pass
// pushes toward it, which is the paper's incoming term. Two limits keep it stable:
//  - no shift brings n's surface above the rest slope from p (half the excess height), so
//    snow never overshoots and oscillates;
//  - the outflows are scaled so their sum never exceeds P (the paper's rescaling: no cell
//    goes negative).
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

struct PowderDiffusionKernel {
  SnowFieldsView v;
  PowderDiffusionArgs a;

  SNOW_HD void operator()(int x, int y) const {
    const int i = v.index(x, y);
    if (!v.valid[i]) return;
    const float powder = v.powder[i];
    if (!(powder > 0.f)) return;
    const float ap = v.surface(i);
    const int dxs[4] = {1, -1, 0, 0};
    const int dys[4] = {0, 0, 1, -1};
    float out[4] = {0.f, 0.f, 0.f, 0.f};
    float total = 0.f;
    for (int d = 0; d < 4; ++d) {
      const int nx = x + dxs[d], ny = y + dys[d];
      if (!v.isValid(nx, ny)) continue;
      const float dist = dxs[d] != 0 ? v.cellSizeXM : v.cellSizeYM;
      const int n = v.index(nx, ny);
      const float drop = ap - v.surface(n);
      const float excess = drop - a.restSlope * dist;  // height above the rest slope
      if (!(excess > 0.f)) continue;
      const float share = a.dtDays * a.diffusionRatePerDay * (a.referenceCellSizeM / dist) * (excess / dist);
      out[d] = minf(share * powder, 0.5f * excess);
      total += out[d];
    }
    if (!(total > 0.f)) return;
    const float scale = total > powder ? powder / total : 1.f;
    float moved = 0.f;
    for (int d = 0; d < 4; ++d) {
      if (!(out[d] > 0.f)) continue;
      const float amount = out[d] * scale;
      const int n = v.index(x + dxs[d], y + dys[d]);
      v.powder[n] = v.powder[n] + amount;
      moved += amount;
    }
    v.powder[i] = maxf(0.f, powder - moved);
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
