// The wind bedforms' arguments, storage list and kernels. The model (Werner's slab saltation,
// its batches, the repose relaxation, the cohesion) is described in bedforms.h, where a reader
// starts.
#pragma once
#include <cstdint>

#include "../atomics.h"
#include "../hd.h"
#include "../rng.h"
#include "../snow_state.h"

namespace snow {

struct BedformArgs {
  float dtDays = 0.f;          // time covered by the step (sintering)
  int rounds = 1;              // polling rounds (each cell polled once a round)
  int batches = 4;             // batches a round
  uint64_t roundBase = 0;      // index of the step's first round (the RNG key)
  uint64_t seed = 1;
  float slabM = 0.02f;
  float hopLengthM = 2.5f;      // at referenceWindMps
  float referenceWindMps = 10.f;
  float thresholdWindMps = 4.f;  // no erosion, and hops end, where |W| is below it
  float depositSnow = 0.6f;      // p_s: landing probability on a cell holding slabs
  float depositBare = 0.4f;      // p_ns: on a cell without slabs
  float tanShadow = 0.2679492f;  // tan 15 deg
  float shadowLengthM = 10.f;
  float tanRepose = 0.5773503f;  // tan 30 deg
  float speedupLinear = 1.2f;    // hop metres per metre of take-off height above the mean
  float speedupQuadraticPerM = 0.018f;
  float meanSlabs = 0.f;         // mean slab count of the domain (set by the step)
  float maxSurface = 3.0e38f;    // highest surface of the batch's snapshot: bounds the shadow march
  float tanMaxSlope = 0.3639702f;  // domain: cells whose bed slope is at most this (tan 20 deg)
  float sinteringPerDay = 0.5f;
  float sinteringScaleC = 10.f;
  float seaLevelTemperatureC = 0.f;
  int maxHops = 64;
  bool periodic = false;       // wrap at the grid's edges (test windows); the season's grid is closed
  // Working values of a pass.
  int batch = 0;
  int family = 0;
  uint64_t round = 0;
};

// Cohesion carried by moving slabs is summed in fixed point (integer atomics: any order, same sum).
constexpr float kCohesionUnits = 4096.f;  // 12 bits: up to 524 287 slabs into one cell between passes
SNOW_HD SNOW_INLINE int cohesionUnits(float c) { return static_cast<int>(c * kCohesionUnits + 0.5f); }

// The bedform model's own fields (device or host memory), beside the snow fields.
enum class BedformStart { Zero, Powder, StepCounters };
// SNOW_BEDFORM_FIELDS(X) calls X(member, Element, start) for each of them, `start` saying what
// it holds when the backend makes it at the first bedform step: Zero, the powder layer then
// (Powder), or StepCounters (four values, zeroed at every step).
#define SNOW_BEDFORM_FIELDS(X)                                                                     \
  X(slabs, int, Zero)           /* current slab counts */                                          \
  X(snapshot, int, Zero)        /* slab counts at the batch's start */                             \
  X(exported, int, Zero)        /* slabs that left the domain into this (non-domain) cell */       \
  X(arrived, int, Zero)         /* slabs that arrived in this cell since the last cohesion pass */ \
  X(arrivedCohesion, int, Zero) /* the sum of their cohesions, in units of 1 / kCohesionUnits */   \
  /* [0] slabs eroded, [1] slab moves of the relaxation (a step's totals) */                       \
  X(counters, unsigned long long, StepCounters)                                                    \
  X(cohesion, float, Zero)      /* 0 loose .. 1 bonded (persistent) */                             \
  X(lastPowder, float, Powder)  /* P at the end of the previous step (persistent): fresh snow since */ \
  X(base, float, Zero)          /* surface altitude without the slabs (B + C + S + U + residual) */ \
  /* slab counts at the step's start (the rest of the powder, under one slab, stays put) */       \
  X(initial, int, Zero)                                                                            \
  X(shadow, uint8_t, Zero)                                                                         \
  X(active, uint8_t, Zero)      /* in the bedform domain this step */
struct BedformFields {
#define SNOW_BEDFORM_MEMBER(member, Element, start) Element* member = nullptr;
  SNOW_BEDFORM_FIELDS(SNOW_BEDFORM_MEMBER)
#undef SNOW_BEDFORM_MEMBER
  const uint8_t* mask = nullptr; // scene mask (SnowState::bedformMask; null: whole terrain)
};

namespace bedform {

// Cell (x, y) on the grid: wrapped (any distance) when periodic; false when a closed grid ends.
SNOW_HD SNOW_INLINE bool onGrid(const SnowFieldsView& v, bool periodic, int& x, int& y) {
  if (!periodic) return v.inside(x, y);
  x %= v.width;
  y %= v.height;
  if (x < 0) x += v.width;
  if (y < 0) y += v.height;
  return true;
}

// Surface altitude of cell i from the snapshot.
SNOW_HD SNOW_INLINE float snapSurface(const BedformFields& f, const BedformArgs& a, int i) {
  return f.base[i] + static_cast<float>(f.snapshot[i]) * a.slabM;
}

}  // namespace bedform

// Per cell, at the step's start: the domain, slab counts, residual and base; fresh snow since
// the previous step dilutes the cohesion.
struct BedformPrepareKernel {
  SnowFieldsView v;
  BedformFields f;
  BedformArgs a;

  SNOW_HD void operator()(int x, int y) const {
    const int i = v.index(x, y);
    f.exported[i] = 0;
    f.arrived[i] = 0;
    f.arrivedCohesion[i] = 0;
    const float p = v.powder[i];
    const float bed = v.bedrock[i] + v.compacted[i] + v.stable[i] + v.unstable[i];
    bool active = v.valid[i] != 0 && (f.mask == nullptr || f.mask[i] != 0);
    if (active) {  // bed slope by central differences over valid neighbours
      auto bedAt = [&](int j) { return v.bedrock[j] + v.compacted[j] + v.stable[j] + v.unstable[j]; };
      const int xl = v.isValid(x - 1, y) ? x - 1 : x, xr = v.isValid(x + 1, y) ? x + 1 : x;
      const int yu = v.isValid(x, y - 1) ? y - 1 : y, yd = v.isValid(x, y + 1) ? y + 1 : y;
      const float gx = xr > xl ? (bedAt(v.index(xr, y)) - bedAt(v.index(xl, y))) / (static_cast<float>(xr - xl) * v.cellSizeXM) : 0.f;
      const float gy = yd > yu ? (bedAt(v.index(x, yd)) - bedAt(v.index(x, yu))) / (static_cast<float>(yd - yu) * v.cellSizeYM) : 0.f;
      active = gx * gx + gy * gy <= a.tanMaxSlope * a.tanMaxSlope;
    }
    f.active[i] = active ? 1 : 0;
    // Fresh snow (more powder than the previous step left) has no cohesion yet.
    const float last = f.lastPowder[i];
    if (p > last && p > 0.f) f.cohesion[i] = f.cohesion[i] * (last / p);
    int n = 0;
    if (active && p > 0.f) {
      n = static_cast<int>(minf(floorf(p / a.slabM), 1.0e9f));  // deeper powder keeps the rest as residual
      if (n < 0) n = 0;
      // Under float rounding: the residual non-negative and below one slab.
      while (n > 0 && static_cast<float>(n) * a.slabM > p) --n;
      while (n < 1000000000 && static_cast<float>(n + 1) * a.slabM <= p) ++n;
    }
    const float residual = p - static_cast<float>(n) * a.slabM;
    f.slabs[i] = n;
    f.snapshot[i] = n;
    f.initial[i] = n;
    f.base[i] = bed + residual;
    v.delta[i] = active ? static_cast<float>(n) : 0.f;  // for the domain's mean slab count
    v.surfaceSlope[i] = active ? 1.f : 0.f;             // for the domain's cell count
  }
};

// The batch's snapshot of the slab counts, and its surface in `out` (for the highest surface).
struct BedformSnapshotKernel {
  SnowFieldsView v;
  BedformFields f;
  float slabM;
  float* out;
  SNOW_HD void operator()(int x, int y) const {
    const int i = v.index(x, y);
    f.snapshot[i] = f.slabs[i];
    out[i] = f.base[i] + static_cast<float>(f.slabs[i]) * slabM;
  }
};

// Werner's 15 deg wind shadow along the cell's own upwind direction, as the fraction of the cell
// it covers: each cell a flat plateau, the shadow line leaves the downwind edge of an upwind
// plateau at tan(shadow angle) downward; the fraction of the cell's length under it, 0..255.
// A fractional shadow keeps the model from depending on the slab thickness: a step of one thin
// slab shades part of the next cell instead of nothing (Werner's on/off test needs slabs as
// thick as tan 15 deg x a cell to start any bedform).
struct BedformShadowKernel {
  SnowFieldsView v;
  BedformFields f;
  BedformArgs a;

  SNOW_HD void operator()(int x, int y) const {
    const int i = v.index(x, y);
    f.shadow[i] = 0;
    if (!f.active[i]) return;
    const float wx = v.windX[i], wy = v.windY[i];
    const float speed = sqrtf(wx * wx + wy * wy);
    if (!(speed > 0.f)) return;
    const float ux = -wx / speed, uy = -wy / speed;  // upwind, metres
    const float stepM = minf(v.cellSizeXM, v.cellSizeYM);
    // The cell's length along the wind (the plateau the shadow falls on).
    const float along = minf(fabsf(ux) > 0.f ? v.cellSizeXM / fabsf(ux) : 3.0e38f, fabsf(uy) > 0.f ? v.cellSizeYM / fabsf(uy) : 3.0e38f);
    const float h = bedform::snapSurface(f, a, i);
    // Past rise_max / tan + along upwind, not even the highest surface could shade the cell.
    const float reach = minf(a.shadowLengthM, (a.maxSurface - h) / a.tanShadow + along);
    const int steps = static_cast<int>(reach / stepM) + 1;
    const float cx = (static_cast<float>(x) + 0.5f) * v.cellSizeXM, cy = (static_cast<float>(y) + 0.5f) * v.cellSizeYM;
    float covered = 0.f;  // metres of the cell under the shadow line
    int last = i;
    for (int s = 1; s <= steps; ++s) {
      const float d = static_cast<float>(s) * stepM;
      if (d > a.shadowLengthM) break;
      int nx = static_cast<int>(floorf((cx + ux * d) / v.cellSizeXM));
      int ny = static_cast<int>(floorf((cy + uy * d) / v.cellSizeYM));
      if (!bedform::onGrid(v, a.periodic, nx, ny)) break;  // (a periodic window may be narrower than the reach)
      const int j = v.index(nx, ny);
      if (j == i || j == last) continue;
      last = j;
      if (!v.valid[j]) break;
      // The upwind plateau's downwind edge is about d - along / 2 upwind of the cell's centre; the
      // line from it stays above the cell over (rise / tan - (d - along / 2)) + along / 2 metres.
      const float rise = bedform::snapSurface(f, a, j) - h;
      if (rise > 0.f) covered = maxf(covered, rise / a.tanShadow - d + along);
      if (covered >= along) break;
    }
    const float fraction = clampf(covered / along, 0.f, 1.f);
    f.shadow[i] = static_cast<uint8_t>(fraction * 255.f + 0.5f);
  }
};

// The polled cells of one batch erode a slab each and send it on its hops.
struct BedformSaltationKernel {
  SnowFieldsView v;
  BedformFields f;
  BedformArgs a;

  SNOW_HD float hopLength(int i, float speed) const {
    float l = a.hopLengthM * speed / a.referenceWindMps;
    const float dh = (static_cast<float>(f.snapshot[i]) - a.meanSlabs) * a.slabM;  // Momiji's speed-up
    l += a.speedupLinear * dh + (dh > 0.f ? a.speedupQuadraticPerM * dh * dh : 0.f);
    return maxf(l, maxf(v.cellSizeXM, v.cellSizeYM));  // a hop leaves its cell
  }

  SNOW_HD void operator()(int x, int y) const {
    const int i = v.index(x, y);
    if (!f.active[i] || f.snapshot[i] <= 0 || f.shadow[i] == 255) return;  // no erosion in full shadow
    const RandomKey key{a.seed};
    const Philox4x32 poll = key.draw(a.round, static_cast<uint32_t>(i), RngStream::BedformPoll);
    if (static_cast<int>(poll.v[0] % static_cast<uint32_t>(a.batches)) != a.batch) return;
    float wx = v.windX[i], wy = v.windY[i];
    float speed = sqrtf(wx * wx + wy * wy);
    // Cohesion raises the wind speed that can lift snow: threshold / (1 - c).
    if (!(speed * (1.f - f.cohesion[i]) >= a.thresholdWindMps) || !(speed > 0.f)) return;
    // The shaded part of the cell keeps its snow.
    float erodible = 1.f - static_cast<float>(f.shadow[i]) * (1.f / 255.f);
    if (v.windErosionFactor) erodible *= v.windErosionFactor[i];
    if (!(uniformFloat(poll.v[1]) < erodible)) return;
    atomicAddInt(&f.slabs[i], -1);
    atomicAddCount(&f.counters[0], 1ull);
    const int carried = cohesionUnits(f.cohesion[i]);  // the slab keeps its age on the way

    // Hops, stepped cell by cell in metres from the take-off cell's centre.
    int cx = x, cy = y, ci = i;
    float px = (static_cast<float>(x) + 0.5f) * v.cellSizeXM, py = (static_cast<float>(y) + 0.5f) * v.cellSizeYM;
    const float stepUpX = a.tanRepose * v.cellSizeXM, stepUpY = a.tanRepose * v.cellSizeYM;
    for (int hop = 0; hop < a.maxHops; ++hop) {
      const float dx = wx / speed, dy = wy / speed;
      const float length = hopLength(ci, speed);
      // DDA through the cells the hop's line crosses, in metres along it.
      const int sx = dx > 0.f ? 1 : -1, sy = dy > 0.f ? 1 : -1;
      const float adx = fabsf(dx), ady = fabsf(dy);
      const float fx = px / v.cellSizeXM - floorf(px / v.cellSizeXM), fy = py / v.cellSizeYM - floorf(py / v.cellSizeYM);
      float tx = adx > 0.f ? (sx > 0 ? (1.f - fx) : fx) * v.cellSizeXM / adx : 3.0e38f;
      float ty = ady > 0.f ? (sy > 0 ? (1.f - fy) : fy) * v.cellSizeYM / ady : 3.0e38f;
      const float deltaX = adx > 0.f ? v.cellSizeXM / adx : 3.0e38f, deltaY = ady > 0.f ? v.cellSizeYM / ady : 3.0e38f;
      for (;;) {
        const bool alongX = tx <= ty;
        const float t = alongX ? tx : ty;
        if (t > length) break;
        int nx = alongX ? cx + sx : cx, ny = alongX ? cy : cy + sy;
        if (!bedform::onGrid(v, a.periodic, nx, ny) || !v.valid[v.index(nx, ny)]) {
          land(ci, carried);  // the grid's edge and NODATA are walls
          return;
        }
        const int ni = v.index(nx, ny);
        if (!f.active[ni]) {  // leaves the bedform domain: powder of that cell
          atomicAddInt(&f.exported[ni], 1);
          return;
        }
        if (bedform::snapSurface(f, a, ni) - bedform::snapSurface(f, a, ci) > (alongX ? stepUpX : stepUpY)) {
          land(ci, carried);  // a step steeper than the repose angle stops it
          return;
        }
        cx = nx;
        cy = ny;
        ci = ni;
        if (alongX) tx += deltaX;
        else ty += deltaY;
      }
      px += dx * length;
      py += dy * length;
      if (a.periodic) {  // back inside the grid (the cell was wrapped already), however long the hop
        const float wM = static_cast<float>(v.width) * v.cellSizeXM, hM = static_cast<float>(v.height) * v.cellSizeYM;
        while (px < 0.f) px += wM;
        while (px >= wM) px -= wM;
        while (py < 0.f) py += hM;
        while (py >= hM) py -= hM;
      }
      // Keep the position inside the current cell under float rounding.
      px = clampf(px, static_cast<float>(cx) * v.cellSizeXM, (static_cast<float>(cx) + 0.999f) * v.cellSizeXM);
      py = clampf(py, static_cast<float>(cy) * v.cellSizeYM, (static_cast<float>(cy) + 0.999f) * v.cellSizeYM);
      // Landing: always in the shaded part of the cell, else p_s on snow, p_ns on bare ground.
      const Philox4x32 r = key.draw(a.round | (static_cast<uint64_t>(hop + 1) << 40), static_cast<uint32_t>(i), RngStream::BedformHop);
      const float shade = static_cast<float>(f.shadow[ci]) * (1.f / 255.f);
      const float pDeposit = shade + (1.f - shade) * (f.snapshot[ci] > 0 ? a.depositSnow : a.depositBare);
      if (uniformFloat(r.v[0]) < pDeposit) break;
      wx = v.windX[ci];
      wy = v.windY[ci];
      speed = sqrtf(wx * wx + wy * wy);
      if (!(speed >= a.thresholdWindMps) || !(speed > 0.f)) break;  // calm: it stays
    }
    land(ci, carried);
  }

  SNOW_HD void land(int ci, int carried) const {
    atomicAddInt(&f.slabs[ci], 1);
    atomicAddInt(&f.arrived[ci], 1);
    atomicAddInt(&f.arrivedCohesion[ci], carried);
  }
};

// Avalanching: one family of grid edges (0: x even to x + 1, 1: x odd to x + 1, 2: y even to
// y + 1, 3: y odd to y + 1); launched over (width + 1) / 2 by height, or width by (height + 1) / 2.
// Each edge moves whole slabs from its higher to its lower cell until the step is at most
// tan(repose) x spacing (or the higher cell has no slab left).
struct BedformReposeKernel {
  SnowFieldsView v;
  BedformFields f;
  BedformArgs a;

  SNOW_HD void operator()(int k, int m) const {
    const bool horizontal = a.family < 2;
    const int parity = a.family & 1;
    int x0, y0, x1, y1;
    if (horizontal) {
      x0 = 2 * k + parity;
      y0 = m;
      x1 = x0 + 1;
      y1 = y0;
      if (x0 >= v.width) return;
      if (x1 >= v.width) {
        if (!a.periodic) return;
        x1 = 0;
      }
    } else {
      x0 = k;
      y0 = 2 * m + parity;
      x1 = x0;
      y1 = y0 + 1;
      if (y0 >= v.height) return;
      if (y1 >= v.height) {
        if (!a.periodic) return;
        y1 = 0;
      }
    }
    const int i = v.index(x0, y0), j = v.index(x1, y1);
    if (i == j || !f.active[i] || !f.active[j]) return;
    const float limit = a.tanRepose * (horizontal ? v.cellSizeXM : v.cellSizeYM);
    const float hi = f.base[i] + static_cast<float>(f.slabs[i]) * a.slabM;
    const float hj = f.base[j] + static_cast<float>(f.slabs[j]) * a.slabM;
    const float d = hi - hj;
    if (fabsf(d) <= limit) return;
    const int from = d > 0.f ? i : j, to = d > 0.f ? j : i;
    int move = static_cast<int>(ceilf((fabsf(d) - limit) / (2.f * a.slabM)));
    if (move > f.slabs[from]) move = f.slabs[from];
    if (move <= 0) return;
    f.slabs[from] -= move;
    f.slabs[to] += move;
    f.arrived[to] += move;
    f.arrivedCohesion[to] += move * cohesionUnits(f.cohesion[from]);
    atomicAddCount(&f.counters[1], static_cast<unsigned long long>(move));
  }
};

// Cohesion: slabs that arrived since the last call bring the cohesion of the cell they left (snow
// keeps its age while the wind moves it) and mix in by count; then sintering over dtDays. Run
// after every round and at the step's end. Only new snow (snowfall) starts at 0.
struct BedformCohesionKernel {
  SnowFieldsView v;
  BedformFields f;
  BedformArgs a;

  SNOW_HD void operator()(int x, int y) const {
    const int i = v.index(x, y);
    if (!v.valid[i]) return;
    float c = f.cohesion[i];
    if (f.active[i] && f.arrived[i] > 0) {
      const int resting = maxi(0, f.slabs[i] - f.arrived[i]);
      const float brought = static_cast<float>(f.arrivedCohesion[i]) / kCohesionUnits;
      c = (c * static_cast<float>(resting) + brought) / static_cast<float>(resting + f.arrived[i]);
      f.arrived[i] = 0;
      f.arrivedCohesion[i] = 0;
    }
    if (a.dtDays > 0.f) {
      const float t = minf(0.f, a.seaLevelTemperatureC + v.temperatureBase[i]);
      // Halved at -scale degC, a third at -2 scale...: divisions only, the same bits on both backends.
      c = minf(1.f, c + a.dtDays * a.sinteringPerDay * a.sinteringScaleC / (a.sinteringScaleC - t));
    }
    f.cohesion[i] = c;
  }
};

// Back to the powder layer, and the records.
struct BedformFinishKernel {
  SnowFieldsView v;
  BedformFields f;
  BedformArgs a;

  SNOW_HD void operator()(int x, int y) const {
    const int i = v.index(x, y);
    const float before = v.powder[i];
    float after = before;
    // The slabs gained or lost, added once: a cell whose count did not change keeps its powder
    // to the bit (re-adding residual and slabs would round every domain cell every step).
    if (f.active[i]) {
      if (f.slabs[i] != f.initial[i]) after = before + static_cast<float>(f.slabs[i] - f.initial[i]) * a.slabM;
      if (after < 0.f) after = 0.f;  // (never: a cell loses at most the slabs it had; float guard)
    }
    else if (f.exported[i] > 0) after = before + static_cast<float>(f.exported[i]) * a.slabM;
    v.powder[i] = after;
    if (after < before && v.windScour) v.windScour[i] += before - after;  // records: null when not kept
    else if (after > before && v.windDeposit) v.windDeposit[i] += after - before;
    f.lastPowder[i] = after;
  }
};

}  // namespace snow
