// Float layers as GeoTIFF through GDAL: one float32 band, deflate, with the terrain's coordinate
// system and the image's (or tile's) own geotransform, so QGIS, Terragen and Houdini's GIS import
// place it. outputs.format = "tiff" writes every float raster this way.
#pragma once
#include <string>

#include "core/grid.h"
#include "georeference.h"

namespace snow {

// Writes `path` atomically; `frame` is the image's frame (GeoFrame::pixels). The layer's name goes
// into the band description and the metadata item snowbake:layer. No time stamps.
void writeGeoTiff(const std::string& path, const Grid<float>& grid, const GeoFrame& frame, const std::string& layerName);

}  // namespace snow
