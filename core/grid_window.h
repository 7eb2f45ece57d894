// A rectangle of a grid's cells as a grid of its own: a rank's part of the precompute's
// whole-grid results (the exposure samples, the wind states), cut once they are made.
#pragma once
#include <algorithm>
#include <stdexcept>

#include "grid.h"

namespace snow {

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

}  // namespace snow
