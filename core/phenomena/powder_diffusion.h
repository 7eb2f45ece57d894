// Powder diffusion step (paper §5.3), two per-cell passes a substep, so every cell moves snow at
// once (no colour passes, no atomics, nothing depends on the order cells are visited):
//  1. PowderFlowKernel: each cell's shares toward its four neighbours and what it keeps, from the
//     state at the substep's start, written to its own cell only;
//  2. PowderGatherKernel: each cell's powder becomes what it keeps plus what its neighbours give.
// Shares never see snow moved in the same substep, so snow cannot run on within a substep (a
// directional bias that draws streaks). The CPU runs both passes row by row over strips of the
// grid with the shares in cache (powder_diffusion_rows.h); the serial executor and CUDA run them
// one after the other over the whole grid.
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
//  - the outflows are scaled so their sum never exceeds P at the substep's start (the paper's
//    rescaling: no cell goes negative, whatever its neighbours give it).
// A powder film thinner than diffusion_min_depth_m (1 mm) does not slide: a dusting sticks to
// rock (and the CPU's row path skips a whole vector of cells where none holds more).
// Scratch: scratchSurface (the surface below the powder, PowderBaseKernel) and powderFlow (five
// shares a cell; the TBB executor keeps them in row buffers instead).
// Mass: snow never enters NODATA cells or leaves the grid, so the step conserves mass exactly up
// to float rounding.
// Backend: SnowBackend::powderDiffusion (ExecBackend runs runPowderDiffusion). Season:
// SeasonRun::addTransport (core/season.cpp). Parameters: the §5.3/§5.4 block of ModelParameters
// (core/parameters.h; scene keys in parameterTable, parameters.cpp).
#pragma once
#include <cmath>
#include <functional>
#include "../hd.h"
#include "../parameters.h"
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
// the source never goes negative and needs no clamp. `record`, if given, adds the gain. (Ski
// tracks give this way; powder diffusion's and wind transport's shares do the same against the
// receiver's powder at the step's start, powderSharesAt and windSharesAt.)
// Whether a gain can be given: positive, and not more than the source has left.
SNOW_HD SNOW_INLINE bool acceptedGain(float gained, float remaining) { return gained > 0.f && !(gained > remaining); }

SNOW_HD SNOW_INLINE float giveTo(float& receiver, float amount, float remaining, float* record) {
  const float before = receiver;
  const float after = before + amount;
  const float gained = after - before;
  if (!acceptedGain(gained, remaining)) return remaining;
  receiver = after;
  if (record) *record = *record + gained;
  return remaining - gained;
}

// The four neighbours in the order of the shares: +x, -x, +y, -y.
SNOW_HD SNOW_INLINE int powderDx(int d) { return d == 0 ? 1 : (d == 1 ? -1 : 0); }
SNOW_HD SNOW_INLINE int powderDy(int d) { return d == 2 ? 1 : (d == 3 ? -1 : 0); }

// The downhill slopes toward the four neighbours (drop / distance, 0 uphill) from a surface
// read through `surfaceAt(index)`, and the excess of the steepest-descent magnitude over the
// rest slope.
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
    const int dx = powderDx(d), dy = powderDy(d);
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

// Once a step, before its substeps: the snow surface without the powder, B + ((C + S) + U), which
// the substeps do not change, into scratchSurface (+inf at NODATA cells: a valid cell then sees
// no drop toward one, as the per-cell body's validity test leaves it). A substep reads the
// surface as that plus P.
struct PowderBaseKernel {
  SnowFieldsView v;
  SNOW_HD void operator()(int x, int y) const {
    const int i = v.index(x, y);
    v.scratchSurface[i] = v.valid[i] ? v.bedrock[i] + ((v.compacted[i] + v.stable[i]) + v.unstable[i]) : INFINITY;
  }
};
SNOW_HD SNOW_INLINE float powderSurface(const SnowFieldsView& v, int i) { return v.scratchSurface[i] + v.powder[i]; }

// Where the shares of a substep live: five floats a cell, the shares toward +x, -x, +y, -y and
// what the cell keeps.
SNOW_HD SNOW_INLINE int powderShareSlot(int i, int d) { return 5 * i + d; }
constexpr int kPowderKeepSlot = 4;

// Pass 1 of a substep at one cell, from the state at the substep's start only: the shares the
// cell gives its four neighbours and what it keeps. Each share is what the receiver gains when
// the share is added to what it held at the start, (P_n + a) - P_n, exact in float: a share far
// below a deep receiver's last bit stays at the source instead of vanishing (a bias that added
// up over long seasons). A share that rounding makes larger than what the source still has is
// not given, so the source never goes negative and needs no clamp.
SNOW_HD SNOW_INLINE void powderSharesAt(const SnowFieldsView& v, const PowderDiffusionArgs& a, int x, int y, float share[4],
                                        float& keep) {
  const int i = v.index(x, y);
  share[0] = share[1] = share[2] = share[3] = 0.f;
  const float powder = v.powder[i];
  keep = powder;
  if (!v.valid[i]) return;
  if (v.bedformActive && v.bedformActive[i]) return;  // the bedform model's repose relaxation holds it
  if (!(powder > a.minDepthM)) return;
  const SnowFieldsView& view = v;
  const PowderSlopes s = powderSlopes(v, x, y, a.restSlope, [&view](int j) { return powderSurface(view, j); });
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
  // of it: the float sums of the shares then stay below the powder (a clamp at zero would add
  // a little snow each time, a bias that adds up over a season).
  const float scale = total >= powder ? powder / total * (1.f - 1e-6f) : 1.f;
  float remaining = powder;
  for (int d = 0; d < 4; ++d) {
    const float amount = out[d] * scale;
    if (!(amount > 0.f)) continue;
    const float before = v.powder[v.index(x + powderDx(d), y + powderDy(d))];
    const float gained = (before + amount) - before;
    if (!acceptedGain(gained, remaining)) continue;
    share[d] = gained;
    remaining = remaining - gained;
  }
  keep = remaining;
}

// Pass 1, per cell (writes only its own cell's five slots).
struct PowderFlowKernel {
  SnowFieldsView v;
  PowderDiffusionArgs a;

  SNOW_HD void operator()(int x, int y) const {
    float share[4], keep;
    powderSharesAt(v, a, x, y, share, keep);
    const int i = v.index(x, y);
    for (int d = 0; d < 4; ++d) v.powderFlow[powderShareSlot(i, d)] = share[d];
    v.powderFlow[powderShareSlot(i, kPowderKeepSlot)] = keep;
  }
};

// What a cell holds after a substep: what it keeps plus its neighbours' shares, in this order
// (the CPU's row path adds its vectors in the same order).
SNOW_HD SNOW_INLINE float powderGathered(float keep, float fromPlusX, float fromMinusX, float fromPlusY, float fromMinusY) {
  return (((keep + fromPlusX) + fromMinusX) + fromPlusY) + fromMinusY;
}

// Pass 2, per cell, after pass 1 has run on every cell: a valid cell's powder becomes what it
// keeps plus the shares its four neighbours give it, added in a fixed order (+x, -x, +y, -y
// neighbour; nothing from beyond the grid). Reads pass 1's slots only, writes only its own cell.
struct PowderGatherKernel {
  SnowFieldsView v;

  SNOW_HD void operator()(int x, int y) const {
    const int i = v.index(x, y);
    if (!v.valid[i]) return;
    const float* f = v.powderFlow;
    const float fromPlusX = x + 1 < v.width ? f[powderShareSlot(i + 1, 1)] : 0.f;
    const float fromMinusX = x > 0 ? f[powderShareSlot(i - 1, 0)] : 0.f;
    const float fromPlusY = y + 1 < v.height ? f[powderShareSlot(i + v.width, 3)] : 0.f;
    const float fromMinusY = y > 0 ? f[powderShareSlot(i - v.width, 2)] : 0.f;
    v.powder[i] = powderGathered(f[powderShareSlot(i, kPowderKeepSlot)], fromPlusX, fromMinusX, fromPlusY, fromMinusY);
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

inline PowderDiffusionArgs makePowderDiffusionArgs(const ModelParameters& p, double dtDays) {
  PowderDiffusionArgs a;
  a.dtDays = static_cast<float>(dtDays);
  a.diffusionRatePerDay = static_cast<float>(p.diffusionRatePerDay);
  a.restSlope = static_cast<float>(p.diffusionRestSlope);
  a.diffusionLengthM = static_cast<float>(p.diffusionLengthM);
  a.minDepthM = static_cast<float>(p.diffusionMinDepthM);
  return a;
}

// `afterSubstep`, when set, runs after each substep (a distributed run refreshes the powder's halo
// there, so its halo need not grow with the substeps).
template <class Exec>
void runPowderDiffusion(Exec& exec, const SnowFieldsView& v, const PowderDiffusionArgs& a,
                        const std::function<void()>& afterSubstep = {}) {
  const float minCell = v.cellSizeXM < v.cellSizeYM ? v.cellSizeXM : v.cellSizeYM;
  const int substeps = powderDiffusionSubsteps(a.dtDays, a.diffusionRatePerDay, a.diffusionLengthM, minCell);
  PowderDiffusionArgs sub = a;
  sub.dtDays = a.dtDays / static_cast<float>(substeps);
  exec.forEachCell(v.width, v.height, PowderBaseKernel{v});
  // Each substep: every cell's shares from the state at the substep's start, then every cell
  // gathers what it keeps and what its neighbours give it. The TBB executor interleaves the two
  // passes row by row (powder_diffusion_rows.h); the others run them one after the other.
  for (int s = 0; s < substeps; ++s) {
    exec.forEachCellThen(v.width, v.height, PowderFlowKernel{v, sub}, PowderGatherKernel{v});
    if (afterSubstep) {
      exec.finish();
      afterSubstep();
    }
  }
}

}  // namespace snow
