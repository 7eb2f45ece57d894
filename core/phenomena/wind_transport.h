// Wind transport (paper §5.4), two per-cell passes like a powder-diffusion substep, so nothing
// depends on the order cells are visited (no colour passes):
//  1. WindSharesKernel: each cell's erosion and the shares it gives its downwind neighbours, from
//     the state at the step's start, written to its own cell only;
//  2. WindGatherKernel: each cell's powder becomes what it keeps plus what its upwind neighbours give.
//   curv_W = |W_x| d2A/dx2 + |W_y| d2A/dy2     (A the snow surface, second differences)
// set to zero where it is positive (convex: nothing to scour) or where the wind-effect surface
// stands above the snow (a wind shadow: W_z - A > shadow tolerance). Eroded powder per event:
//   e = min(P, f dt * k_erosion * (-curv_W))   (f the scene's wind-erosion multiplier, 1 without)
// We read Table 2's k_erosion (printed "0.1 m s^-1 day^-1") as metres of snow per day per s^-1 of
// curv_W, i.e. m s day^-1: the only reading under which e is a depth.
// Where the paper is vague: the eroded snow is deposited as powder into the two 4-neighbours
// the wind blows toward (sign of W_x, sign of W_y), split |W_x| : |W_y|. A neighbour that is
// NODATA or off the grid does not receive: its share stays (the boundary is closed, so mass is
// conserved up to float rounding). Records: cumulative scour at the source, deposit at the
// receivers (windScourM, windDepositM). Cells the bedform model runs (bedformActive) give nothing.
// Scratch: scratchSurface and scratchPowder, each cell's signed shares along x and y.
// Backend: SnowBackend::windTransport (ExecBackend runs runWindTransport). Season:
// SeasonRun::addTransport (core/season.cpp), only while the season has wind. Parameters: the
// §5.3/§5.4 block of ModelParameters (core/parameters.h; scene keys in parameterTable,
// parameters.cpp).
#pragma once
#include "../hd.h"
#include "../parameters.h"
#include "../snow_state.h"
#include "powder_diffusion.h"

namespace snow {

struct WindTransportArgs {
  float dtDays = 0.5f;
  float erosionRate = 0.1f;          // k_erosion, m s day^-1 (see above)
  float shadowToleranceM = 0.1f;     // W_z more than this above the snow: in the wind shadow
};

// Pass 1 at one cell, from the state at the step's start only: the powder it gives its downwind
// neighbour along x and along y, each signed by its direction (+: toward +x or +y; 0: none). Each
// share is what the receiver gains when it is added to the receiver's powder at the step's start,
// (P_n + a) - P_n, exact in float, and is given only while the cell still holds it (as
// powderSharesAt): no cell goes negative, and a share below a deep receiver's last bit stays.
SNOW_HD SNOW_INLINE void windSharesAt(const SnowFieldsView& v, const WindTransportArgs& a, int x, int y, float& shareX, float& shareY) {
  shareX = shareY = 0.f;
  const int i = v.index(x, y);
  if (!v.valid[i]) return;
  if (v.bedformActive && v.bedformActive[i]) return;  // the bedform model moves this cell's powder
  const float powder = v.powder[i];
  if (!(powder > 0.f)) return;
  const float ap = v.surface(i);
  if (v.windEffectZ[i] - ap > a.shadowToleranceM) return;  // sheltered
  const float wx = v.windX[i], wy = v.windY[i];
  if (wx == 0.f && wy == 0.f) return;
  // Second differences of the surface; missing neighbours mirror the cell (zero).
  const float aL = v.isValid(x - 1, y) ? v.surface(i - 1) : ap;
  const float aR = v.isValid(x + 1, y) ? v.surface(i + 1) : ap;
  const float aU = v.isValid(x, y - 1) ? v.surface(i - v.width) : ap;
  const float aD = v.isValid(x, y + 1) ? v.surface(i + v.width) : ap;
  const float dxx = (aL - 2.f * ap + aR) / (v.cellSizeXM * v.cellSizeXM);
  const float dyy = (aU - 2.f * ap + aD) / (v.cellSizeYM * v.cellSizeYM);
  const float curv = fabsf(wx) * dxx + fabsf(wy) * dyy;
  if (!(curv < 0.f)) return;
  // All but a millionth at most, so the shares' float sums stay below the powder (no clamp).
  const float factor = v.windErosionFactor ? v.windErosionFactor[i] : 1.f;  // art direction
  const float eroded = minf(powder * (1.f - 1e-6f), factor * a.dtDays * a.erosionRate * (-curv));
  if (!(eroded > 0.f)) return;
  // Receivers downwind; the second share is the rest of the first, so the two sum to what was eroded.
  const int nx = x + (wx > 0.f ? 1 : -1), ny = y + (wy > 0.f ? 1 : -1);
  const float wsum = fabsf(wx) + fabsf(wy);
  const bool rx = wx != 0.f && v.isValid(nx, y), ry = wy != 0.f && v.isValid(x, ny);
  const float toX = rx ? eroded * fabsf(wx) / wsum : 0.f;
  const float toY = ry ? (rx ? maxf(0.f, eroded - toX) : eroded * fabsf(wy) / wsum) : 0.f;
  float remaining = powder;
  if (toX > 0.f) {
    const float before = v.powder[v.index(nx, y)];
    const float gained = (before + toX) - before;
    if (acceptedGain(gained, remaining)) shareX = wx > 0.f ? gained : -gained, remaining = remaining - gained;
  }
  if (toY > 0.f) {
    const float before = v.powder[v.index(x, ny)];
    const float gained = (before + toY) - before;
    if (acceptedGain(gained, remaining)) shareY = wy > 0.f ? gained : -gained;
  }
}

// What a cell keeps of its powder after giving its two shares: pass 1's `remaining`, the same
// float operations in the same order.
SNOW_HD SNOW_INLINE float windKept(float powder, float shareX, float shareY) { return (powder - fabsf(shareX)) - fabsf(shareY); }

// Pass 1, per cell (writes only its own cell's two shares: scratchSurface along x, scratchPowder
// along y).
struct WindSharesKernel {
  SnowFieldsView v;
  WindTransportArgs a;

  SNOW_HD void operator()(int x, int y) const {
    float shareX, shareY;
    windSharesAt(v, a, x, y, shareX, shareY);
    const int i = v.index(x, y);
    v.scratchSurface[i] = shareX;
    v.scratchPowder[i] = shareY;
  }
};

// Pass 2, per cell: its powder becomes what it keeps plus the shares its four neighbours send
// it (summed first, west, east, north, south, so the small gifts round once against the powder).
// Records: what the cell gave to its scour, what it received to its deposit (null when no
// output reads them, SeasonConfig::recordFields).
struct WindGatherKernel {
  SnowFieldsView v;

  SNOW_HD void operator()(int x, int y) const {
    const int i = v.index(x, y);
    if (!v.valid[i]) return;
    const float* sx = v.scratchSurface;
    const float* sy = v.scratchPowder;
    const float fromW = x > 0 ? maxf(sx[i - 1], 0.f) : 0.f;
    const float fromE = x + 1 < v.width ? maxf(-sx[i + 1], 0.f) : 0.f;
    const float fromN = y > 0 ? maxf(sy[i - v.width], 0.f) : 0.f;
    const float fromS = y + 1 < v.height ? maxf(-sy[i + v.width], 0.f) : 0.f;
    const float gifts = ((fromW + fromE) + fromN) + fromS;
    const float powder = v.powder[i];
    const float kept = windKept(powder, sx[i], sy[i]);
    if (kept == powder && !(gifts > 0.f)) return;
    v.powder[i] = kept + gifts;
    if (v.windScour && kept != powder) v.windScour[i] = v.windScour[i] + (powder - kept);
    if (v.windDeposit && gifts > 0.f) v.windDeposit[i] = v.windDeposit[i] + gifts;
  }
};

inline WindTransportArgs makeWindTransportArgs(const ModelParameters& p, double dtDays) {
  WindTransportArgs a;
  a.dtDays = static_cast<float>(dtDays);
  a.erosionRate = static_cast<float>(p.windErosionRateMPerSPerDay);
  a.shadowToleranceM = static_cast<float>(p.windShadowToleranceM);
  return a;
}

// One step: the shares of every cell from the step's start, then every cell gathers. Erosion is
// bounded by the powder there and the deposit moves one cell: no substeps needed for stability.
template <class Exec>
void runWindTransport(Exec& exec, const SnowFieldsView& v, const WindTransportArgs& a) {
  exec.forEachCell(v.width, v.height, WindSharesKernel{v, a});
  exec.forEachCell(v.width, v.height, WindGatherKernel{v});
}

}  // namespace snow
