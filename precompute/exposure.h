// Sun exposure (paper §4.1): I = I_sun + I_sky + I_ind per cell, in hours of equivalent direct
// sun per day, at a documented set of season days (interpolated between them).
//   I_sun = k_sun sum_h s_h max(0, n . i_h) dh      shadow rays toward the sun, hour by hour
//   I_sky = k_sky pi / N sum_i cos^2(phi_i)          horizon angle phi_i per azimuth, by bisection
//   I_ind = (k_ind / k_sun) sum_ij A_ij I_sun(p_ij) cos(phi_s) cos(phi_r) / (pi d^2)
// Ray queries go through RayScene (Embree), so occluder meshes shade too; pure height fields use
// the horizon-sweep fast path by default (horizon.h).
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "core/grid.h"
#include "core/grid_window.h"
#include "core/parameters.h"
#include "ray_scene.h"
#include "scene/sun_quality.h"

namespace snow {


struct ExposureSettings {
  SunQuality quality = sunQuality("draft");
  // The fast path for pure height fields (horizon.h): sky and shadows from swept horizon angles
  // (sky: quality.azimuths directions; shadows: 4x as many, interpolated). false: Embree rays
  // for both (needed with occluder meshes).
  bool horizonSweep = true;
  double latitudeDeg = 45.0;
  int startDayOfYear = 335;
  double seasonDays = 120.0;
};

struct DailyExposure {
  double seasonDay = 0.0;
  int dayOfYear = 0;
  Grid<float> sunHours;       // I_sun
  Grid<float> indirectHours;  // I_ind
};

// Which of the three terms a bake traces: a term whose weight is zero is all zeros (each is its
// weight times a non-negative sum) and is not computed. One decision for computeExposure and the plan.
struct ExposureTerms {
  bool sky = true, direct = true, indirect = true;
  std::vector<std::string> skipped;  // why each left-out term is left out ("sky: sky_ambient_weight_hours = 0")
};
ExposureTerms exposureTermsFor(const ModelParameters& p);

struct ExposureTimings {
  double sunSeconds = 0, skySeconds = 0, indirectSeconds = 0;
  unsigned long long sunRays = 0, skyRays = 0;
  double horizonSeconds = 0;  // the fast path's sweeps (counted in neither sun nor sky)
  std::vector<std::string> skipped;  // the terms whose weight is zero, not computed ("sky: sky_ambient_weight_hours = 0")
};

struct Exposure {
  Grid<float> skyHours;  // I_sky: rotation invariant, the same every day
  std::vector<DailyExposure> days;
  ExposureTimings timings;
  // I on a season day: I_sky + the linear interpolation of I_sun + I_ind between sample days.
  Grid<float> totalAt(double seasonDay) const;
  // For the season, which reads I_sun + I_ind only: each sample day's sunHours becomes that sum
  // (in float, as totalAt adds them) and indirectHours is freed; totalAt gives the same bytes.
  void foldIndirect();
  bool folded = false;
  // Frees the grids once nothing will read them (a bake whose outputs read no sun, after its
  // season); totalAt then throws.
  void release();
  bool released = false;
  // One rectangle of its cells (a rank's local grid, across ranks): its totalAt gives those
  // cells' bytes of this one's, each cell's sum being its own.
  Exposure window(int x0, int y0, int width, int height) const;
  // The whole grid's cells its grids cover: nullopt for the whole grid.
  std::optional<CellRect> cells;
};

// Unit surface normals (x east, y north, z up) from central differences that skip NODATA; with
// `cells`, those cells' alone, row by row.
void terrainNormals(const Grid<float>& heights, const Grid<uint8_t>& valid, const GridSpec& spec, std::vector<std::array<float, 3>>& out,
                    std::optional<CellRect> cells = std::nullopt);

// The season days exposure is computed at (0, dayStep, 2 dayStep, ..., and the last day), each
// with its day of the year: DailyExposure entries with empty grids.
std::vector<DailyExposure> exposureSampleDays(const ExposureSettings& settings);

// `scene` may be null when settings.horizonSweep is true. With `cells` (a rank's local grid), the
// grids hold those cells alone, the bytes of the whole grid's cut to them: the horizon sweep
// sweeps the lines through them, the Embree path traces their rays alone (against the whole
// terrain's scene), and the direct sun covers them widened by the indirect term's radius (its
// senders).
Exposure computeExposure(const RayScene* scene, const Grid<float>& heights, const Grid<uint8_t>& valid, const GridSpec& spec,
                         const ModelParameters& params, const ExposureSettings& settings, std::optional<CellRect> cells = std::nullopt);

// Pieces, for tests and benchmarks; with `cells`, the grids hold those cells alone (the whole
// grid's bytes cut to them).
Grid<float> computeDirectSun(const RayScene& scene, const Grid<float>& heights, const Grid<uint8_t>& valid, const GridSpec& spec,
                             double latitudeDeg, int dayOfYear, double hourStep, double kSunHours, unsigned long long* rays = nullptr,
                             std::optional<CellRect> cells = std::nullopt);
Grid<float> computeSkyExposure(const RayScene& scene, const Grid<uint8_t>& valid, const GridSpec& spec,
                               int azimuths, int bisections, double kSkyHours, unsigned long long* rays = nullptr,
                               std::vector<Grid<float>>* horizonAnglesDeg = nullptr, std::optional<CellRect> cells = std::nullopt);
Grid<float> computeIndirectSun(const Grid<float>& sunHours, const Grid<float>& heights, const Grid<uint8_t>& valid, const GridSpec& spec,
                               int directions, int rings, double radiusM, double kIndOverKSun);
// The same for several days' direct sun at once (the geometry computed once): the same bytes.
// With `receivers`, for those cells alone, the suns given on `senders` (which hold them and every
// cell within the radius of them; indirectSenderCells).
std::vector<Grid<float>> computeIndirectSunForDays(const std::vector<const Grid<float>*>& sunHours, const Grid<float>& heights,
                                                   const Grid<uint8_t>& valid, const GridSpec& spec, int directions, int rings,
                                                   double radiusM, double kIndOverKSun, std::optional<CellRect> receivers = std::nullopt,
                                                   std::optional<CellRect> senders = std::nullopt);
// The cells whose direct sun the indirect term of `receivers` reads: widened by the radius and a cell.
CellRect indirectSenderCells(const CellRect& receivers, const GridSpec& spec, double radiusM);

}  // namespace snow
