// The season's wind: one precomputed field and wind-effect surface per distinct wind state of
// the weather keyframes, blended linearly between keyframes (the same weights as the keyframes'
// own interpolation). No wind anywhere in the season: nothing is computed.
#pragma once
#include <algorithm>
#include <functional>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "cache.h"
#include "core/weather.h"
#include "wind.h"

namespace snow {

struct WindFieldsAtDay {
  Grid<float> windXMps, windYMps, windEffectZM;
  Grid<float> windLoadingMps2;  // max(0, W . grad W_sz): where the vertical wind speed rises
};

// max(0, W . grad W_sz) by central differences (NODATA neighbours skipped).
Grid<float> windLoading(const WindField& field, const Grid<uint8_t>& valid, const GridSpec& spec);
// The same for the cells `over` of a field held on `fieldCells` (which holds their neighbours):
// a grid of fieldCells, zero outside `over`.
Grid<float> windLoading(const WindField& field, const Grid<uint8_t>& valid, const GridSpec& spec, const CellRect& fieldCells,
                        const CellRect& over);

// A timeline made for part of the grid (a rank's local grid, across ranks): its cells, and how a
// state's fields and loading are solved on them (the whole grid's bytes), or false where they
// cannot be (the timeline then solves the whole grid and cuts it). Every rank's timeline calls
// `solve` for the same states in the same order. Each rank's part of a state is an entry of its
// own in the cache (partCacheKey); `everyRankFound` says whether every rank found its part there
// (this rank's `found` beside the others'; empty: a part alone, its own finding), so the ranks
// read them all or solve together (a rank that read its part alone would leave the others'
// exchanges waiting).
struct WindPart {
  CellRect cells;
  std::function<bool(const Grid<float>& altitude, const Grid<uint8_t>& valid, const GridSpec& spec, const WindState& state,
                     const ModelParameters& params, const WindSolverOptions& options, WindField& fields, Grid<float>& loading)>
      solve;
  std::function<bool(bool found)> everyRankFound{};
};

class WindTimeline {
 public:
  // Computes (or loads from `cache`) the field of every distinct wind state the keyframes use.
  WindTimeline(const Grid<float>& altitude, const Grid<uint8_t>& valid, const GridSpec& spec, const WeatherTimeline& weather,
               const ModelParameters& params, const PrecomputeCache& cache, const WindSolverOptions& options = {},
               std::ostream* log = nullptr, const WindPart* part = nullptr);

  bool hasWind() const { return !states_.empty(); }
  // True when the fields differ between days (several states, or calm keyframes among windy ones).
  bool varies() const {
    return states_.size() > 1 || (hasWind() && std::find(keyframeState_.begin(), keyframeState_.end(), -1) != keyframeState_.end());
  }
  size_t stateCount() const { return states_.size(); }
  size_t computedStates() const { return computed_; }
  size_t cachedStates() const { return cached_; }
  const std::vector<WindState>& states() const { return states_; }
  const WindField& field(size_t state) const { return fields_[state]; }
  // The fields in force on `day`; zero wind and W_z = A when the season has no wind.
  WindFieldsAtDay at(double day) const;
  // Frees the fields once nothing will read them (a constant wind the state holds, no output
  // reading wind); at() then throws.
  void releaseFields();
  // One rectangle of its cells (a rank's local grid, across ranks), the altitude included: its
  // at() gives those cells' bytes of this one's (the loading made on the whole grid, then cut).
  WindTimeline window(int x0, int y0, int width, int height) const;
  // The whole grid's cells its fields cover: nullopt for the whole grid.
  const std::optional<CellRect>& cells() const { return cells_; }
  // This part's timeline made the whole grid's (across ranks, where every rank made its part):
  // each of its grids by `gather`, which makes the whole grid's from every rank's part of it, over
  // the whole grid's `altitude` (which must outlive it).
  WindTimeline gatheredWhole(const Grid<float>& altitude, const std::function<Grid<float>(const Grid<float>&)>& gather) const;

 private:
  WindTimeline() = default;
  // A copy of its states and keyframes with each of its grids (fields and loading) made by `each`.
  WindTimeline withGrids(const std::function<Grid<float>(const Grid<float>&)>& each) const;
  const Grid<float>& altitude() const { return altitude_ ? *altitude_ : windowAltitude_; }
  const Grid<float>* altitude_ = nullptr;  // the terrain's; null in a window, which holds its own
  Grid<float> windowAltitude_;
  WeatherTimeline weather_;
  std::vector<WindState> states_;
  std::vector<WindField> fields_;
  std::vector<Grid<float>> loading_;
  std::vector<int> keyframeState_;  // per keyframe: index into states_, -1 for calm
  size_t computed_ = 0, cached_ = 0;
  bool released_ = false;
  std::optional<CellRect> cells_;
};

}  // namespace snow
