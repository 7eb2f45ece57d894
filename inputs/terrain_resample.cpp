// NODATA filling and resampling of loaded terrains.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/errors.h"
#include "terrain_loader.h"

namespace snow {

// Rings inward: each pass gives every NODATA cell that touches known cells (8 neighbours) the
// mean of those, from a snapshot of the previous pass (so the scan order does not matter); then
// 50 Jacobi smoothing sweeps over the filled cells only, known cells held fixed.
size_t fillNodata(Terrain& t) {
  const int w = t.heightsM.width(), h = t.heightsM.height();
  std::vector<uint8_t> known(t.valid.values());
  std::vector<uint8_t> filled(known.size(), 0);
  std::vector<float>& z = t.heightsM.values();
  size_t count = 0;
  for (bool progress = true; progress;) {
    progress = false;
    const std::vector<uint8_t> before = known;
    const std::vector<float> zBefore = z;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const size_t i = static_cast<size_t>(y) * w + x;
        if (before[i]) continue;
        double sum = 0.0;
        int n = 0;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int nx = x + dx, ny = y + dy;
            if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
            const size_t j = static_cast<size_t>(ny) * w + nx;
            if (before[j]) sum += zBefore[j], ++n;
          }
        if (n == 0) continue;
        z[i] = static_cast<float>(sum / n);
        known[i] = 1;
        filled[i] = 1;
        ++count;
        progress = true;
      }
  }
  for (int sweep = 0; sweep < 50; ++sweep) {
    const std::vector<float> zBefore = z;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const size_t i = static_cast<size_t>(y) * w + x;
        if (!filled[i]) continue;
        double sum = 0.0;
        int n = 0;
        const int dxs[4] = {1, -1, 0, 0}, dys[4] = {0, 0, 1, -1};
        for (int k = 0; k < 4; ++k) {
          const int nx = x + dxs[k], ny = y + dys[k];
          if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
          sum += zBefore[static_cast<size_t>(ny) * w + nx];
          ++n;
        }
        z[i] = static_cast<float>(sum / n);
      }
  }
  t.valid.values() = known;
  t.info.filledCells += count;
  updateTerrainStatistics(t);
  return count;
}

Terrain cropTerrain(const Terrain& src, const TerrainSource& request) {
  const GridSpec& s = src.info.spec;
  const auto& c = *request.cropM;
  // Cells whose centres lie in [west, east) x [north, south).
  const int x0 = std::max(0, static_cast<int>(std::ceil(c[0] / s.cellSizeXM - 0.5)));
  const int y0 = std::max(0, static_cast<int>(std::ceil(c[1] / s.cellSizeYM - 0.5)));
  const int x1 = std::min(s.width, static_cast<int>(std::ceil(c[2] / s.cellSizeXM - 0.5)));
  const int y1 = std::min(s.height, static_cast<int>(std::ceil(c[3] / s.cellSizeYM - 0.5)));
  std::ostringstream where;
  where << (request.declaredAt.empty() ? src.info.source : request.declaredAt) << ": terrain.crop_m [" << c[0] << ", " << c[1] << ", "
        << c[2] << ", " << c[3] << "]";
  if (x1 - x0 < 3 || y1 - y0 < 3) {
    std::ostringstream m;
    m << where.str() << " keeps " << std::max(0, x1 - x0) << " x " << std::max(0, y1 - y0) << " cells of a terrain "
      << s.width * s.cellSizeXM << " m east x " << s.height * s.cellSizeYM << " m south: a window needs at least 3 x 3 cells inside it";
    throw InputError(m.str());
  }
  Terrain out;
  out.info = src.info;
  out.heightsM.resize(x1 - x0, y1 - y0, 0.f);
  out.valid.resize(x1 - x0, y1 - y0, 0);
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      out.heightsM(x - x0, y - y0) = src.heightsM(x, y);
      out.valid(x - x0, y - y0) = src.valid(x, y);
    }
  out.info.spec.width = x1 - x0;
  out.info.spec.height = y1 - y0;
  // The window's north-west corner, in the source's own units.
  const double stepX = src.info.georeferenced ? src.info.geoCellX : s.cellSizeXM;
  const double stepY = src.info.georeferenced ? src.info.geoCellY : s.cellSizeYM;
  out.info.spec.originX = s.originX + x0 * stepX;
  out.info.spec.originY = s.originY - y0 * stepY;
  size_t nodata = 0;
  for (uint8_t v : out.valid.values()) nodata += v == 0;
  if (nodata == out.valid.size()) throw InputError(where.str() + ": every cell of the window is NODATA");
  std::ostringstream o;
  o << "cropped to cells " << x0 << ".." << x1 - 1 << " x " << y0 << ".." << y1 - 1 << " of " << s.width << " x " << s.height << " ("
    << (x1 - x0) * s.cellSizeXM << " x " << (y1 - y0) * s.cellSizeYM << " m)";
  out.info.resampling = src.info.resampling.empty() ? o.str() : src.info.resampling + "; " + o.str();
  updateTerrainStatistics(out);
  return out;
}

Terrain resampleTerrain(const Terrain& src, const TerrainSource& request) {
  const GridSpec& s = src.info.spec;
  const int w = s.width, h = s.height;
  const double extentX = w * s.cellSizeXM, extentY = h * s.cellSizeYM;
  int64_t newW, newH;
  double cellX, cellY;
  if (request.resampleCellSizeM) {
    cellX = cellY = *request.resampleCellSizeM;
    newW = std::max<int64_t>(1, std::llround(extentX / cellX));
    newH = std::max<int64_t>(1, std::llround(extentY / cellY));
  } else {
    newW = (*request.resampleSize)[0];
    newH = (*request.resampleSize)[1];
    cellX = extentX / static_cast<double>(newW);
    cellY = extentY / static_cast<double>(newH);
  }
  checkGridSize(src.info.source + " (resampled)", newW, newH);
  Terrain out;
  out.info = src.info;
  out.heightsM.resize(static_cast<int>(newW), static_cast<int>(newH), 0.f);
  out.valid.resize(static_cast<int>(newW), static_cast<int>(newH), 0);
  const double sx = cellX / s.cellSizeXM, sy = cellY / s.cellSizeYM;  // target cell in source cells
  const bool box = sx > 1.0 + 1e-9 || sy > 1.0 + 1e-9;
  for (int j = 0; j < newH; ++j)
    for (int i = 0; i < newW; ++i) {
      double sum = 0.0, weight = 0.0, footprint = 0.0;
      if (box) {
        // Area-weighted mean of the source cells under the target cell (NODATA left out).
        const double x0 = i * sx, x1 = (i + 1) * sx, y0 = j * sy, y1 = (j + 1) * sy;
        for (int y = std::max(0, static_cast<int>(std::floor(y0))); y < std::min(h, static_cast<int>(std::ceil(y1))); ++y)
          for (int x = std::max(0, static_cast<int>(std::floor(x0))); x < std::min(w, static_cast<int>(std::ceil(x1))); ++x) {
            const double a = (std::min<double>(x + 1, x1) - std::max<double>(x, x0)) * (std::min<double>(y + 1, y1) - std::max<double>(y, y0));
            if (a <= 0) continue;
            footprint += a;
            if (!src.valid(x, y)) continue;
            sum += a * src.heightsM(x, y);
            weight += a;
          }
      } else {
        // Bilinear between the four nearest source centres (edges clamped; NODATA left out).
        const double u = (i + 0.5) * sx - 0.5, v = (j + 0.5) * sy - 0.5;
        const int x0 = static_cast<int>(std::floor(u)), y0 = static_cast<int>(std::floor(v));
        const double fx = u - x0, fy = v - y0;
        footprint = 1.0;
        for (int k = 0; k < 4; ++k) {
          const int x = std::clamp(x0 + (k & 1), 0, w - 1), y = std::clamp(y0 + (k >> 1), 0, h - 1);
          const double a = ((k & 1) ? fx : 1 - fx) * ((k >> 1) ? fy : 1 - fy);
          if (a <= 0 || !src.valid(x, y)) continue;
          sum += a * src.heightsM(x, y);
          weight += a;
        }
      }
      if (weight >= 0.5 * footprint && weight > 0) {
        out.heightsM(i, j) = static_cast<float>(sum / weight);
        out.valid(i, j) = 1;
      }
    }
  out.info.spec.width = static_cast<int>(newW);
  out.info.spec.height = static_cast<int>(newH);
  out.info.spec.cellSizeXM = cellX;
  out.info.spec.cellSizeYM = cellY;
  out.info.geoCellX = src.info.geoCellX * cellX / s.cellSizeXM;
  out.info.geoCellY = src.info.geoCellY * cellY / s.cellSizeYM;
  std::ostringstream o;
  o << (box ? "area-weighted box filter" : "bilinear") << " from " << w << " x " << h << " cells of " << s.cellSizeXM << " x "
    << s.cellSizeYM << " m to " << newW << " x " << newH << " cells of " << cellX << " x " << cellY
    << " m; a cell is NODATA when less than half its footprint (box) or weight (bilinear) is valid";
  out.info.resampling = src.info.resampling.empty() ? o.str() : src.info.resampling + "; " + o.str();
  updateTerrainStatistics(out);
  return out;
}

}  // namespace snow
