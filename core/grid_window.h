// A rectangle of a grid's cells, and its cells as a grid of their own: a rank's local grid,
// and its part of the precompute's whole-grid results (the exposure samples, the wind states).
#pragma once
#include <algorithm>
#include <cstddef>
#include <stdexcept>

#include "grid.h"

namespace snow {

// Cells [x0, x1) × [y0, y1) of the whole grid.
struct CellRect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  static CellRect whole(const GridSpec& spec) { return {0, 0, spec.width, spec.height}; }
  int width() const { return x1 - x0; }
  int height() const { return y1 - y0; }
  bool empty() const { return x1 <= x0 || y1 <= y0; }
  size_t cells() const { return empty() ? 0 : static_cast<size_t>(width()) * static_cast<size_t>(height()); }
  bool contains(int x, int y) const { return x >= x0 && x < x1 && y >= y0 && y < y1; }
  // Where whole-grid cell (x, y) lies in a row-major grid of this rectangle's cells.
  size_t offsetOf(int x, int y) const { return static_cast<size_t>(y - y0) * static_cast<size_t>(width()) + static_cast<size_t>(x - x0); }
  CellRect intersect(const CellRect& o) const {
    const CellRect r{std::max(x0, o.x0), std::max(y0, o.y0), std::min(x1, o.x1), std::min(y1, o.y1)};
    return r.empty() ? CellRect{} : r;
  }
  // Widened by `cx` columns and `cy` rows each side, within `bounds`.
  CellRect widened(int cx, int cy, const CellRect& bounds) const { return CellRect{x0 - cx, y0 - cy, x1 + cx, y1 + cy}.intersect(bounds); }
  bool operator==(const CellRect&) const = default;
};

// The cells x0 <= x < x0 + width, y0 <= y < y0 + height of `whole`, row by row. An empty grid
// stays empty (a term the bake did not compute).
template <class T>
Grid<T> gridWindow(const Grid<T>& whole, int x0, int y0, int width, int height) {
  if (whole.empty()) return Grid<T>();
  if (x0 < 0 || y0 < 0 || width < 0 || height < 0 || x0 + width > whole.width() || y0 + height > whole.height())
    throw std::invalid_argument("gridWindow: the window is not inside the grid");
  Grid<T> out(width, height);
  for (int y = 0; y < height; ++y) {
    const T* row = whole.data() + static_cast<size_t>(y0 + y) * whole.width() + x0;
    std::copy(row, row + width, out.data() + static_cast<size_t>(y) * width);
  }
  return out;
}

template <class T>
Grid<T> gridWindow(const Grid<T>& whole, const CellRect& r) {
  return gridWindow(whole, r.x0, r.y0, r.width(), r.height());
}

// The spec of `cells` of the grid `whole` as a grid of their own: its origin at their north-west
// corner (north-up: y runs south).
inline GridSpec windowSpec(const GridSpec& whole, const CellRect& cells) {
  GridSpec local = whole;
  local.width = cells.width();
  local.height = cells.height();
  local.originX = whole.originX + cells.x0 * whole.cellSizeXM;
  local.originY = whole.originY - cells.y0 * whole.cellSizeYM;
  return local;
}

}  // namespace snow
