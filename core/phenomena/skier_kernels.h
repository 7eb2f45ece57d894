// The skiers' arguments, agents and kernels. What they model and how a batch runs them is in
// skiers.h, where a reader starts.
#pragma once
#include <climits>
#include <cstdint>

#include "../atomics.h"
#include "../hd.h"
#include "../rng.h"
#include "../snow_state.h"
#include "../util.h"
#include "powder_diffusion.h"

namespace snow {

// One step of the route map's cellular automaton: out = max over lower valid neighbours of
// in(n) + |cn| (0 with none). Iterate until out == in.
struct RouteMapStepKernel {
  const float* altitude;
  const uint8_t* valid;
  const float* in;
  float* out;
  int width, height;
  float dx, dy, diagonal;
  SNOW_HD void operator()(int x, int y) const {
    const int i = y * width + x;
    float best = 0.f;
    if (valid[i]) {
      for (int oy = -1; oy <= 1; ++oy)
        for (int ox = -1; ox <= 1; ++ox) {
          if (ox == 0 && oy == 0) continue;
          const int nx = x + ox, ny = y + oy;
          if (nx < 0 || ny < 0 || nx >= width || ny >= height) continue;
          const int n = ny * width + nx;
          if (!valid[n] || !(altitude[n] < altitude[i])) continue;
          const float d = ox == 0 ? dy : oy == 0 ? dx : diagonal;
          const float through = in[n] + d;
          best = through > best ? through : best;
        }
    }
    out[i] = best;
  }
};

namespace skimath {
// atan(t) for t >= 0 in + - * / only: reduced to |t| <= tan(pi/12) (1/t past 1, then the
// addition formula at pi/6) and summed to t^25 (truncation below 1e-16; tested against std::atan).
SNOW_HD SNOW_INLINE double atanPositive(double t) {
  const bool invert = t > 1.0;
  if (invert) t = 1.0 / t;
  const bool shift = t > 0.2679491924311227;  // tan(pi/12)
  const double sqrt3 = 1.7320508075688772;
  if (shift) t = (t * sqrt3 - 1.0) / (sqrt3 + t);
  const double t2 = t * t;
  double s = 1.0 / 25.0;
  for (int k = 11; k >= 0; --k) s = 1.0 / (2 * k + 1) - t2 * s;
  double r = t * s;
  if (shift) r += kPi / 6.0;
  if (invert) r = kPi / 2.0 - r;
  return r;
}
// exp(x) for x <= 0 (0 below -700 and for NaN): 2^k e^r with |r| <= ln2 / 2, e^r to r^14.
SNOW_HD SNOW_INLINE double expNonPositive(double x) {
  if (!(x > -700.0)) return 0.0;
  if (x > 0.0) x = 0.0;
  const double k = floor(x * 1.4426950408889634 + 0.5);
  const double r = (x - k * 0.6931471803691238) - k * 1.9082149292705877e-10;  // ln 2, high and low parts
  double s = 1.0;
  for (int n = 14; n >= 1; --n) s = 1.0 + r * s / n;
  return ldexp(s, static_cast<int>(k));
}
}  // namespace skimath

// Why a skier stopped (kSkierActive while it runs).
enum SkierStatus : int {
  kSkierActive = 0,
  kSkierStepLimit,
  kSkierRouteEnd,
  kSkierNoCellAhead,
  kSkierReachedEdge,
  kSkierNodataAhead,
  kSkierSnowRanOut,
  kSkierTriggered,
  kSkierStartNodata,
  kSkierNoSnowAtStart,
};

// One skier of a batch.
struct SkierAgent {
  double x = 0.0, y = 0.0;    // position, metres (x east from the west edge, y south from the north edge)
  double hx = 0.0, hy = 0.0;  // heading (0, 0 before the first step)
  double lengthM = 0.0;       // large-scale path length so far
  unsigned long long id = 0;  // the skier's random stream
  int cell = -1;              // the cell it is in
  int startCell = -1;
  int dest = -1;              // the new cell it entered this step (-1: none, or already applied)
  int steps = 0;              // moves made (the random draws' counter)
  int cells = 0;              // cells entered
  int status = kSkierActive;
  int triggerCell = -1;
  int pathCount = 0;          // points in its slot of the path buffer since the host last read it
};

struct SkierArgs {
  double dx = 1.0, dy = 1.0, stepM = 1.0;  // cell size; a move's length (the smaller side)
  int reach = 1;                           // look-ahead in cells
  double reachM = 1.0;                     // look-ahead in metres (reach x stepM)
  double targetRad = 0.5236, sigmaRad = 0.1745;
  double cosHalfCone = -0.17364817766693033;  // cos 100 deg: cells behind the heading are not looked at
  double tanRest = 0.0;                       // avalanche rest slope
  double minSnowM = 0.3, steering = 0.5, triggerFactor = 0.0, minUnstableM = 0.0;
  float compactionM = 0.05f;
  int maxSteps = 1;
  int pathStride = 1;  // points per skier in the path buffer
  unsigned long long seed = 0;
};

struct SkierFields {
  SkierAgent* agents = nullptr;
  int count = 0;
  double* path = nullptr;        // 2 x pathStride doubles per skier
  const float* route = nullptr;  // the route map
  int* claim = nullptr;          // per cell: INT_MAX, or the lowest index of the skiers entering it
  int* counters = nullptr;       // [0] skiers still running after a move, [1] entries left after a round
};

namespace skier {
SNOW_HD SNOW_INLINE void record(const SkierFields& f, const SkierArgs& a, int i, SkierAgent& s) {
  double* p = f.path + 2 * (static_cast<size_t>(i) * a.pathStride + s.pathCount);
  p[0] = s.x;
  p[1] = s.y;
  ++s.pathCount;
}
// `amount` of U becomes S, and what U lacks of it, S becomes C (a part of a layer moves as
// transport moves it; a whole layer whole).
SNOW_HD SNOW_INLINE void compact(const SnowFieldsView& v, int c, float amount) {
  float u = v.unstable[c], st = v.stable[c], cc = v.compacted[c];
  auto move = [](float& from, float& to, float m) {
    if (m >= from) {
      to += from;
      from = 0.f;
    } else {
      from = giveTo(to, m, from, nullptr);
    }
  };
  const float fromU = minf(u, amount);
  move(u, st, fromU);
  move(st, cc, minf(st, amount - fromU));
  v.unstable[c] = u;
  v.stable[c] = st;
  v.compacted[c] = cc;
}
}  // namespace skier

// Puts each skier on its start cell (or stops it there) and records its first point; the start
// cell's compaction then goes through the claim rounds like any entry.
struct SkierStartKernel {
  SnowFieldsView v;
  SkierFields f;
  SkierArgs a;
  SNOW_HD void operator()(int i) const {
    SkierAgent& s = f.agents[i];
    s.dest = -1;
    const int c = s.startCell, cx = c % v.width, cy = c / v.width;
    if (!v.valid[c]) {
      s.status = kSkierStartNodata;
      return;
    }
    if (v.snowDepth(c) < a.minSnowM) {
      s.status = kSkierNoSnowAtStart;
      return;
    }
    s.status = kSkierActive;
    s.cell = c;
    s.x = (cx + 0.5) * a.dx;
    s.y = (cy + 0.5) * a.dy;
    s.hx = s.hy = 0.0;
    skier::record(f, a, i, s);
    s.dest = c;
  }
};

// One move of every running skier (see the top of this file and core/ski_runs.h).
struct SkierMoveKernel {
  SnowFieldsView v;
  SkierFields f;
  SkierArgs a;

  // Eq. 4's weight of the cell at offset (ox, oy) from (cx, cy); 0 when it may not be aimed at.
  SNOW_HD double weight(const SkierAgent& s, int cx, int cy, int ox, int oy, float here) const {
    const int nx = cx + ox, ny = cy + oy;
    if ((ox == 0 && oy == 0) || !v.isValid(nx, ny)) return 0.0;
    const double ddx = ox * a.dx, ddy = oy * a.dy, dist = sqrt(ddx * ddx + ddy * ddy);
    if (dist > a.reachM * 1.0001) return 0.0;
    if ((s.hx != 0.0 || s.hy != 0.0) && ddx * s.hx + ddy * s.hy < a.cosHalfCone * dist) return 0.0;
    const int n = v.index(nx, ny);
    if (v.snowDepth(n) < a.minSnowM) return 0.0;
    const double drop = here - v.surface(n);
    if (!(drop > 0.0)) return 0.0;
    const double e = (skimath::atanPositive(drop / dist) - a.targetRad) / a.sigmaRad;
    const double w = skimath::expNonPositive(-e * e) * (static_cast<double>(f.route[n]) + dist);
    return w > 0.0 ? w : 0.0;
  }

  // The cell the skier aims at this step: drawn among the cells within reach, each by its weight
  // (counter-based: the same on every backend); -1 when none has weight.
  SNOW_HD int drawTarget(const SkierAgent& s, int cx, int cy, float here, int step) const {
    const int w = v.width;
    const int R = a.reach;
    double total = 0.0;
    for (int oy = -R; oy <= R; ++oy)
      for (int ox = -R; ox <= R; ++ox) total += weight(s, cx, cy, ox, oy, here);
    if (!(total > 0.0)) return -1;
    const RandomKey key{a.seed};
    const Philox4x32 draw = key.draw(s.id * 1000003ull + static_cast<unsigned long long>(step), 0, RngStream::Skier);
    double u = uniformOpenDouble(draw.v[0], draw.v[1]) * total;
    int chosen = -1, last = -1;
    for (int oy = -R; oy <= R && chosen < 0; ++oy)
      for (int ox = -R; ox <= R; ++ox) {
        const double wgt = weight(s, cx, cy, ox, oy, here);
        if (!(wgt > 0.0)) continue;
        last = (cy + oy) * w + (cx + ox);
        if ((u -= wgt) <= 0.0) {
          chosen = last;
          break;
        }
      }
    return chosen < 0 ? last : chosen;
  }

  // The heading turned towards the target's direction (wantX, wantY) by the steering share.
  SNOW_HD void turn(SkierAgent& s, double wantX, double wantY) const {
    if (s.hx == 0.0 && s.hy == 0.0) {
      s.hx = wantX;
      s.hy = wantY;
    } else {
      const double hx = (1 - a.steering) * s.hx + a.steering * wantX;
      const double hy = (1 - a.steering) * s.hy + a.steering * wantY, hl = sqrt(hx * hx + hy * hy);
      if (hl > 1e-9) {
        s.hx = hx / hl;
        s.hy = hy / hl;
      } else {
        s.hx = wantX;
        s.hy = wantY;
      }
    }
  }

  // Where the step ends (toX, toY), or why the skier stops (kSkierActive: it goes on). The smooth
  // turn must not carry the skier where it would not go: uphill, out of the snow, or into a dead
  // end (a route much shorter than the target's). Then it turns straight at the target in the
  // same step (redrawing would turn it toward an old target and could spin it in place); if even
  // that fails, it steps to the neighbour nearest the target's direction.
  SNOW_HD int stepEnd(SkierAgent& s, int cur, int chosen, double wantX, double wantY, double& toX, double& toY) const {
    const int w = v.width, h = v.height, cx = cur % w, cy = cur / w;
    const float routeFloor = 0.5f * f.route[chosen];
    auto enterable = [&](int c) {
      return v.snowDepth(c) >= a.minSnowM && v.surface(c) <= v.surface(cur) && f.route[c] >= routeFloor;
    };
    double nextX = 0.0, nextY = 0.0;
    int ncell = -1;
    auto aim = [&]() -> int {
      nextX = s.x + s.hx * a.stepM;
      nextY = s.y + s.hy * a.stepM;
      if (nextX < 0 || nextY < 0 || nextX >= w * a.dx || nextY >= h * a.dy) return kSkierReachedEdge;
      const int nx = static_cast<int>(nextX / a.dx), ny = static_cast<int>(nextY / a.dy);
      if (!v.valid[ny * w + nx]) return kSkierNodataAhead;
      ncell = ny * w + nx;
      return kSkierActive;
    };
    int stop = aim();
    if (stop == kSkierActive && ncell != cur && !enterable(ncell) && !(s.hx == wantX && s.hy == wantY)) {
      s.hx = wantX;
      s.hy = wantY;
      stop = aim();
    }
    if (stop != kSkierActive) return stop;
    toX = nextX, toY = nextY;
    if (ncell == cur || enterable(ncell)) return kSkierActive;
    int best = -1;
    double bestDot = 0.5;  // cos 60 deg
    for (int oy = -1; oy <= 1; ++oy)
      for (int ox = -1; ox <= 1; ++ox) {
        const int bx = cx + ox, by = cy + oy;
        if ((ox == 0 && oy == 0) || !v.isValid(bx, by)) continue;
        const int b = by * w + bx;
        if (!enterable(b)) continue;
        const double ex = (bx + 0.5) * a.dx - s.x, ey = (by + 0.5) * a.dy - s.y, el = sqrt(ex * ex + ey * ey);
        const double dot = (ex * wantX + ey * wantY) / el;
        if (dot > bestDot) bestDot = dot, best = b;
      }
    if (best < 0) return kSkierNoCellAhead;
    toX = (best % w + 0.5) * a.dx;
    toY = (best / w + 0.5) * a.dy;
    const double ex = toX - s.x, ey = toY - s.y, el = sqrt(ex * ex + ey * ey);
    s.hx = ex / el;
    s.hy = ey / el;
    return kSkierActive;
  }

  SNOW_HD void operator()(int i) const {
    SkierAgent& s = f.agents[i];
    s.dest = -1;
    if (s.status != kSkierActive) return;
    const int w = v.width;
    const int step = s.steps++;
    if (step >= a.maxSteps) {
      s.status = kSkierStepLimit;
      return;
    }
    const int cur = s.cell, cx = cur % w, cy = cur / w;
    if (f.route[cur] <= 0.f) {
      s.status = kSkierRouteEnd;
      return;
    }
    const int chosen = drawTarget(s, cx, cy, v.surface(cur), step);
    if (chosen < 0) {
      s.status = kSkierNoCellAhead;
      return;
    }
    const double tx = (chosen % w + 0.5) * a.dx - s.x, ty = (chosen / w + 0.5) * a.dy - s.y;
    const double tl = sqrt(tx * tx + ty * ty);
    const double wantX = tx / tl, wantY = ty / tl;
    turn(s, wantX, wantY);
    double toX = 0.0, toY = 0.0;
    const int stop = stepEnd(s, cur, chosen, wantX, wantY, toX, toY);
    if (stop != kSkierActive) {
      s.status = stop;
      return;
    }
    const double mx = toX - s.x, my = toY - s.y;
    s.lengthM += sqrt(mx * mx + my * my);
    s.x = toX;
    s.y = toY;
    skier::record(f, a, i, s);
    const int entering = static_cast<int>(s.y / a.dy) * w + static_cast<int>(s.x / a.dx);
    if (entering != cur) s.dest = entering;
    atomicAddInt(&f.counters[0], 1);
  }
};

// Each skier with an entry to apply bids for its cell: the lowest index wins.
struct SkierClaimKernel {
  SkierFields f;
  SNOW_HD void operator()(int i) const {
    const int d = f.agents[i].dest;
    if (d >= 0) atomicMinInt(&f.claim[d], i);
  }
};

// The claims' winners apply their entries (the start cell's compaction on a skier's first entry;
// later: the snow check, the avalanche trigger and the compaction) and free their cells; the
// others count themselves for the next round.
struct SkierEnterKernel {
  SnowFieldsView v;
  SkierFields f;
  SkierArgs a;
  SNOW_HD void operator()(int i) const {
    SkierAgent& s = f.agents[i];
    const int c = s.dest;
    if (c < 0) return;
    if (atomicLoadInt(&f.claim[c]) != i) {
      atomicAddInt(&f.counters[1], 1);
      return;
    }
    if (s.steps > 0) {
      const int w = v.width, h = v.height, cx = c % w, cy = c / w;
      s.cell = c;
      ++s.cells;
      const float U = v.unstable[c];
      if (v.snowDepth(c) < a.minSnowM) {
        s.status = kSkierSnowRanOut;
      } else if (U >= a.minUnstableM && a.triggerFactor > 0.0) {
        // Crossing unstable snow on a slope above the rest angle: the raised release probability.
        auto at = [&](int xx, int yy) {
          xx = xx < 0 ? 0 : (xx >= w ? w - 1 : xx);
          yy = yy < 0 ? 0 : (yy >= h ? h - 1 : yy);
          return v.surface(yy * w + xx);
        };
        const double gx = (at(cx + 1, cy) - at(cx - 1, cy)) / (2 * a.dx), gy = (at(cx, cy + 1) - at(cx, cy - 1)) / (2 * a.dy);
        const double slope = sqrt(gx * gx + gy * gy);
        if (slope > a.tanRest) {
          double pRelease = a.triggerFactor * U * (slope - a.tanRest) / (1.0 - a.tanRest);
          if (pRelease > 1.0) pRelease = 1.0;
          const RandomKey key{a.seed};
          const Philox4x32 t = key.draw(s.id * 1000003ull + static_cast<unsigned long long>(s.steps - 1), 1, RngStream::Skier);
          if (uniformOpenDouble(t.v[0], t.v[1]) < pRelease) {
            s.status = kSkierTriggered;
            s.triggerCell = c;
          }
        }
      }
    }
    skier::compact(v, c, a.compactionM);
    s.dest = -1;
    atomicStoreInt(&f.claim[c], INT_MAX);
  }
};

}  // namespace snow
