#include "wind.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>

#include "core/util.h"

namespace snow {

namespace {

constexpr double kCalmMps = 1e-9;  // below this, W = 0: no shadow (the paper's special case)

// The upwind discretisation of v . grad f at a cell: a_x (f - f_ux) + a_y (f - f_uy), with
// a_x = |v_x| / dx and f_ux the neighbour the flow comes from along x. Missing upwind
// neighbours (grid edge, NODATA) drop their term: the inflow boundary.
//
// Two winds enter. On the ground, W_sz = W . grad A with W the terrain-following field of
// Eq. (2). Airborne (in a cap), W_sz and W_z are carried by the free-stream wind W_venturi =
// (1 + k_venturi A) W_d: above the cap the air no longer feels the slope beneath it, and Eq. (2)'s
// field diverges along ridges, where two neighbours are each other's upwind cell and the cap
// equation W . grad W_sz = -c has no solution (W_sz falls by c / a on every pass round the loop;
// Gauss-Seidel cycles, and cutting such loops leaves one-row streaks in the caps). The
// free stream has one direction everywhere, so the upwind graph has no loops, the fixed point is
// unique, and one sweep from the upwind corner reaches it.
struct Upwind {
  double ax = 0, ay = 0;
  int ux = -1, uy = -1;  // indices of the upwind neighbours, -1 if none
};

Upwind upwindOf(int x, int y, int w, int h, double vx, double vy, const GridSpec& spec, const Grid<uint8_t>& valid) {
  Upwind u;
  const int nx = vx > 0 ? x - 1 : x + 1, ny = vy > 0 ? y - 1 : y + 1;
  if (std::abs(vx) > kCalmMps && nx >= 0 && nx < w && valid(nx, y)) {
    u.ax = std::abs(vx) / spec.cellSizeXM;
    u.ux = y * w + nx;
  }
  if (std::abs(vy) > kCalmMps && ny >= 0 && ny < h && valid(x, ny)) {
    u.ay = std::abs(vy) / spec.cellSizeYM;
    u.uy = ny * w + x;
  }
  return u;
}

// The discrete equations, their coefficients made per cell as each update needs them from the
// free stream, the ground wind and the altitude (the same doubles as stored ones: 8 bytes a cell
// held, the free stream, where links and ground speeds held 32).
class WindSystem {
 public:
  WindSystem(const Grid<float>& altitude, const Grid<uint8_t>& valid, const GridSpec& spec, const Grid<float>& groundX,
             const Grid<float>& groundY, const Grid<float>& freeX, const Grid<float>& freeY, double c)
      : w_(spec.width), h_(spec.height), c_(c), spec_(spec), altitude_(altitude), valid_(valid), groundX_(groundX),
        groundY_(groundY), freeX_(freeX), freeY_(freeY) {}

  void initialise(std::vector<double>& wz, std::vector<double>& wsz) const {
    wz.assign(altitude_.values().begin(), altitude_.values().end());
    wsz.resize(wz.size());
    for (int y = 0; y < h_; ++y)
      for (int x = 0; x < w_; ++x) wsz[index(x, y)] = groundSpeed(x, y);
  }

  // One Gauss-Seidel update of cell (x, y) (the paper's three steps); returns the larger change.
  double update(int x, int y, std::vector<double>& wz, std::vector<double>& wsz) const {
    const size_t i = index(x, y);
    if (!valid_.values()[i]) return 0.0;
    const Upwind u = upwindOf(x, y, w_, h_, freeX_(x, y), freeY_(x, y), spec_, valid_);
    const double a = u.ax + u.ay;
    const double ground = altitude_.values()[i];
    double newSz, newZ;
    if (a <= 0.0) {  // calm, or an inflow boundary: the surface is the ground
      newZ = ground;
      newSz = groundSpeed(x, y);  // 0: no upwind neighbour to differ from
    } else {
      // 1. W_sz from W . grad W_sz = -c, independently of W_z;
      double sz = -c_, z = 0.0;
      if (u.ux >= 0) sz += u.ax * wsz[u.ux], z += u.ax * wz[u.ux];
      if (u.uy >= 0) sz += u.ay * wsz[u.uy], z += u.ay * wz[u.uy];
      newSz = sz / a;
      // 2. W_z from W . grad W_z = W_sz with the new W_sz;
      newZ = (newSz + z) / a;
      // 3. corrected where the surface meets the ground.
      if (newZ <= ground) {
        newZ = ground;
        newSz = groundSpeed(x, y);
      }
    }
    const double change = std::max(std::abs(newZ - wz[i]), std::abs(newSz - wsz[i]));
    wz[i] = newZ;
    wsz[i] = newSz;
    return change;
  }

  int width() const { return w_; }
  int height() const { return h_; }

 private:
  size_t index(int x, int y) const { return static_cast<size_t>(y) * w_ + x; }
  // W . grad A with the terrain-following wind, upwind like everything else.
  double groundSpeed(int x, int y) const {
    const Upwind g = upwindOf(x, y, w_, h_, groundX_(x, y), groundY_(x, y), spec_, valid_);
    const float here = altitude_.values()[index(x, y)];  // the differences in float, as the terrain
    double speed = 0.0;
    if (g.ux >= 0) speed += g.ax * (here - altitude_.values()[g.ux]);
    if (g.uy >= 0) speed += g.ay * (here - altitude_.values()[g.uy]);
    return speed;
  }

  int w_, h_;
  double c_;
  const GridSpec& spec_;
  const Grid<float>& altitude_;
  const Grid<uint8_t>& valid_;
  const Grid<float>&groundX_, &groundY_, &freeX_, &freeY_;
};

double redBlackHalf(const WindSystem& sys, int colour, std::vector<double>& wz, std::vector<double>& wsz) {
  const int w = sys.width();
  return tbb::parallel_reduce(
      tbb::blocked_range<int>(0, sys.height(), 16), 0.0,
      [&](const tbb::blocked_range<int>& rows, double acc) {
        for (int y = rows.begin(); y < rows.end(); ++y)
          for (int x = (colour + y) & 1; x < w; x += 2) acc = std::max(acc, sys.update(x, y, wz, wsz));
        return acc;
      },
      [](double a, double b) { return std::max(a, b); });
}

double sweep(const WindSystem& sys, bool xForward, bool yForward, std::vector<double>& wz, std::vector<double>& wsz) {
  const int w = sys.width(), h = sys.height();
  double change = 0.0;
  for (int k = 0; k < h; ++k) {
    const int y = yForward ? k : h - 1 - k;
    for (int j = 0; j < w; ++j) {
      const int x = xForward ? j : w - 1 - j;
      change = std::max(change, sys.update(x, y, wz, wsz));
    }
  }
  return change;
}

}  // namespace

const char* windOrderingName(WindOrdering o) { return o == WindOrdering::RedBlack ? "red-black" : "upwind sweep"; }

float WindField::speed(int x, int y) const { return std::hypot(windXMps(x, y), windYMps(x, y)); }

void dominantWind(const WindState& s, double& wx, double& wy) {
  const double t = s.directionDeg * kPi / 180.0;
  wx = -std::sin(t) * s.speedMps;  // blowing from the west (270) moves east (+x)
  wy = std::cos(t) * s.speedMps;   // blowing from the north (0) moves south (+y, rows)
  if (std::abs(wx) < 1e-12 * s.speedMps) wx = 0.0;
  if (std::abs(wy) < 1e-12 * s.speedMps) wy = 0.0;
}

void computeWindVectors(const Grid<float>& altitude, const Grid<uint8_t>& valid, const GridSpec& spec, const WindState& state,
                        const ModelParameters& p, Grid<float>& windX, Grid<float>& windY) {
  const int w = spec.width, h = spec.height;
  windX.resize(w, h, 0.f);
  windY.resize(w, h, 0.f);
  double dx, dy;
  dominantWind(state, dx, dy);
  tbb::parallel_for(tbb::blocked_range<int>(0, h, 16), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y < rows.end(); ++y)
      for (int x = 0; x < w; ++x) {
        if (!valid(x, y)) continue;
        const double a = altitude(x, y);
        // Venturi: W_venturi = (1 + k_venturi A) W_d
        const double f = 1.0 + p.venturiPerM * a;
        const double vx = f * dx, vy = f * dy;
        // Terrain gradient, central differences that skip NODATA.
        auto at = [&](int i, int j, double fallback) { return i >= 0 && j >= 0 && i < w && j < h && valid(i, j) ? altitude(i, j) : fallback; };
        const bool l = x > 0 && valid(x - 1, y), r = x + 1 < w && valid(x + 1, y);
        const bool u = y > 0 && valid(x, y - 1), d = y + 1 < h && valid(x, y + 1);
        const double gx = (l || r) ? (at(x + 1, y, a) - at(x - 1, y, a)) / ((l && r ? 2.0 : 1.0) * spec.cellSizeXM) : 0.0;
        const double gy = (u || d) ? (at(x, y + 1, a) - at(x, y - 1, a)) / ((u && d ? 2.0 : 1.0) * spec.cellSizeYM) : 0.0;
        // n_xy: horizontal part of the unit normal (-gx, -gy, 1) / |.|; |n_xy| = sin(slope).
        const double norm = std::sqrt(1.0 + gx * gx + gy * gy);
        const double nx = -gx / norm, ny = -gy / norm;
        const double nLen = std::sqrt(nx * nx + ny * ny);
        // n_xy rotated by 90 degrees, toward the wind (W_venturi . n_perp >= 0).
        double px = -ny, py = nx;
        if (px * vx + py * vy < 0.0) px = -px, py = -py;
        const double vLen = std::sqrt(vx * vx + vy * vy);
        // Eq. (2): W = W_venturi (1 - |n_xy|) + k_terrain |W_venturi| n_xy_perp
        windX(x, y) = static_cast<float>(vx * (1.0 - nLen) + p.terrainWindEffect * vLen * px);
        windY(x, y) = static_cast<float>(vy * (1.0 - nLen) + p.terrainWindEffect * vLen * py);
      }
  });
}

void computeFreeStream(const Grid<float>& altitude, const Grid<uint8_t>& valid, const GridSpec& spec, const WindState& state,
                       const ModelParameters& p, Grid<float>& freeX, Grid<float>& freeY) {
  double dx, dy;
  dominantWind(state, dx, dy);
  freeX.resize(spec.width, spec.height, 0.f);
  freeY.resize(spec.width, spec.height, 0.f);
  for (size_t i = 0; i < altitude.size(); ++i) {
    if (!valid.values()[i]) continue;
    const double f = 1.0 + p.venturiPerM * altitude.values()[i];
    freeX.values()[i] = static_cast<float>(f * dx);
    freeY.values()[i] = static_cast<float>(f * dy);
  }
}

WindSolveStats solveWindEffectSurface(const Grid<float>& altitude, const Grid<uint8_t>& valid, const GridSpec& spec,
                                      const Grid<float>& groundX, const Grid<float>& groundY, const Grid<float>& freeX,
                                      const Grid<float>& freeY, double c, const WindSolverOptions& o, Grid<float>& windEffectZ,
                                      Grid<float>& verticalSpeed) {
  const auto t0 = WallClock::now();
  const WindSystem sys(altitude, valid, spec, groundX, groundY, freeX, freeY, c);
  std::vector<double> wz, wsz;
  sys.initialise(wz, wsz);
  WindSolveStats stats;
  stats.ordering = windOrderingName(o.ordering);
  // The sweep orders, the free stream's first: that one sweep carries information across the
  // whole grid (the others matter only where the free stream is calm).
  double mx = 0, my = 0;
  for (size_t i = 0; i < freeX.size(); ++i) mx += freeX.values()[i], my += freeY.values()[i];
  const bool xf = mx >= 0, yf = my >= 0;
  const bool orders[4][2] = {{xf, yf}, {!xf, yf}, {xf, !yf}, {!xf, !yf}};
  for (int it = 0; it < o.maxIterations; ++it) {
    double change;
    if (o.ordering == WindOrdering::RedBlack) {
      change = std::max(redBlackHalf(sys, 0, wz, wsz), redBlackHalf(sys, 1, wz, wsz));
    } else {
      change = sweep(sys, orders[it % 4][0], orders[it % 4][1], wz, wsz);
    }
    stats.iterations = it + 1;
    stats.lastUpdate = change;
    if (change <= o.toleranceM) {
      stats.converged = true;
      break;
    }
  }
  // The residual of the discrete equations: how far one more update would move any cell (each
  // cell updated, then put back: its neighbours see the solution, not a copy of it).
  double residual = 0.0;
  for (int y = 0; y < spec.height; ++y)
    for (int x = 0; x < spec.width; ++x) {
      const size_t i = static_cast<size_t>(y) * spec.width + x;
      const double z = wz[i], sz = wsz[i];
      residual = std::max(residual, sys.update(x, y, wz, wsz));
      wz[i] = z, wsz[i] = sz;
    }
  stats.residual = residual;
  windEffectZ.resize(spec.width, spec.height);
  verticalSpeed.resize(spec.width, spec.height);
  for (size_t i = 0; i < wz.size(); ++i) {
    windEffectZ.values()[i] = static_cast<float>(wz[i]);
    verticalSpeed.values()[i] = static_cast<float>(wsz[i]);
  }
  stats.seconds = elapsedSeconds(t0);
  return stats;
}

WindField computeWindField(const Grid<float>& altitude, const Grid<uint8_t>& valid, const GridSpec& spec, const WindState& state,
                           const ModelParameters& p, const WindSolverOptions& o) {
  WindField f;
  computeWindVectors(altitude, valid, spec, state, p, f.windXMps, f.windYMps);
  Grid<float> freeX, freeY;
  computeFreeStream(altitude, valid, spec, state, p, freeX, freeY);
  f.stats = solveWindEffectSurface(altitude, valid, spec, f.windXMps, f.windYMps, freeX, freeY, p.windCapDecelerationMps2, o,
                                   f.windEffectZM, f.verticalSpeedMps);
  return f;
}

}  // namespace snow
