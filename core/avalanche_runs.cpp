#include "avalanche_runs.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <utility>

#include "simd_lanes.h"
#include "util.h"

namespace snow {

namespace {

GridCrop crop(const Grid<float>& g, int x0, int y0, int x1, int y1) {
  GridCrop c;
  c.x0 = x0;
  c.y0 = y0;
  c.grid = Grid<float>(std::max(0, x1 - x0), std::max(0, y1 - y0), 0.f);
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) c.grid(x - x0, y - y0) = g(x, y);
  return c;
}

// A = B + C + S + U + P of cell i (of the box's cell j), summed in double.
double surfaceAt(const Grid<float>& bedrock, size_t i, const SnowBox& b, size_t j) {
  return static_cast<double>(bedrock.values()[i]) + b.compacted.values()[j] + b.stable.values()[j] + b.unstable.values()[j] +
         b.powder.values()[j];
}
}  // namespace

AvalancheRun::~AvalancheRun() {
  if (active_) backend_.beforeNextWrite(nullptr);  // its hook calls back into this runner
}

AvalancheRun::AvalancheRun(SnowBackend& backend, const ModelParameters& params, const SnowState& terrain)
    : backend_(backend), p_(params), terrain_(terrain) {
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx)
      neighbourDistanceM_[3 * (dy + 1) + (dx + 1)] = std::hypot(dx * terrain.spec.cellSizeXM, dy * terrain.spec.cellSizeYM);
}

double AvalancheRun::layersSurface(size_t i) const {
  return static_cast<double>(terrain_.bedrockM.values()[i]) + layers_[0][i] + layers_[1][i] + layers_[2][i] + layers_[3][i];
}

void AvalancheRun::takeSnapshot() {
  if (!backend_.hostSnowLayers(layers_)) {
    snapshot_.x0 = snapshot_.y0 = 0;
    snapshot_.width = terrain_.spec.width, snapshot_.height = terrain_.spec.height;
    backend_.downloadBox(snapshot_, false);
    const Grid<float>* g[4] = {&snapshot_.compacted, &snapshot_.stable, &snapshot_.unstable, &snapshot_.powder};
    for (int l = 0; l < 4; ++l) layers_[l] = g[l]->data();
  }
  haveSnapshot_ = true;
  snapshotVersion_ = backend_.stateVersion();
  rowWeights_.assign(static_cast<size_t>(terrain_.spec.height), 0.0);
  staleY0_ = 0, staleY1_ = terrain_.spec.height;
}

// The settled box into the snapshot (where one is held), so that it holds the state again: its
// rows' weights are stale.
void AvalancheRun::keepSnapshotOfBox() {
  const int w = terrain_.spec.width;
  const bool held = layers_[0] == snapshot_.compacted.data();  // not where the layers are read in place
  for (int y = unionBox_.y0; held && y < unionBox_.y1; ++y) {
    const size_t i = static_cast<size_t>(y) * w + unionBox_.x0, j = after_.index(unionBox_.x0, y);
    const size_t n = static_cast<size_t>(unionBox_.x1 - unionBox_.x0);
    for (auto [to, from] : {std::pair{&snapshot_.compacted, &after_.compacted}, {&snapshot_.stable, &after_.stable},
                            {&snapshot_.unstable, &after_.unstable}, {&snapshot_.powder, &after_.powder}})
      std::copy_n(from->values().data() + j, n, to->values().data() + i);
  }
  if (unionBox_.y1 > unionBox_.y0) {
    staleY0_ = staleY1_ > staleY0_ ? std::min(staleY0_, unionBox_.y0) : unionBox_.y0;
    staleY1_ = std::max(staleY1_, unionBox_.y1);
  }
}

bool AvalancheRun::release(int x, int y, double day, double seaLevelTemperatureC, bool user) {
  takeSnapshot();
  return releaseFromSnapshot(x, y, day, seaLevelTemperatureC, user);
}

double AvalancheRun::steepestDrop(int x, int y) const {
  const GridSpec& g = terrain_.spec;
  const double a = layersSurface(static_cast<size_t>(y) * g.width + x);
  double slope = 0.0;
  for (int ny = std::max(0, y - 1); ny < std::min(g.height, y + 2); ++ny)
    for (int nx = std::max(0, x - 1); nx < std::min(g.width, x + 2); ++nx) {
      if ((nx == x && ny == y) || !terrain_.validCell(nx, ny)) continue;
      const double dist = neighbourDistanceM_[3 * (ny - y + 1) + (nx - x + 1)];
      slope = std::max(slope, (a - layersSurface(static_cast<size_t>(ny) * g.width + nx)) / dist);
    }
  return slope;
}

#if SNOW_LANES_AVX2
#pragma GCC push_options
#pragma GCC target("avx2")
namespace {
// releaseWeights' cells [0, width) of a row four at a time from x (its ring rows padded with +inf
// at both ends, so every cell has its neighbours): the per-cell loop's double operations in its
// order. std::min(a, b) is (b < a ? b : a), MINPD(b, a); std::max(a, b) is (a < b ? b : a),
// MAXPD(b, a). Returns where it stopped.
int releaseWeightsLanes(const double* up, const double* mid, const double* down, const float* u, const uint8_t* valid, const float* factor,
                        int width, double minUnstable, double lx, double ly, double ld, double tanRest, double share, double* out) {
  const __m256d one = _mm256_set1_pd(1.0), zero = _mm256_setzero_pd(), least = _mm256_set1_pd(minUnstable);
  const __m256d perX = _mm256_set1_pd(lx), perY = _mm256_set1_pd(ly), perD = _mm256_set1_pd(ld);
  const __m256d rest = _mm256_set1_pd(tanRest), perShare = _mm256_set1_pd(share);
  int x = 0;
  for (; x + 4 <= width; x += 4) {
    int32_t bytes;
    std::memcpy(&bytes, valid + x, 4);
    const __m256d isValid = _mm256_castsi256_pd(_mm256_xor_si256(_mm256_cmpeq_epi64(_mm256_cvtepu8_epi64(_mm_cvtsi32_si128(bytes)), _mm256_setzero_si256()),
                                                                 _mm256_set1_epi64x(-1)));
    const __m256d ux = _mm256_cvtps_pd(_mm_loadu_ps(u + x));
    const __m256d candidate = _mm256_and_pd(isValid, _mm256_cmp_pd(ux, least, _CMP_GE_OQ));
    if (_mm256_movemask_pd(candidate) == 0) {
      _mm256_storeu_pd(out + x, zero);
      continue;
    }
    const __m256d a = _mm256_loadu_pd(mid + x + 1);
    const __m256d nx = _mm256_min_pd(_mm256_loadu_pd(mid + x + 2), _mm256_loadu_pd(mid + x));
    const __m256d ny = _mm256_min_pd(_mm256_loadu_pd(down + x + 1), _mm256_loadu_pd(up + x + 1));
    const __m256d nd = _mm256_min_pd(_mm256_min_pd(_mm256_loadu_pd(down + x + 2), _mm256_loadu_pd(down + x)),
                                     _mm256_min_pd(_mm256_loadu_pd(up + x + 2), _mm256_loadu_pd(up + x)));
    const __m256d first = _mm256_max_pd(_mm256_div_pd(_mm256_sub_pd(a, nx), perX), zero);
    const __m256d second = _mm256_max_pd(_mm256_div_pd(_mm256_sub_pd(a, nd), perD), _mm256_div_pd(_mm256_sub_pd(a, ny), perY));
    const __m256d excess = _mm256_sub_pd(_mm256_max_pd(second, first), rest);
    const __m256d f = factor ? _mm256_cvtps_pd(_mm_loadu_ps(factor + x)) : one;
    const __m256d weight = _mm256_min_pd(_mm256_div_pd(_mm256_mul_pd(_mm256_mul_pd(f, ux), excess), perShare), one);
    _mm256_storeu_pd(out + x, _mm256_and_pd(_mm256_and_pd(candidate, _mm256_cmp_pd(excess, zero, _CMP_GT_OQ)), weight));
  }
  return x;
}
}  // namespace
#pragma GCC pop_options
#endif

// The release weights of rows [y0, y1) into w, row after row: min(1, f U (s - tan theta_c) /
// (1 - tan theta_c)) where the cell is valid with U >= avalanche_min_unstable_m and s > tan theta_c,
// else 0. s is steepestDrop's value: the largest of (A - A_n) / L_n is, for each of the three
// lengths L, (A - min A_n) / L (subtraction and division are monotonic), so a ring of three
// surface rows (+inf where not valid or outside) gives it with three divisions.
void AvalancheRun::releaseWeights(int y0, int y1, double* w) const {
  const GridSpec& g = terrain_.spec;
  const int width = g.width;
  const double inf = std::numeric_limits<double>::infinity();
  const double tanRest = std::tan(p_.avalancheRestAngleDeg * kPi / 180.0);
  const double share = std::max(1e-6, 1.0 - tanRest);  // the weight's denominator
  const bool factors = terrain_.avalancheReleaseFactor.size() == g.cellCount();
  const double lx = neighbourDistanceM_[5], ly = neighbourDistanceM_[7], ld = neighbourDistanceM_[8];
  const uint8_t* valid = terrain_.validCell.values().data();
  const float* u = layers_[2];
  const float* factor = factors ? terrain_.avalancheReleaseFactor.values().data() : nullptr;
  std::vector<double> ring(3 * static_cast<size_t>(width + 2), inf);
  auto rowOf = [&](int y) { return &ring[static_cast<size_t>((y + 3) % 3) * (width + 2)]; };
  auto fill = [&](int y) {
    double* r = rowOf(y) + 1;
    if (y < 0 || y >= g.height) return std::fill(r, r + width, inf);
    const size_t i0 = static_cast<size_t>(y) * width;
    const float *b = terrain_.bedrockM.values().data() + i0, *c = layers_[0] + i0;
    const float *st = layers_[1] + i0, *un = u + i0, *p = layers_[3] + i0;
    for (int x = 0; x < width; ++x) r[x] = static_cast<double>(b[x]) + c[x] + st[x] + un[x] + p[x];  // layersSurface's sum
    for (int x = 0; x < width; ++x)
      if (!valid[i0 + x]) r[x] = inf;
  };
  fill(y0 - 1), fill(y0);
  for (int y = y0; y < y1; ++y) {
    fill(y + 1);
    const double *up = rowOf(y - 1), *mid = rowOf(y), *down = rowOf(y + 1);
    double* out = w + static_cast<size_t>(y - y0) * width;
    const size_t i0 = static_cast<size_t>(y) * width;
    int x = 0;
#if SNOW_LANES_AVX2
    if (cpuHasAvx2() && lanesAvx2Allowed().load(std::memory_order_relaxed))
      x = releaseWeightsLanes(up, mid, down, u + i0, valid + i0, factor ? factor + i0 : nullptr, width, p_.avalancheMinUnstableM, lx, ly, ld,
                              tanRest, share, out);
#endif
    for (; x < width; ++x) {
      out[x] = 0.0;
      const double ux = u[i0 + x];
      if (!valid[i0 + x] || !(ux >= p_.avalancheMinUnstableM)) continue;
      const double a = mid[x + 1];
      const double nx = std::min(mid[x], mid[x + 2]), ny = std::min(up[x + 1], down[x + 1]);
      const double nd = std::min(std::min(up[x], up[x + 2]), std::min(down[x], down[x + 2]));
      const double excess = std::max(std::max(0.0, (a - nx) / lx), std::max((a - ny) / ly, (a - nd) / ld)) - tanRest;
      const double f = factor ? factor[i0 + x] : 1.0;
      if (excess > 0.0) out[x] = std::min(1.0, f * ux * excess / share);
    }
  }
}

// The release weights' row sums of rows [r0, r1), band by band on the backend's host threads,
// each row summed in order: the same doubles on any thread count. A band's weights (512 KiB)
// stay in cache for its sums.
void AvalancheRun::weighRows(int r0, int r1) {
  const int width = terrain_.spec.width;
  constexpr int kRowsPerChunk = 4;
  const int bandRows = kRowsPerChunk * std::max(1, (1 << 16) / std::max(1, kRowsPerChunk * width));
  weights_.resize(static_cast<size_t>(std::min(bandRows, terrain_.spec.height)) * width);
  for (int b0 = r0; b0 < r1; b0 += bandRows) {
    const int b1 = std::min(r1, b0 + bandRows);
    // Each row's sum in order beside its weights: the same doubles on any thread count.
    backend_.forEachHostChunk(b1 - b0, kRowsPerChunk, [&](int a, int b) {
      releaseWeights(b0 + a, b0 + b, &weights_[static_cast<size_t>(a) * width]);
      for (int y = b0 + a; y < b0 + b; ++y) {
        const double* w = &weights_[static_cast<size_t>(y - b0) * width];
        double sum = 0.0;
        for (int x = 0; x < width; ++x)
          if (w[x] != 0.0) sum += w[x];
        rowWeights_[static_cast<size_t>(y)] = sum;
      }
    });
  }
}

bool AvalancheRun::trySpontaneous(double cellDraw, double day, double seaLevelTemperatureC) {
  // Only the last avalanches' rows have changed since the snapshot when no other step has run
  // (settle copied their box in); a row's weights read the rows beside it.
  if (!haveSnapshot_ || backend_.stateVersion() != snapshotVersion_) takeSnapshot();
  else ++snapshotsKept_;
  const GridSpec& g = terrain_.spec;
  const int width = g.width;
  weighRows(std::max(0, staleY0_ - 1), std::min(g.height, staleY1_ + 1));
  staleY0_ = staleY1_ = 0;
  rowStartWeights_.assign(static_cast<size_t>(g.height) + 1, 0.0);
  double total = 0.0;
  for (int y = 0; y < g.height; ++y) rowStartWeights_[static_cast<size_t>(y)] = total, total += rowWeights_[static_cast<size_t>(y)];
  rowStartWeights_[static_cast<size_t>(g.height)] = total;
  if (!(total > 0.0)) return false;
  // The row is the last whose start total is at most the target (one with weight: the target is
  // below the next start); in it, the first cell whose running sum passes what is left, or the
  // row's last weighted cell where rounding leaves the sum just short.
  const double target = cellDraw * total;
  const auto above = std::upper_bound(rowStartWeights_.begin(), rowStartWeights_.end() - 1, target);
  const int y = std::max(0, static_cast<int>(above - rowStartWeights_.begin()) - 1);
  releaseWeights(y, y + 1, weights_.data());
  const double left = target - rowStartWeights_[static_cast<size_t>(y)];
  double running = 0.0;
  int found = -1;
  for (int x = 0; x < width; ++x) {
    if (weights_[static_cast<size_t>(x)] == 0.0) continue;
    found = x;
    if ((running += weights_[static_cast<size_t>(x)]) > left) break;
  }
  if (found < 0) return false;
  return releaseFromSnapshot(found, y, day, seaLevelTemperatureC, false);
}

void AvalancheRun::beginRecord(int rx, int ry, double day, bool user) {
  record_ = AvalancheRecord{};
  record_.day = day;
  record_.ruptureX = rx;
  record_.ruptureY = ry;
  record_.user = user;
  active_ = atRest_ = false;
}

bool AvalancheRun::releaseZone(const std::vector<uint8_t>& zone, double day, double seaLevelTemperatureC, bool user) {
  const auto t0 = WallClock::now();
  takeSnapshot();
  const SnowState& s = terrain_;
  const int w = s.spec.width;
  std::vector<uint8_t>& moving = movingCells();
  CellBox box;
  int rx = -1, ry = -1;
  double highest = -std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < moving.size() && i < zone.size(); ++i) {
    if (!zone[i] || !s.validCell.values()[i] || layers_[2][i] < p_.avalancheMinUnstableM) continue;
    moving[i] = 1;
    box.add(static_cast<int>(i % w), static_cast<int>(i / w));
    const double a = layersSurface(i);
    if (a > highest) highest = a, rx = static_cast<int>(i % w), ry = static_cast<int>(i / w);
  }
  if (rx < 0) {
    size_t zoneCells = 0;
    for (uint8_t z : zone) zoneCells += z != 0;
    beginRecord(0, 0, day, user);
    record_.why = "no unstable snow inside the release mask (" + std::to_string(zoneCells) + " cells)";
    return false;
  }
  beginRecord(rx, ry, day, user);
  start(box, seaLevelTemperatureC, t0);
  return true;
}

bool AvalancheRun::releaseFromSnapshot(int rx, int ry, double day, double seaLevelTemperatureC, bool user) {
  const auto t0 = WallClock::now();
  beginRecord(rx, ry, day, user);
  const SnowState& s = terrain_;
  const int w = s.spec.width, h = s.spec.height;
  auto unstable = [&](int x, int y) { return layers_[2][static_cast<size_t>(y) * w + x]; };
  if (rx < 0 || ry < 0 || rx >= w || ry >= h || !s.validCell(rx, ry)) {
    record_.why = "rupture point outside the terrain";
    return false;
  }
  record_.ruptureSlopeDeg = std::atan(steepestDrop(rx, ry)) * 180.0 / kPi;
  const double minU = p_.avalancheMinUnstableM;
  if (unstable(rx, ry) < minU) {
    record_.why = "no unstable snow at the rupture point (U = " + std::to_string(unstable(rx, ry)) + " m)";
    return false;
  }
  // Release zone: connected unstable snow within the reach of the rupture point.
  const double reach = p_.avalancheReachMPerM * unstable(rx, ry);
  std::vector<uint8_t>& moving = movingCells();
  CellBox box;
  std::deque<int> queue;
  auto index = [w](int x, int y) { return static_cast<size_t>(y) * w + x; };
  auto holds = [&](int x, int y) {
    return x >= 0 && y >= 0 && x < w && y < h && s.validCell(x, y) && unstable(x, y) >= minU;
  };
  moving[index(rx, ry)] = 1;
  box.add(rx, ry);
  queue.push_back(ry * w + rx);
  while (!queue.empty()) {
    const int c = queue.front();
    queue.pop_front();
    const int cx = c % w, cy = c / w;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int nx = cx + dx, ny = cy + dy;
        if (!holds(nx, ny) || moving[index(nx, ny)]) continue;
        if (std::hypot((nx - rx) * s.spec.cellSizeXM, (ny - ry) * s.spec.cellSizeYM) > reach) continue;
        moving[index(nx, ny)] = 1;
        box.add(nx, ny);
        queue.push_back(ny * w + nx);
      }
  }
  start(box, seaLevelTemperatureC, t0);
  return true;
}

void AvalancheRun::releaseScratch() {
  if (active_) return;
  snapshot_ = SnowBox{};
  before_ = SnowBox{};
  after_ = SnowBox{};
  for (auto& l : layers_) l = nullptr;
  haveSnapshot_ = false;
  moving_ = std::vector<uint8_t>();  // all zeros between releases: made again at the next one
  weights_ = std::vector<double>();
}

std::vector<uint8_t>& AvalancheRun::movingCells() {
  moving_.resize(terrain_.spec.cellCount(), 0);
  return moving_;
}

void AvalancheRun::start(const CellBox& released, double seaLevelTemperatureC, WallClock::time_point t0) {
  const SnowState& s = terrain_;
  const int w = s.spec.width, h = s.spec.height;
  std::vector<uint8_t>& moving = moving_;
  auto index = [w](int x, int y) { return static_cast<size_t>(y) * w + x; };
  const int x0 = released.x0, y0 = released.y0, x1 = released.x1, y1 = released.y1;  // the released cells' bounds
  double deepest = 0.0;
  for (int y = y0; y < y1; ++y)  // row by row, as over the whole grid: the same sums
    for (int x = x0; x < x1; ++x)
      if (moving[index(x, y)]) {
        const double depth = static_cast<double>(layers_[2][index(x, y)]) + layers_[3][index(x, y)];
        ++record_.releaseCells;
        record_.releasedM3 += depth * s.spec.cellAreaM2();
        deepest = std::max(deepest, depth);
      }
  // The first step's substeps (substepsOfStep): the released snow at rest, its gravity waves.
  lastSignal_ = static_cast<float>(std::sqrt(p_.gravityMps2 * deepest) * (1.0 / s.spec.cellSizeXM + 1.0 / s.spec.cellSizeYM));
  // What the release reads of the layers, before it changes them: the released box's layers, the maps.
  before_ = SnowBox{};
  growBeforeBox(x0, y0, x1, y1);
  if (keepMaps_) {
    record_.maps = std::make_shared<AvalancheMaps>();
    Grid<float> zone(w, h, 0.f);
    for (size_t i = 0; i < moving.size(); ++i) zone.values()[i] = moving[i] ? 1.f : 0.f;
    record_.maps->release = crop(zone, x0, y0, x1, y1);
    if (frameIntervalS_ > 0.0) {
      record_.maps->depthAtRelease = Grid<float>(w, h, 0.f);
      for (size_t i = 0; i < record_.maps->depthAtRelease.size(); ++i)
        record_.maps->depthAtRelease.values()[i] = layers_[0][i] + layers_[1][i] + layers_[2][i] + layers_[3][i];
      record_.maps->frames.push_back({0.0, crop(record_.maps->depthAtRelease, x0, y0, x1, y1)});
      nextFrameS_ = frameIntervalS_;
    }
  }
  args_ = makeAvalancheArgs(p_, seaLevelTemperatureC);
  args_.x0 = x0, args_.y0 = y0, args_.x1 = x1, args_.y1 = y1;
  backend_.avalancheRelease(moving, args_);
  liveFrom_ = 2, liveSteps_ = 0;
  staticFieldsSeen_ = backend_.staticFieldsVersion();
  backend_.beforeNextWrite([this] { onOutsideWrite(); });
  unionBox_ = args_;
  record_.released = true;
  for (int y = y0; y < y1; ++y) std::fill_n(moving.begin() + static_cast<std::ptrdiff_t>(index(x0, y)), x1 - x0, uint8_t{0});
  active_ = true;
  lastSpeed_ = 0.f;
  peakEnergy_ = 0.0;
  wallSeconds_ = elapsedSeconds(t0);
}

// A fixed-time action (a user's skiers, an edit, a storm's edge) may write the state while this
// avalanche runs: first, every cell's layers at release; and the next two steps' passes keep to
// the source spans (a cell the action changed is not one a pipe touched). Again at every write.
void AvalancheRun::onOutsideWrite() {
  if (!active_) return;
  growBeforeBox(0, 0, terrain_.spec.width, terrain_.spec.height);
  liveFrom_ = record_.steps + 2;
  backend_.beforeNextWrite([this] { onOutsideWrite(); });
}

// Widens before_ to hold [x0, x1) x [y0, y1) (with a margin, so that a box growing a cell a
// substep widens it every few steps only): its cells outside the old box have not changed since
// the release (no step has reached them, and a write by anything else first widens the box to the
// grid: SnowBackend::beforeNextWrite), so layers_ holds their values at release.
void AvalancheRun::growBeforeBox(int x0, int y0, int x1, int y1) {
  const GridSpec& g = terrain_.spec;
  SnowBox& b = before_;
  const bool empty = b.width == 0 || b.height == 0;
  if (!empty && x0 >= b.x0 && y0 >= b.y0 && x1 <= b.x0 + b.width && y1 <= b.y0 + b.height) return;
  constexpr int kMargin = 8;
  const int nx0 = std::max(0, std::min(x0, empty ? x0 : b.x0) - kMargin), ny0 = std::max(0, std::min(y0, empty ? y0 : b.y0) - kMargin);
  const int nx1 = std::min(g.width, std::max(x1, empty ? x1 : b.x0 + b.width) + kMargin);
  const int ny1 = std::min(g.height, std::max(y1, empty ? y1 : b.y0 + b.height) + kMargin);
  SnowBox grown;
  grown.x0 = nx0, grown.y0 = ny0, grown.width = nx1 - nx0, grown.height = ny1 - ny0;
  Grid<float>* to[4] = {&grown.compacted, &grown.stable, &grown.unstable, &grown.powder};
  const Grid<float>* from[4] = {&b.compacted, &b.stable, &b.unstable, &b.powder};
  for (int l = 0; l < 4; ++l) {
    to[l]->resize(grown.width, grown.height);
    for (int y = ny0; y < ny1; ++y) {
      float* row = to[l]->data() + static_cast<size_t>(y - ny0) * grown.width;
      std::copy_n(layers_[l] + static_cast<size_t>(y) * g.width + nx0, grown.width, row);
      const bool oldRow = !empty && y >= b.y0 && y < b.y0 + b.height;
      if (oldRow) std::copy_n(from[l]->data() + static_cast<size_t>(y - b.y0) * b.width, b.width, row + (b.x0 - nx0));
    }
  }
  before_ = std::move(grown);
}

AvalancheArgs AvalancheRun::stepArgs(double stepS, int substeps) {
  AvalancheArgs a = args_;
  a.dtS = static_cast<float>(stepS / substeps);
  // After the first step, the last step's row statistics give the spans the passes run over.
  const bool spans = rowSpans_ && record_.steps > 0;
  a.spanY0 = spans ? args_.y0 : 0;
  a.spanY1 = spans ? args_.y1 : 0;
  a.statsIn = record_.steps % 2;
  // With one substep a step, the last two steps' touched columns bound the passes too; not for two
  // steps after a day's static fields came (the friction reads the temperature of every cell).
  if (backend_.staticFieldsVersion() != staticFieldsSeen_) {
    staticFieldsSeen_ = backend_.staticFieldsVersion();
    liveFrom_ = std::max(liveFrom_, record_.steps + 2);
  }
  a.live = spans && substeps == 1 && record_.steps >= liveFrom_ && liveSpans_ && !a.shallowWater;
  liveSteps_ += a.live;
  for (int set = 0; set < 2; ++set) a.liveY0[set] = statsY0_[set], a.liveY1[set] = statsY1_[set];
  return a;
}

// The grown box the step covered (the last 4 floats of `stats`) and its rows' statistics (5 a row
// before them, written to set `statsOut`): the box and cost records, and the next step's box
// around the snow that can still flow.
AvalancheRun::StepTotals AvalancheRun::takeStepStats(const std::vector<float>& stats, int statsOut) {
  const size_t n = stats.size() - 4;
  const int bx0 = static_cast<int>(stats[n]), by0 = static_cast<int>(stats[n + 1]);
  const int bx1 = static_cast<int>(stats[n + 2]), by1 = static_cast<int>(stats[n + 3]);
  statsY0_[statsOut] = by0, statsY1_[statsOut] = by1;
  unionBox_.x0 = std::min(unionBox_.x0, bx0), unionBox_.y0 = std::min(unionBox_.y0, by0);
  unionBox_.x1 = std::max(unionBox_.x1, bx1), unionBox_.y1 = std::max(unionBox_.y1, by1);
  record_.boxCellsMax = std::max(record_.boxCellsMax, (bx1 - bx0) * (by1 - by0));
  record_.boxCellSteps += static_cast<double>(bx1 - bx0) * (by1 - by0);
  StepTotals t;
  int x0 = terrain_.spec.width, y0 = terrain_.spec.height, x1 = 0, y1 = 0;
  for (int r = 0; r < by1 - by0; ++r) {
    const float* s = &stats[5 * static_cast<size_t>(r)];
    t.speed = std::max(t.speed, s[0]);
    t.energy += s[1];
    t.signal = std::max(t.signal, s[4]);
    if (s[3] >= 0.f) {
      x0 = std::min(x0, static_cast<int>(s[2])), x1 = std::max(x1, static_cast<int>(s[3]) + 1);
      y0 = std::min(y0, by0 + r), y1 = std::max(y1, by0 + r + 1);
    }
  }
  args_.x0 = x0, args_.y0 = y0, args_.x1 = x1, args_.y1 = y1;
  return t;
}

void AvalancheRun::checkRest(const StepTotals& t) {
  if (args_.x1 <= args_.x0) {
    record_.why = "all moving snow deposited";
    atRest_ = true;
  } else if (t.speed < p_.avalancheStopSpeedMps && (record_.maxSpeedMps >= p_.avalancheStopSpeedMps || record_.simulatedS >= 2.0)) {
    // (Not before the snow has once moved faster than the stop speed, or 2 s have passed: with
    // short steps, snow that has only begun to accelerate is not yet at rest.)
    record_.why = "at rest (fastest flow " + std::to_string(t.speed) + " m/s)";
    atRest_ = true;
  } else if (t.energy < p_.avalancheStopEnergyFraction * peakEnergy_) {
    // com1DFA's stopping criterion (stopCrit 0.01 of the peak kinetic energy): what still moves
    // is the creep of a thin tail, which would otherwise hold the run open for minutes.
    record_.why = "at rest (kinetic energy " + std::to_string(t.energy / peakEnergy_) + " of its peak)";
    atRest_ = true;
  } else if (record_.simulatedS >= p_.avalancheMaxDurationS) {
    record_.why = "stopped at the duration cap (fastest flow still " + std::to_string(t.speed) + " m/s)";
    atRest_ = true;
  }
}

// The pipes: at most 0.2 sqrt(L_min / g) a substep (their pressure waves). The shallow water: as
// many more as keep the last step's fastest signal (AvalancheWaterRowStatsKernel; at the first
// step, the gravity waves of the deepest released snow) to the Courant number
// kAvalancheWaterCourant; at most kMaxSubsteps (the velocity limit keeps every depth
// non-negative whatever the count).
int AvalancheRun::substepsOfStep(double stepS) const {
  constexpr double kMaxSubsteps = 10000.0;
  const double minCell = std::min(terrain_.spec.cellSizeXM, terrain_.spec.cellSizeYM);
  const double maxSubstep = 0.2 * std::sqrt(minCell / p_.gravityMps2);
  double n = std::ceil(stepS / maxSubstep);
  if (args_.shallowWater) n = std::max(n, std::ceil(stepS * lastSignal_ / kAvalancheWaterCourant));
  return static_cast<int>(std::clamp(n, 1.0, kMaxSubsteps));
}

bool AvalancheRun::step() {
  if (!active_ || atRest_) return true;
  const auto t0 = WallClock::now();
  const double stepS = p_.avalancheStepS;
  const int substeps = substepsOfStep(stepS);
  // Snow moves at most a cell a substep: the step stays within its box grown by `substeps`.
  growBeforeBox(std::max(0, args_.x0 - substeps), std::max(0, args_.y0 - substeps), std::min(terrain_.spec.width, args_.x1 + substeps),
                std::min(terrain_.spec.height, args_.y1 + substeps));
  const AvalancheArgs a = stepArgs(stepS, substeps);
  const StepTotals totals = takeStepStats(backend_.avalancheSteps(a, substeps), 1 - a.statsIn);
  ++record_.steps;
  record_.substeps += substeps;
  record_.simulatedS += stepS;
  lastSpeed_ = totals.speed;
  lastSignal_ = totals.signal;
  peakEnergy_ = std::max(peakEnergy_, totals.energy);
  record_.maxSpeedMps = std::max(record_.maxSpeedMps, totals.speed);
  const double seconds = elapsedSeconds(t0);
  wallSeconds_ += seconds;
  record_.stepSeconds += seconds;
  if (record_.maps && frameIntervalS_ > 0.0 && record_.simulatedS + 1e-9 >= nextFrameS_) {
    captureFrame();
    while (nextFrameS_ <= record_.simulatedS + 1e-9) nextFrameS_ += frameIntervalS_;
  }
  checkRest(totals);
  return atRest_;
}

AvalancheRecord AvalancheRun::runToRest() {
  while (active_ && !step()) {
  }
  return settle();
}

// The union box's layers (and peaks) after the last step, into after_.
void AvalancheRun::captureFrame() {
  downloadAfter(false);
  record_.maps->frames.push_back({record_.simulatedS, boxDepth()});
}

void AvalancheRun::downloadAfter(bool peaks) {
  after_.x0 = unionBox_.x0, after_.y0 = unionBox_.y0;
  after_.width = std::max(0, unionBox_.x1 - unionBox_.x0), after_.height = std::max(0, unionBox_.y1 - unionBox_.y0);
  backend_.downloadBox(after_, peaks);
}

// The depth C + S + U + P of after_'s box, as a crop of the grid.
GridCrop AvalancheRun::boxDepth() const {
  GridCrop c;
  c.x0 = after_.x0, c.y0 = after_.y0;
  c.grid = Grid<float>(after_.width, after_.height, 0.f);
  for (size_t j = 0; j < c.grid.size(); ++j) c.grid.values()[j] = after_.depth(j);
  return c;
}

AvalancheRecord AvalancheRun::settle() {
  if (!active_) return record_;
  const auto t0 = WallClock::now();
  backend_.avalancheSettle(unionBox_);
  backend_.beforeNextWrite(nullptr);
  active_ = false;
  downloadAfter(record_.maps != nullptr);
  const SnowBox& after = after_;
  const SnowBox& b = before_;
  const SnowState& s = terrain_;
  const int w = s.spec.width;
  const double area = s.spec.cellAreaM2();
  const double ruptureA = surfaceAt(s.bedrockM, static_cast<size_t>(record_.ruptureY) * w + record_.ruptureX, b,
                                    b.index(record_.ruptureX, record_.ruptureY));
  double lowest = ruptureA;
  for (int y = unionBox_.y0; y < unionBox_.y1; ++y)
    for (int x = unionBox_.x0; x < unionBox_.x1; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x, j = after.index(x, y), k = b.index(x, y);
      if (!s.validCell.values()[i]) continue;
      const double change = (static_cast<double>(after.stable.values()[j]) + after.unstable.values()[j] + after.powder.values()[j]) -
                            (static_cast<double>(b.stable.values()[k]) + b.unstable.values()[k] + b.powder.values()[k]);
      if (std::abs(change) > 1e-3) ++record_.footprintCells;
      if (change > 0) record_.depositM3 += change * area;
      if (change > 0.01) {
        record_.runoutM = std::max(record_.runoutM, std::hypot((x - record_.ruptureX) * s.spec.cellSizeXM,
                                                               (y - record_.ruptureY) * s.spec.cellSizeYM));
        lowest = std::min(lowest, surfaceAt(s.bedrockM, i, after, j));
      }
    }
  record_.fallHeightM = ruptureA - lowest;
  if (record_.maps) {
    GridCrop scour, deposit;
    scour.x0 = deposit.x0 = after.x0, scour.y0 = deposit.y0 = after.y0;
    scour.grid = deposit.grid = Grid<float>(after.width, after.height, 0.f);
    for (int y = unionBox_.y0; y < unionBox_.y1; ++y)
      for (int x = unionBox_.x0; x < unionBox_.x1; ++x) {
        const size_t i = static_cast<size_t>(y) * w + x, j = after.index(x, y), k = b.index(x, y);
        if (!s.validCell.values()[i]) continue;
        const float change = (after.stable.values()[j] + after.unstable.values()[j] + after.powder.values()[j]) -
                             (b.stable.values()[k] + b.unstable.values()[k] + b.powder.values()[k]);
        if (change > 0.f) deposit.grid.values()[j] = change;
        if (change < 0.f) scour.grid.values()[j] = -change;
      }
    record_.maps->scour = std::move(scour);
    record_.maps->deposit = std::move(deposit);
    record_.maps->peakThickness = GridCrop{after.x0, after.y0, after.peakThickness};
    record_.maps->peakSpeed = GridCrop{after.x0, after.y0, after.peakSpeed};
    if (frameIntervalS_ > 0.0) record_.maps->frames.push_back({record_.simulatedS, boxDepth()});
  }
  keepSnapshotOfBox();
  wallSeconds_ += elapsedSeconds(t0);
  record_.seconds = wallSeconds_;
  return record_;
}

}  // namespace snow
