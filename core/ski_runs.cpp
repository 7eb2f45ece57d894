#include "ski_runs.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

#include "rng.h"
#include "util.h"

namespace snow {

Grid<float> routeMap(const Grid<float>& altitude, const Grid<uint8_t>& valid, const GridSpec& spec) {
  const int w = spec.width, h = spec.height;
  const float dx = static_cast<float>(spec.cellSizeXM), dy = static_cast<float>(spec.cellSizeYM);
  std::vector<int> order;
  order.reserve(static_cast<size_t>(w) * h);
  for (int i = 0; i < w * h; ++i)
    if (valid.values()[i]) order.push_back(i);
  // Lowest first: every lower neighbour is final before a cell is computed.
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return altitude.values()[a] < altitude.values()[b]; });
  Grid<float> d(w, h, 0.f);
  // In place: the kernel reads only lower, finished neighbours (the same float sums as the
  // device automaton's, so the same bytes).
  const RouteMapStepKernel k{altitude.data(), valid.data(), d.data(), d.data(), w, h, dx, dy, std::sqrt(dx * dx + dy * dy)};
  for (int i : order) k(i % w, i / w);
  return d;
}

int poissonCount(double mean, const std::function<double(uint32_t)>& uniform) {
  if (!(mean > 0.0)) return 0;
  if (!(mean < 1e6)) throw std::invalid_argument("poissonCount: mean too large");
  const uint32_t parts = static_cast<uint32_t>(std::ceil(mean / 30.0));
  const double lambda = mean / parts;
  int total = 0;
  for (uint32_t j = 0; j < parts; ++j) {
    const double u = uniform(j);
    double p = std::exp(-lambda), cdf = p;
    int k = 0;
    while (u > cdf && k < 1000) {
      ++k;
      p *= lambda / k;
      cdf += p;
      if (!(p > 0.0)) break;  // the tail's rounding: u beyond the representable CDF
    }
    total += k;
  }
  return total;
}

double turnFrequency(double slope, double target, double a, double minFrequency) {
  if (!(slope > target) || a <= 0.0) return 0.0;
  // Slope along the curve: sin(s_e) = G / mean over a period of sqrt(1 + G^2 + c^2 cos^2),
  // G = tan(slope), c = 2 pi f a. Solve mean(c) = G / sin(target) by bisection (mean grows with c).
  const double G = std::tan(slope), want = G / std::sin(target);
  auto mean = [&](double c) {
    const int n = 64;  // Simpson over a quarter period (the integrand is symmetric)
    double sum = 0.0;
    for (int i = 0; i <= n; ++i) {
      const double t = 0.5 * kPi * i / n, cs = std::cos(t);
      const double v = std::sqrt(1.0 + G * G + c * c * cs * cs);
      sum += v * (i == 0 || i == n ? 1.0 : (i % 2 ? 4.0 : 2.0));
    }
    return sum / (3.0 * n);
  };
  double lo = 0.0, hi = 1.0;
  while (mean(hi) < want && hi < 1e6) hi *= 2.0;
  for (int it = 0; it < 100; ++it) {
    const double mid = 0.5 * (lo + hi);
    (mean(mid) < want ? lo : hi) = mid;
  }
  return std::max(minFrequency, 0.5 * (lo + hi) / (2.0 * kPi * a));
}

Path2 refineTrack(const Path2& path, const std::function<double(double, double)>& altitude, const ModelParameters& p, double maxGapM) {
  Path2 out;
  if (path.size() < 2) return path;
  const double target = p.skierTargetSlopeDeg * kPi / 180.0, a = p.trackAmplitudeM;
  const size_t segments = path.size() - 1;
  std::vector<double> length(segments), freq(segments);
  std::vector<std::array<double, 2>> dir(segments), normal(segments);
  for (size_t k = 0; k < segments; ++k) {
    const double ex = path[k + 1][0] - path[k][0], ey = path[k + 1][1] - path[k][1];
    length[k] = std::hypot(ex, ey);
    dir[k] = length[k] > 0 ? std::array<double, 2>{ex / length[k], ey / length[k]} : std::array<double, 2>{1.0, 0.0};
    normal[k] = {-dir[k][1], dir[k][0]};
    const double drop = length[k] > 0 ? altitude(path[k][0], path[k][1]) - altitude(path[k + 1][0], path[k + 1][1]) : 0.0;
    freq[k] = length[k] > 0 ? turnFrequency(std::atan2(drop, length[k]), target, a, p.trackFrequencyPerM) : 0.0;
  }
  auto blend = [](const std::array<double, 2>& m, const std::array<double, 2>& n, double w) {
    const double x = (1 - w) * m[0] + w * n[0], y = (1 - w) * m[1] + w * n[1], l = std::hypot(x, y);
    return l > 1e-12 ? std::array<double, 2>{x / l, y / l} : n;
  };
  double phase = 0.0;
  for (size_t k = 0; k < segments; ++k) {
    const double L = length[k];
    const double hStart = k > 0 ? 0.5 * std::min(length[k - 1], L) : 0.0;
    const double hEnd = k + 1 < segments ? 0.5 * std::min(L, length[k + 1]) : 0.0;
    const double c = 2.0 * kPi * freq[k] * a;
    const double ds = std::max(1e-3, 0.5 * maxGapM / std::sqrt(1.0 + c * c));
    const int m = std::max(1, static_cast<int>(std::ceil(L / ds)));
    for (int i = (k == 0 ? 0 : 1); i <= m; ++i) {
      const double s = L * i / m;
      std::array<double, 2> n = normal[k];
      if (hStart > 0 && s < hStart) n = blend(normal[k - 1], normal[k], 0.5 + 0.5 * s / hStart);
      if (hEnd > 0 && L - s < hEnd) n = blend(normal[k], normal[k + 1], 0.5 - 0.5 * (L - s) / hEnd);
      const double offset = a * std::sin(phase + 2.0 * kPi * freq[k] * s);
      out.push_back({path[k][0] + dir[k][0] * s + n[0] * offset, path[k][1] + dir[k][1] * s + n[1] * offset});
    }
    phase += 2.0 * kPi * freq[k] * L;
  }
  // No gap wider than maxGapM: fill any with points on the chord.
  Path2 filled;
  filled.reserve(out.size());
  filled.push_back(out[0]);
  for (size_t i = 1; i < out.size(); ++i) {
    const auto& q = out[i];
    const auto prev = filled.back();
    const double gap = std::hypot(q[0] - prev[0], q[1] - prev[1]);
    const int extra = static_cast<int>(std::ceil(gap / maxGapM)) - 1;
    for (int e = 1; e <= extra; ++e) {
      const double t = static_cast<double>(e) / (extra + 1);
      filled.push_back({prev[0] + t * (q[0] - prev[0]), prev[1] + t * (q[1] - prev[1])});
    }
    filled.push_back(q);
  }
  return filled;
}

SkiTracks::SkiTracks(const GridSpec& spec, int factor)
    : spec_(spec), factor_(factor), depth_(spec.width * factor, spec.height * factor, 0.f),
      lastSurface_(spec.cellCount(), std::numeric_limits<float>::quiet_NaN()) {}

void SkiTracks::fadeCell(int cell, float now) {
  float& last = lastSurface_[static_cast<size_t>(cell)];
  if (std::isnan(last)) {
    last = now;
    return;
  }
  const float fill = now - last;
  last = now;
  if (!(fill > 0.f)) return;
  const int cx = cell % spec_.width, cy = cell / spec_.width;
  for (int ty = cy * factor_; ty < (cy + 1) * factor_; ++ty)
    for (int tx = cx * factor_; tx < (cx + 1) * factor_; ++tx) depth_(tx, ty) = std::max(0.f, depth_(tx, ty) - fill);
}

void SkiTracks::fade(const SnowState& s) {
  const float* layers[4] = {s.compactedM.data(), s.stableM.data(), s.unstableM.data(), s.powderM.data()};
  fade(s.bedrockM, layers);
}

void SkiTracks::fade(const Grid<float>& bedrock, const float* const layers[4]) {
  for (size_t c = 0; c < lastSurface_.size(); ++c)
    if (!std::isnan(lastSurface_[c]))  // SnowState::depthM's sum
      fadeCell(static_cast<int>(c), bedrock.values()[c] + (layers[0][c] + layers[1][c] + layers[2][c] + layers[3][c]));
}

void SkiTracks::stamp(const Path2& track, double depthM, double widthM, const std::function<float(int)>& surface) {
  const double tx = spec_.cellSizeXM / factor_, ty = spec_.cellSizeYM / factor_;
  // At least 1.5 texels wide, so a track marks a texel however it lies across the texture.
  const double hw = std::max(0.5 * widthM, 0.75 * std::max(tx, ty));
  const int W = depth_.width(), H = depth_.height();
  // The texels within reach of segment i: [x0, x1] x [y0, y1], clipped to the texture.
  auto texelBox = [&](size_t i) {
    const auto &P = track[i], &Q = track[i + 1];
    return std::array<int, 4>{std::max(0, static_cast<int>(std::floor((std::min(P[0], Q[0]) - hw) / tx))),
                              std::min(W - 1, static_cast<int>(std::floor((std::max(P[0], Q[0]) + hw) / tx))),
                              std::max(0, static_cast<int>(std::floor((std::min(P[1], Q[1]) - hw) / ty))),
                              std::min(H - 1, static_cast<int>(std::floor((std::max(P[1], Q[1]) + hw) / ty)))};
  };
  // First bring every touched cell's fading up to now, then cut the grooves.
  std::vector<int> cells;
  for (size_t i = 0; i + 1 < track.size(); ++i) {
    const auto [x0, x1, y0, y1] = texelBox(i);
    for (int cy = y0 / factor_; cy <= y1 / factor_; ++cy)
      for (int cx = x0 / factor_; cx <= x1 / factor_; ++cx) cells.push_back(cy * spec_.width + cx);
  }
  std::sort(cells.begin(), cells.end());
  cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
  for (int c : cells) fadeCell(c, surface(c));
  for (size_t i = 0; i + 1 < track.size(); ++i) {
    const auto &P = track[i], &Q = track[i + 1];
    const double ex = Q[0] - P[0], ey = Q[1] - P[1], len2 = ex * ex + ey * ey;
    const auto [x0, x1, y0, y1] = texelBox(i);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const double cx = (x + 0.5) * tx, cy = (y + 0.5) * ty;
        const double t = len2 > 0 ? std::clamp(((cx - P[0]) * ex + (cy - P[1]) * ey) / len2, 0.0, 1.0) : 0.0;
        const double d = std::hypot(cx - (P[0] + t * ex), cy - (P[1] + t * ey));
        if (d >= hw) continue;
        const float v = static_cast<float>(depthM * (1.0 - (d / hw) * (d / hw)));
        depth_(x, y) = std::max(depth_(x, y), v);
      }
  }
}

SkiRun::SkiRun(SnowBackend& backend, const ModelParameters& p, const SnowState& state, SkiTracks* tracks)
    : backend_(backend), p_(p), spec_(state.spec), bedrock_(state.bedrockM), valid_(state.validCell),
      tracks_(tracks) {
  // On a GPU backend, the paper's automaton on the device; on the host, the one-pass sort (the
  // same bytes, tested).
  if (!backend.routeMapOnDevice(route_)) route_ = snow::routeMap(state.bedrockM, state.validCell, state.spec);
  backend.uploadRouteMap(route_);
  // The scene's skier_spawn multiplier (art direction) scales where automatic skiers start.
  if (state.skierSpawnFactor.size() == route_.size()) spawn_ = &state.skierSpawnFactor;
  rowStartWeights_.assign(static_cast<size_t>(spec_.height) + 1, 0.0);
  double sum = 0.0;
  for (int y = 0; y < spec_.height; ++y) {
    rowStartWeights_[static_cast<size_t>(y)] = sum;
    for (int x = 0; x < spec_.width; ++x) addStartWeight(static_cast<size_t>(y) * spec_.width + x, sum);
  }
  rowStartWeights_[static_cast<size_t>(spec_.height)] = sum;
}

void SkiRun::addStartWeight(size_t i, double& sum) const {
  sum += route_.values()[i] * (spawn_ ? std::max(0.f, spawn_->values()[i]) : 1.f);
}

long long pickByCumulativeWeight(const std::vector<double>& cumulative, double draw) {
  if (cumulative.empty() || !(cumulative.back() > 0.0)) return -1;
  const double target = draw * cumulative.back();
  const auto at = std::upper_bound(cumulative.begin(), cumulative.end(), target) - cumulative.begin();
  return std::min(static_cast<long long>(cumulative.size()) - 1, static_cast<long long>(at));
}

// As pickByCumulativeWeight over the running totals, which are summed again within the row the
// target falls in (the same doubles in the same order) instead of being held for every cell.
bool SkiRun::pickStart(double draw, int& x, int& y) const {
  const double total = rowStartWeights_.empty() ? 0.0 : rowStartWeights_.back();
  if (!(total > 0.0)) return false;
  const double target = draw * total;
  size_t i = spec_.cellCount() - 1;
  const auto above = std::upper_bound(rowStartWeights_.begin(), rowStartWeights_.end() - 1, target);
  bool found = false;
  for (int r = std::max(0, static_cast<int>(above - rowStartWeights_.begin()) - 1); r < spec_.height && !found; ++r) {
    double sum = rowStartWeights_[static_cast<size_t>(r)];
    for (int c = 0; c < spec_.width && !found; ++c) {
      const size_t j = static_cast<size_t>(r) * spec_.width + c;
      addStartWeight(j, sum);
      if (sum > target) i = j, found = true;
    }
  }
  x = static_cast<int>(i % spec_.width);
  y = static_cast<int>(i / spec_.width);
  return true;
}

bool SkiRun::canStart(int x, int y) {
  if (!valid_(x, y)) return false;
  std::vector<float> depth, unstable;
  backend_.readCells(x, y, 1, 1, depth, unstable);
  return depth[0] >= p_.skiMinSnowM;
}

const char* skierStopReason(int status) {
  switch (status) {
    case kSkierActive: return "still running";
    case kSkierStepLimit: return "step limit";
    case kSkierRouteEnd: return "end of the route";
    case kSkierNoCellAhead: return "no acceptable cell ahead (a dead end, or no snow)";
    case kSkierReachedEdge: return "reached the terrain's edge";
    case kSkierNodataAhead: return "NODATA ahead";
    case kSkierSnowRanOut: return "the snow ran out";
    case kSkierTriggered: return "triggered an avalanche";
    case kSkierStartNodata: return "the start cell is NODATA";
    case kSkierNoSnowAtStart: return "not enough snow at the start";
    default: return "unknown";
  }
}

std::vector<SkierRecord> SkiRun::descendTogether(const std::vector<SkierStart>& starts, double day, uint64_t seed) {
  const int w = spec_.width, h = spec_.height;
  std::vector<SkierAgent> agents(starts.size());
  std::vector<SkierRecord> records(starts.size());
  for (size_t k = 0; k < starts.size(); ++k) {
    const SkierStart& st = starts[k];
    if (st.x < 0 || st.y < 0 || st.x >= w || st.y >= h) throw std::invalid_argument("skier start outside the grid");
    agents[k].startCell = st.y * w + st.x;
    agents[k].id = st.id;
    records[k].day = day, records[k].startX = st.x, records[k].startY = st.y, records[k].user = st.user;
  }
  std::vector<std::vector<double>> paths;
  backend_.skierBatch(makeSkierArgs(p_, spec_, seed), agents, paths);

  const double dx = spec_.cellSizeXM, dy = spec_.cellSizeYM;
  std::vector<float> box, depth, unstable;  // the path's surroundings; one cell outside them
  for (size_t k = 0; k < agents.size(); ++k) {
    const SkierAgent& s = agents[k];
    SkierRecord& r = records[k];
    r.why = skierStopReason(s.status);
    if (s.status == kSkierStartNodata || s.status == kSkierNoSnowAtStart) continue;
    r.cells = s.cells;
    r.lengthM = s.lengthM;
    r.triggered = s.status == kSkierTriggered;
    if (r.triggered) r.triggerX = s.triggerCell % w, r.triggerY = s.triggerCell / w;
    for (size_t i = 0; i + 1 < paths[k].size(); i += 2) r.path.push_back({paths[k][i], paths[k][i + 1]});
    // The snow surface around the path (skiers change no surface: the values of the descent).
    int x0 = w, y0 = h, x1 = 0, y1 = 0;
    for (const auto& q : r.path) {
      const int qx = std::clamp(static_cast<int>(q[0] / dx), 0, w - 1), qy = std::clamp(static_cast<int>(q[1] / dy), 0, h - 1);
      x0 = std::min(x0, qx), x1 = std::max(x1, qx), y0 = std::min(y0, qy), y1 = std::max(y1, qy);
    }
    x0 = std::max(0, x0 - 2), y0 = std::max(0, y0 - 2), x1 = std::min(w - 1, x1 + 2), y1 = std::min(h - 1, y1 + 2);
    backend_.readCells(x0, y0, x1 - x0 + 1, y1 - y0 + 1, box, unstable);
    auto surfaceOf = [&](int cell) -> float {
      const int cx = cell % w, cy = cell / w;
      if (cx >= x0 && cx <= x1 && cy >= y0 && cy <= y1)
        return bedrock_.values()[static_cast<size_t>(cell)] + box[static_cast<size_t>(cy - y0) * (x1 - x0 + 1) + (cx - x0)];
      backend_.readCells(cx, cy, 1, 1, depth, unstable);
      return bedrock_.values()[static_cast<size_t>(cell)] + depth[0];
    };
    r.dropM = surfaceOf(s.startCell) - surfaceOf(s.cell);
    if (tracks_ && r.path.size() >= 2) {
      auto altitude = [&](double px, double py) {
        const int ix = std::clamp(static_cast<int>(px / dx), 0, w - 1), iy = std::clamp(static_cast<int>(py / dy), 0, h - 1);
        return static_cast<double>(surfaceOf(iy * w + ix));
      };
      const Path2 track = refineTrack(r.path, altitude, p_, 0.5 * std::min(dx, dy) / tracks_->factor());
      tracks_->stamp(track, p_.skiTrackDepthM, p_.skiTrackWidthM, surfaceOf);
    }
  }
  return records;
}

SkierRecord SkiRun::descend(int x, int y, double day, uint64_t seed, uint64_t id, bool user) {
  return descendTogether({SkierStart{x, y, id, user}}, day, seed).front();
}

}  // namespace snow
