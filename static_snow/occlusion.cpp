#include "occlusion.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>

#include "core/errors.h"
#include "core/util.h"
#include "core/mesh_normals.h"
#include "scene/sun_quality.h"
#include "precompute/exposure.h"
#include "precompute/solar.h"

namespace snow {

namespace {

// A 64-bit mix (splitmix64's finaliser): the per-point turn of the ray pattern.
uint64_t mix64(uint64_t z) {
  z += 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

double radicalInverse2(uint32_t bits) {
  bits = (bits << 16u) | (bits >> 16u);
  bits = ((bits & 0x55555555u) << 1u) | ((bits & 0xAAAAAAAAu) >> 1u);
  bits = ((bits & 0x33333333u) << 2u) | ((bits & 0xCCCCCCCCu) >> 2u);
  bits = ((bits & 0x0F0F0F0Fu) << 4u) | ((bits & 0xF0F0F0F0u) >> 4u);
  bits = ((bits & 0x00FF00FFu) << 8u) | ((bits & 0xFF00FF00u) >> 8u);
  return bits * 2.3283064365386963e-10;
}

// An orthonormal basis around n (Duff et al. 2017).
void basis(const std::array<float, 3>& n, std::array<float, 3>& t, std::array<float, 3>& b) {
  const float sign = std::copysign(1.0f, n[2]);
  const float a = -1.0f / (sign + n[2]);
  const float c = n[0] * n[1] * a;
  t = {1.0f + sign * n[0] * n[0] * a, sign * c, -sign * n[0]};
  b = {c, sign + n[1] * n[1] * a, -n[1]};
}

double f(double x) { return 0.91 + 10.0 * std::exp(-3.0 * x) + 0.45 * std::cos(x) * std::cos(x); }

}  // namespace

int occlusionRaysForQuality(const std::string& quality) {
  for (const SunQuality& q : sunQualities())
    if (q.name == quality) return q.occlusionAoRays;
  throw InputError("occlusion quality '" + quality + "' is not one of: draft, production, reference");
}

double clearSkyRelativeLuminance(double theta, double gamma, double z0) {
  const double c = std::cos(theta);
  const double horizon = c > 1e-9 ? 1.0 - std::exp(-0.32 / c) : 1.0;
  return f(gamma) * horizon / (0.274 * f(z0));
}

double skyAngleToSun(double z0, double theta, double alpha) {
  // As printed: with sin(alpha), alpha is measured from 90 degrees off the sun's azimuth (the
  // spherical law of cosines with the azimuth difference 90 deg - alpha), so gamma = 0 at the sun.
  const double c = std::cos(z0) * std::cos(theta) + std::sin(z0) * std::sin(theta) * std::sin(alpha);
  return std::acos(std::clamp(c, -1.0, 1.0));
}

double zenithLuminanceKcd(double z0, double turbidity) {
  const double chi = (4.0 / 9.0 - turbidity / 120.0) * (kPi - 2.0 * z0);
  return std::max(0.0, (4.0453 * turbidity - 4.9710) * std::tan(chi) - 0.2155 * turbidity + 2.4192);
}

std::vector<SunSample> sunTrajectory(double latitudeDeg, double dayOfYear, int positions, double turbidity) {
  std::vector<SunSample> out;
  if (positions <= 0) return out;
  // Daylight hours from the hour angle of sunrise, cos H0 = -tan(lat) tan(decl).
  const SunPosition noon = sunPosition(latitudeDeg, dayOfYear, 12.0);
  const double lat = latitudeDeg * kPi / 180.0, decl = noon.declinationDeg * kPi / 180.0;
  const double cosH0 = -std::tan(lat) * std::tan(decl);
  if (cosH0 >= 1.0) return out;  // polar night
  const double halfDayHours = cosH0 <= -1.0 ? 12.0 : std::acos(cosH0) * 12.0 / kPi;
  double total = 0.0;
  for (int k = 0; k < positions; ++k) {
    const double hour = 12.0 - halfDayHours + (k + 0.5) * (2.0 * halfDayHours / positions);
    const SunPosition s = sunPosition(latitudeDeg, dayOfYear, hour);
    if (s.elevationDeg <= 0.0) continue;
    SunSample x;
    x.direction = {static_cast<float>(s.direction[0]), static_cast<float>(s.direction[1]), static_cast<float>(s.direction[2])};
    x.solarHour = hour;
    x.elevationDeg = s.elevationDeg;
    x.azimuthDeg = s.azimuthDeg;
    const double z0 = (90.0 - s.elevationDeg) * kPi / 180.0;
    x.weight = clearSkyRelativeLuminance(z0, 0.0, z0) * zenithLuminanceKcd(z0, turbidity);
    total += x.weight;
    out.push_back(x);
  }
  if (total > 0.0)
    for (auto& x : out) x.weight /= total;
  else
    out.clear();
  return out;
}

OcclusionSnow computeOcclusionSnow(const RayScene& scene, const std::vector<std::array<float, 3>>& points,
                                   const std::vector<std::array<float, 3>>& normals, const std::vector<uint8_t>& active,
                                   float originOffsetM, const OcclusionSettings& s) {
  if (points.size() != normals.size() || (!active.empty() && active.size() != points.size()))
    throw std::invalid_argument("computeOcclusionSnow: points, normals and active differ in size");
  if (s.aoRays < 1) throw InputError("occlusion: ao_rays must be at least 1");
  const size_t n = points.size();
  OcclusionSnow out;
  out.ambient.assign(n, 0.f);
  out.sunVisibility.assign(n, 0.f);
  out.accumulationM.assign(n, 0.f);
  out.dissipationM.assign(n, 0.f);
  out.snowM.assign(n, 0.f);
  out.sun = sunTrajectory(s.latitudeDeg, s.dayOfYear, s.sunPositions, s.turbidity);
  auto on = [&](size_t k) { return active.empty() || active[k]; };
  const float tfar = s.aoRadiusM > 0.0 ? static_cast<float>(s.aoRadiusM) : std::numeric_limits<float>::infinity();
  const int rays = s.aoRays;

  // Pass 1: ambient occlusion, 16-ray packets from one point.
  auto t0 = WallClock::now();
  std::atomic<unsigned long long> aoRays{0};
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 64), [&](const tbb::blocked_range<size_t>& r) {
    unsigned long long local = 0;
    for (size_t k = r.begin(); k < r.end(); ++k) {
      if (!on(k)) continue;
      const auto& nn = normals[k];
      std::array<float, 3> t, b;
      basis(nn, t, b);
      const std::array<float, 3> o{points[k][0] + originOffsetM * nn[0], points[k][1] + originOffsetM * nn[1],
                                   points[k][2] + originOffsetM * nn[2]};
      const uint64_t h = mix64(k);
      const double turn = (h >> 11) * 0x1.0p-53, shift = (mix64(h) >> 11) * 0x1.0p-53;
      int open = 0;
      for (int r0 = 0; r0 < rays; r0 += 16) {
        bool want[16], hit[16];
        std::array<float, 3> origins[16], dirs[16];
        for (int q = 0; q < 16; ++q) {
          const int i = r0 + q;
          want[q] = i < rays;
          origins[q] = o;
          dirs[q] = nn;
          if (!want[q]) continue;
          // Malley: uniform on the disk (stratified in radius^2, Hammersley in angle), lifted.
          double u1 = (i + 0.5) / rays + shift;
          u1 -= std::floor(u1);
          const double phi = 2.0 * kPi * (radicalInverse2(static_cast<uint32_t>(i)) + turn);
          const double rr = std::sqrt(u1), z = std::sqrt(std::max(0.0, 1.0 - u1));
          const double x = rr * std::cos(phi), y = rr * std::sin(phi);
          for (int c = 0; c < 3; ++c) dirs[q][c] = static_cast<float>(x * t[c] + y * b[c] + z * nn[c]);
        }
        scene.occluded16(want, origins, dirs, tfar, hit);
        for (int q = 0; q < 16; ++q)
          if (want[q] && !hit[q]) ++open;
        local += static_cast<unsigned long long>(std::min(16, rays - r0));
      }
      out.ambient[k] = static_cast<float>(static_cast<double>(open) / rays);
    }
    aoRays += local;
  });
  out.aoSeconds = elapsedSeconds(t0);
  out.aoRayCount = aoRays;

  // Pass 2: the sun trajectory, one packet per 16 points and sun position.
  t0 = WallClock::now();
  std::atomic<unsigned long long> sunRays{0};
  const float inf = std::numeric_limits<float>::infinity();
  if (!out.sun.empty())
    tbb::parallel_for(tbb::blocked_range<size_t>(0, (n + 15) / 16, 16), [&](const tbb::blocked_range<size_t>& r) {
      unsigned long long local = 0;
      for (size_t blk = r.begin(); blk < r.end(); ++blk) {
        double seen[16] = {0};
        for (const SunSample& sun : out.sun) {
          bool want[16], hit[16];
          std::array<float, 3> origins[16], dirs[16];
          for (int q = 0; q < 16; ++q) {
            const size_t k = blk * 16 + q;
            want[q] = false;
            dirs[q] = sun.direction;
            if (k >= n || !on(k)) continue;
            const auto& nn = normals[k];
            if (nn[0] * sun.direction[0] + nn[1] * sun.direction[1] + nn[2] * sun.direction[2] <= 0.f) continue;
            origins[q] = {points[k][0] + originOffsetM * nn[0], points[k][1] + originOffsetM * nn[1], points[k][2] + originOffsetM * nn[2]};
            want[q] = true;
            ++local;
          }
          scene.occluded16(want, origins, dirs, inf, hit);
          for (int q = 0; q < 16; ++q)
            if (want[q] && !hit[q]) seen[q] += sun.weight;
        }
        for (int q = 0; q < 16; ++q) {
          const size_t k = blk * 16 + q;
          if (k < n && on(k)) out.sunVisibility[k] = static_cast<float>(std::min(1.0, seen[q]));
        }
      }
      sunRays += local;
    });
  out.sunSeconds = elapsedSeconds(t0);
  out.sunRayCount = sunRays;

  for (size_t k = 0; k < n; ++k) {
    if (!on(k)) continue;
    const double cosTheta = std::max(0.0f, normals[k][2]);
    const double acc = s.sMaxM * std::max(0.0, s.tauAmbient - out.ambient[k]) * cosTheta;
    const double dis = s.sMaxM * std::max(0.0, static_cast<double>(out.sunVisibility[k]) - s.tauSun) * cosTheta;
    out.accumulationM[k] = static_cast<float>(acc);
    out.dissipationM[k] = static_cast<float>(dis);
    out.snowM[k] = static_cast<float>(std::max(0.0, acc - dis));
  }
  return out;
}

OcclusionSnow computeOcclusionSnowOnTerrain(const RayScene& scene, const Grid<float>& heights, const Grid<uint8_t>& valid,
                                            const GridSpec& spec, const OcclusionSettings& settings) {
  std::vector<std::array<float, 3>> normals;
  terrainNormals(heights, valid, spec, normals);
  const int w = spec.width, h = spec.height;
  std::vector<std::array<float, 3>> points(static_cast<size_t>(w) * h);
  std::vector<uint8_t> active(points.size());
  float maxAbsZ = 0.f;
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const size_t k = static_cast<size_t>(j) * w + i;
      points[k] = scene.cellPoint(i, j);
      active[k] = valid(i, j);
      if (active[k]) maxAbsZ = std::max(maxAbsZ, std::abs(points[k][2]));
    }
  // As the sun-exposure rays: a little above the surface, so rays miss their own cell.
  const float eps = static_cast<float>(1e-3 * std::min(spec.cellSizeXM, spec.cellSizeYM) + 1e-5 * maxAbsZ);
  return computeOcclusionSnow(scene, points, normals, active, eps, settings);
}

OcclusionSnow computeOcclusionSnowOnMesh(const RayScene& scene, const TriangleMesh& mesh, const OcclusionSettings& settings) {
  const std::vector<std::array<float, 3>> normals = areaWeightedNormals(mesh.positions, mesh.triangles);
  // Vertices no triangle uses take no part.
  std::vector<uint8_t> used(mesh.positions.size(), 0);
  for (const auto& t : mesh.triangles) used[t[0]] = used[t[1]] = used[t[2]] = 1;
  double diagonal = 0.0, maxAbsZ = 0.0;
  for (int c = 0; c < 3; ++c) diagonal += std::pow(double(mesh.boundsMax[c]) - mesh.boundsMin[c], 2.0);
  for (const auto& p : mesh.positions) maxAbsZ = std::max(maxAbsZ, std::abs(double(p[2])));
  const float eps = static_cast<float>(1e-5 * std::sqrt(diagonal) + 1e-5 * maxAbsZ);
  return computeOcclusionSnow(scene, mesh.positions, normals, used, eps, settings);
}

}  // namespace snow
