#include "exposure.h"

#include <tbb/blocked_range2d.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "core/bracket.h"
#include "core/errors.h"
#include "core/grid_window.h"
#include "core/util.h"
#include "horizon.h"
#include "solar.h"

namespace snow {

namespace {

// Rays start a little above the surface along the normal, so they do not hit their own cell.
std::array<float, 3> rayOrigin(const RayScene& scene, int i, int j, const std::array<float, 3>& n, const GridSpec& spec) {
  const auto p = scene.cellPoint(i, j);
  const float eps = static_cast<float>(1e-3 * std::min(spec.cellSizeXM, spec.cellSizeYM) + 1e-5 * std::abs(p[2]));
  return {p[0] + eps * n[0], p[1] + eps * n[1], p[2] + eps * n[2]};
}

}  // namespace


void terrainNormals(const Grid<float>& a, const Grid<uint8_t>& valid, const GridSpec& spec, std::vector<std::array<float, 3>>& out,
                    std::optional<CellRect> cells) {
  const int w = spec.width, h = spec.height;
  const CellRect r = cells.value_or(CellRect::whole(spec));
  out.assign(r.cells(), {0.f, 0.f, 1.f});
  for (int j = r.y0; j < r.y1; ++j)
    for (int i = r.x0; i < r.x1; ++i) {
      auto ok = [&](int x, int y) { return x >= 0 && y >= 0 && x < w && y < h && valid(x, y); };
      const bool l = ok(i - 1, j), rt = ok(i + 1, j), u = ok(i, j - 1), d = ok(i, j + 1);
      const double aL = l ? a(i - 1, j) : a(i, j), aR = rt ? a(i + 1, j) : a(i, j);
      const double aN = u ? a(i, j - 1) : a(i, j), aS = d ? a(i, j + 1) : a(i, j);
      const double gx = (l || rt) ? (aR - aL) / ((l && rt ? 2.0 : 1.0) * spec.cellSizeXM) : 0.0;
      const double gyNorth = (u || d) ? (aN - aS) / ((u && d ? 2.0 : 1.0) * spec.cellSizeYM) : 0.0;  // rows run south
      const double norm = std::sqrt(1.0 + gx * gx + gyNorth * gyNorth);
      out[r.offsetOf(i, j)] = {static_cast<float>(-gx / norm), static_cast<float>(-gyNorth / norm), static_cast<float>(1.0 / norm)};
    }
}

// Direct sun for one day: for each sun position above the horizon, shadow rays in 4 x 4 tiles
// (coherent 16-ray packets). With `cells`, the whole grid's tiles that cover them, each traced
// whole (Embree may trace a packet's rays one by one when few are active, so a ray's result can
// depend on its packet's others), and the cells' results kept.
Grid<float> computeDirectSun(const RayScene& scene, const Grid<float>& heights, const Grid<uint8_t>& valid, const GridSpec& spec,
                             double latitudeDeg, int doy, double hourStep, double kSun, unsigned long long* rayCount,
                             std::optional<CellRect> cells) {
  const CellRect c = cells.value_or(CellRect::whole(spec));
  const CellRect tiles = CellRect{c.x0 / 4 * 4, c.y0 / 4 * 4, (c.x1 + 3) / 4 * 4, (c.y1 + 3) / 4 * 4}.intersect(CellRect::whole(spec));
  std::vector<std::array<float, 3>> normals;
  terrainNormals(heights, valid, spec, normals, tiles);
  Grid<float> sun(c.width(), c.height(), 0.f);
  std::atomic<unsigned long long> rays{0};
  for (double hour = hourStep / 2; hour < 24.0; hour += hourStep) {
    const SunPosition s = sunPosition(latitudeDeg, doy, hour);
    if (s.elevationDeg <= 0.0) continue;
    const std::array<float, 3> dir{static_cast<float>(s.direction[0]), static_cast<float>(s.direction[1]),
                                   static_cast<float>(s.direction[2])};
    tbb::parallel_for(tbb::blocked_range2d<int>(tiles.y0 / 4, (tiles.y1 + 3) / 4, tiles.x0 / 4, (tiles.x1 + 3) / 4), [&](const tbb::blocked_range2d<int>& r) {
      unsigned long long local = 0;
      for (int tj = r.rows().begin(); tj < r.rows().end(); ++tj)
        for (int ti = r.cols().begin(); ti < r.cols().end(); ++ti) {
          bool want[16], hit[16];
          std::array<float, 3> origins[16], dirs[16];
          float cosine[16];
          for (int k = 0; k < 16; ++k) {
            const int i = ti * 4 + (k & 3), j = tj * 4 + (k >> 2);
            want[k] = false;
            cosine[k] = 0.f;
            dirs[k] = dir;
            if (!tiles.contains(i, j) || !valid(i, j)) continue;
            const auto& n = normals[tiles.offsetOf(i, j)];
            cosine[k] = n[0] * dir[0] + n[1] * dir[1] + n[2] * dir[2];
            if (cosine[k] <= 0.f) continue;  // self-shadowed: facing away from the sun
            origins[k] = rayOrigin(scene, i, j, n, spec);
            want[k] = true;
            ++local;
          }
          scene.occluded16(want, origins, dirs, std::numeric_limits<float>::infinity(), hit);
          for (int k = 0; k < 16; ++k) {
            const int i = ti * 4 + (k & 3), j = tj * 4 + (k >> 2);
            if (want[k] && !hit[k] && c.contains(i, j)) sun(i - c.x0, j - c.y0) += static_cast<float>(kSun * cosine[k] * hourStep);
          }
        }
      rays += local;
    });
  }
  if (rayCount) *rayCount += rays;
  return sun;
}

// The horizon angle per azimuth: the lowest elevation whose ray escapes, found by bisection on
// exact ray queries (no marching step to jump a thin ridge); angles are above the horizontal
// and never negative (a summit sees the whole sky).
Grid<float> computeSkyExposure(const RayScene& scene, const Grid<uint8_t>& valid, const GridSpec& spec,
                               int azimuths, int bisections, double kSky, unsigned long long* rayCount,
                               std::vector<Grid<float>>* horizons, std::optional<CellRect> cells) {
  const CellRect c = cells.value_or(CellRect::whole(spec));
  Grid<float> sky(c.width(), c.height(), 0.f);
  if (horizons) horizons->assign(azimuths, Grid<float>(c.width(), c.height(), 0.f));
  std::atomic<unsigned long long> rays{0};
  tbb::parallel_for(tbb::blocked_range2d<int>(c.y0, c.y1, c.x0, c.x1), [&](const tbb::blocked_range2d<int>& r) {
    unsigned long long local = 0;
    for (int j = r.rows().begin(); j < r.rows().end(); ++j)
      for (int i = r.cols().begin(); i < r.cols().end(); ++i) {
        if (!valid(i, j)) continue;
        const auto origin = rayOrigin(scene, i, j, {0.f, 0.f, 1.f}, spec);
        double sum = 0.0;
        for (int k = 0; k < azimuths; ++k) {
          // Azimuths offset by half a step so none runs exactly along a grid axis or diagonal.
          const double az = (k + 0.5) * 2.0 * kPi / azimuths;
          const double ex = std::sin(az), ey = std::cos(az);
          auto blocked = [&](double elevation) {
            ++local;
            const std::array<float, 3> d{static_cast<float>(ex * std::cos(elevation)), static_cast<float>(ey * std::cos(elevation)),
                                         static_cast<float>(std::sin(elevation))};
            return scene.occluded(origin, d, std::numeric_limits<float>::infinity());
          };
          double phi = 0.0;
          if (blocked(0.0)) {
            double lo = 0.0, hi = kPi / 2;
            for (int b = 0; b < bisections; ++b) {
              const double mid = 0.5 * (lo + hi);
              (blocked(mid) ? lo : hi) = mid;
            }
            phi = 0.5 * (lo + hi);
          }
          if (horizons) (*horizons)[k](i - c.x0, j - c.y0) = static_cast<float>(phi * 180.0 / kPi);
          sum += std::cos(phi) * std::cos(phi);
        }
        sky(i - c.x0, j - c.y0) = static_cast<float>(kSky * kPi / azimuths * sum);
      }
    rays += local;
  });
  if (rayCount) *rayCount += rays;
  return sky;
}

// One bounce: polar sampling around each receiver (rings at the middle of equal-width
// annuli, directions rotated by half a step every other ring), senders read from the direct
// sun map at the nearest cell. Senders are not tested for visibility: the two cosines already
// drop those behind the receiver's horizon plane or facing away; a ridge between two facing
// slopes is not seen (documented in docs/precompute.md).
std::vector<Grid<float>> computeIndirectSunForDays(const std::vector<const Grid<float>*>& suns, const Grid<float>& heights,
                                                   const Grid<uint8_t>& valid, const GridSpec& spec, int directions, int rings,
                                                   double radiusM, double kIndOverKSun, std::optional<CellRect> receiverCells,
                                                   std::optional<CellRect> senderCells) {
  const int w = spec.width, h = spec.height;
  const CellRect rc = receiverCells.value_or(CellRect::whole(spec)), sc = senderCells.value_or(CellRect::whole(spec));
  const size_t n = suns.size();
  std::vector<Grid<float>> ind(n, Grid<float>(rc.width(), rc.height(), 0.f));
  if (n == 0 || directions <= 0 || rings <= 0 || kIndOverKSun == 0.0) return ind;
  if (rc.intersect(sc) != rc) throw std::invalid_argument("computeIndirectSunForDays: the receivers are not among the senders' cells");
  std::vector<std::array<float, 3>> normals;  // the senders' cells, the receivers' among them
  terrainNormals(heights, valid, spec, normals, sc);
  const double dr = radiusM / rings;
  // The sample pattern is the same round every cell: its offsets and areas once, not a sine
  // and cosine per cell and sample.
  struct Sample {
    double dx, dy, area;
  };
  std::vector<Sample> pattern;
  for (int ring = 0; ring < rings; ++ring) {
    const double rIn = ring * dr, rOut = (ring + 1) * dr, rMid = 0.5 * (rIn + rOut);
    const double area = kPi * (rOut * rOut - rIn * rIn) / directions;  // A_ij
    for (int k = 0; k < directions; ++k) {
      const double az = (k + (ring % 2 ? 0.5 : 0.0)) * 2.0 * kPi / directions + 0.1;
      pattern.push_back({rMid * std::sin(az), rMid * std::cos(az), area});
    }
  }
  // Every sample day at once: the geometry of a receiver and a sender (their cosines and
  // distance) does not depend on the day, only the sender's sun does.
  tbb::parallel_for(tbb::blocked_range2d<int>(rc.y0, rc.y1, rc.x0, rc.x1), [&](const tbb::blocked_range2d<int>& r) {
    std::vector<double> sum(n);
    for (int j = r.rows().begin(); j < r.rows().end(); ++j)
      for (int i = r.cols().begin(); i < r.cols().end(); ++i) {
        if (!valid(i, j)) continue;
        const auto& nr = normals[sc.offsetOf(i, j)];
        const double px = (i + 0.5) * spec.cellSizeXM, py = (h - j - 0.5) * spec.cellSizeYM, pz = heights(i, j);
        std::fill(sum.begin(), sum.end(), 0.0);
        for (const Sample& sample : pattern) {
          const double sx = px + sample.dx, sy = py + sample.dy;
          const int si = static_cast<int>(std::floor(sx / spec.cellSizeXM));
          const int sj = h - 1 - static_cast<int>(std::floor(sy / spec.cellSizeYM));
          if (si < 0 || sj < 0 || si >= w || sj >= h || !valid(si, sj) || (si == i && sj == j)) continue;
          if (!sc.contains(si, sj)) throw std::logic_error("computeIndirectSunForDays: a sender outside the senders' cells");
          const double vx = (si + 0.5) * spec.cellSizeXM - px, vy = (h - sj - 0.5) * spec.cellSizeYM - py, vz = heights(si, sj) - pz;
          const double d2 = vx * vx + vy * vy + vz * vz, d = std::sqrt(d2);
          const double cosR = (nr[0] * vx + nr[1] * vy + nr[2] * vz) / d;
          const auto& ns = normals[sc.offsetOf(si, sj)];
          const double cosS = -(ns[0] * vx + ns[1] * vy + ns[2] * vz) / d;
          if (cosR <= 0.0 || cosS <= 0.0) continue;
          const size_t sender = sc.offsetOf(si, sj);
          for (size_t k = 0; k < n; ++k) sum[k] += sample.area * suns[k]->values()[sender] * cosS * cosR / (kPi * d2);
        }
        for (size_t k = 0; k < n; ++k) ind[k](i - rc.x0, j - rc.y0) = static_cast<float>(kIndOverKSun * sum[k]);
      }
  });
  return ind;
}

Grid<float> computeIndirectSun(const Grid<float>& sun, const Grid<float>& heights, const Grid<uint8_t>& valid, const GridSpec& spec,
                               int directions, int rings, double radiusM, double kIndOverKSun) {
  return std::move(computeIndirectSunForDays({&sun}, heights, valid, spec, directions, rings, radiusM, kIndOverKSun)[0]);
}

void Exposure::release() {
  skyHours = Grid<float>();
  days = std::vector<DailyExposure>();
  released = true;
}

Exposure Exposure::window(int x0, int y0, int width, int height) const {
  Exposure out;
  out.timings = timings;
  out.folded = folded;
  out.released = released;
  out.skyHours = gridWindow(skyHours, x0, y0, width, height);
  const CellRect base = cells.value_or(CellRect{0, 0, skyHours.width(), skyHours.height()});
  out.cells = CellRect{base.x0 + x0, base.y0 + y0, base.x0 + x0 + width, base.y0 + y0 + height};
  for (const DailyExposure& d : days)
    out.days.push_back({d.seasonDay, d.dayOfYear, gridWindow(d.sunHours, x0, y0, width, height),
                        gridWindow(d.indirectHours, x0, y0, width, height)});
  return out;
}

Grid<float> Exposure::totalAt(double seasonDay) const {
  if (released) throw std::logic_error("Exposure::totalAt: the exposure was released");
  Grid<float> total = skyHours;
  if (days.empty()) return total;
  const Bracket br = bracketOf(days.size(), seasonDay, [&](size_t i) { return days[i].seasonDay; });
  const size_t a = br.first, b = br.second;
  const double t = br.weight;
  auto at = [&](size_t d, size_t i) -> double {
    return folded ? days[d].sunHours.values()[i] : days[d].sunHours.values()[i] + days[d].indirectHours.values()[i];
  };
  for (size_t i = 0; i < total.size(); ++i) {
    const double ea = at(a, i), eb = at(b, i);
    total.values()[i] += static_cast<float>(ea + (eb - ea) * t);
  }
  return total;
}

void Exposure::foldIndirect() {
  if (folded) return;
  for (DailyExposure& d : days) {
    for (size_t i = 0; i < d.sunHours.size(); ++i) d.sunHours.values()[i] = d.sunHours.values()[i] + d.indirectHours.values()[i];
    d.indirectHours = Grid<float>();
  }
  folded = true;
}

std::vector<DailyExposure> exposureSampleDays(const ExposureSettings& s) {
  std::vector<double> seasonDays;
  for (double d = 0.0; d < s.seasonDays; d += s.quality.dayStep) seasonDays.push_back(d);
  seasonDays.push_back(s.seasonDays);
  std::vector<DailyExposure> days;
  for (double d : seasonDays) {
    DailyExposure day;
    day.seasonDay = d;
    day.dayOfYear = static_cast<int>(std::fmod(s.startDayOfYear - 1 + std::floor(d), 365.0)) + 1;
    days.push_back(std::move(day));
  }
  return days;
}

ExposureTerms exposureTermsFor(const ModelParameters& p) {
  ExposureTerms t;
  t.sky = p.skyAmbientWeightHours != 0;
  t.direct = p.directSunWeightHours != 0;
  t.indirect = t.direct && p.indirectSunWeightHours != 0;  // I_ind scales the direct sun's grids
  if (!t.sky) t.skipped.push_back("sky: sky_ambient_weight_hours = 0");
  if (!t.direct) t.skipped.push_back("direct sun: direct_sun_weight_hours = 0");
  if (!t.indirect)
    t.skipped.push_back(t.direct ? "indirect sun: indirect_sun_weight_hours = 0" : "indirect sun: direct_sun_weight_hours = 0");
  return t;
}

CellRect indirectSenderCells(const CellRect& receivers, const GridSpec& spec, double radiusM) {
  const int cx = static_cast<int>(std::ceil(radiusM / spec.cellSizeXM)) + 1, cy = static_cast<int>(std::ceil(radiusM / spec.cellSizeYM)) + 1;
  return receivers.widened(cx, cy, CellRect::whole(spec));
}

// A skipped term's zeros are the bytes computing it gives, without its rays.
Exposure computeExposure(const RayScene* scene, const Grid<float>& heights, const Grid<uint8_t>& valid, const GridSpec& spec,
                         const ModelParameters& p, const ExposureSettings& s, std::optional<CellRect> cells) {
  if (!s.horizonSweep && !scene) throw std::invalid_argument("computeExposure: the Embree path needs a RayScene");
  const CellRect mine = cells.value_or(CellRect::whole(spec));
  Exposure e;
  const ExposureTerms terms = exposureTermsFor(p);
  e.timings.skipped = terms.skipped;
  const auto zeros = [&] { return Grid<float>(mine.width(), mine.height(), 0.f); };  // made only for a skipped term
  auto t0 = WallClock::now();
  if (!terms.sky) {
    e.skyHours = zeros();
  } else if (s.horizonSweep) {
    // The sky's horizons are freed before the shadows' four times as many are swept, and those
    // one azimuth after another (directSunForDaysBySweep): never all held at once.
    const std::vector<Grid<float>> skyHorizons = computeHorizonsBySweep(heights, valid, spec, s.quality.azimuths, mine);
    e.timings.horizonSeconds = elapsedSeconds(t0);
    t0 = WallClock::now();
    const Grid<uint8_t> validOfCells = cells ? gridWindow(valid, mine) : Grid<uint8_t>();
    e.skyHours = skyFromHorizons(skyHorizons, cells ? validOfCells : valid, p.skyAmbientWeightHours);
  } else {
    e.skyHours = computeSkyExposure(*scene, valid, spec, s.quality.azimuths, s.quality.bisections, p.skyAmbientWeightHours,
                                    &e.timings.skyRays, nullptr, mine);
  }
  e.timings.skySeconds = elapsedSeconds(t0);
  const double kIndOverKSun = p.directSunWeightHours > 0 ? p.indirectSunWeightHours / p.directSunWeightHours : 0.0;
  // The direct sun of the cells and, for their indirect term, of its senders around them.
  const CellRect lit = terms.indirect ? indirectSenderCells(mine, spec, s.quality.indirectRadiusM) : mine;
  t0 = WallClock::now();
  e.days = exposureSampleDays(s);
  if (!terms.direct) {
    for (DailyExposure& day : e.days) day.sunHours = zeros();
  } else if (s.horizonSweep) {
    std::vector<int> doys;
    for (const DailyExposure& day : e.days) doys.push_back(day.dayOfYear);
    std::vector<Grid<float>> suns = directSunForDaysBySweep(heights, valid, spec, 4 * s.quality.azimuths, s.latitudeDeg, doys,
                                                            s.quality.hourStep, p.directSunWeightHours, lit);
    for (size_t d = 0; d < e.days.size(); ++d) e.days[d].sunHours = std::move(suns[d]);
  } else {
    for (DailyExposure& day : e.days)
      day.sunHours = computeDirectSun(*scene, heights, valid, spec, s.latitudeDeg, day.dayOfYear, s.quality.hourStep,
                                      p.directSunWeightHours, &e.timings.sunRays, lit);
  }
  e.timings.sunSeconds = elapsedSeconds(t0);  // the shadows' sweeps included
  t0 = WallClock::now();
  if (!terms.indirect) {
    for (DailyExposure& day : e.days) day.indirectHours = zeros();
  } else {
    std::vector<const Grid<float>*> suns;
    for (const DailyExposure& day : e.days) suns.push_back(&day.sunHours);
    std::vector<Grid<float>> indirect = computeIndirectSunForDays(suns, heights, valid, spec, s.quality.indirectDirections,
                                                                  s.quality.indirectRings, s.quality.indirectRadiusM, kIndOverKSun, mine, lit);
    for (size_t k = 0; k < e.days.size(); ++k) e.days[k].indirectHours = std::move(indirect[k]);
  }
  if (lit != mine)  // the senders' sun cut to the cells
    for (DailyExposure& day : e.days) day.sunHours = gridWindow(day.sunHours, CellRect{mine.x0 - lit.x0, mine.y0 - lit.y0, mine.x1 - lit.x0, mine.y1 - lit.y0});
  e.timings.indirectSeconds = elapsedSeconds(t0);
  e.cells = cells;
  return e;
}

}  // namespace snow
