#include "geotiff_writer.h"

#include <stdexcept>

#include "core/atomic_file.h"
#include "inputs/gdal_support.h"

namespace snow {

void writeGeoTiff(const std::string& path, const Grid<float>& grid, const GeoFrame& frame, const std::string& layerName) {
  registerGdal();
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
  if (!driver) throw std::runtime_error("cannot write " + path + ": GDAL has no GTiff driver");
  writeAtomically(path, [&](const std::string& temp) {
    char** options = nullptr;
    options = CSLSetNameValue(options, "COMPRESS", "DEFLATE");
    options = CSLSetNameValue(options, "PREDICTOR", "3");  // floating-point predictor: smaller float files
    CPLErrorReset();
    GdalDataset ds(driver->Create(temp.c_str(), grid.width(), grid.height(), 1, GDT_Float32, options));
    CSLDestroy(options);
    if (!ds) throw std::runtime_error("cannot write " + path + ": " + lastGdalError());
    double gt[6] = {frame.originX, frame.cellX, 0.0, frame.originY, 0.0, -frame.cellY};
    ds->SetGeoTransform(gt);
    if (!frame.crsWkt.empty()) {
      OGRSpatialReference srs;
      if (srs.importFromWkt(frame.crsWkt.c_str()) == OGRERR_NONE) ds->SetSpatialRef(&srs);
    }
    ds->SetMetadataItem("snowbake:layer", layerName.c_str());
    ds->SetMetadataItem("TIFFTAG_SOFTWARE", "snowbake");
    GDALRasterBand* band = ds->GetRasterBand(1);
    band->SetDescription(layerName.c_str());
    if (band->RasterIO(GF_Write, 0, 0, grid.width(), grid.height(), const_cast<float*>(grid.data()), grid.width(), grid.height(),
                       GDT_Float32, 0, 0) != CE_None)
      throw std::runtime_error("cannot write " + path + ": " + lastGdalError());
    ds.reset();  // flushes and closes
  });
}

}  // namespace snow
