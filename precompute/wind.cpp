#include "wind.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <optional>

#include "core/util.h"
#include "wind_system.h"

namespace snow {

namespace {

double redBlackHalf(const WindSystem& sys, int colour, std::vector<double>& wz, std::vector<double>& wsz) {
  const CellRect& r = sys.cells();
  return tbb::parallel_reduce(
      tbb::blocked_range<int>(r.y0, r.y1, 16), 0.0,
      [&](const tbb::blocked_range<int>& rows, double acc) {
        for (int y = rows.begin(); y < rows.end(); ++y)
          for (int x = r.x0 + ((colour + y + r.x0) & 1); x < r.x1; x += 2) acc = std::max(acc, sys.update(x, y, wz, wsz));
        return acc;
      },
      [](double a, double b) { return std::max(a, b); });
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
                        const ModelParameters& p, Grid<float>& windX, Grid<float>& windY, std::optional<CellRect> part) {
  const int w = spec.width, h = spec.height;
  const CellRect cells = part.value_or(CellRect::whole(spec));
  windX.resize(cells.width(), cells.height(), 0.f);
  windY.resize(cells.width(), cells.height(), 0.f);
  double dx, dy;
  dominantWind(state, dx, dy);
  tbb::parallel_for(tbb::blocked_range<int>(cells.y0, cells.y1, 16), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y < rows.end(); ++y)
      for (int x = cells.x0; x < cells.x1; ++x) {
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
        windX.values()[cells.offsetOf(x, y)] = static_cast<float>(vx * (1.0 - nLen) + p.terrainWindEffect * vLen * px);
        windY.values()[cells.offsetOf(x, y)] = static_cast<float>(vy * (1.0 - nLen) + p.terrainWindEffect * vLen * py);
      }
  });
}

void computeFreeStream(const Grid<float>& altitude, const Grid<uint8_t>& valid, const GridSpec& spec, const WindState& state,
                       const ModelParameters& p, Grid<float>& freeX, Grid<float>& freeY, std::optional<CellRect> part) {
  double dx, dy;
  dominantWind(state, dx, dy);
  const CellRect cells = part.value_or(CellRect::whole(spec));
  freeX.resize(cells.width(), cells.height(), 0.f);
  freeY.resize(cells.width(), cells.height(), 0.f);
  for (int y = cells.y0; y < cells.y1; ++y)
    for (int x = cells.x0; x < cells.x1; ++x) {
      if (!valid(x, y)) continue;
      const double f = 1.0 + p.venturiPerM * altitude(x, y);
      freeX.values()[cells.offsetOf(x, y)] = static_cast<float>(f * dx);
      freeY.values()[cells.offsetOf(x, y)] = static_cast<float>(f * dy);
    }
}

WindSolveStats solveWindEffectSurface(const Grid<float>& altitude, const Grid<uint8_t>& valid, const GridSpec& spec,
                                      const Grid<float>& groundX, const Grid<float>& groundY, const Grid<float>& freeX,
                                      const Grid<float>& freeY, double c, const WindSolverOptions& o, Grid<float>& windEffectZ,
                                      Grid<float>& verticalSpeed) {
  const auto t0 = WallClock::now();
  const CellRect whole = CellRect::whole(spec);
  const WindSystem sys(altitude, valid, spec, whole, groundX, groundY, freeX, freeY, c);
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
      change = sweepCells(sys, whole, orders[it % 4][0], orders[it % 4][1], wz, wsz);
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
  stats.residual = residualOver(sys, whole, wz, wsz);
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
