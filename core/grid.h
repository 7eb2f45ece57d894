// 2D grids: a host-owned Grid<T> and a plain GridView<T> (pointer + size + cell size) that
// kernels receive by value on either backend.
//
// Layout: row-major, x (column) increases eastward, y (row) increases southward, as in images
// and in ESRI ASCII / GeoTIFF north-up rasters. Cell sizes are in metres and may differ in x
// and y (DEMs in geographic coordinates have non-square cells).
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "hd.h"

namespace snow {

struct GridSpec {
  int width = 0;
  int height = 0;
  double cellSizeXM = 1.0;  // metres between cell centres along x (east)
  double cellSizeYM = 1.0;  // metres between cell centres along y (south)
  // World position of the north-west corner of cell (0, 0), in the terrain's own units
  // (metres for projected data; kept for georeferencing outputs, never used by kernels).
  double originX = 0.0;
  double originY = 0.0;

  size_t cellCount() const { return static_cast<size_t>(width) * static_cast<size_t>(height); }
  double cellAreaM2() const { return cellSizeXM * cellSizeYM; }
  bool operator==(const GridSpec& o) const {
    return width == o.width && height == o.height && cellSizeXM == o.cellSizeXM &&
           cellSizeYM == o.cellSizeYM && originX == o.originX && originY == o.originY;
  }
};

template <class T>
struct GridView {
  T* data = nullptr;
  int width = 0;
  int height = 0;

  SNOW_HD SNOW_INLINE bool inside(int x, int y) const { return x >= 0 && y >= 0 && x < width && y < height; }
  SNOW_HD SNOW_INLINE size_t index(int x, int y) const {
    return static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x);
  }
  SNOW_HD SNOW_INLINE T& operator()(int x, int y) const { return data[index(x, y)]; }
  // Clamped read: edge cells repeat outward (zero-gradient boundary).
  SNOW_HD SNOW_INLINE T clamped(int x, int y) const {
    return data[index(clampi(x, width), clampi(y, height))];
  }

 private:
  SNOW_HD SNOW_INLINE static int clampi(int v, int n) { return v < 0 ? 0 : (v >= n ? n - 1 : v); }
};

template <class T>
class Grid {
 public:
  using value_type = T;
  Grid() = default;
  Grid(int width, int height, T fill = T{}) { resize(width, height, fill); }

  void resize(int width, int height, T fill = T{}) {
    if (width < 0 || height < 0) throw std::invalid_argument("Grid: negative size");
    width_ = width;
    height_ = height;
    values_.assign(static_cast<size_t>(width) * static_cast<size_t>(height), fill);
  }
  void fill(T v) { values_.assign(values_.size(), v); }
  // Takes `values` (width x height of them, row order) as the grid's, without a copy.
  void adopt(int width, int height, std::vector<T>&& values) {
    if (width < 0 || height < 0 || values.size() != static_cast<size_t>(width) * static_cast<size_t>(height))
      throw std::invalid_argument("Grid: adopted values do not match the size");
    width_ = width;
    height_ = height;
    values_ = std::move(values);
  }

  int width() const { return width_; }
  int height() const { return height_; }
  size_t size() const { return values_.size(); }
  bool empty() const { return values_.empty(); }

  T& operator()(int x, int y) { return values_[static_cast<size_t>(y) * width_ + x]; }
  const T& operator()(int x, int y) const { return values_[static_cast<size_t>(y) * width_ + x]; }
  T* data() { return values_.data(); }
  const T* data() const { return values_.data(); }
  std::vector<T>& values() { return values_; }
  const std::vector<T>& values() const { return values_; }

  GridView<T> view() { return GridView<T>{values_.data(), width_, height_}; }
  GridView<const T> view() const { return GridView<const T>{values_.data(), width_, height_}; }

  bool operator==(const Grid& o) const { return width_ == o.width_ && height_ == o.height_ && values_ == o.values_; }

 private:
  int width_ = 0;
  int height_ = 0;
  std::vector<T> values_;
};

// Bilinear value at (x, y) of w x h samples read through `at(i, j)` (sample (i, j) at continuous
// coordinates (i, j)), the coordinates clamped to the samples' extent (edges repeat outward). It
// reads samples (x0, y0) to (x0 + 1, y0 + 1) clamped to the extent, even at a weight of 0: a
// caller holding only part of the samples holds those (bakers' cellsReadBy). Host only.
template <class At>
double sampleBilinearClamped(int w, int h, double x, double y, const At& at) {
  const double fx = std::clamp(x, 0.0, static_cast<double>(w - 1)), fy = std::clamp(y, 0.0, static_cast<double>(h - 1));
  const int x0 = std::min(static_cast<int>(fx), w - 1), x1 = std::min(x0 + 1, w - 1);
  const int y0 = std::min(static_cast<int>(fy), h - 1), y1 = std::min(y0 + 1, h - 1);
  const double tx = fx - x0, ty = fy - y0;
  const double top = at(x0, y0) * (1 - tx) + at(x1, y0) * tx, bottom = at(x0, y1) * (1 - tx) + at(x1, y1) * tx;
  return top * (1 - ty) + bottom * ty;
}

// The same of row-major samples.
inline double sampleBilinearClamped(const float* values, int w, int h, double x, double y) {
  return sampleBilinearClamped(w, h, x, y, [&](int i, int j) { return static_cast<double>(values[static_cast<size_t>(j) * w + i]); });
}

}  // namespace snow
