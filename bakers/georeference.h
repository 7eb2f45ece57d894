// Where a raster output lies on the map: the terrain's coordinate system and geotransform, and
// the frame of one image (or tile) of it, whatever its pixel count.
#pragma once
#include <string>

namespace snow {

// Grid cell (i, j)'s north-west corner is at (originX + i cellX, originY - j cellY) in the
// terrain's coordinates (crsWkt; empty when the input names none). Without a georeferenced
// input: metres from the grid's north-west corner.
struct GeoFrame {
  bool georeferenced = false;
  std::string crsWkt;
  double originX = 0, originY = 0, cellX = 1, cellY = 1;
  int gridWidth = 0, gridHeight = 0;

  // The frame of an image of imageWidth x imageHeight pixels over the grid's extent, from its
  // pixel (x0, y0) on: the north-west corner of that pixel and a pixel's size.
  GeoFrame pixels(int imageWidth, int imageHeight, int x0 = 0, int y0 = 0) const {
    GeoFrame f = *this;
    f.cellX = cellX * gridWidth / imageWidth, f.cellY = cellY * gridHeight / imageHeight;
    f.originX = originX + x0 * f.cellX, f.originY = originY - y0 * f.cellY;
    f.gridWidth = imageWidth, f.gridHeight = imageHeight;
    return f;
  }
};

}  // namespace snow
