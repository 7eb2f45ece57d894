// What the GDAL readers (terrain DEMs, painted rasters) share: one-time driver registration with
// GDAL's own error printing silenced (errors become InputError messages), the last error's text,
// a dataset handle that closes itself, and a coordinate system as WKT.
#pragma once
#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include <memory>
#include <mutex>
#include <string>

namespace snow {

inline void registerGdal() {
  static std::once_flag once;
  std::call_once(once, [] {
    GDALAllRegister();
    CPLSetErrorHandler(CPLQuietErrorHandler);  // errors are reported through InputError instead
  });
}

inline std::string lastGdalError() {
  const char* m = CPLGetLastErrorMsg();
  return m && *m ? std::string(m) : std::string("unknown format or unreadable file");
}

struct GdalDatasetCloser {
  void operator()(GDALDataset* d) const { GDALClose(d); }
};
using GdalDataset = std::unique_ptr<GDALDataset, GdalDatasetCloser>;

// Opens `path` read-only (null when GDAL cannot), after registering the drivers.
inline GdalDataset openGdalReadOnly(const std::string& path) {
  registerGdal();
  CPLErrorReset();
  return GdalDataset(static_cast<GDALDataset*>(GDALOpen(path.c_str(), GA_ReadOnly)));
}

// The dataset's coordinate system as WKT; empty when it names none.
inline std::string crsWktOf(const GDALDataset& ds) {
  const OGRSpatialReference* srs = ds.GetSpatialRef();
  std::string out;
  if (!srs || srs->IsEmpty()) return out;
  char* wkt = nullptr;
  if (srs->exportToWkt(&wkt) == OGRERR_NONE && wkt) out = wkt;
  CPLFree(wkt);
  return out;
}

}  // namespace snow
