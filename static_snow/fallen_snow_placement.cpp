// Fearing's snow placement (fallen_snow.h): launch sites on a lattice over the mesh, flakes traced
// up to the sky with flutter, adaptive refinement where coverage changes, each sky bucket's snow
// shared among the sites that reached it.
#include "fallen_snow.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>

#include "core/errors.h"
#include "core/rng.h"
#include "core/util.h"
#include "precompute/ray_scene.h"
#include "surface_lift.h"

namespace snow {
namespace {

// Edge function of the directed edge P -> Q at (x, y): positive to its left. Evaluated on the
// edge's endpoints in a fixed order, so the two triangles sharing an edge get the same number
// with opposite signs, bit for bit (a lattice point on a shared edge belongs to one of them).
double edgeFunction(const std::array<float, 3>& P, const std::array<float, 3>& Q, double x, double y) {
  const bool swap = Q[0] < P[0] || (Q[0] == P[0] && Q[1] < P[1]);
  const auto& p0 = swap ? Q : P;
  const auto& p1 = swap ? P : Q;
  const double e = (static_cast<double>(p1[0]) - p0[0]) * (y - p0[1]) - (static_cast<double>(p1[1]) - p0[1]) * (x - p0[0]);
  return swap ? -e : e;
}
// Inside a counter-clockwise edge: left of it, or on it when the edge points up (or left).
bool insideEdge(double e, const std::array<float, 3>& P, const std::array<float, 3>& Q) {
  if (e != 0.0) return e > 0.0;
  const double ex = static_cast<double>(Q[0]) - P[0], ey = static_cast<double>(Q[1]) - P[1];
  return ey > 0.0 || (ey == 0.0 && ex < 0.0);
}
}  // namespace

namespace {

// The mesh's bounds (the world box's floor and top), the site spacing and the sky bucket side in
// sites: what the sites and the flakes are placed by.
struct PlacementFrame {
  std::array<float, 3> lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
  double s = 0;  // site spacing (level 0)
  int k = 1;     // sky bucket side in sites
};

PlacementFrame placementFrame(const TriangleMesh& mesh, const FallenSnowSettings& st) {
  if (!(st.siteSpacingM > 0.0) || st.skyCellSites < 1 || st.flakesPerSite < 1 || !(st.swirlHeightM > 0.0) ||
      !(st.flutterMeanM >= 0.0) || !(st.flutterSigmaM >= 0.0) || !(st.depthM >= 0.0) || !(st.skyClearanceM >= 0.0))
    throw InputError(mesh.source + ": snow on meshes: site spacing, sky cell, flakes and swirl height must be positive, flutter and depth at least 0");
  PlacementFrame frame;
  for (const auto& p : mesh.positions)
    for (int k = 0; k < 3; ++k) frame.lo[k] = std::min(frame.lo[k], p[k]), frame.hi[k] = std::max(frame.hi[k], p[k]);
  if (mesh.triangles.empty() || !(frame.hi[0] > frame.lo[0]) || !(frame.hi[1] > frame.lo[1]))
    throw InputError(mesh.source + ": snow on meshes: the mesh has no extent in x and y");
  frame.s = st.siteSpacingM;
  frame.k = st.skyCellSites;
  return frame;
}

// The sites of triangle t (index t of `mesh`) at `level` on the lattice of `out`: the lattice
// points over it when it faces up, those of the cells `refined` marks (one byte a cell) left out
// at level 0 and the only ones kept at level 1.
void addTriangleSites(const TriangleMesh& mesh, uint32_t t, const PlacementFrame& fr, const FallenSnow& out, int level,
                      const std::vector<uint8_t>* refined, std::vector<SnowSite>& sites) {
  const auto& lo = fr.lo;
  const auto& hi = fr.hi;
  const double sl = fr.s / (1 << level);
  const int cols = out.columns << level, rows = out.rows << level;
  const auto& a = mesh.positions[mesh.triangles[t][0]];
  const auto& b = mesh.positions[mesh.triangles[t][1]];
  const auto& c = mesh.positions[mesh.triangles[t][2]];
  const double ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2], vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2];
  const double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
  const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
  if (!(len > 0.0) || nz / len <= 1e-6) return;  // downward, vertical or degenerate: no snow
  const int i0 = std::max(0, static_cast<int>(std::ceil((std::min({a[0], b[0], c[0]}) - lo[0]) / sl - 0.5)));
  const int i1 = std::min(cols - 1, static_cast<int>(std::floor((std::max({a[0], b[0], c[0]}) - lo[0]) / sl - 0.5)));
  const int j0 = std::max(0, static_cast<int>(std::ceil((hi[1] - std::max({a[1], b[1], c[1]})) / sl - 0.5)));
  const int j1 = std::min(rows - 1, static_cast<int>(std::floor((hi[1] - std::min({a[1], b[1], c[1]})) / sl - 0.5)));
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      const bool split = refined && (*refined)[static_cast<size_t>(j >> level) * out.columns + (i >> level)];
      if (level == 0 ? split : !split) continue;
      const double px = lo[0] + (i + 0.5) * sl, py = hi[1] - (j + 0.5) * sl;
      // In the xy projection (counter-clockwise: the face looks up).
      const double eab = edgeFunction(a, b, px, py), ebc = edgeFunction(b, c, px, py), eca = edgeFunction(c, a, px, py);
      if (!insideEdge(eab, a, b) || !insideEdge(ebc, b, c) || !insideEdge(eca, c, a)) continue;
      const double z = (ebc * a[2] + eca * b[2] + eab * c[2]) / (eab + ebc + eca);
      SnowSite site;
      site.position = {static_cast<float>(px), static_cast<float>(py), static_cast<float>(z)};
      site.face = t;
      site.level = level;
      site.column = i;
      site.row = j;
      site.footprintM2 = static_cast<float>(sl * sl);
      sites.push_back(site);
    }
}

// Sites: lattice points over every upward-facing triangle, in triangle order.
std::vector<SnowSite> makeSites(const TriangleMesh& mesh, const PlacementFrame& fr, const FallenSnow& out, int level,
                                const std::vector<uint8_t>* refined) {
  std::vector<SnowSite> sites;
  for (uint32_t t = 0; t < mesh.triangles.size(); ++t) addTriangleSites(mesh, t, fr, out, level, refined, sites);
  return sites;
}

// The flakes' random walks up to the sky.
struct FlakeTracer {
  const RayScene& rays;
  const FallenSnowSettings& st;
  const PlacementFrame& fr;
  const FallenSnow& out;
  double skyZ;  // the sky plane

  // Flake f of site si (in trace pass `pass`): the bucket it reached, -1 blocked, -2 left the world.
  int traceFlake(const SnowSite& site, size_t si, int f, uint64_t pass) const {
    const RandomKey key{st.seed};
    std::array<float, 3> p{site.position[0], site.position[1], lifted(site.position[2])};
    for (uint32_t step = 0;; ++step) {
      double r = 0.0, phi = 0.0;
      if (st.flutterMeanM > 0.0 || st.flutterSigmaM > 0.0) {
        const Philox4x32 d = key.draw(pass << 40 | si, static_cast<uint32_t>(f) << 20 | (step & 0xFFFFF), RngStream::FallenSnowFlake);
        const double u1 = uniformOpenDouble(d.v[0], d.v[1]), u2 = uniformFloat(d.v[2]), u3 = uniformFloat(d.v[3]);
        const double normal = std::clamp(std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * kPi * u2), -3.0, 3.0);
        r = std::max(0.0, st.flutterMeanM + st.flutterSigmaM * normal);
        phi = 2.0 * kPi * u3;
      }
      const std::array<float, 3> q{static_cast<float>(p[0] + r * std::cos(phi)), static_cast<float>(p[1] + r * std::sin(phi)),
                                   static_cast<float>(p[2] + st.swirlHeightM)};
      const float dx = q[0] - p[0], dy = q[1] - p[1], dz = q[2] - p[2];
      const float length = std::sqrt(dx * dx + dy * dy + dz * dz);
      if (rays.occluded(p, {dx / length, dy / length, dz / length}, length)) return -1;  // blocked
      if (q[2] >= skyZ) {
        const int bi = static_cast<int>(std::floor((q[0] - fr.lo[0]) / (fr.k * fr.s)));
        const int bj = static_cast<int>(std::floor((fr.hi[1] - q[1]) / (fr.k * fr.s)));
        return bi >= 0 && bj >= 0 && bi < out.bucketColumns && bj < out.bucketRows ? bj * out.bucketColumns + bi : -2;
      }
      p = q;
    }
  }

  // Every flake, site by site in parallel (each site's draws depend on its index only).
  std::vector<int> trace(const std::vector<SnowSite>& sites, uint64_t pass) const {
    const int flakes = st.flakesPerSite;
    std::vector<int> bucketOf(sites.size() * static_cast<size_t>(flakes), -1);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, sites.size(), 64), [&](const tbb::blocked_range<size_t>& range) {
      for (size_t si = range.begin(); si < range.end(); ++si)
        for (int f = 0; f < flakes; ++f) bucketOf[si * flakes + static_cast<size_t>(f)] = traceFlake(sites[si], si, f, pass);
    });
    return bucketOf;
  }
};

// Adaptive sampling: coverage per site; a cell is split when one of its sites differs from the
// nearest-in-height site of a 4-neighbour cell by more than maxCoverageDiff (both cells are split).
std::vector<uint8_t> cellsToRefine(const FallenSnow& out, const std::vector<int>& bucketOf, const FallenSnowSettings& st) {
  const int flakes = st.flakesPerSite;
  std::vector<std::vector<size_t>> inCell(static_cast<size_t>(out.columns) * out.rows);
  std::vector<double> coverage(out.sites.size());
  for (size_t si = 0; si < out.sites.size(); ++si) {
    int reached = 0;
    for (int f = 0; f < flakes; ++f) reached += bucketOf[si * flakes + static_cast<size_t>(f)] >= 0;
    coverage[si] = static_cast<double>(reached) / flakes;
    inCell[static_cast<size_t>(out.sites[si].row) * out.columns + out.sites[si].column].push_back(si);
  }
  std::vector<uint8_t> refined(inCell.size(), 0);
  for (size_t si = 0; si < out.sites.size(); ++si) {
    const SnowSite& a = out.sites[si];
    const int di[4] = {1, -1, 0, 0}, dj[4] = {0, 0, 1, -1};
    for (int n = 0; n < 4; ++n) {
      const int ni = a.column + di[n], nj = a.row + dj[n];
      if (ni < 0 || nj < 0 || ni >= out.columns || nj >= out.rows) continue;
      const auto& others = inCell[static_cast<size_t>(nj) * out.columns + ni];
      long long nearest = -1;
      for (size_t o : others)
        if (nearest < 0 || std::abs(out.sites[o].position[2] - a.position[2]) < std::abs(out.sites[static_cast<size_t>(nearest)].position[2] - a.position[2]))
          nearest = static_cast<long long>(o);
      if (nearest >= 0 && std::abs(coverage[si] - coverage[static_cast<size_t>(nearest)]) > st.maxCoverageDiff)
        refined[static_cast<size_t>(a.row) * out.columns + a.column] = refined[static_cast<size_t>(nj) * out.columns + ni] = 1;
    }
  }
  return refined;
}

// Each bucket's snow shared among the flakes that reached it, by weight (in site order). A
// flake's weight: its site's footprint over the flakes a site (in site order, so the sums are the
// same on any thread count).
void shareBucketSnow(FallenSnow& out, const std::vector<int>& bucketOf, const FallenSnowSettings& st, const PlacementFrame& fr) {
  const int flakes = st.flakesPerSite, k = fr.k;
  const double s = fr.s;
  const size_t buckets = static_cast<size_t>(out.bucketColumns) * out.bucketRows;
  auto weightOf = [&](size_t si) { return static_cast<double>(out.sites[si].footprintM2) / flakes; };
  std::vector<double> bucketWeight(buckets, 0.0);
  for (size_t si = 0; si < out.sites.size(); ++si)
    for (int f = 0; f < flakes; ++f)
      if (const int b = bucketOf[si * flakes + static_cast<size_t>(f)]; b >= 0) bucketWeight[static_cast<size_t>(b)] += weightOf(si);
  auto bucketMass = [&](size_t b) {
    const int bi = static_cast<int>(b % out.bucketColumns), bj = static_cast<int>(b / out.bucketColumns);
    const int cols = std::min(k, out.columns - bi * k), rows = std::min(k, out.rows - bj * k);
    return st.depthM * cols * rows * s * s * (st.skyMask.empty() ? 1.0 : st.skyMask[b]);
  };
  for (size_t b = 0; b < buckets; ++b) {
    if (bucketWeight[b] > 0.0) out.skyMassM3 += bucketMass(b);
    else ++out.emptyBuckets;
  }
  for (size_t si = 0; si < out.sites.size(); ++si) {
    double volume = 0.0;
    for (int f = 0; f < flakes; ++f) {
      const int b = bucketOf[si * flakes + static_cast<size_t>(f)];
      ++out.flakes;
      if (b == -1) ++out.blocked;
      if (b == -2) ++out.leftTheWorld;
      if (b < 0) continue;
      volume += bucketMass(static_cast<size_t>(b)) * weightOf(si) / bucketWeight[static_cast<size_t>(b)];
      ++out.sites[si].flakesReached;
    }
    out.sites[si].depthM = static_cast<float>(volume / out.sites[si].footprintM2);
    out.placedM3 += volume;
  }
}

}  // namespace

FallenSnow placeFallenSnow(const TriangleMesh& mesh, const FallenSnowSettings& st) {
  const auto t0 = WallClock::now();
  const PlacementFrame fr = placementFrame(mesh, st);
  FallenSnow out;
  out.columns = static_cast<int>(std::ceil((fr.hi[0] - fr.lo[0]) / fr.s - 1e-9));
  out.rows = static_cast<int>(std::ceil((fr.hi[1] - fr.lo[1]) / fr.s - 1e-9));
  out.originX = fr.lo[0];
  out.originY = fr.hi[1];
  out.bucketColumns = (out.columns + fr.k - 1) / fr.k;
  out.bucketRows = (out.rows + fr.k - 1) / fr.k;
  const size_t buckets = static_cast<size_t>(out.bucketColumns) * out.bucketRows;
  if (!st.skyMask.empty() && st.skyMask.size() != buckets)
    throw InputError(mesh.source + ": snow on meshes: the sky mask has " + std::to_string(st.skyMask.size()) + " values for " +
                     std::to_string(buckets) + " sky buckets");
  const Grid<float> noTerrain;  // the scene keeps a reference
  const RayScene rays(noTerrain, GridSpec{}, {mesh});
  const FlakeTracer tracer{rays, st, fr, out, fr.hi[2] + std::max(1e-3, st.skyClearanceM)};
  out.sites = makeSites(mesh, fr, out, 0, nullptr);
  std::vector<int> bucketOf = tracer.trace(out.sites, 0);
  if (st.maxCoverageDiff < 1.0) {
    const std::vector<uint8_t> refined = cellsToRefine(out, bucketOf, st);
    for (uint8_t r : refined) out.refinedCells += r;
    if (out.refinedCells > 0) {  // the refined cells' quarter sites, and every flake traced again
      std::vector<SnowSite> sites = makeSites(mesh, fr, out, 0, &refined), quarter = makeSites(mesh, fr, out, 1, &refined);
      sites.insert(sites.end(), quarter.begin(), quarter.end());
      out.sites = std::move(sites);
      bucketOf = tracer.trace(out.sites, 1);
    }
  }
  shareBucketSnow(out, bucketOf, st, fr);
  out.siteSpacingM = fr.s;
  out.seconds = elapsedSeconds(t0);
  return out;
}

}  // namespace snow
