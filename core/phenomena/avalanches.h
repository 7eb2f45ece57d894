// Avalanches (paper §6.1 and §7.2): the hydrostatic pipe model over the Moore neighbourhood,
// with granular friction and viscosity, moving the unstable layer of the cells whose "snow
// moving" flag is set (powder on top joins it when a cell starts moving).
//
// Storage (§7.2): one signed flow per pipe, four pipes owned per cell (east, south-east, south,
// south-west), flows[4 i + d] in m^3/s, positive from the owner toward the neighbour. Each pipe
// is written by its owner only; heights are updated by gathering the eight pipes. No atomics.
//
// One substep of length dt runs three per-cell passes over the active box:
//   1. AvalancheFlowKernel: phi += dt c a, a = g (A_p - A_n) / L (rho cancels in dP / (rho dx));
//      granular friction of norm dt c alpha g tan(theta_c) opposes the flow and sets it to zero
//      rather than reversing it (static friction: snow on a slope below theta_c never starts);
//      viscosity -k_v U phi, applied implicitly (phi / (1 + dt (1 - alpha) k_v U)) so that no
//      k_v can make it oscillate. c = dx dy (the paper's dx^2), L the pipe length (dx, dy or
//      the diagonal). alpha = 1 for dry snow at or below T_dry, alpha_wet for wet snow at or
//      above T_wet, linear between, from the source cell's temperature. alpha_wet (0.2) is ours:
//      with alpha = 0 wet snow has no yield stress, and with the paper's small k_v it keeps
//      flowing down any slope, however gentle, for as long as it is simulated.
//   2. AvalancheScaleKernel: the outflow of each cell is scaled so it never takes more than the
//      unstable snow there (the paper's min(V_out, dx^2 U) / V_out, to all but a millionth).
//      Each pipe takes the factor of the cell it drains where it is read (movedPipe), not in a
//      pass of its own.
//   3. AvalancheHeightKernel: U += dt (inflow - outflow) / c, summed and kept in double through
//      the avalanche (avalancheU; the float layer holds its rounding, which the flow reads). A
//      cell that receives snow starts moving and its own unstable snow and powder are entrained.
// A flow may only leave a moving cell that holds snow, so flows never grow where there is
// nothing to move. The sum of U over the grid changes only by double rounding during the run and
// by one float rounding per cell when it settles.
//
// Preconditions: snowMoving marks the released cells (avalancheRelease uploads it); scratch:
// flows, avalancheBefore, avalancheU and rowStats (made by the backend at the first avalanche),
// scratchPowder (the outflow scales). A release costs its box, not the grid: the scratch is
// kept at rest outside the box an avalanche touches (AvalancheTouched below).
// Mass: conserved (see above); the scour and deposit records (avalancheScourM, avalancheDepositM)
// are kept at the settle.
// Backend: SnowBackend::avalancheRelease, avalancheSteps and avalancheSettle (ExecBackend runs
// the functions below; the TBB executor runs the three passes' rows several cells at a time,
// avalanche_rows.h, to the per-cell bodies' bytes). Host runner: AvalancheRun (core/avalanche_runs.h: the release zone,
// the substep length, the box, the records). Season: SeasonRun::addAvalanches
// (core/season_avalanches.cpp). Parameters: the §6.1 blocks of ModelParameters
// (core/parameters.h; scene keys in parameterTable, parameters.cpp).
#pragma once
#include <cmath>
#include <vector>

#include "../parameters.h"
#include "../util.h"
#include "avalanche_kernels.h"
#include "avalanche_shallow_water.h"

namespace snow {

// The flow's constants for a day of sea-level temperature T0; the box is the caller's.
inline AvalancheArgs makeAvalancheArgs(const ModelParameters& p, double seaLevelTemperatureC) {
  AvalancheArgs a;
  a.gravity = static_cast<float>(p.gravityMps2);
  a.tanRestAngle = static_cast<float>(std::tan(p.avalancheRestAngleDeg * kPi / 180.0));
  a.viscosity = static_cast<float>(p.snowViscosityPerS2);
  a.dryTemperatureC = static_cast<float>(p.avalancheDryTemperatureC);
  a.wetTemperatureC = static_cast<float>(p.avalancheWetTemperatureC);
  a.seaLevelTemperatureC = static_cast<float>(seaLevelTemperatureC);
  a.alphaWet = static_cast<float>(p.avalancheWetGranularFraction);
  a.tanDynamicAngle = static_cast<float>(std::tan(p.avalancheDynamicFrictionDeg * kPi / 180.0));
  a.stopThicknessM = static_cast<float>(p.avalancheStopThicknessM);
  a.inverseDragMps2 = p.avalancheTurbulenceMps2 > 0.0 ? static_cast<float>(1.0 / p.avalancheTurbulenceMps2) : 0.f;
  a.shallowWater = p.avalancheFlow == AvalancheFlow::ShallowWater;
  return a;
}

// The cells an avalanche has written: its release box, grown to each substep's box. Outside it
// the avalanche's scratch is at rest (flows, both peaks and the flowing flag zero), and U + P and
// U at release are recorded on a cell only when the box first reaches it (growTouchedBox): no
// pass reads them elsewhere, and the cell has not changed since the release (while an avalanche
// runs nothing else does), so each value is the one a whole-grid release would record.
struct AvalancheTouched {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

template <class Exec>
void releaseKernelInBox(Exec& exec, const SnowFieldsView& v, int x0, int y0, int x1, int y1) {
  if (x1 > x0 && y1 > y0) exec.forEachCell(x1 - x0, y1 - y0, InBox<AvalancheReleaseKernel>{AvalancheReleaseKernel{v}, x0, y0});
}

// Widens `t` to hold the box [x0, x1) x [y0, y1), with a margin so that a box growing by a cell a
// substep widens it every few substeps only; the release kernel records the new cells.
template <class Exec>
void growTouchedBox(Exec& exec, const SnowFieldsView& v, AvalancheTouched& t, int x0, int y0, int x1, int y1) {
  if (x0 >= t.x0 && y0 >= t.y0 && x1 <= t.x1 && y1 <= t.y1) return;
  constexpr int kMargin = 8;
  const int nx0 = x0 < t.x0 ? (x0 > kMargin ? x0 - kMargin : 0) : t.x0;
  const int ny0 = y0 < t.y0 ? (y0 > kMargin ? y0 - kMargin : 0) : t.y0;
  const int nx1 = x1 > t.x1 ? (x1 + kMargin < v.width ? x1 + kMargin : v.width) : t.x1;
  const int ny1 = y1 > t.y1 ? (y1 + kMargin < v.height ? y1 + kMargin : v.height) : t.y1;
  releaseKernelInBox(exec, v, nx0, ny0, nx1, t.y0);  // the rows above the old box, then below it
  releaseKernelInBox(exec, v, nx0, t.y1, nx1, ny1);
  releaseKernelInBox(exec, v, nx0, t.y0, t.x0, t.y1);  // the columns left of it, then right of it
  releaseKernelInBox(exec, v, t.x1, t.y0, nx1, t.y1);
  t = {nx0, ny0, nx1, ny1};
}

// The last avalanche's touched box back at rest (its moving flags too, should it not have
// settled), before the next release's flags are uploaded.
template <class Exec>
void putAvalancheAtRest(Exec& exec, const SnowFieldsView& v, const AvalancheTouched& t) {
  if (t.x1 > t.x0 && t.y1 > t.y0)
    exec.forEachCell(t.x1 - t.x0, t.y1 - t.y0, InBox<AvalancheRestKernel>{AvalancheRestKernel{v}, t.x0, t.y0});
}

// The released cells (snowMoving, uploaded by the caller; all inside `box`) start moving. With
// `wholeGrid` (the first avalanche after the state's upload, whose peaks may be anywhere) the
// release kernel runs on every cell; else on the release box, the rest being at rest
// (putAvalancheAtRest). `t` becomes the release box.
template <class Exec>
void runAvalancheRelease(Exec& exec, const SnowFieldsView& v, AvalancheTouched& t, const AvalancheTouched& box, bool wholeGrid) {
  if (wholeGrid) exec.forEachCell(v.width, v.height, AvalancheReleaseKernel{v});
  else releaseKernelInBox(exec, v, box.x0, box.y0, box.x1, box.y1);
  t = box;
  exec.finish();
}

// Avalanche substeps over a box that grows by one cell per substep (snow moves at most one cell
// a substep), each pass over the box's rows' spans only (InRowSpans), then the per-row statistics
// of the grown box. Returns the grown box in `a`.
template <class Exec>
void runAvalancheSubsteps(Exec& exec, const SnowFieldsView& v, AvalancheTouched& touched, AvalancheArgs& a, int substeps) {
  avalanchePipeLengths(v, a);
  for (int s = 0; s < substeps; ++s) {
    a.x0 = a.x0 > 0 ? a.x0 - 1 : 0;
    a.y0 = a.y0 > 0 ? a.y0 - 1 : 0;
    a.x1 = a.x1 < v.width ? a.x1 + 1 : v.width;
    a.y1 = a.y1 < v.height ? a.y1 + 1 : v.height;
    const int w = a.x1 - a.x0, h = a.y1 - a.y0;
    if (w <= 0 || h <= 0) return;
    growTouchedBox(exec, v, touched, a.x0, a.y0, a.x1, a.y1);
    // Every cell with moving snow is at least one cell inside the row spans, so all of its pipes
    // and neighbours are processed; cells outside hold no flows (AvalancheClearIdleKernel).
    const int k = s + 1;
    if (a.shallowWater) {
      exec.forEachCell(1, h, InRowSpans<AvalancheWaterMomentumKernel>{AvalancheWaterMomentumKernel{v, a}, v, a, k});
      exec.forEachCell(1, h, InRowSpans<AvalancheWaterTransportKernel>{AvalancheWaterTransportKernel{v, a}, v, a, k});
      exec.forEachCell(1, h, InRowSpans<AvalancheWaterCommitKernel>{AvalancheWaterCommitKernel{v, a}, v, a, k});
      continue;
    }
    exec.forEachCell(1, h, InRowSpans<AvalancheFlowKernel>{AvalancheFlowKernel{v, a}, v, a, k});
    exec.forEachCell(1, h, InRowSpans<AvalancheScaleKernel>{AvalancheScaleKernel{v, a}, v, a, k});
    exec.forEachCell(1, h, InRowSpans<AvalancheHeightKernel>{AvalancheHeightKernel{v, a}, v, a, k});
  }
  if (a.x1 > a.x0 && a.y1 > a.y0) {
    if (a.shallowWater) exec.forEachCell(1, a.y1 - a.y0, AvalancheWaterRowStatsKernel{v, a, substeps});
    else exec.forEachCell(1, a.y1 - a.y0, AvalancheRowStatsKernel{v, a, substeps});
  }
}

// `substeps` substeps from `args`' box, then what the host reads back: the step's 5 floats per
// row of the grown box (from `rowStats`, the buffer behind v.rowStats: the fastest snow, the
// energy, the columns of snow that can flow, the fastest signal), then the box x0, y0, x1, y1.
template <class Exec, class RowStatsBuffer>
std::vector<float> runAvalancheSteps(Exec& exec, const SnowFieldsView& v, RowStatsBuffer& rowStats, AvalancheTouched& touched,
                                     const AvalancheArgs& args, int substeps) {
  AvalancheArgs a = args;
  runAvalancheSubsteps(exec, v, touched, a, substeps);
  // The grown box's rows only, both sets (side by side): not the grid's rows.
  const size_t rows = a.y1 > a.y0 ? static_cast<size_t>(a.y1 - a.y0) : 0, row = 2 * kAvalancheRowStats;
  std::vector<float> stats(row * rows);
  exec.downloadRange(rowStats, row * static_cast<size_t>(a.y0 > 0 ? a.y0 : 0), stats.size(), stats.data());
  std::vector<float> box;
  box.reserve(5 * rows + 4);
  for (size_t r = 0; r < rows; ++r) {
    const size_t at = row * r + kAvalancheRowStats * static_cast<size_t>(1 - a.statsIn);
    box.insert(box.end(), stats.begin() + at, stats.begin() + at + 4);
    box.push_back(stats[at + 6]);
  }
  box.push_back(static_cast<float>(a.x0));
  box.push_back(static_cast<float>(a.y0));
  box.push_back(static_cast<float>(a.x1));
  box.push_back(static_cast<float>(a.y1));
  return box;
}

// The moving snow in the box comes to rest, with the scour and deposit records.
template <class Exec>
void runAvalancheSettle(Exec& exec, const SnowFieldsView& v, const AvalancheArgs& a) {
  if (a.x1 > a.x0 && a.y1 > a.y0)
    exec.forEachCell(a.x1 - a.x0, a.y1 - a.y0, InBox<AvalancheSettleKernel>{AvalancheSettleKernel{v}, a.x0, a.y0});
  exec.finish();
}

}  // namespace snow
