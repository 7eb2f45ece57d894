// Wind transport (paper §5.4), five colour passes of the §7.1 cross tiling like powder
// diffusion, from a snapshot of A and P taken before the passes (order-independent).
//   curv_W = |W_x| d2A/dx2 + |W_y| d2A/dy2     (A the snow surface, second differences)
// set to zero where it is positive (convex: nothing to scour) or where the wind-effect surface
// stands above the snow (a wind shadow: W_z - A > shadow tolerance). Eroded powder per event:
//   e = min(P, f dt * k_erosion * (-curv_W))   (f the scene's wind-erosion multiplier, 1 without)
// We read Table 2's k_erosion (printed "0.1 m s^-1 day^-1") as metres of snow per day per s^-1 of
// curv_W, i.e. m s day^-1: the only reading under which e is a depth.
// Where the paper is vague: the eroded snow is deposited as powder into the two 4-neighbours
// the wind blows toward (sign of W_x, sign of W_y), split |W_x| : |W_y|. A neighbour that is
// NODATA or off the grid does not receive: its share stays (the boundary is closed, so mass is
// conserved exactly up to float rounding). Records: cumulative scour at the source, deposit at
// the receivers (windScourM, windDepositM). Cells the bedform model runs (bedformActive) are
// left to it.
// Scratch: scratchSurface and scratchPowder, the snapshot (PowderSnapshotKernel, powder_diffusion.h).
// Mass: conserved (one cell's powder moves to its downwind neighbours; see giveTo).
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

struct WindTransportKernel {
  SnowFieldsView v;
  WindTransportArgs a;

  SNOW_HD void operator()(int x, int y) const {
    const int i = v.index(x, y);
    if (!v.valid[i]) return;
    if (v.bedformActive && v.bedformActive[i]) return;  // the bedform model moves this cell's powder
    const float powder = v.scratchPowder[i];
    if (!(powder > 0.f)) return;
    const float ap = v.scratchSurface[i];
    if (v.windEffectZ[i] - ap > a.shadowToleranceM) return;  // sheltered
    const float wx = v.windX[i], wy = v.windY[i];
    if (wx == 0.f && wy == 0.f) return;
    // Second differences of the snapshot surface; missing neighbours mirror the cell (zero).
    const float aL = v.isValid(x - 1, y) ? v.scratchSurface[i - 1] : ap;
    const float aR = v.isValid(x + 1, y) ? v.scratchSurface[i + 1] : ap;
    const float aU = v.isValid(x, y - 1) ? v.scratchSurface[i - v.width] : ap;
    const float aD = v.isValid(x, y + 1) ? v.scratchSurface[i + v.width] : ap;
    const float dxx = (aL - 2.f * ap + aR) / (v.cellSizeXM * v.cellSizeXM);
    const float dyy = (aU - 2.f * ap + aD) / (v.cellSizeYM * v.cellSizeYM);
    const float curv = fabsf(wx) * dxx + fabsf(wy) * dyy;
    if (!(curv < 0.f)) return;
    // All but a millionth at most, so the shares' float sums stay below the powder (no clamp).
    const float factor = v.windErosionFactor ? v.windErosionFactor[i] : 1.f;  // art direction
    const float eroded = minf(powder * (1.f - 1e-6f), factor * a.dtDays * a.erosionRate * (-curv));
    if (!(eroded > 0.f)) return;
    // Receivers downwind.
    const int nx = x + (wx > 0.f ? 1 : -1), ny = y + (wy > 0.f ? 1 : -1);
    const float wsum = fabsf(wx) + fabsf(wy);
    const bool rx = wx != 0.f && v.isValid(nx, y), ry = wy != 0.f && v.isValid(x, ny);
    // The second share is the rest of the first, so the two sum to what was eroded.
    const float toX = rx ? eroded * fabsf(wx) / wsum : 0.f;
    const float toY = ry ? (rx ? maxf(0.f, eroded - toX) : eroded * fabsf(wy) / wsum) : 0.f;
    if (!(toX + toY > 0.f)) return;
    // giveTo (powder_diffusion.h): the source gives exactly what each receiver gained.
    const float start = v.powder[i];
    float remaining = start;
    // The records are null when no output reads them (SeasonConfig::recordFields).
    float* deposit = v.windDeposit;
    if (rx) remaining = giveTo(v.powder[v.index(nx, y)], toX, remaining, deposit ? &deposit[v.index(nx, y)] : nullptr);
    if (ry) remaining = giveTo(v.powder[v.index(x, ny)], toY, remaining, deposit ? &deposit[v.index(x, ny)] : nullptr);
    v.powder[i] = remaining;
    if (v.windScour) v.windScour[i] = v.windScour[i] + (start - remaining);
  }
};

inline WindTransportArgs makeWindTransportArgs(const ModelParameters& p, double dtDays) {
  WindTransportArgs a;
  a.dtDays = static_cast<float>(dtDays);
  a.erosionRate = static_cast<float>(p.windErosionRateMPerSPerDay);
  a.shadowToleranceM = static_cast<float>(p.windShadowToleranceM);
  return a;
}

// One pass of five colours from a snapshot. Erosion per event is bounded by the powder there,
// and the deposit moves one cell: no substeps needed for stability.
template <class Exec>
void runWindTransport(Exec& exec, const SnowFieldsView& v, const WindTransportArgs& a) {
  exec.forEachCell(v.width, v.height, PowderSnapshotKernel{v});
  exec.forEachCellInColourOrder(v.width, v.height, WindTransportKernel{v, a});
}

}  // namespace snow
