// [outputs.tiles]: how a raster output of width x height pixels is cut into equal tiles, and the
// tiles' names. Neighbours share `overlap` rows and columns (Unreal and Unity: 1, the edge they
// both hold); the last row and column of tiles reach past the image, padded with its edge pixels,
// so every tile has the same size. Untiled (convention none) an image is one tile, itself.
#pragma once
#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "core/grid.h"
#include "core/grid_window.h"
#include "scene/scene.h"

namespace snow {

struct TileLayout {
  int tileWidth = 0, tileHeight = 0;  // pixels of each tile
  int step = 0;                       // pixels between neighbouring tiles' first columns (and rows)
  int columns = 1, rows = 1;
  TileConvention convention = TileConvention::None;
  bool tiled() const { return convention != TileConvention::None; }
};

TileLayout tileLayout(const OutputTiles& tiles, int width, int height);

// One set of raster files: how they are cut, and the size the grid's layers are written at.
struct RasterSet {
  OutputTiles tiles;                      // convention None: whole files
  int resizeWidth = 0, resizeHeight = 0;  // 0: the grid's size
  bool resized() const { return resizeWidth > 0; }
};
// The bake's sets: one, whole or tiled, at outputs.resize; with [outputs.tiles] resize two: the
// whole files at outputs.resize and the tiles at the tile set's own size.
std::vector<RasterSet> rasterSets(const OutputRequest& out);
// The suffix of tile (column, row), column 0 west, row 0 north: "_x<c>_y<r>" (Unreal, grid),
// "_<c>_<z>" with z counted from the south (Unity's terrain grid); "" untiled.
std::string tileSuffix(const TileLayout& layout, int column, int row);

// The pixels of an image held in memory: the whole image of width x height pixels, or a window
// of it (a rank's local grid, bakers across ranks) from pixel (x0, y0) on.
struct ImageWindow {
  int width = 0, height = 0;                // the whole image
  int x0 = 0, y0 = 0, windowWidth = 0, windowHeight = 0;  // the pixels held, row-major
  static ImageWindow whole(int width, int height) { return {width, height, 0, 0, width, height}; }
};

// Tile (column, row) of an image of `channels` interleaved values a pixel, edge pixels repeated
// past the image, cut from the window `w` of it, which must hold every pixel the tile shows.
template <class T>
std::vector<T> cutTile(const T* pixels, const ImageWindow& w, int channels, const TileLayout& l, int column, int row) {
  std::vector<T> tile(static_cast<size_t>(l.tileWidth) * l.tileHeight * channels);
  const int x0 = column * l.step, y0 = row * l.step;
  const int inside = std::clamp(w.width - x0, 0, l.tileWidth);  // columns of the tile within the image
  auto at = [&](int x, int y) { return pixels + (static_cast<size_t>(y - w.y0) * w.windowWidth + (x - w.x0)) * channels; };
  for (int y = 0; y < l.tileHeight; ++y) {
    const int imageY = std::min(y0 + y, w.height - 1);
    T* out = tile.data() + static_cast<size_t>(y) * l.tileWidth * channels;
    if (inside > 0) std::copy_n(at(x0, imageY), static_cast<size_t>(inside) * channels, out);
    for (int x = inside; x < l.tileWidth; ++x) std::copy_n(at(w.width - 1, imageY), channels, out + static_cast<size_t>(x) * channels);
  }
  return tile;
}
template <class T>
std::vector<T> cutTile(const T* image, int width, int height, int channels, const TileLayout& l, int column, int row) {
  return cutTile(image, ImageWindow::whole(width, height), channels, l, column, row);
}
template <class T>
Grid<T> cutTile(const Grid<T>& g, const TileLayout& l, int column, int row) {
  if (!l.tiled()) return g;
  Grid<T> tile(l.tileWidth, l.tileHeight);
  tile.values() = cutTile(g.data(), g.width(), g.height(), 1, l, column, row);
  return tile;
}
// The same from the window `w` of the image that `g` holds.
template <class T>
Grid<T> cutTile(const Grid<T>& g, const ImageWindow& w, const TileLayout& l, int column, int row) {
  Grid<T> tile(l.tileWidth, l.tileHeight);
  tile.values() = cutTile(g.data(), w, 1, l, column, row);
  return tile;
}
// Whether the tile's first pixel lies over `cells` of a grid of gridWidth x gridHeight cells (the
// tiles a rank writes; every tile when empty). The image of imageWidth x imageHeight pixels spans
// the grid's extent, so its pixel lies over the cell under the pixel's centre: the cell itself at
// the grid's size, one cell of a texture's f x f texels.
inline bool tileStartsIn(const CellRect& cells, int gridWidth, int gridHeight, const TileLayout& l, int column, int row, int imageWidth,
                         int imageHeight) {
  if (cells.empty()) return true;
  auto cellUnder = [](int pixel, int pixels, int cellCount) {
    return static_cast<int>((2 * static_cast<int64_t>(pixel) + 1) * cellCount / (2 * static_cast<int64_t>(pixels)));
  };
  return cells.contains(cellUnder(column * l.step, imageWidth, gridWidth), cellUnder(row * l.step, imageHeight, gridHeight));
}

}  // namespace snow
