#include "default_terrain.h"

#include <algorithm>
#include <cmath>

#include "rng.h"

namespace snow {
namespace {

// Gradient noise (Perlin-style) on an integer lattice with hashed unit-ish gradients.
double lattice(int64_t ix, int64_t iy, uint64_t seed, double fx, double fy) {
  const Philox4x32 r = philox4x32(static_cast<uint32_t>(ix), static_cast<uint32_t>(iy), 0x5eedu,
                                  static_cast<uint32_t>(RngStream::Terrain), static_cast<uint32_t>(seed),
                                  static_cast<uint32_t>(seed >> 32));
  // One of 16 directions, from a table (no trigonometry: identical everywhere).
  static const double gx[16] = {1, 0.9239, 0.7071, 0.3827, 0, -0.3827, -0.7071, -0.9239,
                                -1, -0.9239, -0.7071, -0.3827, 0, 0.3827, 0.7071, 0.9239};
  static const double gy[16] = {0, 0.3827, 0.7071, 0.9239, 1, 0.9239, 0.7071, 0.3827,
                                0, -0.3827, -0.7071, -0.9239, -1, -0.9239, -0.7071, -0.3827};
  const int k = static_cast<int>(r.v[0] & 15u);
  return gx[k] * fx + gy[k] * fy;
}

double fade(double t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); }

double gradientNoise(double x, double y, uint64_t seed) {
  const double fx0 = std::floor(x), fy0 = std::floor(y);
  const int64_t ix = static_cast<int64_t>(fx0), iy = static_cast<int64_t>(fy0);
  const double tx = x - fx0, ty = y - fy0;
  const double n00 = lattice(ix, iy, seed, tx, ty);
  const double n10 = lattice(ix + 1, iy, seed, tx - 1, ty);
  const double n01 = lattice(ix, iy + 1, seed, tx, ty - 1);
  const double n11 = lattice(ix + 1, iy + 1, seed, tx - 1, ty - 1);
  const double u = fade(tx), v = fade(ty);
  const double a = n00 + (n10 - n00) * u, b = n01 + (n11 - n01) * u;
  return a + (b - a) * v;  // about [-0.7, 0.7]
}

// Ridged multifractal (Musgrave): sharp crests from 1 - |noise|, later octaves weighted by the
// earlier ones so valleys stay smooth and ridges get detail.
double ridged(double x, double y, uint64_t seed) {
  double sum = 0.0, amplitude = 1.0, frequency = 1.0, weight = 1.0, norm = 0.0;
  for (int octave = 0; octave < 6; ++octave) {
    double n = 1.0 - std::abs(gradientNoise(x * frequency, y * frequency, seed + 101u * octave) * 1.4);
    n = n * n;
    n *= weight;
    weight = std::clamp(n * 1.6, 0.0, 1.0);
    sum += n * amplitude;
    norm += amplitude;
    amplitude *= 0.5;
    frequency *= 2.03;
  }
  return sum / norm;
}

}  // namespace

Grid<float> generateDefaultTerrain(const DefaultTerrainOptions& o, GridSpec* spec) {
  Grid<float> heights(o.size, o.size, 0.f);
  std::vector<double> raw(static_cast<size_t>(o.size) * o.size);
  const double extent = o.size * o.cellSizeM;
  for (int y = 0; y < o.size; ++y) {
    for (int x = 0; x < o.size; ++x) {
      const double wx = (x + 0.5) * o.cellSizeM, wy = (y + 0.5) * o.cellSizeM;
      const double r = ridged(wx / o.ridgeWavelengthM, wy / o.ridgeWavelengthM, o.seed);
      // A broad dome so the range rises toward the middle and falls to valleys at the edges.
      const double cx = wx / extent - 0.5, cy = wy / extent - 0.5;
      const double dome = 1.0 - 1.6 * (cx * cx + cy * cy);
      raw[static_cast<size_t>(y) * o.size + x] = 0.75 * r + 0.35 * dome;
    }
  }
  const auto [lo, hi] = std::minmax_element(raw.begin(), raw.end());
  const double span = std::max(*hi - *lo, 1e-12);
  for (size_t i = 0; i < raw.size(); ++i)
    heights.values()[i] = static_cast<float>(o.minAltitudeM + (raw[i] - *lo) / span * (o.maxAltitudeM - o.minAltitudeM));
  if (spec) {
    spec->width = spec->height = o.size;
    spec->cellSizeXM = spec->cellSizeYM = o.cellSizeM;
    spec->originX = 0.0;
    spec->originY = extent;
  }
  return heights;
}

}  // namespace snow
