// The avalanche's shallow-water flow (season.avalanche_flow = "shallow_water"): the moving snow
// as a depth-averaged layer whose momentum moves with it, in place of the paper's pipes, whose
// momentum stays in eight fixed directions (docs/models/avalanches.md says why it was built).
//
// State: the moving snow's depth h = U of a moving cell (snow at rest is bed: it does not flow)
// and its momentum per area (h u, h w) in flows[4 i + 0, 1] (m^2/s, east and south);
// flows[4 i + 2, 3] hold the substep's accelerated momentum between the passes. First order,
// finite volume, three passes a substep over the box's row spans, the velocity updated before the
// snow moves with it (semi-implicit Euler: the surface's waves do not grow):
//   1. AvalancheWaterMomentumKernel: on each cell that can send snow (avalancheSource), the
//      surface's pull -g h grad A (the minmod of the one-sided slopes, waterSlope; A = B + C + S +
//      U + P as the pipes read it), then friction, semi-implicitly so it only slows the snow:
//      Coulomb's alpha g mu (mu = tan theta_c for a cell that did not flow in the last substep,
//      tan delta otherwise), the viscosity (1 - alpha) k_v U and Voellmy's drag g s^2 / (xi h).
//      Momentum into a wall (NODATA or the grid's edge) is dropped.
//   2. AvalancheWaterTransportKernel: across each face, depth dt u_f h / dx from the upwind cell
//      (which must be able to send), u_f the mean of the two cells' velocities, with the upwind
//      cell's momentum. Each face is evaluated alike by its two cells (waterFace), so the mass
//      leaves one and reaches the other to double rounding. Velocities are limited to a quarter of
//      a cell a substep along each axis (waterVelocity): no cell sends more than its snow.
//   3. AvalancheWaterCommitKernel: U from the double sum, entrainment where snow arrived (as the
//      pipes' height pass), the peaks.
// The host picks the substeps from the last step's fastest signal (AvalancheWaterRowStatsKernel):
// Courant number kAvalancheWaterCourant for the flow and its gravity waves sqrt(g h).
#pragma once
#include "../hd.h"
#include "../snow_state.h"
#include "avalanche_kernels.h"

namespace snow {

// The Courant number the substeps keep to (AvalancheRun::substepsOfStep): (|u| + sqrt(g h)) dt / dx
// + the same along y at most this, on the last step's fastest cell; at most the quarter cell a
// substep each axis allows, so the velocity limit binds only when a flow speeds up within a step.
constexpr double kAvalancheWaterCourant = 0.25;

// Cell i's accelerated velocity (u east, w south, m/s) where it can send snow, each component
// limited to (1 - 1e-6) / 4 cells a substep (the four faces' outflows then sum to at most its
// snow); zero elsewhere.
SNOW_HD SNOW_INLINE void waterVelocity(const SnowFieldsView& v, const AvalancheArgs& a, int i, float& u, float& w) {
  u = w = 0.f;
  if (!avalancheSource(v, a, i)) return;
  const float h = v.unstable[i];
  const float* m = v.flows + 4 * static_cast<size_t>(i);
  constexpr float kQuarter = 0.25f * (1.f - 1e-6f);
  const float limitU = kQuarter * v.cellSizeXM / a.dtS, limitW = kQuarter * v.cellSizeYM / a.dtS;
  u = clampf(m[2] / h, -limitU, limitU);
  w = clampf(m[3] / h, -limitW, limitW);
}

// The face between cell l (west or north) and cell r (east or south): the depth that crosses it in
// a substep, positive toward r, and the velocity the snow carries (the upwind cell's). Both cells
// call it with the same arguments, so they add and subtract the same floats.
struct WaterFace {
  float depth = 0.f, u = 0.f, w = 0.f;
};
SNOW_HD SNOW_INLINE WaterFace waterFace(const SnowFieldsView& v, const AvalancheArgs& a, int l, int r, bool alongX) {
  float lu, lw, ru, rw;
  waterVelocity(v, a, l, lu, lw);
  waterVelocity(v, a, r, ru, rw);
  const float normal = 0.5f * (alongX ? lu + ru : lw + rw);
  WaterFace f;
  const int from = normal > 0.f ? l : r;
  if (!(normal != 0.f) || !avalancheSource(v, a, from)) return f;
  f.depth = a.dtS * normal / (alongX ? v.cellSizeXM : v.cellSizeYM) * v.unstable[from];
  f.u = normal > 0.f ? lu : ru;
  f.w = normal > 0.f ? lw : rw;
  return f;
}

// The slope along one axis from the forward rise `ahead` (to the east or south neighbour, per
// metre) and the backward one `behind` (from the west or north neighbour): minmod, or the one
// there is beside a wall.
SNOW_HD SNOW_INLINE float waterSlope(float ahead, float behind, bool wallAhead, bool wallBehind) {
  if (wallAhead && wallBehind) return 0.f;
  if (wallAhead) return behind;
  if (wallBehind) return ahead;
  if (ahead > 0.f && behind > 0.f) return ahead < behind ? ahead : behind;
  if (ahead < 0.f && behind < 0.f) return ahead > behind ? ahead : behind;
  return 0.f;
}

struct AvalancheWaterMomentumKernel {
  SnowFieldsView v;
  AvalancheArgs a;
  SNOW_HD void operator()(int x, int y) const {
    const int i = v.index(x, y);
    float* m = v.flows + 4 * static_cast<size_t>(i);
    m[2] = m[3] = 0.f;
    if (!v.valid[i] || !avalancheSource(v, a, i)) return;
    const float h = v.unstable[i], ap = v.surface(i);
    // The surface's slope along each axis: the smaller of the two one-sided slopes where they agree,
    // zero at a crest or a trough (minmod), the one there is beside a wall. Central differences
    // would push snow at the foot of a cliff with half the cliff's slope.
    float side[4];  // the rise to the east, west, south and north neighbour over the distance
    bool wall[4];
    constexpr int kOx[4] = {1, -1, 0, 0}, kOy[4] = {0, 0, 1, -1};
    for (int f = 0; f < 4; ++f) {
      const int nx = x + kOx[f], ny = y + kOy[f];
      wall[f] = !v.isValid(nx, ny);
      side[f] = wall[f] ? 0.f : (v.surface(v.index(nx, ny)) - ap) / (kOx[f] != 0 ? v.cellSizeXM : v.cellSizeYM);
    }
    const float slopeX = waterSlope(side[0], -side[1], wall[0], wall[1]);
    const float slopeY = waterSlope(side[2], -side[3], wall[2], wall[3]);
    float mx = m[0] - a.dtS * a.gravity * h * slopeX;
    float my = m[1] - a.dtS * a.gravity * h * slopeY;
    if ((wall[0] && mx > 0.f) || (wall[1] && mx < 0.f)) mx = 0.f;  // no snow crosses a wall
    if ((wall[2] && my > 0.f) || (wall[3] && my < 0.f)) my = 0.f;
    // Momentum whose square underflows is at rest (0 / 0 below would make it NaN).
    const float norm2 = mx * mx + my * my;
    if (!(norm2 > 0.f)) return;
    const float s = sqrtf(norm2) / h;
    const float alpha = avalancheAlpha(a, a.seaLevelTemperatureC + v.temperatureBase[i]);
    const float mu = v.avalancheFlowing[i] ? a.tanDynamicAngle : a.tanRestAngle;
    const float coulomb = a.dtS * alpha * a.gravity * mu;
    float slowed = s > coulomb ? s - coulomb : 0.f;
    if (1.f - alpha != 0.f) slowed = slowed / (1.f + a.dtS * (1.f - alpha) * a.viscosity * h);
    if (a.inverseDragMps2 > 0.f) slowed = slowed / (1.f + a.dtS * a.gravity * a.inverseDragMps2 * slowed / h);
    const float k = slowed / s;
    // No faster than the snow can move (waterVelocity's limit): what a substep too long for the
    // flow would add is not kept, so no flow outruns its own fall.
    constexpr float kQuarter = 0.25f * (1.f - 1e-6f);
    const float limitU = kQuarter * v.cellSizeXM / a.dtS * h, limitW = kQuarter * v.cellSizeYM / a.dtS * h;
    m[2] = clampf(mx * k, -limitU, limitU);
    m[3] = clampf(my * k, -limitW, limitW);
  }
};

struct AvalancheWaterTransportKernel {
  SnowFieldsView v;
  AvalancheArgs a;
  SNOW_HD void operator()(int x, int y) const {
    const int i = v.index(x, y);
    float* m = v.flows + 4 * static_cast<size_t>(i);
    if (!v.valid[i]) {
      m[0] = m[1] = 0.f;
      return;
    }
    // In double, as the pipes' heights: the depth a face moves is the float both cells use.
    double depth = v.avalancheU[i];
    float mx = m[2], my = m[3];
    bool moved = false;
    constexpr int kOx[4] = {1, -1, 0, 0}, kOy[4] = {0, 0, 1, -1};
    for (int f = 0; f < 4; ++f) {
      const int nx = x + kOx[f], ny = y + kOy[f];
      if (!v.isValid(nx, ny)) continue;
      const int n = v.index(nx, ny);
      const bool towardPlus = kOx[f] + kOy[f] > 0;  // n is east or south of i
      const WaterFace face = towardPlus ? waterFace(v, a, i, n, kOx[f] != 0) : waterFace(v, a, n, i, kOx[f] != 0);
      if (face.depth == 0.f) continue;
      const float out = towardPlus ? face.depth : -face.depth;  // leaving i when positive
      depth -= out;
      mx -= out * face.u;
      my -= out * face.w;
      moved = true;
    }
    depth = depth > 0.0 ? depth : 0.0;  // never below: the velocity limit; a guard against rounding
    v.avalancheU[i] = depth;
    m[0] = depth > 0.0 ? mx : 0.f;
    m[1] = depth > 0.0 ? my : 0.f;
    // Touched when its snow moved or moves: the dynamic friction's flag, the row statistics' columns.
    v.avalancheFlowing[i] = moved || m[0] != 0.f || m[1] != 0.f;
  }
};

// After the transport on every cell of the span: the float U, entrainment and the peaks. Reads and
// writes its own cell only.
struct AvalancheWaterCommitKernel {
  SnowFieldsView v;
  AvalancheArgs a;
  SNOW_HD void operator()(int x, int y) const {
    const int i = v.index(x, y);
    if (!v.valid[i] || !v.avalancheFlowing[i]) return;
    double u = v.avalancheU[i];
    // Snow arrived on a cell at rest (it sends nothing, so it changed by what came): the pipes' rule.
    if (!v.moving[i] && u + v.powder[i] - v.avalancheBefore[i] > a.stopThicknessM) {
      v.moving[i] = 1;
      u = u + v.powder[i];
      v.powder[i] = 0.f;
      v.avalancheU[i] = u;
    }
    v.unstable[i] = static_cast<float>(u);
    if (!v.avalanchePeakSpeed) return;
    const float h = v.unstable[i];
    const float* m = v.flows + 4 * static_cast<size_t>(i);
    const float speed = h > a.stopThicknessM ? sqrtf(m[0] * m[0] + m[1] * m[1]) / h : 0.f;
    v.avalanchePeakSpeed[i] = maxf(v.avalanchePeakSpeed[i], speed);
    v.avalanchePeakThickness[i] = maxf(v.avalanchePeakThickness[i], h);
  }
};

// One thread a row of the box after the step's substeps: the fastest snow, its kinetic energy, the
// columns of snow that can flow and of cells that changed (AvalancheRowStatsKernel's six floats),
// and in the seventh the fastest signal, max (|u| + sqrt(g h)) / dx + (|w| + sqrt(g h)) / dy (1/s).
struct AvalancheWaterRowStatsKernel {
  SnowFieldsView v;
  AvalancheArgs a;
  int k;
  SNOW_HD void operator()(int, int row) const {
    const int y = a.y0 + row;
    float speed = 0.f, energy = 0.f, signal = 0.f;
    int lo = v.width, hi = -1, touchedLo = v.width, touchedHi = -1;
    int x0 = 0, x1 = -1;
    avalancheRowSpan(v, a, y, k, x0, x1, false);
    const float c = v.cellSizeXM * v.cellSizeYM;
    for (int x = x0; x <= x1; ++x) {
      const int i = v.index(x, y);
      if (v.avalancheFlowing[i]) {
        if (x < touchedLo) touchedLo = x;
        touchedHi = x;
      }
      if (!avalancheSource(v, a, i)) continue;
      const float h = v.unstable[i];
      const float* m = v.flows + 4 * static_cast<size_t>(i);
      const float u = fabsf(m[0]) / h, w = fabsf(m[1]) / h, wave = sqrtf(a.gravity * h);
      const float s = sqrtf(u * u + w * w);
      speed = maxf(speed, s);
      energy += 0.5f * c * h * s * s;
      signal = maxf(signal, (u + wave) / v.cellSizeXM + (w + wave) / v.cellSizeYM);
      if (x < lo) lo = x;
      hi = x;
    }
    storeAvalancheRowStats(v, a, y, speed, energy, lo, hi, touchedLo, touchedHi, signal);
  }
};

}  // namespace snow
