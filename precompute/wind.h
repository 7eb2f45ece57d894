// The wind of the paper's §4.2: a 2D field over the terrain (venturi speed-up with altitude,
// redirection along slopes, Eq. 2) and the wind-effect surface W_z, the lowest altitude above
// which the wind blows at full strength, with its vertical speed W_sz:
//   W . grad W_sz = -c        where W_z > A (a wind-shadow cap)
//   W_sz = W . grad A         otherwise (the surface hugs the ground)
//   W . grad W_z  = W_sz
// Directional derivatives are discretised upwind; the system is solved by Gauss-Seidel, either
// red-black (the paper's checkerboard) or sweeping from the upwind side. Airborne, the cap is
// carried by the free-stream wind rather than Eq. (2)'s terrain-following one (wind.cpp).
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "core/grid.h"
#include "core/grid_window.h"
#include "core/parameters.h"

namespace snow {

struct WindState {
  double directionDeg = 270.0;  // where the wind blows from, clockwise from north
  double speedMps = 0.0;        // at sea level
  bool operator==(const WindState& o) const { return directionDeg == o.directionDeg && speedMps == o.speedMps; }
};

enum class WindOrdering { RedBlack, UpwindSweep };
const char* windOrderingName(WindOrdering o);

struct WindSolverOptions {
  WindOrdering ordering = WindOrdering::UpwindSweep;  // the faster (docs/benchmarks.md)
  double toleranceM = 1e-4;    // stop when no cell's W_z (m) or W_sz (m/s) moves more than this in an iteration
  int maxIterations = 100000;  // full iterations (both colours, or one sweep)
};

struct WindSolveStats {
  std::string ordering;
  int iterations = 0;
  double lastUpdate = 0.0;   // largest change in the last iteration
  double residual = 0.0;     // largest residual of the discrete equations at the end (m)
  double seconds = 0.0;
  bool converged = false;
};

struct WindField {
  Grid<float> windXMps, windYMps;  // W: x east, y south (rows)
  Grid<float> windEffectZM;        // W_z
  Grid<float> verticalSpeedMps;    // W_sz
  WindSolveStats stats;
  float speed(int x, int y) const;
};

// The dominant wind vector W_d (x east, y south) for a state.
void dominantWind(const WindState& state, double& wx, double& wy);

// Eq. (2) with the venturi term, per cell, from the altitude A (bedrock); with `cells`, grids
// of those cells alone.
void computeWindVectors(const Grid<float>& altitude, const Grid<uint8_t>& valid, const GridSpec& spec, const WindState& state,
                        const ModelParameters& params, Grid<float>& windX, Grid<float>& windY,
                        std::optional<CellRect> cells = std::nullopt);

// The free stream W_venturi = (1 + k_venturi A) W_d: the wind above the caps.
void computeFreeStream(const Grid<float>& altitude, const Grid<uint8_t>& valid, const GridSpec& spec, const WindState& state,
                       const ModelParameters& params, Grid<float>& freeX, Grid<float>& freeY, std::optional<CellRect> cells = std::nullopt);

// Solves for W_z and W_sz: on the ground W_sz = W . grad A with the terrain-following wind
// (ground*), airborne the cap is carried by the free stream (free*); see wind.cpp for why.
// Initialisation W_z = A, W_sz = W . grad A (the paper's).
WindSolveStats solveWindEffectSurface(const Grid<float>& altitude, const Grid<uint8_t>& valid, const GridSpec& spec,
                                      const Grid<float>& groundX, const Grid<float>& groundY, const Grid<float>& freeX,
                                      const Grid<float>& freeY, double capDecelerationMps2, const WindSolverOptions& options,
                                      Grid<float>& windEffectZ, Grid<float>& verticalSpeed);

WindField computeWindField(const Grid<float>& altitude, const Grid<uint8_t>& valid, const GridSpec& spec, const WindState& state,
                           const ModelParameters& params, const WindSolverOptions& options = {});

}  // namespace snow
