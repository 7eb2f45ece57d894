// The fast path for pure height fields: horizon angles per azimuth by a sweep over the grid
// (an upper convex hull along lines in each direction, O(cells) per azimuth), after which the
// sky term is a sum and direct shadowing for any sun position is a lookup. Used by default
// where no occluder mesh is in the scene; docs/precompute.md gives its measured agreement
// with the Embree path.
#pragma once
#include <optional>
#include <vector>

#include "core/grid.h"
#include "core/grid_window.h"

namespace snow {

// Horizon elevation angles in degrees (>= 0) for azimuths (k + 0.5) 360 / count, k = 0..count-1,
// clockwise from north (the same directions as the Embree sky pass). With `cells`, grids of those
// cells alone (a rank's local grid), the whole grid's bytes: only the lines through them are swept.
std::vector<Grid<float>> computeHorizonsBySweep(const Grid<float>& heights, const Grid<uint8_t>& valid, const GridSpec& spec,
                                                int count, std::optional<CellRect> cells = std::nullopt);

// I_sky = k_sky pi / N sum cos^2(phi).
Grid<float> skyFromHorizons(const std::vector<Grid<float>>& horizonsDeg, const Grid<uint8_t>& valid, double kSkyHours);

// I_sun for one day: a sun position lights a cell when it faces the sun and the sun is above
// the horizon interpolated between the two nearest azimuths.
Grid<float> directSunFromHorizons(const std::vector<Grid<float>>& horizonsDeg, const Grid<float>& heights, const Grid<uint8_t>& valid,
                                  const GridSpec& spec, double latitudeDeg, int dayOfYear, double hourStep, double kSunHours);

// directSunFromHorizons for each day of `daysOfYear` over `count` azimuths, the same bytes, with
// the azimuths swept one after the other: two horizon grids (and the first) are held at a time,
// not `count`, and each sun position's shadow test is kept as one bit a cell until the day's
// sum, added in hour order as directSunFromHorizons adds it. With `cells`, on those cells alone.
std::vector<Grid<float>> directSunForDaysBySweep(const Grid<float>& heights, const Grid<uint8_t>& valid, const GridSpec& spec, int count,
                                                 double latitudeDeg, const std::vector<int>& daysOfYear, double hourStep, double kSunHours,
                                                 std::optional<CellRect> cells = std::nullopt);

}  // namespace snow
