// Skiers (paper §6.2, §7.3): the route map, skier agents on the grid, refined sine-wave tracks in
// a finer track texture, and their two-way interaction with the snow.
//
// Route map: for every cell, the length in metres of the longest strictly descending 8-neighbour
// path from it (to a local minimum, which includes cells at the terrain's edge with no lower
// neighbour). The paper's cellular automaton, D(c) = max over lower neighbours n of D(n) + |cn|,
// is RouteMapStepKernel (phenomena/skiers.h), iterated on the device by GPU backends
// (SnowBackend::routeMapOnDevice); routeMap() gets the same numbers in one pass over the cells
// sorted by altitude (tested equal, bit for bit).
//
// Large-scale paths: a skier is an agent (position, heading). Each step it looks at the cells
// within ski_lookahead_m ahead of it (within 100 degrees of its heading) and aims at cell n with
// probability proportional to Eq. 4: 1[snow_n >= ski_min_snow_m] f(|s_n - s_t|) w_d(n), where s_n
// is the slope angle from its cell down to n (uphill and level cells get 0), f(d) =
// exp(-(d / ski_slope_tolerance_deg)^2) and w_d(n) = D(n) + |cn| (the route length through n: a
// dead-end basin's short routes weigh little). Its heading turns ski_steering of the way toward
// the target each step; it moves one cell length a step and stops at a route's end (D = 0), where
// the snow runs out, at the terrain's edge, or when no cell ahead is acceptable.
//
// Refined tracks: along each straight segment of the path, a lateral sine p(t) = a sin(phase),
// the phase advancing 2 pi f per metre and carried from segment to segment (one continuous
// curve). Where the segment is steeper than s_t, f is solved so that the slope measured along the
// curve itself equals s_t (the paper's closed form f = sqrt(sin^2 s_n - sin^2 s_t) / (4 a sin s_t)
// measures it on the chord between extrema, 29.0 deg along the curve for 30 at 45 deg), and is at
// least Table 2's f (track_frequency_per_m: a skier on a slope barely steeper than s_t still turns
// every 1 / (2 f) metres); where it is not steeper, f = 0 and the track runs straight. The lateral
// direction is blended across each path vertex, so the curve has no gaps.
//
// Track texture: depth of the ski tracks in metres below the snow surface, on a grid
// `textureFactor` times finer than the simulation's (a parabolic groove ski_track_depth_m deep and
// ski_track_width_m wide). It fades as snow covers it: a cell's texels lose the rise of the snow
// surface since the track was made (snowfall, wind or diffusion deposits, avalanche debris), so a
// snowfall deeper than the track erases it and a light one softens it (the paper's alpha-blending).
//
// Agents in parallel (§7.3): the skiers of a batch (an hour's automatic skiers, a scene's group)
// move together, one move of every skier at a time, on the backend (phenomena/skiers.h: a move only
// reads the snow, so all skiers move at once; the cells they enter are then written one skier at
// a time in skier order through integer claims): the same bytes on any thread count and on CUDA.
//
// Snow: each cell a skier enters turns ski_compaction_m of U into S, or of S into C where U runs
// short, as it enters (later skiers of the batch, and the same skier coming back, see it). Crossing unstable snow on a slope above the avalanche rest
// angle raises the cell's release probability (the spontaneous one, core/avalanche_runs.h) by
// ski_trigger_factor: when the draw releases, the skier stops there and an avalanche starts.
#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "backend.h"
#include "grid.h"
#include "hd.h"
#include "parameters.h"
#include "phenomena/skiers.h"
#include "snow_state.h"

namespace snow {

Grid<float> routeMap(const Grid<float>& altitude, const Grid<uint8_t>& valid, const GridSpec& spec);

// A Poisson count of mean `mean` by inversion of uniform draws in (0, 1) from uniform(0),
// uniform(1), ...; a mean above 30 is split into equal parts, each drawn on its own (so exp(-part)
// stays far from underflow).
int poissonCount(double mean, const std::function<double(uint32_t)>& uniform);

// Turn frequency (1/m) for a segment of slope angle `slopeRad` (see above); 0 at or below the target.
double turnFrequency(double slopeRad, double targetRad, double amplitudeM, double minFrequencyPerM);

// The cell drawn with probability proportional to its weight, given the running sums of the
// weights in row order and a draw in (0, 1); -1 when every weight is 0.
long long pickByCumulativeWeight(const std::vector<double>& cumulative, double draw);

// A path as points in metres (x east from the grid's west edge, y south from its north edge).
using Path2 = std::vector<std::array<double, 2>>;
// The refined track of a path; `altitude(x, y)` gives the snow surface; samples at most
// `maxGapM` apart.
Path2 refineTrack(const Path2& path, const std::function<double(double, double)>& altitude, const ModelParameters& p, double maxGapM);

// The ski-track texture (depth below the surface, metres) and its fading.
class SkiTracks {
 public:
  SkiTracks(const GridSpec& spec, int factor);
  int factor() const { return factor_; }
  const Grid<float>& depth() const { return depth_; }
  // Swaps the texture with `other` (a frame set aside writes the texture of its own instant).
  void swapDepth(Grid<float>& other) { std::swap(depth_, other); }
  // Grooves along a refined track; `surface(cell)` is the snow surface of a cell now.
  void stamp(const Path2& track, double depthM, double widthM, const std::function<float(int cell)>& surface);
  // Fades every cell with tracks by the rise of its snow surface since it was last looked at.
  void fade(const SnowState& state);
  // The same from the bedrock and the four snow layers (C, S, U, P) of every cell.
  void fade(const Grid<float>& bedrock, const float* const layers[4]);
  // The same for one cell.
  void fadeCell(int cell, float surfaceNow);

 private:
  GridSpec spec_;
  int factor_;
  Grid<float> depth_;
  std::vector<float> lastSurface_;  // per cell; NaN where no track
};

struct SkierRecord {
  double day = 0;
  int startX = 0, startY = 0;
  bool user = false;
  int cells = 0;           // cells entered
  double lengthM = 0;      // large-scale path length
  double dropM = 0;        // surface drop from start to end
  bool triggered = false;  // set off an avalanche
  int triggerX = -1, triggerY = -1;
  std::string why;         // why it stopped
  Path2 path;              // the large-scale path (metres, x east, y south)
};

struct SkierStart {
  int x = 0, y = 0;
  uint64_t id = 0;
  bool user = false;
};
const char* skierStopReason(int status);

// Skiers on a backend: the route map, start cells, and batches of descents.
class SkiRun {
 public:
  SkiRun(SnowBackend& backend, const ModelParameters& p, const SnowState& state, SkiTracks* tracks);
  ~SkiRun() { backend_.releaseRouteMap(); }  // a host backend reads route_ itself
  SkiRun(const SkiRun&) = delete;
  SkiRun& operator=(const SkiRun&) = delete;
  const Grid<float>& routeMap() const { return route_; }
  // The route map on the backend again, after SnowBackend::releaseScratch freed its copy.
  void uploadRouteMap() { backend_.uploadRouteMap(route_); }
  // A start cell drawn with probability proportional to the route map (cells where a route
  // starts) times the scene's skier_spawn multiplier; false when no cell has one.
  bool pickStart(double draw, int& x, int& y) const;
  // Whether the cell has snow enough to start a descent (reads one cell).
  bool canStart(int x, int y);
  // Descents from the given cells, all skiers moved together (one move of every skier at a time,
  // on the backend: phenomena/skiers.h), in the order given; `seed` and each skier's id seed its
  // choices. When one triggers an avalanche its record says where. Tracks are stamped in order.
  std::vector<SkierRecord> descendTogether(const std::vector<SkierStart>& starts, double day, uint64_t seed);
  // One descent from cell (x, y): a batch of one.
  SkierRecord descend(int x, int y, double day, uint64_t seed, uint64_t id, bool user);

 private:
  SnowBackend& backend_;
  ModelParameters p_;
  GridSpec spec_;
  const Grid<float>& bedrock_;
  const Grid<uint8_t>& valid_;
  Grid<float> route_;
  const Grid<float>* spawn_ = nullptr;  // the scene's skier_spawn multiplier, where it paints one
  // Running totals of the start weights (route map x spawn) at each row's start, for pickStart
  // (one double a row, not a cell).
  std::vector<double> rowStartWeights_;
  void addStartWeight(size_t i, double& sum) const;
  SkiTracks* tracks_;
};


}  // namespace snow
