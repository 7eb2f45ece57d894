// The avalanche's arguments and kernels. The model, its storage and the three passes of a
// substep are described in avalanches.h, where a reader starts.
#pragma once
#include "../hd.h"
#include "../snow_state.h"

namespace snow {

struct AvalancheArgs {
  float dtS = 0.01f;                 // substep, seconds
  float gravity = 9.81f;
  float tanRestAngle = 0.57735f;     // tan(theta_c), 30 degrees: static friction (start, stop)
  float tanDynamicAngle = 0.57735f;  // tan(delta): Coulomb friction while the source cell flows
  float inverseDragMps2 = 0.f;       // 1 / xi (Voellmy's turbulent drag g s^2 / (xi h)); 0: none
  float viscosity = 5e-4f;           // k_v
  float dryTemperatureC = -10.f;     // alpha = 1 (granular) at or below
  float wetTemperatureC = 0.f;       // alpha = alphaWet (mostly viscous) at or above
  float alphaWet = 0.2f;             // the granular share left in wet snow
  float seaLevelTemperatureC = 0.f;  // T0 of the day
  float stopThicknessM = 0.f;        // h_stop: moving snow this thin or thinner does not flow
  float pipeLengthM[4] = {};         // L of pipes east, south-east, south, south-west (avalanchePipeLengths)
  int shallowWater = 0;              // the flow: 1 shallow water (avalanche_shallow_water.h), 0 the paper's pipes
  // The box the pass runs over: [x0, x1) x [y0, y1).
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  // The step's start: rows [spanY0, spanY1) whose statistics (set statsIn of rowStats) hold the
  // columns of the snow that could flow; spanY1 <= spanY0: none yet (the passes run over the box).
  // The step's statistics go to the other set.
  int spanY0 = 0, spanY1 = 0, statsIn = 0;
  // With `live` (one substep a step, the last two steps' statistics this avalanche's and nothing
  // else written since): the flow, scale and height passes also keep to the cells within k of one
  // a pipe touched in either of the last two steps (avalancheLiveSpan); set s of rowStats holds
  // those columns for rows [liveY0[s], liveY1[s]).
  int live = 0, liveY0[2] = {0, 0}, liveY1[2] = {0, 0};
};

// Floats a row of one set of the avalanche's row statistics: the fastest pipe, the kinetic
// energy, the first and last column of snow that can flow, the first and last column a pipe
// touched in the last substep (each -1 when none), and the shallow-water flow's fastest signal
// (AvalancheWaterRowStatsKernel; 0 for the pipes).
constexpr int kAvalancheRowStats = 7;
static_assert(scratchCount(ScratchExtent::AvalancheRows, 0, 1, false) == 2 * kAvalancheRowStats, "rowStats holds two sets a row");

// Row y's statistics of set `set` (AvalancheRowStatsKernel).
SNOW_HD SNOW_INLINE float* avalancheRowStats(const SnowFieldsView& v, int y, int set) {
  return v.rowStats + 2 * kAvalancheRowStats * static_cast<size_t>(y) + kAvalancheRowStats * set;
}

// Row y's statistics of a step, into the set the next step reads (kAvalancheRowStats's order);
// `signal` is the shallow water's fastest signal, 0 for the pipes.
SNOW_HD SNOW_INLINE void storeAvalancheRowStats(const SnowFieldsView& v, const AvalancheArgs& a, int y, float speed, float energy, int lo, int hi,
                                                int touchedLo, int touchedHi, float signal) {
  float* s = avalancheRowStats(v, y, 1 - a.statsIn);
  s[0] = speed;
  s[1] = energy;
  s[2] = static_cast<float>(lo);
  s[3] = static_cast<float>(hi);
  s[4] = static_cast<float>(touchedLo);
  s[5] = static_cast<float>(touchedHi);
  s[6] = signal;
}

// Why the live spans give the box's bytes: a pipe's flow in a substep is a function of its own
// moved flow and its two end cells' state (surface, moving snow, flowing flag, temperature),
// nothing else. If no pipe touched either end in the last two substeps (and no static field
// came since: AvalancheRun turns the spans off then), the pipe was zero in the last one and its
// inputs are now what they were then, so it is zero again. With one substep a step, every pipe
// that can flow at a step's substep has an end a pipe touched in the last two steps, and every
// cell a pass would change is within one cell of one.
SNOW_HD SNOW_INLINE void avalancheLiveSpan(const SnowFieldsView& v, const AvalancheArgs& a, int y, int k, int& lo, int& hi) {
  int l = a.x1, h = a.x0 - 1;
  for (int set = 0; set < 2; ++set) {
    const int r0 = y - k > a.liveY0[set] ? y - k : a.liveY0[set], r1 = y + k < a.liveY1[set] - 1 ? y + k : a.liveY1[set] - 1;
    for (int r = r0; r <= r1; ++r) {
      const float* s = avalancheRowStats(v, r, set);
      if (!(s[5] >= 0.f)) continue;
      const int sl = static_cast<int>(s[4]) - k, sh = static_cast<int>(s[5]) + k;
      l = sl < l ? sl : l;
      h = sh > h ? sh : h;
    }
  }
  lo = l > lo ? l : lo;
  hi = h < hi ? h : hi;
}

// The columns [lo, hi] of row y that snow can reach within k substeps of the step's start: every
// cell within k cells of one that could flow then (snow crosses at most one cell a substep), cut
// to the box, and with `live` (the flow, scale and height passes) to avalancheLiveSpan's; lo > hi
// when none.
SNOW_HD SNOW_INLINE void avalancheRowSpan(const SnowFieldsView& v, const AvalancheArgs& a, int y, int k, int& lo, int& hi, bool live) {
  if (a.spanY1 <= a.spanY0) {
    lo = a.x0, hi = a.x1 - 1;
    return;
  }
  lo = a.x1, hi = a.x0 - 1;
  const int r0 = y - k > a.spanY0 ? y - k : a.spanY0, r1 = y + k < a.spanY1 - 1 ? y + k : a.spanY1 - 1;
  for (int r = r0; r <= r1; ++r) {
    const float* s = avalancheRowStats(v, r, a.statsIn);
    if (!(s[3] >= 0.f)) continue;
    const int l = static_cast<int>(s[2]) - k, h = static_cast<int>(s[3]) + k;
    lo = l < lo ? l : lo;
    hi = h > hi ? h : hi;
  }
  lo = lo > a.x0 ? lo : a.x0;
  hi = hi < a.x1 - 1 ? hi : a.x1 - 1;
  if (live && a.live && lo <= hi) avalancheLiveSpan(v, a, y, k, lo, hi);
}

// A cell that can send snow: moving snow thicker than h_stop (a granular layer thinner than its
// h_stop comes to rest, Pouliquen 1999; it still receives snow, and flows again once thicker).
SNOW_HD SNOW_INLINE bool avalancheSource(const SnowFieldsView& v, const AvalancheArgs& a, int i) {
  return v.moving[i] != 0 && v.unstable[i] > a.stopThicknessM;
}

// Pipe d of a cell: east, south-east, south, south-west.
SNOW_HD SNOW_INLINE int pipeDx(int d) { return d == 0 ? 1 : (d == 1 ? 1 : (d == 2 ? 0 : -1)); }
SNOW_HD SNOW_INLINE int pipeDy(int d) { return d == 0 ? 0 : 1; }

// The pipes' lengths, once a step rather than once a pipe a substep.
SNOW_HD SNOW_INLINE void avalanchePipeLengths(const SnowFieldsView& v, AvalancheArgs& a) {
  for (int d = 0; d < 4; ++d) {
    const float lx = pipeDx(d) != 0 ? v.cellSizeXM : 0.f, ly = pipeDy(d) != 0 ? v.cellSizeYM : 0.f;
    a.pipeLengthM[d] = sqrtf(lx * lx + ly * ly);
  }
}

SNOW_HD SNOW_INLINE float avalancheAlpha(const AvalancheArgs& a, float temperatureC) {
  float dry;
  if (!(a.wetTemperatureC > a.dryTemperatureC)) dry = temperatureC < a.wetTemperatureC ? 1.f : 0.f;
  // Outside (T_dry, T_wet) the ratio below is at least 1 or at most 0 (rounding is monotonic), so
  // its clamp is known without the division (a -0 it could give adds as 0 below).
  else if (temperatureC <= a.dryTemperatureC) dry = 1.f;
  else if (temperatureC >= a.wetTemperatureC) dry = 0.f;
  else dry = clampf((a.wetTemperatureC - temperatureC) / (a.wetTemperatureC - a.dryTemperatureC), 0.f, 1.f);
  return a.alphaWet + (1.f - a.alphaWet) * dry;
}

// Calls kernel(x0 + x, y0 + y) for the cells of the box, so any Exec runs over the box only.
template <class K>
struct InBox {
  K kernel;
  int x0, y0;
  SNOW_HD void operator()(int x, int y) const { kernel(x0 + x, y0 + y); }
};

// One thread a row of the box (row = y - a.y0), calling kernel(x, y) over the row's span at
// substep k (avalancheRowSpan): the cells a box holds around a long diagonal path cost nothing.
// The cells it leaves out hold no flows and no snow that can flow, so each kernel would leave
// them as they are (AvalancheClearIdleKernel keeps it so), and the bytes are the box's.
template <class K>
struct InRowSpans {
  K kernel;
  SnowFieldsView v;
  AvalancheArgs a;
  int k;
  SNOW_HD void operator()(int, int row) const {
    const int y = a.y0 + row;
    int lo = 0, hi = -1;
    avalancheRowSpan(v, a, y, k, lo, hi, true);
    for (int x = lo; x <= hi; ++x) kernel(x, y);
  }
};

// Pipe d of cell i = (x, y) as the last substep moved it: its flow times the outflow scale of
// the cell it drains (AvalancheScaleKernel). The pipes keep their unscaled flows and every reader
// scales them, the same float product a pass writing them back would store, so no pass does.
// A pipe that flows has a valid neighbour (the flow pass zeroes the others).
SNOW_HD SNOW_INLINE float movedPipe(const SnowFieldsView& v, int x, int y, int i, int d) {
  const float f = v.flows[4 * static_cast<size_t>(i) + d];
  if (f > 0.f) return f * v.scratchPowder[i];
  if (f < 0.f) return f * v.scratchPowder[v.index(x + pipeDx(d), y + pipeDy(d))];
  return f;
}

struct AvalancheFlowKernel {
  SnowFieldsView v;
  AvalancheArgs a;
  SNOW_HD bool source(int i) const { return avalancheSource(v, a, i); }
  SNOW_HD void operator()(int x, int y) const {
    const int i = v.index(x, y);
    float* f = v.flows + 4 * static_cast<size_t>(i);
    if (!v.valid[i]) {
      f[0] = f[1] = f[2] = f[3] = 0.f;
      return;
    }
    const bool here = source(i);
    const float ap = v.surface(i);
    const float c = v.cellSizeXM * v.cellSizeYM;
    for (int d = 0; d < 4; ++d) {
      const int nx = x + pipeDx(d), ny = y + pipeDy(d);
      if (!v.isValid(nx, ny)) {
        f[d] = 0.f;
        continue;
      }
      const int n = v.index(nx, ny);
      const bool there = source(n);
      if (!here && !there) {
        f[d] = 0.f;
        continue;
      }
      const float length = a.pipeLengthM[d];
      float phi = movedPipe(v, x, y, i, d) + a.dtS * c * a.gravity * (ap - v.surface(n)) / length;
      const int src = phi > 0.f ? i : n;
      if (!(phi != 0.f) || !(phi > 0.f ? here : there)) {
        f[d] = 0.f;
        continue;
      }
      const float alpha = avalancheAlpha(a, a.seaLevelTemperatureC + v.temperatureBase[src]);
      const float mu = v.avalancheFlowing[src] ? a.tanDynamicAngle : a.tanRestAngle;
      const float friction = a.dtS * c * alpha * a.gravity * mu;
      const float magnitude = fabsf(phi);
      if (magnitude <= friction) {
        f[d] = 0.f;
        continue;
      }
      phi = phi > 0.f ? magnitude - friction : friction - magnitude;
      if (1.f - alpha != 0.f)  // dry snow has no viscous share: the division would be by 1
        phi = phi / (1.f + a.dtS * (1.f - alpha) * a.viscosity * v.unstable[src]);
      if (a.inverseDragMps2 > 0.f)  // implicit, like the viscosity: it only slows the flow
        phi = phi / (1.f + a.dtS * a.gravity * a.inverseDragMps2 * (fabsf(phi) / c) / maxf(v.unstable[src], 1e-3f));
      f[d] = phi;
    }
  }
};

// Outflow of a cell in one substep, from its own pipes (positive) and its neighbours' (negative).
struct AvalancheScaleKernel {
  SnowFieldsView v;
  AvalancheArgs a;
  SNOW_HD void operator()(int x, int y) const {
    const int i = v.index(x, y);
    float out = 0.f;
    const float* f = v.flows + 4 * static_cast<size_t>(i);
    for (int d = 0; d < 4; ++d) out += maxf(0.f, f[d]);
    for (int d = 0; d < 4; ++d) {
      const int nx = x - pipeDx(d), ny = y - pipeDy(d);  // the neighbour whose pipe d ends here
      if (!v.inside(nx, ny)) continue;
      out += maxf(0.f, -v.flows[4 * static_cast<size_t>(v.index(nx, ny)) + d]);
    }
    const float volumeOut = a.dtS * out;
    const float available = v.cellSizeXM * v.cellSizeYM * v.unstable[i] * (1.f - 1e-6f);
    v.scratchPowder[i] = volumeOut > available ? (volumeOut > 0.f ? available / volumeOut : 0.f) : 1.f;
  }
};

struct AvalancheHeightKernel {
  SnowFieldsView v;
  AvalancheArgs a;
  SNOW_HD void operator()(int x, int y) const {
    const int i = v.index(x, y);
    if (!v.valid[i]) return;
    // In double: a pipe's volume leaves one cell and reaches the other to double rounding, and
    // a deep cell does not lose the small inflows a float would round away at every substep
    // (a drift that grew to 1e-4 of the mass over 200 000 substeps in pits of deep snow).
    double in = 0.0, out = 0.0;
    float moved[8];  // the cell's own four pipes, then the four ending here (0 at the grid's edge)
    for (int d = 0; d < 4; ++d) {
      moved[d] = movedPipe(v, x, y, i, d);
      if (moved[d] > 0.f) out += moved[d]; else in -= moved[d];
      moved[4 + d] = 0.f;
      const int nx = x - pipeDx(d), ny = y - pipeDy(d);
      if (!v.inside(nx, ny)) continue;
      const float g = moved[4 + d] = movedPipe(v, nx, ny, v.index(nx, ny), d);
      if (g > 0.f) in += g; else out -= g;
    }
    // Touched exactly when the cell changes below (a NaN flow too): the live spans rely on it.
    v.avalancheFlowing[i] = !(in == 0.0 && out == 0.0);
    if (in == 0.0 && out == 0.0) return;
    const double c = static_cast<double>(v.cellSizeXM) * v.cellSizeYM;
    double u = v.avalancheU[i];
    u = u + (static_cast<double>(a.dtS) * (in - out)) / c;
    u = u > 0.0 ? u : 0.0;
    // Snow arrives: once the snow it brought (U + P above their value at release) is thicker than
    // h_stop, the cell starts moving and entrains its own unstable snow and powder. A thinner
    // trickle rests on it (it could not flow on) and entrains nothing, so a sluff does not set
    // every slope below it moving.
    if (in > 0.0 && !v.moving[i] && u + v.powder[i] - v.avalancheBefore[i] > a.stopThicknessM) {
      v.moving[i] = 1;
      u = u + v.powder[i];
      v.powder[i] = 0.f;
    }
    v.avalancheU[i] = u;
    v.unstable[i] = static_cast<float>(u);
    if (!v.avalanchePeakSpeed) return;  // the peak fields are kept only where an output reads them
    float speed = 0.f;  // the fastest of the cell's eight pipes, as the row statistics read them
    for (int d = 0; d < 4; ++d) {
      speed = maxf(speed, fabsf(moved[d]));
      const int nx = x - pipeDx(d), ny = y - pipeDy(d);
      if (v.inside(nx, ny)) speed = maxf(speed, fabsf(moved[4 + d]));
    }
    v.avalanchePeakSpeed[i] = maxf(v.avalanchePeakSpeed[i], speed / static_cast<float>(c));
    v.avalanchePeakThickness[i] = maxf(v.avalanchePeakThickness[i], v.unstable[i]);
  }
};

// After a step's substeps: zero the pipes neither of whose ends holds moving snow (what the flow
// pass would do next). The host then shrinks the box to the moving snow; every cell more than
// one cell outside it has only such pipes, so the cells the next box reads but does not write
// carry no stale flows. Run cell by cell by AvalancheRowStatsKernel, which reads only the cell's
// own pipes after it.
struct AvalancheClearIdleKernel {
  SnowFieldsView v;
  AvalancheArgs a;
  SNOW_HD bool source(int i) const { return avalancheSource(v, a, i); }
  SNOW_HD void operator()(int x, int y) const {
    const int i = v.index(x, y);
    float* f = v.flows + 4 * static_cast<size_t>(i);
    const bool here = source(i);
    for (int d = 0; d < 4; ++d) {
      const int nx = x + pipeDx(d), ny = y + pipeDy(d);
      if (!here && (!v.inside(nx, ny) || !source(v.index(nx, ny)))) f[d] = 0.f;
    }
  }
};

// One thread per row of the box, after the step's substeps: the idle pipes cleared
// (AvalancheClearIdleKernel), then the fastest pipe, the kinetic energy of the snow that can flow
// (the sum of c U s^2 / 2, s its fastest pipe) and its columns, for the host to pick the next
// box and to tell when the avalanche is at rest.
struct AvalancheRowStatsKernel {
  SnowFieldsView v;
  AvalancheArgs a;
  int k;  // the step's substeps: the span the step's snow can have reached
  SNOW_HD void operator()(int, int row) const {
    const int y = a.y0 + row;
    float speed = 0.f, energy = 0.f;
    int lo = v.width, hi = -1, touchedLo = v.width, touchedHi = -1;
    int x0 = 0, x1 = -1;
    avalancheRowSpan(v, a, y, k, x0, x1, false);  // the snow that can flow, wherever it is
    for (int x = x0; x <= x1; ++x) cell(x, y, speed, energy, lo, hi, touchedLo, touchedHi);
    store(y, speed, energy, lo, hi, touchedLo, touchedHi);
  }
  // Cell (x, y) of the row, in column order: its idle pipes cleared, then the row's fastest pipe,
  // kinetic energy, columns of snow that can flow and columns a pipe touched taken in.
  SNOW_HD void cell(int x, int y, float& speed, float& energy, int& lo, int& hi, int& touchedLo, int& touchedHi) const {
    AvalancheClearIdleKernel{v, a}(x, y);  // the cell's own pipes, which are all it reads
    const int i = v.index(x, y);
    if (v.avalancheFlowing[i]) {  // every touched cell is in the span: it is next to a source
      if (x < touchedLo) touchedLo = x;
      touchedHi = x;
    }
    const float c = v.cellSizeXM * v.cellSizeYM;
    float fastest = 0.f;
    for (int d = 0; d < 4; ++d) fastest = maxf(fastest, fabsf(movedPipe(v, x, y, i, d)) / c);
    speed = maxf(speed, fastest);
    if (avalancheSource(v, a, i)) {  // the box follows the snow that can still flow
      energy += 0.5f * c * v.unstable[i] * fastest * fastest;
      if (x < lo) lo = x;
      hi = x;
    }
  }
  SNOW_HD void store(int y, float speed, float energy, int lo, int hi, int touchedLo, int touchedHi) const {
    storeAvalancheRowStats(v, a, y, speed, energy, lo, hi, touchedLo, touchedHi, 0.f);
  }
};

// At release: U + P of every cell (for the scour and deposit records), flows cleared, and the
// released cells' powder joined to their unstable snow.
struct AvalancheReleaseKernel {
  SnowFieldsView v;
  SNOW_HD void operator()(int x, int y) const {
    const int i = v.index(x, y);
    v.avalancheBefore[i] = v.unstable[i] + v.powder[i];
    float* f = v.flows + 4 * static_cast<size_t>(i);
    f[0] = f[1] = f[2] = f[3] = 0.f;
    if (v.moving[i] && v.valid[i]) {
      v.unstable[i] = v.unstable[i] + v.powder[i];
      v.powder[i] = 0.f;
    }
    v.avalancheU[i] = v.unstable[i];
    if (v.avalanchePeakSpeed) {
      v.avalanchePeakSpeed[i] = 0.f;
      v.avalanchePeakThickness[i] = v.moving[i] && v.valid[i] ? v.unstable[i] : 0.f;
    }
    v.avalancheFlowing[i] = 0;
  }
};

// A cell the last avalanche touched, back at rest for the next one: what the release kernel
// gives a cell it does not release, but U + P and U (recorded where the next avalanche reaches).
struct AvalancheRestKernel {
  SnowFieldsView v;
  SNOW_HD void operator()(int x, int y) const {
    const int i = v.index(x, y);
    float* f = v.flows + 4 * static_cast<size_t>(i);
    f[0] = f[1] = f[2] = f[3] = 0.f;
    if (v.avalanchePeakSpeed) v.avalanchePeakSpeed[i] = 0.f, v.avalanchePeakThickness[i] = 0.f;
    v.avalancheFlowing[i] = 0;
    v.moving[i] = 0;
  }
};

// At rest: the moving snow is deposited as stable snow (avalanche debris is dense and fused),
// the net change of each cell is recorded as scour or deposit, flows and flags cleared.
struct AvalancheSettleKernel {
  SnowFieldsView v;
  SNOW_HD void operator()(int x, int y) const {
    const int i = v.index(x, y);
    float* f = v.flows + 4 * static_cast<size_t>(i);
    f[0] = f[1] = f[2] = f[3] = 0.f;
    if (!v.valid[i]) return;
    const float net = (v.unstable[i] + v.powder[i]) - v.avalancheBefore[i];
    // Each record only where the season keeps it (null otherwise).
    if (net > 0.f && v.avalancheDeposit) v.avalancheDeposit[i] = v.avalancheDeposit[i] + net;
    if (net < 0.f && v.avalancheScour) v.avalancheScour[i] = v.avalancheScour[i] - net;
    if (v.avalancheSeasonPeakThickness) v.avalancheSeasonPeakThickness[i] = maxf(v.avalancheSeasonPeakThickness[i], v.avalanchePeakThickness[i]);
    if (v.avalancheSeasonPeakSpeed) v.avalancheSeasonPeakSpeed[i] = maxf(v.avalancheSeasonPeakSpeed[i], v.avalanchePeakSpeed[i]);
    if (v.moving[i]) {
      v.stable[i] = v.stable[i] + v.unstable[i];
      v.unstable[i] = 0.f;
      v.moving[i] = 0;
    } else if (net > 0.f) {  // a trickle that came to rest on a cell it did not set moving
      v.stable[i] = v.stable[i] + net;
      v.unstable[i] = maxf(0.f, v.unstable[i] - net);
    }
  }
};

}  // namespace snow
