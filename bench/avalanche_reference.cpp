#include "avalanche_reference.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "core/avalanche_runs.h"
#include "core/cpu_backend.h"
#include "core/errors.h"
#include "core/util.h"
#include "inputs/raster_input.h"
#include "inputs/terrain_loader.h"

namespace snow {

namespace {

namespace fs = std::filesystem;
constexpr double kFootprintM = 0.1;  // AIMEC's footprint threshold on the peak flow thickness
constexpr double kColdC = -15.0;     // sea-level temperature of the runs: dry snow (below T_dry)

std::vector<std::pair<double, double>> readPath(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open the avalanche path");
  std::string line;
  std::getline(in, line);  // x,y
  std::vector<std::pair<double, double>> points;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    std::istringstream s(line);
    double x = 0, y = 0;
    char comma = 0;
    if (!(s >> x >> comma >> y)) throw InputError(path + ": line " + std::to_string(points.size() + 2) + " is not x,y");
    points.push_back({x, y});
  }
  if (points.size() < 2) throw InputError(path + ": the path needs at least two points");
  return points;
}

// Arc length of the point of `path` nearest to (x, y).
double projectOnPath(const std::vector<std::pair<double, double>>& path, double x, double y) {
  double best = std::numeric_limits<double>::infinity(), bestS = 0, s0 = 0;
  for (size_t k = 0; k + 1 < path.size(); ++k) {
    const double ax = path[k].first, ay = path[k].second, dx = path[k + 1].first - ax, dy = path[k + 1].second - ay;
    const double len2 = dx * dx + dy * dy, len = std::sqrt(len2);
    const double t = len2 > 0 ? std::clamp(((x - ax) * dx + (y - ay) * dy) / len2, 0.0, 1.0) : 0.0;
    const double ex = ax + t * dx - x, ey = ay + t * dy - y, d2 = ex * ex + ey * ey;
    if (d2 < best) best = d2, bestS = s0 + t * len;
    s0 += len;
  }
  return bestS;
}

// The point of `path` at arc length s.
std::pair<double, double> pointOnPath(const std::vector<std::pair<double, double>>& path, double s) {
  for (size_t k = 0; k + 1 < path.size(); ++k) {
    const double dx = path[k + 1].first - path[k].first, dy = path[k + 1].second - path[k].second;
    const double len = std::hypot(dx, dy);
    if (s <= len || k + 2 == path.size()) {
      const double t = len > 0 ? std::clamp(s / len, 0.0, 1.0) : 0.0;
      return {path[k].first + t * dx, path[k].second + t * dy};
    }
    s -= len;
  }
  return path.back();
}

struct PathScore {
  double runoutS = 0, alphaDeg = 0;
  int cells = 0;
};

// Runout (farthest footprint cell's arc length) and travel angle from the release top.
PathScore scoreFootprint(const AvalancheReferenceCase& c, const Grid<float>& peak, double topS, double topZ) {
  PathScore r;
  r.runoutS = topS;
  for (int y = 0; y < c.spec.height; ++y)
    for (int x = 0; x < c.spec.width; ++x) {
      if (!(peak(x, y) > kFootprintM) || !c.valid(x, y)) continue;
      ++r.cells;
      const double wx = c.spec.originX + (x + 0.5) * c.geoCellX, wy = c.spec.originY - (y + 0.5) * c.geoCellY;
      r.runoutS = std::max(r.runoutS, projectOnPath(c.pathXY, wx, wy));
    }
  const auto [px, py] = pointOnPath(c.pathXY, r.runoutS);
  const int cx = std::clamp(static_cast<int>(std::floor((px - c.spec.originX) / c.geoCellX)), 0, c.spec.width - 1);
  const int cy = std::clamp(static_cast<int>(std::floor((c.spec.originY - py) / c.geoCellY)), 0, c.spec.height - 1);
  const double distance = r.runoutS - topS;
  r.alphaDeg = distance > 0 ? std::atan2(topZ - c.bedrockM(cx, cy), distance) * 180.0 / kPi : 90.0;
  return r;
}

// The case's DEM on a grid k times finer: bilinear between the valid coarse cells around each
// fine cell's centre (the containing cell's height where one of them is NODATA).
void refineTerrain(AvalancheReferenceCase& c, int k) {
  const GridSpec coarse = c.spec;
  const Grid<float> h = c.bedrockM;
  const Grid<uint8_t> v = c.valid;
  c.spec.width *= k, c.spec.height *= k;
  c.spec.cellSizeXM /= k, c.spec.cellSizeYM /= k;
  c.geoCellX /= k, c.geoCellY /= k;
  c.bedrockM = Grid<float>(c.spec.width, c.spec.height, 0.f);
  c.valid = Grid<uint8_t>(c.spec.width, c.spec.height, 0);
  for (int y = 0; y < c.spec.height; ++y)
    for (int x = 0; x < c.spec.width; ++x) {
      const double u = std::clamp((x + 0.5) / k - 0.5, 0.0, coarse.width - 1.0), w = std::clamp((y + 0.5) / k - 0.5, 0.0, coarse.height - 1.0);
      const int x0 = std::min(static_cast<int>(u), coarse.width - 2), y0 = std::min(static_cast<int>(w), coarse.height - 2);
      const double fx = u - x0, fy = w - y0;
      const int cx = x / k, cy = y / k;
      c.valid(x, y) = v(cx, cy);
      if (v(x0, y0) && v(x0 + 1, y0) && v(x0, y0 + 1) && v(x0 + 1, y0 + 1))
        c.bedrockM(x, y) = static_cast<float>((1 - fy) * ((1 - fx) * h(x0, y0) + fx * h(x0 + 1, y0)) +
                                              fy * ((1 - fx) * h(x0, y0 + 1) + fx * h(x0 + 1, y0 + 1)));
      else
        c.bedrockM(x, y) = h(cx, cy);
    }
}

// The case's DEM and release on a grid k times coarser (the cells a whole k x k block covers): the
// block's mean height, valid where all its cells are, and its mean release (the same volume).
void coarsenCase(AvalancheReferenceCase& c, int k) {
  const Grid<float> h = c.bedrockM, release = c.releaseM;
  const Grid<uint8_t> v = c.valid;
  c.spec.width /= k, c.spec.height /= k;
  c.spec.cellSizeXM *= k, c.spec.cellSizeYM *= k;
  c.geoCellX *= k, c.geoCellY *= k;
  c.bedrockM = c.releaseM = Grid<float>(c.spec.width, c.spec.height, 0.f);
  c.valid = Grid<uint8_t>(c.spec.width, c.spec.height, 0);
  for (int y = 0; y < c.spec.height; ++y)
    for (int x = 0; x < c.spec.width; ++x) {
      double height = 0, thickness = 0;
      bool all = true;
      for (int j = 0; j < k; ++j)
        for (int i = 0; i < k; ++i) {
          all = all && v(k * x + i, k * y + j);
          height += h(k * x + i, k * y + j), thickness += release(k * x + i, k * y + j);
        }
      c.valid(x, y) = all;
      c.bedrockM(x, y) = static_cast<float>(height / (k * k));
      c.releaseM(x, y) = all ? static_cast<float>(thickness / (k * k)) : 0.f;
    }
}

// `r` at the centres of the case's cells.
Grid<float> sampledAtCentres(const GeoRaster& r, const AvalancheReferenceCase& c) {
  Grid<float> out(c.spec.width, c.spec.height, 0.f);
  for (int y = 0; y < c.spec.height; ++y)
    for (int x = 0; x < c.spec.width; ++x)
      out(x, y) = r.sampleAt(c.spec.originX + (x + 0.5) * c.geoCellX, c.spec.originY - (y + 0.5) * c.geoCellY);
  return out;
}

}  // namespace

float GeoRaster::sampleAt(double wx, double wy) const {
  const double fx = (wx - originX) / cellX, fy = (originY - wy) / cellY;
  if (!(fx >= 0 && fy >= 0 && fx < width && fy < height)) return 0.f;
  return values[static_cast<size_t>(fy) * width + static_cast<size_t>(fx)];
}

GeoRaster readGeoRaster(const std::string& path) {
  const RasterImage img = readRasterImage(path);
  if (!img.georeferenced) throw InputError(path + ": the reference raster has no georeference");
  GeoRaster r;
  r.width = img.width, r.height = img.height, r.values = img.values;
  r.originX = img.geoTransform[0], r.originY = img.geoTransform[3];
  r.cellX = img.geoTransform[1], r.cellY = -img.geoTransform[5];
  if (!(r.cellX > 0 && r.cellY > 0)) throw InputError(path + ": expected a north-up raster");
  return r;
}

const std::vector<std::string>& avalancheReferenceCaseNames() {
  static const std::vector<std::string> names{"avaKot", "avaWog", "avaAlr", "avaHelix"};
  return names;
}

AvalancheReferenceCase loadAvalancheReferenceCase(const std::string& folder, int cellScale) {
  AvalancheReferenceCase c;
  c.name = fs::path(folder).filename().string();
  const Terrain t = loadDem((fs::path(folder) / "dem.tif").string());
  if (!t.info.georeferenced) throw InputError(folder + "/dem.tif: the DEM has no georeference");
  c.spec = t.info.spec, c.geoCellX = t.info.geoCellX, c.geoCellY = t.info.geoCellY;
  c.bedrockM = t.heightsM, c.valid = t.valid;
  const GeoRaster release = readGeoRaster((fs::path(folder) / "release_thickness_m.tif").string());
  const GeoRaster pft = readGeoRaster((fs::path(folder) / "reference_pft.tif").string());
  const GeoRaster pfv = readGeoRaster((fs::path(folder) / "reference_pfv.tif").string());
  c.releaseM = sampledAtCentres(release, c);
  if (cellScale > 1) {
    coarsenCase(c, cellScale);
  } else if (cellScale < -1) {
    refineTerrain(c, -cellScale);
    c.releaseM = sampledAtCentres(release, c);  // each fine cell its coarse cell's: the same volume
  }
  if (cellScale > 1 || cellScale < -1) {
    char size[32];
    std::snprintf(size, sizeof size, "_%.3gm", c.spec.cellSizeXM);
    c.name += size;
  }
  for (size_t i = 0; i < c.spec.cellCount(); ++i)
    c.releaseM.values()[i] = c.valid.values()[i] ? std::max(0.f, c.releaseM.values()[i]) : 0.f;
  c.referencePftM = sampledAtCentres(pft, c);
  for (float v : pfv.values) c.referencePeakSpeedMps = std::max(c.referencePeakSpeedMps, static_cast<double>(v));
  c.pathXY = readPath((fs::path(folder) / "path_ab.csv").string());
  return c;
}

AvalancheReferenceScores runAvalancheReferenceCase(const AvalancheReferenceCase& c, const ModelParameters& p) {
  AvalancheReferenceScores r;
  r.name = c.name;
  SnowState s;
  s.allocate(c.spec);
  s.bedrockM = c.bedrockM;
  s.validCell = c.valid;
  s.unstableM = c.releaseM;
  std::vector<uint8_t> zone(c.spec.cellCount(), 0);
  int topX = -1, topY = -1;
  for (int y = 0; y < c.spec.height; ++y)
    for (int x = 0; x < c.spec.width; ++x)
      if (c.releaseM(x, y) > 0.f) {
        zone[static_cast<size_t>(y) * c.spec.width + x] = 1;
        if (topX < 0 || c.bedrockM(x, y) > c.bedrockM(topX, topY)) topX = x, topY = y;
      }
  if (topX < 0) throw InputError(c.name + ": the release raster holds no snow");
  auto backend = createCpuBackend();
  backend->upload(s);
  const double before = backend->totals().totalM3();
  const auto t0 = WallClock::now();
  AvalancheRun run(*backend, p, s);
  if (!run.releaseZone(zone, 0.0, kColdC, true)) throw InputError(c.name + ": " + run.record().why);
  const AvalancheRecord rec = run.runToRest();
  r.seconds = elapsedSeconds(t0);
  r.simulatedS = rec.simulatedS;
  r.why = rec.why;
  r.massError = std::abs(backend->totals().totalM3() - before) / before;
  SnowState after = s;
  backend->download(after);
  r.peakThicknessM = after.avalanchePeakThicknessM;
  for (float v : after.avalanchePeakSpeedMps.values()) r.peakSpeedMps = std::max(r.peakSpeedMps, static_cast<double>(v));
  r.referencePeakSpeedMps = c.referencePeakSpeedMps;
  const double wx = c.spec.originX + (topX + 0.5) * c.geoCellX, wy = c.spec.originY - (topY + 0.5) * c.geoCellY;
  r.releaseTopS = projectOnPath(c.pathXY, wx, wy);
  const double topZ = c.bedrockM(topX, topY);
  const PathScore ours = scoreFootprint(c, r.peakThicknessM, r.releaseTopS, topZ);
  const PathScore ref = scoreFootprint(c, c.referencePftM, r.releaseTopS, topZ);
  r.runoutM = ours.runoutS, r.referenceRunoutM = ref.runoutS;
  r.alphaDeg = ours.alphaDeg, r.referenceAlphaDeg = ref.alphaDeg;
  r.footprintCells = ours.cells, r.referenceFootprintCells = ref.cells;
  r.runoutError = (ours.runoutS - ref.runoutS) / std::max(1.0, ref.runoutS - r.releaseTopS);
  int both = 0, either = 0;
  for (size_t i = 0; i < c.spec.cellCount(); ++i) {
    const bool a = c.valid.values()[i] && r.peakThicknessM.values()[i] > kFootprintM;
    const bool b = c.valid.values()[i] && c.referencePftM.values()[i] > kFootprintM;
    both += a && b, either += a || b;
  }
  r.iou = either > 0 ? static_cast<double>(both) / either : 0.0;
  return r;
}

}  // namespace snow
