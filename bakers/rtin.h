// Adaptive triangulation of height fields with a vertical error bound: a right-triangulated
// irregular network (RTIN; Evans, Kirkpatrick and Townsend 2001, the scheme of Mapbox's
// "Martini"), over the smallest (2^k + 1)^2 square holding the grid. Triangles are split at
// their hypotenuse's midpoint while the largest vertical error at any grid point inside them
// (the true error, measured at every grid point, not the midpoint alone) exceeds the bound, for
// every field given (a snow body's top and bottom share one triangulation). Errors propagate from
// children to parents and are shared across each hypotenuse, so the mesh is conforming: no
// T-junctions, every interior edge shared by two triangles. Triangles reaching outside the grid
// or onto NODATA are split down to the cells and dropped there.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "core/grid.h"

namespace snow {

struct RtinMesh {
  int width = 0, height = 0;  // the grid
  // Triangles as three grid points, each numbered column by column (x * height + y: 12 bytes a
  // triangle, not 24, and sorted by (x, y) as numbers), counter-clockwise seen from above (rows
  // run south).
  std::vector<std::array<uint32_t, 3>> triangles;
  uint32_t point(int x, int y) const { return static_cast<uint32_t>(x) * static_cast<uint32_t>(height) + static_cast<uint32_t>(y); }
  int x(uint32_t point) const { return static_cast<int>(point / static_cast<uint32_t>(height)); }
  int y(uint32_t point) const { return static_cast<int>(point % static_cast<uint32_t>(height)); }
  double maxErrorM = 0.0;  // the bound it was built for
};

// `fields` share `valid`'s size. maxErrorM >= 0 (0: only exactly planar areas are merged).
RtinMesh buildRtin(const std::vector<const Grid<float>*>& fields, const Grid<uint8_t>& valid, double maxErrorM);

// The largest |mesh - field| over the grid points the mesh covers (planar interpolation in each
// triangle), for tests and benchmarks.
double rtinMaxVerticalError(const RtinMesh& mesh, const Grid<float>& field);

}  // namespace snow
