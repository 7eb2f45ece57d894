// The wind-effect surface's discrete equations (wind.h), shared by the whole grid's solve
// (wind.cpp) and a rank's part of it across ranks (distributed/wind_across_ranks.cpp).
#pragma once
#include <algorithm>
#include <cmath>
#include <vector>

#include "core/grid.h"
#include "core/grid_window.h"

namespace snow {

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
  long long ux = -1, uy = -1;  // indices of the upwind neighbours, -1 if none
};

// Whole-grid cell (x, y); the neighbours' indices are offsets in `cells`, which holds them.
inline Upwind upwindOf(int x, int y, const CellRect& cells, double vx, double vy, const GridSpec& spec, const Grid<uint8_t>& valid) {
  Upwind u;
  const int nx = vx > 0 ? x - 1 : x + 1, ny = vy > 0 ? y - 1 : y + 1;
  if (std::abs(vx) > kCalmMps && nx >= 0 && nx < spec.width && valid(nx, y)) {
    u.ax = std::abs(vx) / spec.cellSizeXM;
    u.ux = static_cast<long long>(cells.offsetOf(nx, y));
  }
  if (std::abs(vy) > kCalmMps && ny >= 0 && ny < spec.height && valid(x, ny)) {
    u.ay = std::abs(vy) / spec.cellSizeYM;
    u.uy = static_cast<long long>(cells.offsetOf(x, ny));
  }
  return u;
}

// The discrete equations on `cells` of the grid (the whole grid, or a rank's local grid), their
// coefficients made per cell as each update needs them from the free stream, the ground wind and
// the altitude (the same doubles as stored ones: 8 bytes a cell held, the free stream, where links
// and ground speeds held 32). The altitude and validity are the whole grid's; the winds, W_z and
// W_sz are the cells'. A cell's update reads its upwind neighbours alone, which `cells` must hold.
class WindSystem {
 public:
  WindSystem(const Grid<float>& altitude, const Grid<uint8_t>& valid, const GridSpec& spec, const CellRect& cells,
             const Grid<float>& groundX, const Grid<float>& groundY, const Grid<float>& freeX, const Grid<float>& freeY, double c)
      : cells_(cells), c_(c), spec_(spec), altitude_(altitude), valid_(valid), groundX_(groundX), groundY_(groundY), freeX_(freeX),
        freeY_(freeY) {}

  // W_z = A, W_sz = W . grad A (the paper's).
  void initialise(std::vector<double>& wz, std::vector<double>& wsz) const {
    wz.resize(cells_.cells());
    wsz.resize(cells_.cells());
    for (int y = cells_.y0; y < cells_.y1; ++y)
      for (int x = cells_.x0; x < cells_.x1; ++x) {
        wz[index(x, y)] = altitude_(x, y);
        wsz[index(x, y)] = groundSpeed(x, y);
      }
  }

  // One Gauss-Seidel update of whole-grid cell (x, y) (the paper's three steps); returns the larger change.
  double update(int x, int y, std::vector<double>& wz, std::vector<double>& wsz) const {
    if (!valid_(x, y)) return 0.0;
    const size_t i = index(x, y);
    const Upwind u = upwindOf(x, y, cells_, freeX_.values()[i], freeY_.values()[i], spec_, valid_);
    const double a = u.ax + u.ay;
    const double ground = altitude_(x, y);
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

  const CellRect& cells() const { return cells_; }
  size_t index(int x, int y) const { return cells_.offsetOf(x, y); }
  // W . grad A with the terrain-following wind, upwind like everything else.
  double groundSpeed(int x, int y) const {
    const size_t i = index(x, y);
    const int nx = groundX_.values()[i] > 0 ? x - 1 : x + 1, ny = groundY_.values()[i] > 0 ? y - 1 : y + 1;
    const Upwind g = upwindOf(x, y, cells_, groundX_.values()[i], groundY_.values()[i], spec_, valid_);
    const float here = altitude_(x, y);  // the differences in float, as the terrain
    double speed = 0.0;
    if (g.ux >= 0) speed += g.ax * (here - altitude_(nx, y));
    if (g.uy >= 0) speed += g.ay * (here - altitude_(x, ny));
    return speed;
  }

 private:
  CellRect cells_;
  double c_;
  const GridSpec& spec_;
  const Grid<float>& altitude_;
  const Grid<uint8_t>& valid_;
  const Grid<float>&groundX_, &groundY_, &freeX_, &freeY_;
};

// One Gauss-Seidel sweep over the cells `over` (which the system's cells hold), rows in y's order,
// each row in x's; returns the largest change.
inline double sweepCells(const WindSystem& sys, const CellRect& over, bool xForward, bool yForward, std::vector<double>& wz,
                         std::vector<double>& wsz) {
  double change = 0.0;
  for (int k = 0; k < over.height(); ++k) {
    const int y = yForward ? over.y0 + k : over.y1 - 1 - k;
    for (int j = 0; j < over.width(); ++j) {
      const int x = xForward ? over.x0 + j : over.x1 - 1 - j;
      change = std::max(change, sys.update(x, y, wz, wsz));
    }
  }
  return change;
}

// The residual of the discrete equations over `over`: how far one more update would move any cell
// (each cell updated, then put back: its neighbours see the solution, not a copy of it).
inline double residualOver(const WindSystem& sys, const CellRect& over, std::vector<double>& wz, std::vector<double>& wsz) {
  double residual = 0.0;
  for (int y = over.y0; y < over.y1; ++y)
    for (int x = over.x0; x < over.x1; ++x) {
      const size_t i = sys.index(x, y);
      const double z = wz[i], sz = wsz[i];
      residual = std::max(residual, sys.update(x, y, wz, wsz));
      wz[i] = z, wsz[i] = sz;
    }
  return residual;
}

}  // namespace snow
