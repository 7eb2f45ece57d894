#include "bedform_runs.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "rng.h"
#include "util.h"

namespace snow {

std::string validateBedformParameters(const BedformParameters& p, const GridSpec& spec) {
  const double minCellM = std::min(spec.cellSizeXM, spec.cellSizeYM);
  std::ostringstream e;
  if (!(p.slabM > 0.0)) e << "bedforms.slab_m must be positive (got " << p.slabM << ")";
  else if (!(p.hopLengthM > 0.0)) e << "bedforms.hop_length_m must be positive (got " << p.hopLengthM << ")";
  else if (!(p.referenceWindMps > 0.0)) e << "bedforms.reference_wind_mps must be positive";
  else if (!(p.thresholdWindMps >= 0.0)) e << "bedforms.threshold_wind_mps must be at least 0";
  else if (!(p.depositSnow > 0.0 && p.depositSnow <= 1.0) || !(p.depositBare > 0.0 && p.depositBare <= 1.0))
    e << "bedforms.deposit_on_snow and deposit_on_bare must be in (0, 1]";
  else if (!(p.shadowAngleDeg > 0.0 && p.shadowAngleDeg < 90.0)) e << "bedforms.shadow_angle_deg must be in (0, 90)";
  else if (!(p.shadowLengthM >= 0.0)) e << "bedforms.shadow_length_m must be at least 0";
  else if (!(p.reposeAngleDeg > 0.0 && p.reposeAngleDeg < 90.0)) e << "bedforms.repose_angle_deg must be in (0, 90)";
  else if (bedform::tanDeg(p.reposeAngleDeg) * minCellM < p.slabM)
    e << "bedforms.repose_angle_deg = " << p.reposeAngleDeg << " on cells of " << minCellM
      << " m allows a step smaller than one slab (slab_m = " << p.slabM
      << "): use a thinner slab, a larger angle or larger cells";
  else if (!(p.maxSlopeDeg >= 0.0 && p.maxSlopeDeg < 90.0)) e << "bedforms.max_slope_deg must be in [0, 90)";
  else if (!(p.sinteringPerDay >= 0.0)) e << "bedforms.sintering_per_day must be at least 0";
  else if (!(p.sinteringScaleC > 0.0)) e << "bedforms.sintering_scale_c must be positive";
  else if (!(p.roundsPerHour > 0.0) || p.roundsPerHour > 3600.0) e << "bedforms.rounds_per_hour must be in (0, 3600]";
  else if (p.batches < 1 || p.batches > 64) e << "bedforms.batches must be in [1, 64]";
  else if (p.maxHops < 1 || p.maxHops > 4096) e << "bedforms.max_hops must be in [1, 4096]";
  else if (p.periodic && (spec.width % 2 != 0 || spec.height % 2 != 0))
    e << "bedforms.periodic: the grid is " << spec.width << " x " << spec.height
      << " cells; a periodic (tileable) window needs an even width and height";
  return e.str();
}

SnowState makeBedformWindow(int w, int h, double cellM, double meanDepthM, double noiseM, float windXMps,
                            float windYMps, float temperatureC, uint64_t seed) {
  SnowState s;
  GridSpec spec;
  spec.width = w;
  spec.height = h;
  spec.cellSizeXM = cellM;
  spec.cellSizeYM = cellM;
  s.allocate(spec);
  const RandomKey key{seed};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const uint32_t i = static_cast<uint32_t>(y * w + x);
      const float u = key.uniform(0, i, RngStream::Test);
      s.powderM(x, y) = static_cast<float>(std::max(0.0, meanDepthM + noiseM * (2.0 * u - 1.0)));
      s.windXMps(x, y) = windXMps;
      s.windYMps(x, y) = windYMps;
      s.temperatureBaseC(x, y) = temperatureC;
    }
  return s;
}

BedformParameters periodicBedformParameters() {
  BedformParameters p;
  p.periodic = true;
  p.sinteringPerDay = 0.0;
  return p;
}

SnowState makeBarchanWindow(int n) { return makeBedformWindow(n, n, 0.5, 0.05, 0.025, 10.f, 0.f, -10.f, 3); }

double maxReposeExcessM(const SnowState& s, double tanRepose, double slabM, bool periodic) {
  const int w = s.spec.width, h = s.spec.height;
  double worst = -std::numeric_limits<double>::infinity();
  auto surface = [&](int x, int y) { return static_cast<double>(s.bedrockM(x, y)) + s.depthM(x, y); };
  auto check = [&](int x0, int y0, int x1, int y1, double spacing) {
    if (!s.validCell(x0, y0) || !s.validCell(x1, y1)) return;
    const double d = surface(x0, y0) - surface(x1, y1);
    const bool firstHigher = d > 0;
    const float highPowder = firstHigher ? s.powderM(x0, y0) : s.powderM(x1, y1);
    if (highPowder < slabM * (1.0 - 1e-5)) return;
    worst = std::max(worst, std::abs(d) - tanRepose * spacing);
  };
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (x + 1 < w) check(x, y, x + 1, y, s.spec.cellSizeXM);
      else if (periodic) check(x, y, 0, y, s.spec.cellSizeXM);
      if (y + 1 < h) check(x, y, x, y + 1, s.spec.cellSizeYM);
      else if (periodic) check(x, y, x, 0, s.spec.cellSizeYM);
    }
  return worst;
}

int migrationShiftCells(const Grid<float>& a, const Grid<float>& b, int maxShift) {
  const int w = a.width(), h = a.height();
  double ma = 0, mb = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    ma += a.values()[i];
    mb += b.values()[i];
  }
  ma /= static_cast<double>(a.size());
  mb /= static_cast<double>(b.size());
  int best = 0;
  double bestScore = -std::numeric_limits<double>::infinity();
  for (int s = -maxShift; s <= maxShift; ++s) {
    double score = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) score += (a(x, y) - ma) * (b(((x + s) % w + w) % w, y) - mb);
    if (score > bestScore) {
      bestScore = score;
      best = s;
    }
  }
  return best;
}

FaceSlopes faceSlopesAlongX(const Grid<float>& depth, double cellM, double minSlope, double minDepthM, double steepSlope) {
  FaceSlopes f;
  const int w = depth.width(), h = depth.height();
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (std::max(depth((x + 1) % w, y), depth(x, y)) <= minDepthM) continue;
      const double g = (depth((x + 1) % w, y) - depth(x, y)) / cellM;
      if (g > minSlope) {
        f.windward += g;
        ++f.windwardCells;
        f.steepWindwardCells += g > steepSlope;
      } else if (g < -minSlope) {
        f.lee += -g;
        ++f.leeCells;
        f.steepLeeCells += -g > steepSlope;
      }
    }
  if (f.windwardCells) f.windward /= static_cast<double>(f.windwardCells);
  if (f.leeCells) f.lee /= static_cast<double>(f.leeCells);
  return f;
}

std::vector<BedformBody> findBedformBodies(const Grid<float>& depth, double cellM, double thresholdM) {
  const int w = depth.width(), h = depth.height();
  std::vector<int> seen(depth.size(), 0);
  std::vector<BedformBody> bodies;
  std::vector<std::pair<int, int>> cells;  // unwrapped coordinates of the body
  std::vector<std::pair<int, int>> stack;
  for (int y0 = 0; y0 < h; ++y0)
    for (int x0 = 0; x0 < w; ++x0) {
      if (seen[static_cast<size_t>(y0) * w + x0] || !(depth(x0, y0) > thresholdM)) continue;
      cells.clear();
      stack.assign(1, {x0, y0});
      seen[static_cast<size_t>(y0) * w + x0] = 1;
      double top = 0;
      while (!stack.empty()) {
        const auto [ux, uy] = stack.back();
        stack.pop_back();
        cells.push_back({ux, uy});
        const int cx = ((ux % w) + w) % w, cy = ((uy % h) + h) % h;
        top = std::max(top, static_cast<double>(depth(cx, cy)));
        const int dx[4] = {1, -1, 0, 0}, dy[4] = {0, 0, 1, -1};
        for (int k = 0; k < 4; ++k) {
          const int nx = ux + dx[k], ny = uy + dy[k];
          const int wx = ((nx % w) + w) % w, wy = ((ny % h) + h) % h;
          const size_t j = static_cast<size_t>(wy) * w + wx;
          if (seen[j] || !(depth(wx, wy) > thresholdM)) continue;
          seen[j] = 1;
          stack.push_back({nx, ny});
        }
      }
      int xmin = cells[0].first, xmax = xmin, ymin = cells[0].second, ymax = ymin;
      int crestY = cells[0].second;
      double crest = -1.0;
      for (const auto& [x, y] : cells) {
        xmin = std::min(xmin, x);
        xmax = std::max(xmax, x);
        ymin = std::min(ymin, y);
        ymax = std::max(ymax, y);
        const double z = depth(((x % w) + w) % w, ((y % h) + h) % h);
        if (z > crest) crest = z, crestY = y;
      }
      BedformBody b;
      b.cells = static_cast<long long>(cells.size());
      b.lengthM = (xmax - xmin + 1) * cellM;
      b.widthM = (ymax - ymin + 1) * cellM;
      b.heightM = top;
      // Horns: the most downwind cell of each row; the farthest flank row (a quarter of the width
      // or more from the crest's row) against the crest's row and its neighbours.
      std::vector<int> rowFront(static_cast<size_t>(ymax - ymin + 1), std::numeric_limits<int>::min());
      for (const auto& [x, y] : cells) rowFront[static_cast<size_t>(y - ymin)] = std::max(rowFront[static_cast<size_t>(y - ymin)], x);
      const double quarter = std::max(1.5, (ymax - ymin + 1) / 4.0);
      int flank = std::numeric_limits<int>::min(), centre = std::numeric_limits<int>::min();
      for (int y = ymin; y <= ymax; ++y) {
        const int front = rowFront[static_cast<size_t>(y - ymin)];
        if (std::abs(y - crestY) >= quarter) flank = std::max(flank, front);
        else if (std::abs(y - crestY) <= 1) centre = std::max(centre, front);
      }
      if (flank != std::numeric_limits<int>::min() && centre != std::numeric_limits<int>::min())
        b.hornLeadM = (flank - centre) * cellM;
      bodies.push_back(b);
    }
  return bodies;
}

BarchanCensus barchanCensus(const Grid<float>& depth, double cellM, double tanRepose, double slabM) {
  const int w = depth.width(), h = depth.height();
  Grid<float> smooth(w, h, 0.f);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float s = 0;
      for (int j = -1; j <= 1; ++j)
        for (int i = -1; i <= 1; ++i) s += depth((x + i + w) % w, (y + j + h) % h);
      smooth(x, y) = s / 9.f;
    }
  BarchanCensus c;
  for (const BedformBody& b : findBedformBodies(smooth, cellM, std::max(0.1, 1.5 * slabM))) {
    if (b.widthM < 3.0 || b.cells < 40) continue;
    ++c.bodies;
    c.hornsDownwind += b.hornLeadM > 0.0;
    c.centreLeading += b.hornLeadM < 0.0;
    c.inSnowRange += b.lengthM >= 3.0 && b.lengthM <= 20.0 && b.heightM >= 0.1 && b.heightM <= 0.5 + slabM;
    c.meanLengthM += b.lengthM;
    c.meanHeightM += b.heightM;
  }
  if (c.bodies > 0) {
    c.meanLengthM /= c.bodies;
    c.meanHeightM /= c.bodies;
  }
  c.faces = faceSlopesAlongX(depth, cellM, 0.02, std::max(0.1, 1.5 * slabM), 0.7 * tanRepose);
  return c;
}

}  // namespace snow
