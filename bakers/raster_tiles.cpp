#include "raster_tiles.h"

#include <algorithm>

namespace snow {

TileLayout tileLayout(const OutputTiles& t, int width, int height) {
  TileLayout l;
  l.convention = t.convention;
  if (t.convention == TileConvention::None || t.sizePx <= 0) {
    l.convention = TileConvention::None;
    l.tileWidth = width, l.tileHeight = height, l.step = std::max(width, height);
    return l;
  }
  const int overlap = t.convention == TileConvention::Grid ? t.overlapPx : 1;
  l.tileWidth = l.tileHeight = t.sizePx;
  l.step = t.sizePx - overlap;
  // Enough tiles that the last one reaches the image's last pixel.
  auto count = [&](int pixels) { return pixels <= t.sizePx ? 1 : 1 + (pixels - t.sizePx + l.step - 1) / l.step; };
  l.columns = count(width), l.rows = count(height);
  return l;
}

std::vector<RasterSet> rasterSets(const OutputRequest& out) {
  if (out.tiles.convention == TileConvention::None || out.tiles.resizeWidth <= 0)
    return {RasterSet{out.tiles, out.resizeWidth, out.resizeHeight}};
  return {RasterSet{OutputTiles{}, out.resizeWidth, out.resizeHeight}, RasterSet{out.tiles, out.tiles.resizeWidth, out.tiles.resizeHeight}};
}

std::string tileSuffix(const TileLayout& l, int column, int row) {
  if (!l.tiled()) return "";
  if (l.convention == TileConvention::Unity) return "_" + std::to_string(column) + "_" + std::to_string(l.rows - 1 - row);
  return "_x" + std::to_string(column) + "_y" + std::to_string(row);
}

}  // namespace snow
