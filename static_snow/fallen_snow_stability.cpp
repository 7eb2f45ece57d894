// Fearing's stability phase (fallen_snow.h): the placed snow relaxed to its angle of repose over
// the sites' neighbour graph, with drops over edges landing further down or leaving the world.
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

void checkStabilitySettings(const TriangleMesh& mesh, const FallenSnow& snow, const FallenSnowStability& st) {
  if (!(st.reposeAngleDeg >= 0.0 && st.reposeAngleDeg < 90.0) || !(st.transitionWidthDeg >= 0.0) || st.depositRounds < 1 ||
      !(st.stopFraction > 0.0) || st.maxPassesPerRound < 1 || !(st.connectAngleDeg > 0.0 && st.connectAngleDeg < 90.0) ||
      !(st.landingSpreadSpacings > 0.0))
    throw InputError(mesh.source + ": snow on meshes: repose angle in [0, 90), transition width >= 0, rounds and passes >= 1, "
                     "stop fraction and landing spread > 0, connect angle in (0, 90) degrees");
  if (!(snow.siteSpacingM > 0.0)) throw InputError(mesh.source + ": snow on meshes: stability needs placed snow (placeFallenSnow)");
}

// The sites by level-0 lattice cell (a refined cell holds its quarters), for the sites near a point.
class SiteLattice {
 public:
  explicit SiteLattice(const FallenSnow& snow)
      : sites(snow.sites), spacingM(snow.siteSpacingM), snow_(snow), inCell_(static_cast<size_t>(snow.columns) * snow.rows) {
    for (size_t i = 0; i < sites.size(); ++i)
      inCell_[static_cast<size_t>(sites[i].row >> sites[i].level) * snow.columns + (sites[i].column >> sites[i].level)].push_back(
          static_cast<uint32_t>(i));
  }
  double spacing(size_t i) const { return spacingM / (1 << sites[i].level); }
  double xyDistance(size_t a, size_t b) const {
    const double dx = static_cast<double>(sites[a].position[0]) - sites[b].position[0];
    const double dy = static_cast<double>(sites[a].position[1]) - sites[b].position[1];
    return std::sqrt(dx * dx + dy * dy);
  }
  // visit(site) for every site within reachCells lattice cells of (x, y)'s cell.
  template <class Visit>
  void forSitesNear(double x, double y, int reachCells, const Visit& visit) const {
    const double s = spacingM;
    const int ci = static_cast<int>(std::floor((x - snow_.originX) / s)), cj = static_cast<int>(std::floor((snow_.originY - y) / s));
    for (int j = std::max(0, cj - reachCells); j <= std::min(snow_.rows - 1, cj + reachCells); ++j)
      for (int i = std::max(0, ci - reachCells); i <= std::min(snow_.columns - 1, ci + reachCells); ++i)
        for (uint32_t o : inCell_[static_cast<size_t>(j) * snow_.columns + i]) visit(o);
  }

  const std::vector<SnowSite>& sites;
  const double spacingM;  // level 0's

 private:
  const FallenSnow& snow_;
  std::vector<std::vector<uint32_t>> inCell_;
};

// Buried sites: the first face above is hit from behind (an upward-facing face: the site is
// inside a closed solid, e.g. the ground under a block). They take no part (no links, no landings).
std::vector<uint8_t> findBuriedSites(const TriangleMesh& mesh, const RayScene& rays, const std::vector<SnowSite>& sites) {
  std::vector<uint8_t> buried(sites.size(), 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, sites.size(), 256), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t a = range.begin(); a < range.end(); ++a) {
      const auto& P = sites[a].position;
      float t = 0.f;
      int meshIndex = -1;
      unsigned tri = 0;
      if (!rays.intersectPrimitive({P[0], P[1], lifted(P[2])}, {0.f, 0.f, 1.f}, INFINITY, t, meshIndex, tri) || meshIndex != 0) continue;
      const auto& T = mesh.triangles[tri];
      const auto &A = mesh.positions[T[0]], &B = mesh.positions[T[1]], &C = mesh.positions[T[2]];
      const double nz = (static_cast<double>(B[0]) - A[0]) * (static_cast<double>(C[1]) - A[1]) -
                        (static_cast<double>(B[1]) - A[1]) * (static_cast<double>(C[0]) - A[0]);
      buried[a] = nz > 0.0;
    }
  });
  return buried;
}

// The sites' neighbours in CSR form (each site's sorted by index), with each link's reverse slot.
struct NeighbourGraph {
  std::vector<uint32_t> first, nbr, reverse;
  std::vector<double> dist;  // xy distance of each link
};

// Two sites are linked when their bases are within the connect slope and nothing stands between
// them: the segment between points lifted half their distance above the bases is clear (cast
// from the lower index, so both ends get the same answer).
bool clearBetween(const RayScene& rays, const std::vector<SnowSite>& sites, size_t a, size_t b, double d) {
  const size_t lo = std::min(a, b), hi = std::max(a, b);
  const auto& P = sites[lo].position;
  const auto& Q = sites[hi].position;
  const float lift = static_cast<float>(0.5 * d);
  const std::array<float, 3> from{P[0], P[1], P[2] + lift};
  const float ex = Q[0] - P[0], ey = Q[1] - P[1], ez = Q[2] - P[2], len = std::sqrt(ex * ex + ey * ey + ez * ez);
  return !rays.occluded(from, {ex / len, ey / len, ez / len}, len);
}

NeighbourGraph linkNeighbours(const SiteLattice& lattice, const RayScene& rays, const std::vector<uint8_t>& buried, double tanConnect) {
  const std::vector<SnowSite>& sites = lattice.sites;
  const size_t n = sites.size();
  NeighbourGraph g;
  g.first.assign(n + 1, 0);
  std::vector<std::vector<std::pair<uint32_t, double>>> lists(n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 256), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t a = range.begin(); a < range.end(); ++a)
      lattice.forSitesNear(sites[a].position[0], sites[a].position[1], 2, [&](uint32_t b) {
        if (b == a || buried[a] || buried[b]) return;
        const double d = lattice.xyDistance(a, b);
        if (!(d > 0.0) || d > 1.5 * std::max(lattice.spacing(a), lattice.spacing(b)) + 1e-9) return;
        if (std::abs(static_cast<double>(sites[a].position[2]) - sites[b].position[2]) > d * tanConnect) return;
        if (!clearBetween(rays, sites, a, b, d)) return;
        lists[a].push_back({b, d});
      });
  });
  for (size_t a = 0; a < n; ++a) {
    std::sort(lists[a].begin(), lists[a].end());
    g.first[a + 1] = g.first[a] + static_cast<uint32_t>(lists[a].size());
    for (const auto& [b, d] : lists[a]) g.nbr.push_back(b), g.dist.push_back(d);
  }
  g.reverse.resize(g.nbr.size());
  for (size_t a = 0; a < n; ++a)
    for (uint32_t k = g.first[a]; k < g.first[a + 1]; ++k) {
      const uint32_t b = g.nbr[k];
      const auto it = std::lower_bound(g.nbr.begin() + g.first[b], g.nbr.begin() + g.first[b + 1], static_cast<uint32_t>(a));
      if (it == g.nbr.begin() + g.first[b + 1] || *it != a)
        throw std::logic_error("stabilizeFallenSnow: the neighbour graph is not symmetric");
      g.reverse[k] = static_cast<uint32_t>(it - g.nbr.begin());
    }
  return g;
}

// An open direction where snow goes over an edge (stabilizeFallenSnow's comment in the header).
struct Drop {
  uint32_t site;
  double distance;  // from the site to its footprint's edge
  double edgeZ;     // z_e
  std::vector<std::pair<uint32_t, double>> landing;  // sites and their shares (empty: off the world)
};

// The drops of every site (CSR by site), and the counts the report wants.
struct OpenDirections {
  std::vector<uint32_t> dropFirst;
  std::vector<Drop> drops;
  long long walls = 0, unlanded = 0;
};

// What the open directions are found with.
struct DropFinder {
  const SiteLattice& lattice;
  const RayScene& rays;
  const NeighbourGraph& graph;
  const std::vector<uint8_t>& buried;
  double tanConnect, cosConnect, sinConnect;
  double sigma;  // of the landing splat, metres

  // Lattice direction k (of 8) of site a has a neighbour within 30 degrees.
  bool covered(size_t a, double ux, double uy) const {
    const auto& P = lattice.sites[a].position;
    for (uint32_t q = graph.first[a]; q < graph.first[a + 1]; ++q) {
      const double ex = lattice.sites[graph.nbr[q]].position[0] - P[0], ey = lattice.sites[graph.nbr[q]].position[1] - P[1];
      if (ex * ux + ey * uy >= std::cos(kPi / 6.0) * graph.dist[q] - 1e-12) return true;
    }
    return false;
  }

  // The sites near the landing point (hx, hy, hz), in sight of it and below where the snow fell
  // from (`below`), with Gaussian shares summing to 1.
  void spreadLanding(Drop& d, double hx, double hy, double hz, double below) const {
    const std::vector<SnowSite>& sites = lattice.sites;
    const double s = lattice.spacingM;
    double total = 0.0;
    lattice.forSitesNear(hx, hy, static_cast<int>(std::ceil(2.0 * sigma / s)) + 1, [&](uint32_t b) {
      const double ex = sites[b].position[0] - hx, ey = sites[b].position[1] - hy, r2 = ex * ex + ey * ey;
      if (r2 > 4.0 * sigma * sigma || buried[b]) return;
      // Below where it fell from (a site near the edge it fell over must not catch it back: snow
      // went round in that loop for ever).
      if (!(sites[b].position[2] < below)) return;
      if (std::abs(sites[b].position[2] - hz) > std::max(std::sqrt(r2), 0.5 * s) * tanConnect) return;
      if (r2 > 0.0) {  // and in sight of the landing point (not behind a wall)
        const float lift = static_cast<float>(0.5 * std::sqrt(r2));
        const std::array<float, 3> at{static_cast<float>(hx), static_cast<float>(hy), static_cast<float>(hz + lift)};
        const float fx = static_cast<float>(ex), fy = static_cast<float>(ey), fz = static_cast<float>(sites[b].position[2] - hz);
        const float len = std::sqrt(fx * fx + fy * fy + fz * fz);
        if (rays.occluded(at, {fx / len, fy / len, fz / len}, len)) return;
      }
      const double w = std::exp(-r2 / (2.0 * sigma * sigma));
      d.landing.push_back({b, w});
      total += w;
    });
    std::sort(d.landing.begin(), d.landing.end());
    for (auto& l : d.landing) l.second /= total;
  }

  // Direction (ux, uy) of uncovered site a: a wall (true in `wall`), an edge with its drop
  // (returned), or neither (the surface goes on).
  std::optional<Drop> openDirection(size_t a, double ux, double uy, bool& wall) const {
    const double h = lattice.spacing(a);
    const auto& P = lattice.sites[a].position;
    const std::array<float, 3> stabFrom{P[0], P[1], static_cast<float>(P[2] + 0.02 * h)};
    const std::array<float, 3> stabDir{static_cast<float>(ux * cosConnect), static_cast<float>(uy * cosConnect), static_cast<float>(sinConnect)};
    wall = rays.occluded(stabFrom, stabDir, static_cast<float>(0.75 * h / cosConnect));
    if (wall) return std::nullopt;
    const double reach = 0.45 * h * tanConnect;
    const std::array<float, 3> edgeFrom{static_cast<float>(P[0] + 0.45 * h * ux), static_cast<float>(P[1] + 0.45 * h * uy),
                                        static_cast<float>(P[2] + reach)};
    const float te = rays.intersect(edgeFrom, {0.f, 0.f, -1.f}, static_cast<float>(2.0 * reach));
    const double edgeZ = std::isfinite(te) ? edgeFrom[2] - te : P[2];
    // Just past the footprint, from above the edge's level: a surface near that level goes on
    // (no site on it: not an edge); the first one well below is where the snow lands.
    const double band = 0.25 * h * tanConnect;
    const std::array<float, 3> from{static_cast<float>(P[0] + 0.75 * h * ux), static_cast<float>(P[1] + 0.75 * h * uy),
                                    static_cast<float>(std::max<double>(edgeZ, P[2]) + band)};
    const float t = rays.intersect(from, {0.f, 0.f, -1.f}, INFINITY);
    if (std::isfinite(t) && from[2] - t >= std::min<double>(edgeZ, P[2]) - band) return std::nullopt;
    Drop d{static_cast<uint32_t>(a), 0.5 * h, edgeZ, {}};
    if (std::isfinite(t)) spreadLanding(d, from[0], from[1], from[2] - t, std::min<double>(edgeZ, P[2]) - band);
    return d;
  }
};

// Open directions: the lattice directions with no neighbour within 30 degrees.
//  - A wall: a stab from the base, rising at the connect angle to just past the footprint, hits
//    something (a face steeper than the connect slope): snow rests against it.
//  - Otherwise an edge, at the height z_e of the surface at the footprint's edge (the highest
//    within the connect slope; the site's own base where the surface has ended): snow whose top
//    stands above z_e by more than the repose slope goes over it, and falls straight down from
//    just past the footprint. Where it lands (a ray) it is spread over the sites near the
//    landing point (a Gaussian); where the surface simply goes on (no site there: a face with
//    none) the direction is ignored; a fall that meets nothing leaves the world.
OpenDirections findOpenDirections(const DropFinder& finder) {
  const size_t n = finder.lattice.sites.size();
  std::vector<std::vector<Drop>> dropsOf(n);
  std::vector<long long> walls(n, 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 64), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t a = range.begin(); a < range.end(); ++a) {
      if (finder.buried[a]) continue;
      for (int k = 0; k < 8; ++k) {
        const double ang = k * kPi / 4.0, ux = std::cos(ang), uy = std::sin(ang);
        if (finder.covered(a, ux, uy)) continue;
        bool wall = false;
        std::optional<Drop> d = finder.openDirection(a, ux, uy, wall);
        walls[a] += wall;
        if (d) dropsOf[a].push_back(std::move(*d));
      }
    }
  });
  OpenDirections open;
  open.dropFirst.assign(n + 1, 0);
  for (size_t a = 0; a < n; ++a) {
    open.walls += walls[a];
    for (Drop& d : dropsOf[a]) {
      open.unlanded += d.landing.empty();
      open.drops.push_back(std::move(d));
    }
    open.dropFirst[a + 1] = static_cast<uint32_t>(open.drops.size());
  }
  return open;
}

// The deposit rounds, each relaxed by Jacobi passes over the graph and the drops (in double).
class Relaxation {
 public:
  Relaxation(const std::vector<SnowSite>& sites, const NeighbourGraph& g, const OpenDirections& open,
             const FallenSnowStability& st, FallenSnowStabilityReport& rep)
      : g_(g), open_(open), st_(st), rep_(rep), n_(sites.size()), area_(n_), base_(n_), placed_(n_), volume_(n_, 0.0),
        next_(n_), moved_(n_), out_(g.nbr.size()), dropOut_(open.drops.size()), allowedRise_(g.nbr.size() + open.drops.size()) {
    for (size_t i = 0; i < n_; ++i) {
      area_[i] = sites[i].footprintM2;
      base_[i] = sites[i].position[2];
      placed_[i] = static_cast<double>(sites[i].depthM) * area_[i];
      rep_.placedM3 += placed_[i];
      totalArea_ += area_[i];
    }
  }

  void run() {
    for (int round = 0; round < st_.depositRounds; ++round) {
      for (size_t i = 0; i < n_; ++i) volume_[i] += placed_[i] / st_.depositRounds;
      drawAllowedRise(round);
      if (!relaxRound()) ++rep_.unconvergedRounds;
    }
  }

  // The sites' snow volumes (m^3).
  const std::vector<double>& volume() const { return volume_; }
  const std::vector<double>& area() const { return area_; }

 private:
  double top(size_t i) const { return base_[i] + volume_[i] / area_[i]; }

  // Per link (neighbours, then drops) the rise its snow tops may keep: distance x tan(theta*),
  // theta* drawn once per pair and round: a random threshold field the round settles into (a
  // draw per pass kept moving snow at slopes inside the curve, pass after pass).
  void drawAllowedRise(int round) {
    const double loDeg = std::max(0.0, st_.reposeAngleDeg - 0.5 * st_.transitionWidthDeg);
    const double hiDeg = std::min(89.9, st_.reposeAngleDeg + 0.5 * st_.transitionWidthDeg);
    const RandomKey key{st_.seed};
    const size_t links = g_.nbr.size();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, allowedRise_.size(), 1024), [&](const tbb::blocked_range<size_t>& range) {
      for (size_t slot = range.begin(); slot < range.end(); ++slot) {
        double tanTheta = std::tan(loDeg * kPi / 180.0);
        if (hiDeg > loDeg) {
          const Philox4x32 r = key.draw(static_cast<uint64_t>(round), static_cast<uint32_t>(slot), RngStream::FallenSnowStability);
          tanTheta = std::tan((loDeg + (hiDeg - loDeg) * uniformOpenDouble(r.v[0], r.v[1])) * kPi / 180.0);
        }
        allowedRise_[slot] = (slot < links ? g_.dist[slot] : open_.drops[slot - links].distance) * tanTheta;
      }
    });
  }

  // Passes until no site sheds more than the stop height (true), or maxPassesPerRound (false).
  bool relaxRound() {
    const double stop = st_.stopFraction * rep_.placedM3 / st_.depositRounds / std::max(totalArea_, 1e-300);
    ++rep_.rounds;
    for (int pass = 0; pass < st_.maxPassesPerRound; ++pass) {
      tbb::parallel_for(tbb::blocked_range<size_t>(0, n_, 256), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t a = range.begin(); a < range.end(); ++a) outflows(a);
      });
      const double most = gatherAndLand();
      volume_.swap(next_);
      ++rep_.passes;
      rep_.lastMovedM = most;
      if (most < stop || most == 0.0) return true;
    }
    return false;
  }

  // Site a's outflows from this pass's snow tops. Each unstable pair's share: the volume that
  // brings it to theta*, over the number of receivers + 1 (the receivers may take snow from
  // other sites in the same pass); all scaled to the snow there.
  void outflows(size_t a) {
    const double v = volume_[a];
    const uint32_t k0 = g_.first[a], k1 = g_.first[a + 1], d0 = open_.dropFirst[a], d1 = open_.dropFirst[a + 1];
    for (uint32_t k = k0; k < k1; ++k) out_[k] = 0.0;
    for (uint32_t d = d0; d < d1; ++d) dropOut_[d] = 0.0;
    if (!(v > 0.0)) return;
    const double topA = base_[a] + v / area_[a];
    int receivers = 0;
    for (uint32_t k = k0; k < k1; ++k) {
      const uint32_t b = g_.nbr[k];
      const double drop = topA - top(b);
      if (!(drop > 0.0)) continue;
      const double excess = drop - allowedRise_[k];
      if (!(excess > 0.0)) continue;
      out_[k] = excess / (1.0 / area_[a] + 1.0 / area_[b]);
      ++receivers;
    }
    for (uint32_t d = d0; d < d1; ++d) {
      // Over the edge, or onto the snow where it lands when that stands higher (an edge buried
      // in the snow below is no edge: snow went round that loop for ever).
      double floor = open_.drops[d].edgeZ;
      if (!open_.drops[d].landing.empty()) {
        double landingTop = 0.0;
        for (const auto& [b, w] : open_.drops[d].landing) landingTop += w * top(b);
        floor = std::max(floor, landingTop);
      }
      const double excess = topA - floor - allowedRise_[g_.nbr.size() + d];
      if (!(excess > 0.0)) continue;
      dropOut_[d] = excess * area_[a];
      ++receivers;
    }
    if (receivers == 0) return;
    const double shares = receivers + 1.0;
    double total = 0.0;
    for (uint32_t k = k0; k < k1; ++k) total += (out_[k] /= shares);
    for (uint32_t d = d0; d < d1; ++d) total += (dropOut_[d] /= shares);
    if (total > v) {
      const double scale = v / total;
      for (uint32_t k = k0; k < k1; ++k) out_[k] *= scale;
      for (uint32_t d = d0; d < d1; ++d) dropOut_[d] *= scale;
    }
  }

  // Gather (each site: what it keeps plus what its neighbours sent it), then the landings.
  // Returns the largest height that left a site this pass (a steady stream down a face counts).
  double gatherAndLand() {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n_, 256), [&](const tbb::blocked_range<size_t>& range) {
      for (size_t a = range.begin(); a < range.end(); ++a) {
        double gave = 0.0, got = 0.0;
        for (uint32_t k = g_.first[a]; k < g_.first[a + 1]; ++k) gave += out_[k], got += out_[g_.reverse[k]];
        for (uint32_t d = open_.dropFirst[a]; d < open_.dropFirst[a + 1]; ++d) gave += dropOut_[d];
        next_[a] = std::max(0.0, volume_[a] - gave) + got;
        moved_[a] = gave / area_[a];
      }
    });
    for (size_t d = 0; d < open_.drops.size(); ++d) {
      if (!(dropOut_[d] > 0.0)) continue;
      rep_.overEdgesM3 += dropOut_[d];
      if (open_.drops[d].landing.empty()) rep_.leftTheWorldM3 += dropOut_[d];
      for (const auto& [b, w] : open_.drops[d].landing) next_[b] += dropOut_[d] * w;
    }
    double most = 0.0;
    for (size_t i = 0; i < n_; ++i) most = std::max(most, moved_[i]);
    return most;
  }

  const NeighbourGraph& g_;
  const OpenDirections& open_;
  const FallenSnowStability& st_;
  FallenSnowStabilityReport& rep_;
  const size_t n_;
  std::vector<double> area_, base_, placed_, volume_, next_, moved_, out_, dropOut_, allowedRise_;
  double totalArea_ = 0.0;
};

}  // namespace

FallenSnowStabilityReport stabilizeFallenSnow(const TriangleMesh& mesh, FallenSnow& snow, const FallenSnowStability& st) {
  const auto t0 = WallClock::now();
  checkStabilitySettings(mesh, snow, st);
  FallenSnowStabilityReport rep;
  const SiteLattice lattice(snow);
  const double tanConnect = std::tan(st.connectAngleDeg * kPi / 180.0);
  const Grid<float> noTerrain;  // the scene keeps a reference
  const RayScene rays(noTerrain, GridSpec{}, {mesh});
  const std::vector<uint8_t> buried = findBuriedSites(mesh, rays, snow.sites);
  for (uint8_t b : buried) rep.buriedSites += b;
  const NeighbourGraph graph = linkNeighbours(lattice, rays, buried, tanConnect);
  rep.neighbourLinks = static_cast<long long>(graph.nbr.size());
  const DropFinder finder{lattice, rays, graph, buried, tanConnect, std::cos(st.connectAngleDeg * kPi / 180.0),
                          std::sin(st.connectAngleDeg * kPi / 180.0), st.landingSpreadSpacings * snow.siteSpacingM};
  const OpenDirections open = findOpenDirections(finder);
  rep.wallDirections = open.walls;
  rep.unlandedDrops = open.unlanded;
  rep.dropDirections = static_cast<long long>(open.drops.size());
  Relaxation relaxation(snow.sites, graph, open, st, rep);
  relaxation.run();
  for (size_t i = 0; i < snow.sites.size(); ++i) {
    snow.sites[i].depthM = static_cast<float>(relaxation.volume()[i] / relaxation.area()[i]);
    rep.finalM3 += relaxation.volume()[i];
  }
  rep.seconds = elapsedSeconds(t0);
  return rep;
}

}  // namespace snow
