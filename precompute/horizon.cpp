#include "horizon.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <optional>

#include "core/util.h"
#include "exposure.h"
#include "solar.h"

namespace snow {

namespace {

// One azimuth: lines parallel to it, one sample per step of the major axis (a grid line of
// vertices, so the sample lies on an edge of Embree's triangulation), heights interpolated
// along the minor axis. Each line is walked from its far end (the end the azimuth points to)
// back, keeping the upper convex hull of the samples ahead; the tangent from a sample to that
// hull is the sample's horizon. A cell centre lies between two neighbouring lines (one minor
// step apart): its horizon is interpolated between theirs, so the half-cell offset of a
// single line's sample does not shift the observer.
void sweepAzimuth(const Grid<float>& z, const GridSpec& spec, double azimuthRad, const CellRect& cells, Grid<float>& out) {
  const int w = spec.width, h = spec.height;
  // Direction toward the horizon in grid steps: +i east, +j south.
  const double ex = std::sin(azimuthRad), ey = std::cos(azimuthRad);
  const double di = ex / spec.cellSizeXM, dj = -ey / spec.cellSizeYM;
  const bool alongI = std::abs(di) >= std::abs(dj);
  const int major = alongI ? w : h, minor = alongI ? h : w;
  const double slope = alongI ? dj / di : di / dj;        // minor steps per major step
  const int direction = (alongI ? di : dj) > 0 ? 1 : -1;  // major index grows toward the horizon?
  const double stepM = alongI ? std::hypot(spec.cellSizeXM, slope * spec.cellSizeYM) : std::hypot(spec.cellSizeYM, slope * spec.cellSizeXM);
  auto height = [&](int a, int b) { return alongI ? z(a, b) : z(b, a); };
  // Line L passes minor = L + slope * m at major index m; lines -spread .. minor + spread.
  const int spread = static_cast<int>(std::ceil(std::abs(slope) * major)) + 2;
  const int lineCount = minor + 2 * spread;
  // The cells asked for, on the major and minor axes, and the lines their centres lie between:
  // a line's samples depend on that line alone, so these lines give the whole sweep's bytes.
  const int m0 = alongI ? cells.x0 : cells.y0, m1 = alongI ? cells.x1 : cells.y1;
  const int c0 = alongI ? cells.y0 : cells.x0, c1 = alongI ? cells.y1 : cells.x1;
  const double coordLo = std::min(c0 - slope * m0, c0 - slope * (m1 - 1)), coordHi = std::max((c1 - 1) - slope * m0, (c1 - 1) - slope * (m1 - 1));
  const int index0 = std::max(0, static_cast<int>(std::floor(coordLo)) + spread);
  const int index1 = std::min(lineCount, static_cast<int>(std::floor(coordHi)) + 2 + spread);
  const int span = m1 - m0;
  std::vector<float> sampleHorizon(static_cast<size_t>(std::max(0, index1 - index0)) * span, 0.f);
  tbb::parallel_for(tbb::blocked_range<int>(index0, index1, 16), [&](const tbb::blocked_range<int>& lines) {
    std::vector<std::pair<double, double>> hull;  // (distance along the line, height), nearest last
    for (int index = lines.begin(); index < lines.end(); ++index) {
      const int line = index - spread;
      hull.clear();
      // From the far end to the cells' near edge: samples beyond it are never read.
      const int steps = direction > 0 ? major - m0 : m1;
      for (int k = 0; k < steps; ++k) {
        const int m = direction > 0 ? major - 1 - k : k;  // far end first
        const double r = line + slope * m;
        if (r < -1.0 || r > minor) continue;  // one line beyond the grid on each side, clamped
        const int r0 = std::clamp(static_cast<int>(std::floor(r)), 0, minor - 1), r1 = std::clamp(r0 + 1, 0, minor - 1);
        const double f = std::clamp(r - std::floor(r), 0.0, 1.0);
        const double zp = r < 0 ? height(m, 0) : (r > minor - 1 ? height(m, minor - 1) : height(m, r0) * (1.0 - f) + height(m, r1) * f);
        const double sp = (direction > 0 ? m : major - 1 - m) * stepM;  // grows toward the horizon
        while (hull.size() >= 2) {
          const auto& a = hull[hull.size() - 1];
          const auto& b = hull[hull.size() - 2];
          if ((a.second - zp) / (a.first - sp) <= (b.second - zp) / (b.first - sp)) hull.pop_back();
          else break;
        }
        double angle = 0.0;
        if (!hull.empty()) angle = std::max(0.0, std::atan((hull.back().second - zp) / (hull.back().first - sp)));
        if (m >= m0 && m < m1) sampleHorizon[static_cast<size_t>(index - index0) * span + (m - m0)] = static_cast<float>(angle * 180.0 / kPi);
        hull.push_back({sp, zp});
      }
    }
  });
  // Each cell centre between the two lines around it.
  tbb::parallel_for(tbb::blocked_range<int>(m0, m1, 16), [&](const tbb::blocked_range<int>& ms) {
    for (int m = ms.begin(); m < ms.end(); ++m)
      for (int c = c0; c < c1; ++c) {
        const double lineCoord = c - slope * m;  // L at which a line would pass through the centre
        const int l0 = static_cast<int>(std::floor(lineCoord));
        const float t = static_cast<float>(lineCoord - l0);
        const float a = sampleHorizon[static_cast<size_t>(l0 + spread - index0) * span + (m - m0)];
        const float b = sampleHorizon[static_cast<size_t>(l0 + 1 + spread - index0) * span + (m - m0)];
        const float v = a * (1.f - t) + b * t;
        if (alongI) out(m - cells.x0, c - cells.y0) = v;
        else out(c - cells.x0, m - cells.y0) = v;
      }
  });
}

}  // namespace

std::vector<Grid<float>> computeHorizonsBySweep(const Grid<float>& heights, const Grid<uint8_t>& /*valid*/, const GridSpec& spec,
                                                int count, std::optional<CellRect> cells) {
  const CellRect r = cells.value_or(CellRect::whole(spec));
  std::vector<Grid<float>> horizons(count, Grid<float>(r.width(), r.height(), 0.f));
  for (int k = 0; k < count; ++k) sweepAzimuth(heights, spec, (k + 0.5) * 2.0 * kPi / count, r, horizons[k]);
  return horizons;
}

Grid<float> skyFromHorizons(const std::vector<Grid<float>>& horizons, const Grid<uint8_t>& valid, double kSky) {
  const int w = valid.width(), h = valid.height();
  Grid<float> sky(w, h, 0.f);
  const int n = static_cast<int>(horizons.size());
  for (size_t i = 0; i < sky.size(); ++i) {
    if (!valid.values()[i]) continue;
    double sum = 0.0;
    for (int k = 0; k < n; ++k) {
      const double c = std::cos(horizons[k].values()[i] * kPi / 180.0);
      sum += c * c;
    }
    sky.values()[i] = static_cast<float>(kSky * kPi / n * sum);
  }
  return sky;
}

Grid<float> directSunFromHorizons(const std::vector<Grid<float>>& horizons, const Grid<float>& heights, const Grid<uint8_t>& valid,
                                  const GridSpec& spec, double latitudeDeg, int doy, double hourStep, double kSun) {
  const int w = spec.width, h = spec.height, n = static_cast<int>(horizons.size());
  std::vector<std::array<float, 3>> normals;
  terrainNormals(heights, valid, spec, normals);
  Grid<float> sun(w, h, 0.f);
  for (double hour = hourStep / 2; hour < 24.0; hour += hourStep) {
    const SunPosition s = sunPosition(latitudeDeg, doy, hour);
    if (s.elevationDeg <= 0.0) continue;
    // The two horizon azimuths around the sun's, and the weight of the second.
    const double u = s.azimuthDeg / 360.0 * n - 0.5;
    const int k0 = ((static_cast<int>(std::floor(u)) % n) + n) % n, k1 = (k0 + 1) % n;
    const float t = static_cast<float>(u - std::floor(u));
    tbb::parallel_for(tbb::blocked_range<int>(0, h, 16), [&](const tbb::blocked_range<int>& rows) {
      for (int j = rows.begin(); j < rows.end(); ++j)
        for (int i = 0; i < w; ++i) {
          if (!valid(i, j)) continue;
          const auto& nv = normals[static_cast<size_t>(j) * w + i];
          const double cosine = nv[0] * s.direction[0] + nv[1] * s.direction[1] + nv[2] * s.direction[2];
          if (cosine <= 0.0) continue;
          const float horizon = horizons[k0](i, j) * (1.f - t) + horizons[k1](i, j) * t;
          if (s.elevationDeg > horizon) sun(i, j) += static_cast<float>(kSun * cosine * hourStep);
        }
    });
  }
  return sun;
}

std::vector<Grid<float>> directSunForDaysBySweep(const Grid<float>& heights, const Grid<uint8_t>& valid, const GridSpec& spec, int n,
                                                 double latitudeDeg, const std::vector<int>& daysOfYear, double hourStep, double kSun,
                                                 std::optional<CellRect> part) {
  const CellRect r = part.value_or(CellRect::whole(spec));
  const int w = r.width(), h = r.height();
  const size_t cells = r.cells(), words = (cells + 63) / 64;
  // Every sun position above the horizon, with its two azimuths and a bit a cell: lit or not.
  struct Position {
    size_t day;
    SunPosition s;
    int k0, k1;
    float t;
    std::vector<uint64_t> lit;
  };
  std::vector<Position> positions;
  for (size_t d = 0; d < daysOfYear.size(); ++d)
    for (double hour = hourStep / 2; hour < 24.0; hour += hourStep) {
      const SunPosition s = sunPosition(latitudeDeg, daysOfYear[d], hour);
      if (s.elevationDeg <= 0.0) continue;
      const double u = s.azimuthDeg / 360.0 * n - 0.5;
      const int k0 = ((static_cast<int>(std::floor(u)) % n) + n) % n;
      positions.push_back({d, s, k0, (k0 + 1) % n, static_cast<float>(u - std::floor(u)), std::vector<uint64_t>(words, 0)});
    }
  // The shadow test of the positions between azimuths k0 and k0 + 1 once both grids are swept.
  auto test = [&](int k0, const Grid<float>& a, const Grid<float>& b) {
    for (Position& p : positions) {
      if (p.k0 != k0) continue;
      tbb::parallel_for(tbb::blocked_range<size_t>(0, words, 256), [&](const tbb::blocked_range<size_t>& ws) {
        for (size_t wd = ws.begin(); wd < ws.end(); ++wd) {
          uint64_t bits = 0;
          for (size_t i = wd * 64; i < std::min(cells, wd * 64 + 64); ++i) {
            const float horizon = a.values()[i] * (1.f - p.t) + b.values()[i] * p.t;
            if (p.s.elevationDeg > horizon) bits |= uint64_t(1) << (i - wd * 64);
          }
          p.lit[wd] = bits;
        }
      });
    }
  };
  Grid<float> first(w, h, 0.f), previous(w, h, 0.f), current(w, h, 0.f);
  auto sweep = [&](int k, Grid<float>& out) {
    out.fill(0.f);
    sweepAzimuth(heights, spec, (k + 0.5) * 2.0 * kPi / n, r, out);
  };
  sweep(0, first);
  previous = first;
  for (int k = 1; k < n; ++k) {
    sweep(k, current);
    test(k - 1, previous, current);
    std::swap(previous, current);
  }
  test(n - 1, previous, first);
  previous = current = first = Grid<float>();
  // Each day's sum, hour after hour.
  std::vector<std::array<float, 3>> normals;
  terrainNormals(heights, valid, spec, normals, r);
  std::vector<Grid<float>> suns(daysOfYear.size(), Grid<float>(w, h, 0.f));
  for (const Position& p : positions) {
    Grid<float>& sun = suns[p.day];
    tbb::parallel_for(tbb::blocked_range<int>(0, h, 16), [&](const tbb::blocked_range<int>& rows) {
      for (int j = rows.begin(); j < rows.end(); ++j)
        for (int i = 0; i < w; ++i) {
          if (!valid(r.x0 + i, r.y0 + j)) continue;
          const size_t c = static_cast<size_t>(j) * w + i;
          const auto& nv = normals[c];
          const double cosine = nv[0] * p.s.direction[0] + nv[1] * p.s.direction[1] + nv[2] * p.s.direction[2];
          if (cosine <= 0.0) continue;
          if ((p.lit[c / 64] >> (c % 64)) & 1u) sun(i, j) += static_cast<float>(kSun * cosine * hourStep);
        }
    });
  }
  return suns;
}

}  // namespace snow
