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

// Tile (column, row) of an image of `channels` interleaved values a pixel, edge pixels repeated
// past the image.
template <class T>
std::vector<T> cutTile(const T* image, int width, int height, int channels, const TileLayout& l, int column, int row) {
  std::vector<T> tile(static_cast<size_t>(l.tileWidth) * l.tileHeight * channels);
  const int x0 = column * l.step, y0 = row * l.step;
  const int inside = std::clamp(width - x0, 0, l.tileWidth);  // columns of the tile within the image
  for (int y = 0; y < l.tileHeight; ++y) {
    const T* source = image + static_cast<size_t>(std::min(y0 + y, height - 1)) * width * channels;
    T* out = tile.data() + static_cast<size_t>(y) * l.tileWidth * channels;
    if (inside > 0) std::copy_n(source + static_cast<size_t>(x0) * channels, static_cast<size_t>(inside) * channels, out);
    for (int x = inside; x < l.tileWidth; ++x) std::copy_n(source + static_cast<size_t>(width - 1) * channels, channels, out + static_cast<size_t>(x) * channels);
  }
  return tile;
}
template <class T>
Grid<T> cutTile(const Grid<T>& g, const TileLayout& l, int column, int row) {
  if (!l.tiled()) return g;
  Grid<T> tile(l.tileWidth, l.tileHeight);
  tile.values() = cutTile(g.data(), g.width(), g.height(), 1, l, column, row);
  return tile;
}

}  // namespace snow
