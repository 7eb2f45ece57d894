#include "wind_timeline.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/bracket.h"
#include "core/grid_window.h"
#include "core/hash.h"

namespace snow {

namespace {

std::string windCacheKey(const Grid<float>& altitude, const Grid<uint8_t>& valid, const GridSpec& spec, const WindState& state,
                         const ModelParameters& p, const WindSolverOptions& o) {
  Fnv1a64 h;
  h.add("wind-v3");
  h.add(altitude.data(), altitude.size() * sizeof(float));
  h.add(valid.data(), valid.size());
  const double numbers[] = {static_cast<double>(spec.width), static_cast<double>(spec.height), spec.cellSizeXM, spec.cellSizeYM,
                            state.directionDeg, state.speedMps, p.venturiPerM, p.terrainWindEffect, p.windCapDecelerationMps2,
                            static_cast<double>(o.ordering == WindOrdering::RedBlack), o.toleranceM,
                            static_cast<double>(o.maxIterations)};
  h.add(numbers, sizeof numbers);
  return h.hex();
}

// One state's fields and loading on a part's cells: its own solver, or the whole grid's solved
// and cut to them where the part's solver cannot (the free stream turns).
void solvePart(const WindPart& part, const Grid<float>& altitude, const Grid<uint8_t>& valid, const GridSpec& spec, const WindState& s,
               const ModelParameters& params, const WindSolverOptions& options, WindField& f, Grid<float>& loading) {
  if (part.solve(altitude, valid, spec, s, params, options, f, loading)) return;
  const CellRect& c = part.cells;
  const WindField whole = computeWindField(altitude, valid, spec, s, params, options);
  f.windXMps = gridWindow(whole.windXMps, c), f.windYMps = gridWindow(whole.windYMps, c);
  f.windEffectZM = gridWindow(whole.windEffectZM, c), f.verticalSpeedMps = gridWindow(whole.verticalSpeedMps, c);
  f.stats = whole.stats;
  f.stats.ordering += " of the whole grid (the free stream turns)";
  loading = gridWindow(windLoading(whole, valid, spec), c);
}

}  // namespace

WindTimeline::WindTimeline(const Grid<float>& altitude, const Grid<uint8_t>& valid, const GridSpec& spec,
                           const WeatherTimeline& weather, const ModelParameters& params, const PrecomputeCache& cache,
                           const WindSolverOptions& options, std::ostream* log, const WindPart* part)
    : altitude_(&altitude), weather_(weather) {
  for (const auto& k : weather.keyframes) {
    if (!(k.state.windSpeedMps > 0.0)) {
      keyframeState_.push_back(-1);
      continue;
    }
    const WindState s{k.state.windDirectionDeg, k.state.windSpeedMps};
    int index = -1;
    for (size_t i = 0; i < states_.size(); ++i)
      if (states_[i] == s) index = static_cast<int>(i);
    if (index < 0) {
      states_.push_back(s);
      index = static_cast<int>(states_.size()) - 1;
    }
    keyframeState_.push_back(index);
  }
  if (part) {
    cells_ = part->cells;
    windowAltitude_ = gridWindow(altitude, part->cells);
    altitude_ = nullptr;
  }
  for (const WindState& s : states_) {
    WindField f;
    Grid<float> loading;
    // A part's entry keeps its loading: that needs the neighbouring ranks' vertical speeds.
    const CellRect c = part ? part->cells : CellRect::whole(spec);
    const std::string whole = windCacheKey(altitude, valid, spec, s, params, options);
    const std::string key = part ? partCacheKey(whole, c) : whole;
    std::vector<Grid<float>*> entry = {&f.windXMps, &f.windYMps, &f.windEffectZM, &f.verticalSpeedMps};
    if (part) entry.push_back(&loading);
    const bool found = cache.load("wind", key, c.width(), c.height(), entry);
    if (part && part->everyRankFound ? part->everyRankFound(found) : found) {
      ++cached_;
      f.stats.ordering = "cache";
      f.stats.converged = true;
      if (log)
        *log << "  wind from " << s.directionDeg << " deg at " << s.speedMps << " m/s: from the cache"
             << (part ? ", each rank its local grid's" : "") << "\n";
    } else {
      f = WindField(), loading = Grid<float>();  // a part some other rank did not find: all solve
      if (part) solvePart(*part, altitude, valid, spec, s, params, options, f, loading);
      else f = computeWindField(altitude, valid, spec, s, params, options);
      ++computed_;
      if (!found) cache.store("wind", key, {entry.begin(), entry.end()});  // a part this rank found stays as it is
      if (log)
        *log << "  wind from " << s.directionDeg << " deg at " << s.speedMps << " m/s: " << f.stats.ordering << ", "
             << f.stats.iterations << " iterations, residual " << f.stats.residual << " (" << f.stats.seconds << " s)"
             << (f.stats.converged ? "" : " NOT CONVERGED") << (part ? ", each rank its local grid" : "") << "\n";
    }
    loading_.push_back(loading.empty() ? windLoading(f, valid, spec) : std::move(loading));
    fields_.push_back(std::move(f));
  }
}

Grid<float> windLoading(const WindField& f, const Grid<uint8_t>& valid, const GridSpec& spec) {
  return windLoading(f, valid, spec, CellRect::whole(spec), CellRect::whole(spec));
}

Grid<float> windLoading(const WindField& f, const Grid<uint8_t>& valid, const GridSpec& spec, const CellRect& cells, const CellRect& over) {
  const int w = spec.width, h = spec.height;
  if (over.intersect(cells) != over || over.widened(1, 1, CellRect::whole(spec)).intersect(cells) != over.widened(1, 1, CellRect::whole(spec)))
    throw std::invalid_argument("windLoading: the field does not hold the cells and their neighbours");
  Grid<float> out(cells.width(), cells.height(), 0.f);
  const float* s = f.verticalSpeedMps.data();
  auto at = [&](int x, int y) { return s[cells.offsetOf(x, y)]; };
  for (int y = over.y0; y < over.y1; ++y)
    for (int x = over.x0; x < over.x1; ++x) {
      if (!valid(x, y)) continue;
      auto ok = [&](int i, int j) { return i >= 0 && j >= 0 && i < w && j < h && valid(i, j); };
      const bool l = ok(x - 1, y), r = ok(x + 1, y), u = ok(x, y - 1), d = ok(x, y + 1);
      const double gx = (l || r) ? ((r ? at(x + 1, y) : at(x, y)) - (l ? at(x - 1, y) : at(x, y))) / ((l && r ? 2.0 : 1.0) * spec.cellSizeXM) : 0.0;
      const double gy = (u || d) ? ((d ? at(x, y + 1) : at(x, y)) - (u ? at(x, y - 1) : at(x, y))) / ((u && d ? 2.0 : 1.0) * spec.cellSizeYM) : 0.0;
      const size_t i = cells.offsetOf(x, y);
      out.values()[i] = static_cast<float>(std::max(0.0, f.windXMps.values()[i] * gx + f.windYMps.values()[i] * gy));
    }
  return out;
}

void WindTimeline::releaseFields() {
  fields_ = std::vector<WindField>();
  loading_ = std::vector<Grid<float>>();
  released_ = true;
}

WindTimeline WindTimeline::withGrids(const std::function<Grid<float>(const Grid<float>&)>& each) const {
  WindTimeline out;
  out.weather_ = weather_;
  out.states_ = states_;
  out.keyframeState_ = keyframeState_;
  out.computed_ = computed_, out.cached_ = cached_, out.released_ = released_;
  for (const WindField& f : fields_) {
    WindField g;
    g.windXMps = each(f.windXMps), g.windYMps = each(f.windYMps), g.windEffectZM = each(f.windEffectZM);
    g.verticalSpeedMps = each(f.verticalSpeedMps);
    g.stats = f.stats;
    out.fields_.push_back(std::move(g));
  }
  for (const Grid<float>& g : loading_) out.loading_.push_back(each(g));
  return out;
}

WindTimeline WindTimeline::window(int x0, int y0, int width, int height) const {
  auto cut = [&](const Grid<float>& g) { return gridWindow(g, x0, y0, width, height); };
  WindTimeline out = withGrids(cut);
  const CellRect base = cells_.value_or(CellRect{0, 0, altitude().width(), altitude().height()});
  out.cells_ = CellRect{base.x0 + x0, base.y0 + y0, base.x0 + x0 + width, base.y0 + y0 + height};
  out.windowAltitude_ = cut(altitude());
  return out;
}

WindTimeline WindTimeline::gatheredWhole(const Grid<float>& altitude, const std::function<Grid<float>(const Grid<float>&)>& gather) const {
  WindTimeline out = withGrids(gather);
  out.altitude_ = &altitude;
  return out;
}

WindFieldsAtDay WindTimeline::at(double day) const {
  if (released_ && !states_.empty()) throw std::logic_error("WindTimeline::at: the wind fields were released");
  WindFieldsAtDay out;
  const Grid<float>& altitude = this->altitude();
  const int w = altitude.width(), h = altitude.height();
  out.windXMps.resize(w, h, 0.f);
  out.windYMps.resize(w, h, 0.f);
  out.windEffectZM = altitude;
  out.windLoadingMps2.resize(w, h, 0.f);
  if (states_.empty()) return out;
  // The bracketing keyframes and the weight of the later one, as WeatherTimeline::at uses.
  const auto& keys = weather_.keyframes;
  const Bracket br = bracketOf(keys.size(), day, [&](size_t i) { return keys[i].day; });
  const size_t k0 = br.first, k1 = br.second;
  const double t = br.weight;
  auto add = [&](int state, double weight) {
    if (weight <= 0.0) return;
    if (state < 0) {  // calm keyframe: no wind, the surface on the ground
      for (size_t i = 0; i < out.windEffectZM.size(); ++i)
        out.windEffectZM.values()[i] += static_cast<float>(weight * altitude.values()[i]);
      return;
    }
    const WindField& f = fields_[state];
    for (size_t i = 0; i < out.windXMps.size(); ++i) {
      out.windXMps.values()[i] += static_cast<float>(weight * f.windXMps.values()[i]);
      out.windYMps.values()[i] += static_cast<float>(weight * f.windYMps.values()[i]);
      out.windEffectZM.values()[i] += static_cast<float>(weight * f.windEffectZM.values()[i]);
      out.windLoadingMps2.values()[i] += static_cast<float>(weight * loading_[state].values()[i]);
    }
  };
  out.windEffectZM.fill(0.f);
  add(keyframeState_[k0], 1.0 - t);
  add(keyframeState_[k1], t);
  return out;
}

}  // namespace snow
