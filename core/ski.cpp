#include "ski.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <unordered_map>

#include "rng.h"

namespace snow {

namespace {
constexpr double kPi = 3.14159265358979323846;
}  // namespace

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
  for (size_t c = 0; c < lastSurface_.size(); ++c)
    if (!std::isnan(lastSurface_[c])) fadeCell(static_cast<int>(c), s.bedrockM.values()[c] + s.depthM(c % spec_.width, c / spec_.width));
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
  cumulative_.resize(route_.size());
  double sum = 0.0;
  // The scene's skier_spawn multiplier (art direction) scales where automatic skiers start.
  const bool spawn = state.skierSpawnFactor.size() == route_.size();
  for (size_t i = 0; i < route_.size(); ++i)
    cumulative_[i] = (sum += route_.values()[i] * (spawn ? std::max(0.f, state.skierSpawnFactor.values()[i]) : 1.f));
}

long long pickByCumulativeWeight(const std::vector<double>& cumulative, double draw) {
  if (cumulative.empty() || !(cumulative.back() > 0.0)) return -1;
  const double target = draw * cumulative.back();
  const auto at = std::upper_bound(cumulative.begin(), cumulative.end(), target) - cumulative.begin();
  return std::min(static_cast<long long>(cumulative.size()) - 1, static_cast<long long>(at));
}

bool SkiRun::pickStart(double draw, int& x, int& y) const {
  const long long picked = pickByCumulativeWeight(cumulative_, draw);
  if (picked < 0) return false;
  const size_t i = static_cast<size_t>(picked);
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

SkierRecord SkiRun::descend(int x, int y, double day, uint64_t seed, uint64_t id, bool user) {
  SkierRecord r;
  r.day = day, r.startX = x, r.startY = y, r.user = user;
  const int w = spec_.width, h = spec_.height;
  const double dx = spec_.cellSizeXM, dy = spec_.cellSizeYM, stepM = std::min(dx, dy);
  const int R = std::max(1, static_cast<int>(std::lround(p_.skiLookaheadM / stepM)));
  const double target = p_.skierTargetSlopeDeg * kPi / 180.0, sigma = p_.skiSlopeToleranceDeg * kPi / 180.0;
  const double tanC = std::tan(p_.avalancheRestAngleDeg * kPi / 180.0);
  std::unordered_map<int, std::array<float, 2>> seen;  // cell -> {surface, unstable}
  std::vector<float> depth, unstable;
  auto readAround = [&](int cx, int cy, int reach) {
    const int x0 = std::max(0, cx - reach), y0 = std::max(0, cy - reach);
    const int x1 = std::min(w - 1, cx + reach), y1 = std::min(h - 1, cy + reach);
    backend_.readCells(x0, y0, x1 - x0 + 1, y1 - y0 + 1, depth, unstable);
    for (int yy = y0; yy <= y1; ++yy)
      for (int xx = x0; xx <= x1; ++xx) {
        const size_t k = static_cast<size_t>(yy - y0) * (x1 - x0 + 1) + (xx - x0);
        seen[yy * w + xx] = {bedrock_(xx, yy) + depth[k], unstable[k]};
      }
  };
  auto surfaceOf = [&](int cell) -> float {
    const auto it = seen.find(cell);
    return it != seen.end() ? it->second[0] : bedrock_.values()[static_cast<size_t>(cell)];
  };
  auto snowOf = [&](int cell) { return surfaceOf(cell) - bedrock_.values()[static_cast<size_t>(cell)]; };
  if (!valid_(x, y)) {
    r.why = "the start cell is NODATA";
    return r;
  }
  readAround(x, y, R + 1);
  if (snowOf(y * w + x) < p_.skiMinSnowM) {
    r.why = "not enough snow at the start";
    return r;
  }
  const RandomKey key{seed};
  std::array<double, 2> pos{(x + 0.5) * dx, (y + 0.5) * dy}, heading{0.0, 0.0};
  r.path.push_back(pos);
  int cx = x, cy = y;
  std::vector<int> entered{y * w + x};
  const int maxSteps = 4 * (w + h);
  for (int step = 0;; ++step) {
    if (step >= maxSteps) {
      r.why = "step limit";
      break;
    }
    const int cur = cy * w + cx;
    if (route_.values()[static_cast<size_t>(cur)] <= 0.f) {
      r.why = "end of the route";
      break;
    }
    readAround(cx, cy, R + 1);
    // Eq. 4 over the cells ahead.
    std::vector<std::pair<int, double>> candidates;
    double total = 0.0;
    const float here = surfaceOf(cur);
    for (int oy = -R; oy <= R; ++oy)
      for (int ox = -R; ox <= R; ++ox) {
        const int nx = cx + ox, ny = cy + oy;
        if ((ox == 0 && oy == 0) || nx < 0 || ny < 0 || nx >= w || ny >= h || !valid_(nx, ny)) continue;
        const double ddx = ox * dx, ddy = oy * dy, dist = std::hypot(ddx, ddy);
        if (dist > R * stepM * 1.0001) continue;
        if ((heading[0] != 0.0 || heading[1] != 0.0) && ddx * heading[0] + ddy * heading[1] < std::cos(100.0 * kPi / 180.0) * dist) continue;
        const int n = ny * w + nx;
        if (snowOf(n) < p_.skiMinSnowM) continue;
        const double drop = here - surfaceOf(n);
        if (!(drop > 0.0)) continue;
        const double sn = std::atan2(drop, dist), e = (sn - target) / sigma;
        const double weight = std::exp(-e * e) * (route_.values()[static_cast<size_t>(n)] + dist);
        if (weight <= 0.0) continue;
        candidates.push_back({n, weight});
        total += weight;
      }
    if (candidates.empty() || !(total > 0.0)) {
      r.why = "no acceptable cell ahead (a dead end, or no snow)";
      break;
    }
    const Philox4x32 draw = key.draw(id * 1000003ull + static_cast<uint64_t>(step), 0, RngStream::Skier);
    double u = uniformOpenDouble(draw.v[0], draw.v[1]) * total;
    int chosen = candidates.back().first;
    for (const auto& [n, wgt] : candidates)
      if ((u -= wgt) <= 0.0) {
        chosen = n;
        break;
      }
    const double tx = (chosen % w + 0.5) * dx - pos[0], ty = (chosen / w + 0.5) * dy - pos[1], tl = std::hypot(tx, ty);
    std::array<double, 2> want{tx / tl, ty / tl};
    if (heading[0] == 0.0 && heading[1] == 0.0) heading = want;
    else {
      const double hx = (1 - p_.skiSteering) * heading[0] + p_.skiSteering * want[0];
      const double hy = (1 - p_.skiSteering) * heading[1] + p_.skiSteering * want[1], hl = std::hypot(hx, hy);
      heading = hl > 1e-9 ? std::array<double, 2>{hx / hl, hy / hl} : want;
    }
    // The smooth turn must not carry the skier where it would not go: uphill, out of the snow,
    // or into a dead end (a route much shorter than the target's). Then it turns straight at
    // the target (in the same step: redrawing the target would turn it toward an old one, and a
    // skier could spin in place until the step limit); if even that fails, it steps to the
    // neighbour nearest the target's direction.
    auto enterable = [&](int cell) {
      return snowOf(cell) >= p_.skiMinSnowM && surfaceOf(cell) <= surfaceOf(cur) &&
             route_.values()[static_cast<size_t>(cell)] >= 0.5f * route_.values()[static_cast<size_t>(chosen)];
    };
    std::array<double, 2> next{};
    int ncell = -1;
    auto aim = [&]() -> const char* {
      next = {pos[0] + heading[0] * stepM, pos[1] + heading[1] * stepM};
      if (next[0] < 0 || next[1] < 0 || next[0] >= w * dx || next[1] >= h * dy) return "reached the terrain's edge";
      const int nx = static_cast<int>(next[0] / dx), ny = static_cast<int>(next[1] / dy);
      if (!valid_(nx, ny)) return "NODATA ahead";
      ncell = ny * w + nx;
      return nullptr;
    };
    const char* stop = aim();
    if (!stop && ncell != cur && !enterable(ncell) && !(heading == want)) {
      heading = want;
      stop = aim();
    }
    if (stop) {
      r.why = stop;
      break;
    }
    std::array<double, 2> moveTo = next;
    if (ncell != cur && !enterable(ncell)) {
      // Even the straight line crosses a cell it would not enter: step to the acceptable
      // neighbour closest in direction to the target instead, or stop.
      int best = -1;
      double bestDot = std::cos(60.0 * kPi / 180.0);
      for (int oy = -1; oy <= 1; ++oy)
        for (int ox = -1; ox <= 1; ++ox) {
          const int bx = cx + ox, by = cy + oy;
          if ((ox == 0 && oy == 0) || bx < 0 || by < 0 || bx >= w || by >= h || !valid_(bx, by)) continue;
          const int b = by * w + bx;
          if (!enterable(b)) continue;
          const double ex = (bx + 0.5) * dx - pos[0], ey = (by + 0.5) * dy - pos[1], el = std::hypot(ex, ey);
          const double dot = (ex * want[0] + ey * want[1]) / el;
          if (dot > bestDot) bestDot = dot, best = b;
        }
      if (best < 0) {
        r.why = "no acceptable cell ahead (a dead end, or no snow)";
        break;
      }
      moveTo = {(best % w + 0.5) * dx, (best / w + 0.5) * dy};
      const double ex = moveTo[0] - pos[0], ey = moveTo[1] - pos[1], el = std::hypot(ex, ey);
      heading = {ex / el, ey / el};
    }
    r.lengthM += std::hypot(moveTo[0] - pos[0], moveTo[1] - pos[1]);
    pos = moveTo;
    r.path.push_back(pos);
    const int mx = static_cast<int>(pos[0] / dx), my = static_cast<int>(pos[1] / dy), entering = my * w + mx;
    if (entering == cur) continue;
    cx = mx, cy = my;
    entered.push_back(entering);
    ++r.cells;
    if (snowOf(entering) < p_.skiMinSnowM) {
      r.why = "the snow ran out";
      break;
    }
    // Crossing unstable snow on a slope above the rest angle: the raised release probability.
    const auto seenEntering = seen.find(entering);
    const float U = seenEntering != seen.end() ? seenEntering->second[1] : 0.f;
    if (U >= p_.avalancheMinUnstableM && p_.skiTriggerFactor > 0.0) {
      auto at = [&](int xx, int yy) { return surfaceOf(std::clamp(yy, 0, h - 1) * w + std::clamp(xx, 0, w - 1)); };
      const double gx = (at(cx + 1, cy) - at(cx - 1, cy)) / (2 * dx), gy = (at(cx, cy + 1) - at(cx, cy - 1)) / (2 * dy);
      const double s = std::hypot(gx, gy);
      if (s > tanC) {
        const double pRelease = std::min(1.0, p_.skiTriggerFactor * U * (s - tanC) / (1.0 - tanC));
        const Philox4x32 t = key.draw(id * 1000003ull + static_cast<uint64_t>(step), 1, RngStream::Skier);
        if (uniformOpenDouble(t.v[0], t.v[1]) < pRelease) {
          r.triggered = true, r.triggerX = cx, r.triggerY = cy;
          r.why = "triggered an avalanche";
          break;
        }
      }
    }
  }
  r.dropM = surfaceOf(y * w + x) - surfaceOf(cy * w + cx);
  backend_.skierCompaction(entered, static_cast<float>(p_.skiCompactionM));
  if (tracks_ && r.path.size() >= 2) {
    auto altitude = [&](double px, double py) {
      const int ix = std::clamp(static_cast<int>(px / dx), 0, w - 1), iy = std::clamp(static_cast<int>(py / dy), 0, h - 1);
      return static_cast<double>(surfaceOf(iy * w + ix));
    };
    const Path2 track = refineTrack(r.path, altitude, p_, 0.5 * std::min(dx, dy) / tracks_->factor());
    tracks_->stamp(track, p_.skiTrackDepthM, p_.skiTrackWidthM, surfaceOf);
  }
  return r;
}

}  // namespace snow
