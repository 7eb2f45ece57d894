// A GeoTIFF terrain written through GDAL for the tests. (Not in test_support.h: the GPU test
// binary includes that one and links no GDAL.)
#pragma once
#include <gdal_priv.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <string>
#include <vector>

namespace snow::test {

struct GeoTiffSpec {
  int width = 16, height = 16, bands = 1;
  // GDAL's geotransform (north-west corner, pixel sizes) and EPSG code; no georeference if false.
  bool georeferenced = true;
  double geotransform[6] = {500000, 10, 0, 5200000, 0, -10};
  int epsg = 32632;  // UTM 32N
  double scale = 1.0, offset = 0.0;  // set on every band unless 1 and 0
};

// A float32 GeoTIFF of `height(x, y)` (x east, y south, in pixels), the same in every band.
inline void writeGeoTiff(const std::string& path, const GeoTiffSpec& g, const std::function<float(int x, int y)>& height) {
  GDALAllRegister();
  GDALDataset* ds = GetGDALDriverManager()->GetDriverByName("GTiff")->Create(path.c_str(), g.width, g.height, g.bands, GDT_Float32, nullptr);
  ASSERT_TRUE(ds) << path;
  if (g.georeferenced) {
    double gt[6];
    std::copy(g.geotransform, g.geotransform + 6, gt);
    ds->SetGeoTransform(gt);
    OGRSpatialReference srs;
    srs.importFromEPSG(g.epsg);
    ds->SetSpatialRef(&srs);
  }
  std::vector<float> v(static_cast<size_t>(g.width) * g.height);
  for (int y = 0; y < g.height; ++y)
    for (int x = 0; x < g.width; ++x) v[static_cast<size_t>(y) * g.width + x] = height(x, y);
  for (int b = 1; b <= g.bands; ++b) {
    GDALRasterBand* band = ds->GetRasterBand(b);
    EXPECT_EQ(band->RasterIO(GF_Write, 0, 0, g.width, g.height, v.data(), g.width, g.height, GDT_Float32, 0, 0), CE_None) << path;
    if (g.scale != 1.0) band->SetScale(g.scale);
    if (g.offset != 0.0) band->SetOffset(g.offset);
  }
  GDALClose(ds);
}

}  // namespace snow::test
