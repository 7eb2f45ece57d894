#include "art_direction.h"

#include <fstream>
#include <iomanip>
#include <map>
#include <memory>
#include <sstream>
#include <tuple>

#include "core/errors.h"
#include "core/grid_window.h"
#include "core/hash.h"
#include "inputs/raster_input.h"

namespace snow {
namespace {

std::string num(double v) {
  std::ostringstream o;
  o << std::setprecision(4) << v;
  return o.str();
}

int layerIndex(const std::string& name) {
  for (int l = 0; l < kSnowLayerCount; ++l)
    if (name == snowLayerName(static_cast<SnowLayer>(l))) return l;
  throw InputError("unknown snow layer '" + name + "'");
}

// Maps each raster once per (file, values, range, invert, use), and lists every use.
class RasterCache {
 public:
  RasterCache(const Terrain& terrain, std::ostream& log, std::vector<ManifestRaster>& records)
      : terrain_(terrain), log_(log), records_(records) {}

  const Grid<float>& get(const RasterRef& ref, RasterUse use, const std::string& role) {
    auto pair = [](const std::optional<std::array<double, 2>>& p) {
      return p ? std::make_tuple(true, (*p)[0], (*p)[1]) : std::make_tuple(false, 0.0, 0.0);
    };
    const auto key = std::make_tuple(ref.file, pair(ref.values), pair(ref.range), ref.invert, static_cast<int>(use));
    auto it = cache_.find(key);
    if (it == cache_.end()) {
      // Read, placed and described once per raster; each use below only adds its role.
      Entry e{mapRaster(ref, use, terrain_.info, terrain_.valid), {}};
      const MappedRaster& m = e.mapped;
      ManifestRaster& d = e.record;
      d.hash = hashFileFnv1a64(ref.file);
      d.reader = m.reader;
      d.placement = m.placement;
      d.description = m.description;
      d.width = m.sourceWidth;
      d.height = m.sourceHeight;
      d.coverage = m.coverage;
      d.minValue = m.minValue;
      d.maxValue = m.maxValue;
      d.meanValue = m.meanValue;
      it = cache_.emplace(key, std::move(e)).first;
    }
    const MappedRaster& m = it->second.mapped;
    ManifestRaster r = it->second.record;
    r.role = role;
    r.source = ref.label();
    records_.push_back(r);
    log_ << "  " << role << ": " << ref.label() << ", " << m.description << "; " << num(m.minValue) << " to " << num(m.maxValue)
         << ", mean " << num(m.meanValue) << "\n";
    return m.values;
  }

 private:
  using Key = std::tuple<std::string, std::tuple<bool, double, double>, std::tuple<bool, double, double>, bool, int>;
  const Terrain& terrain_;
  std::ostream& log_;
  std::vector<ManifestRaster>& records_;
  struct Entry {
    MappedRaster mapped;
    ManifestRaster record;  // all but the role and the source
  };
  std::map<Key, Entry> cache_;
};

// True when the scene asks for anything this stage does; otherwise the bake skips it silently.
bool needsArtDirection(const Scene& scene) {
  bool anyEvent = false;
  for (const auto* events : {&scene.userAvalanches, &scene.userSkiers})
    for (const auto& e : *events) anyEvent = anyEvent || e.mask.has_value();
  bool anyInitial = false;
  for (const auto& l : scene.initialSnow) anyInitial = anyInitial || l.kind != InitialSnowLayer::Kind::None;
  const bool bedformMask = scene.bedforms.enabled && scene.bedforms.mask.has_value();
  return anyEvent || anyInitial || !scene.edits.empty() || scene.multipliers.any() || bedformMask;
}

// Fills one snow layer from its [initial_snow] entry on `cells` (the state's); returns the volume
// placed on the whole grid (m^3), summed in the whole grid's order whatever `cells`.
double placeInitialLayer(int l, const InitialSnowLayer& spec, RasterCache& rasters, const Grid<uint8_t>& wholeValid, const CellRect& cells,
                         SnowState& state, std::ostream& log) {
  const double area = state.spec.cellAreaM2();
  const std::string role = std::string("initial_snow.") + snowLayerName(static_cast<SnowLayer>(l));
  Grid<float>& layer = state.layer(static_cast<SnowLayer>(l));
  const Grid<float>* raster = nullptr;
  if (spec.kind == InitialSnowLayer::Kind::Raster) raster = &rasters.get(spec.raster, RasterUse::Depth, role);
  if (spec.kind == InitialSnowLayer::Kind::Mask) raster = &rasters.get(spec.raster, RasterUse::Mask, role + ".mask");
  double volume = 0.0;
  for (int y = 0; y < wholeValid.height(); ++y)
    for (int x = 0; x < wholeValid.width(); ++x) {
      float depth = 0.f;
      if (wholeValid(x, y)) {
        switch (spec.kind) {
          case InitialSnowLayer::Kind::Constant: depth = static_cast<float>(spec.depthM); break;
          case InitialSnowLayer::Kind::Raster: depth = (*raster)(x, y); break;
          case InitialSnowLayer::Kind::Mask: depth = static_cast<float>((*raster)(x, y) * spec.depthM); break;
          case InitialSnowLayer::Kind::None: break;  // not placed (placeInitialSnow skips it)
        }
        // -0 as +0: every kernel would drop the sign, and a step skipped as changing nothing
        // (a zero rate, SeasonRun::skipStep) must leave the bytes it would have left.
        if (depth == 0.f) depth = 0.f;
        volume += static_cast<double>(depth) * area;
      }
      if (cells.contains(x, y)) layer(x - cells.x0, y - cells.y0) = depth;
    }
  if (spec.kind == InitialSnowLayer::Kind::Constant) log << "  " << role << ": " << num(spec.depthM) << " m everywhere\n";
  log << "  " << role << ": " << std::scientific << std::setprecision(4) << volume << std::defaultfloat << " m^3 placed\n";
  return volume;
}

// Initial snow cover, layer by layer; returns the total volume placed (m^3).
double placeInitialSnow(const Scene& scene, RasterCache& rasters, const Grid<uint8_t>& wholeValid, const CellRect& cells, SnowState& state,
                        std::ostream& log) {
  double total = 0.0;
  for (int l = 0; l < kSnowLayerCount; ++l) {
    const InitialSnowLayer& spec = scene.initialSnow[static_cast<size_t>(l)];
    if (spec.kind == InitialSnowLayer::Kind::None) continue;
    total += placeInitialLayer(l, spec, rasters, wholeValid, cells, state, log);
  }
  return total;
}

// A 0/1 grid on `cells` of the valid cells where `mask` is at least 0.5; `count` counts the ones
// of the whole grid.
Grid<uint8_t> thresholdMask(const Grid<float>& mask, const Grid<uint8_t>& wholeValid, const CellRect& cells, size_t& count) {
  Grid<uint8_t> whole(wholeValid.width(), wholeValid.height(), 0);
  count = 0;
  for (size_t i = 0; i < whole.size(); ++i)
    if (wholeValid.values()[i] && mask.values()[i] >= 0.5f) whole.values()[i] = 1, ++count;
  return cells == CellRect{0, 0, whole.width(), whole.height()} ? whole : gridWindow(whole, cells);
}

std::string percentOfGrid(size_t cells, size_t n) { return num(100.0 * cells / std::max<size_t>(1, n)); }

// The per-cell multipliers and the no-snow mask, on `cells` (the state's).
void applyMultipliers(const Multipliers& mu, RasterCache& rasters, const Grid<uint8_t>& wholeValid, const CellRect& cells, SnowState& state,
                      std::ostream& log) {
  const std::pair<const std::optional<RasterRef>*, Grid<float>*> factors[] = {
      {&mu.snowfall, &state.snowfallFactor},
      {&mu.melt, &state.meltFactor},
      {&mu.windErosion, &state.windErosionFactor},
      {&mu.avalancheRelease, &state.avalancheReleaseFactor},
      {&mu.skierSpawn, &state.skierSpawnFactor}};
  const char* names[] = {"snowfall", "melt", "wind_erosion", "avalanche_release", "skier_spawn"};
  for (size_t k = 0; k < std::size(factors); ++k)
    if (*factors[k].first)
      *factors[k].second = gridWindow(rasters.get(**factors[k].first, RasterUse::Mask, std::string("multipliers.") + names[k]), cells);
  if (!mu.noSnow) return;
  size_t count = 0;
  state.noSnow = thresholdMask(rasters.get(*mu.noSnow, RasterUse::Mask, "multipliers.no_snow"), wholeValid, cells, count);
  log << "  multipliers.no_snow: " << count << " cells kept bare (" << percentOfGrid(count, wholeValid.size()) << " % of the grid)\n";
}

// Where the wind bedforms run.
void applyBedformMask(const RasterRef& mask, RasterCache& rasters, const Grid<uint8_t>& wholeValid, const CellRect& cells, SnowState& state,
                      std::ostream& log) {
  size_t count = 0;
  state.bedformMask = thresholdMask(rasters.get(mask, RasterUse::Mask, "bedforms.mask"), wholeValid, cells, count);
  log << "  bedforms.mask: " << count << " cells (" << percentOfGrid(count, wholeValid.size()) << " % of the grid)\n";
}

// The edit's one-line description, shared by the log and the manifest.
std::string editLabel(size_t k, const EditSpec& e) {
  std::ostringstream label;
  label << "edit " << k + 1 << ": " << enumName(e.op) << " " << e.layer;
  if (!e.to.empty()) label << " to " << e.to;
  if (e.depthM) label << " " << num(*e.depthM) << " m";
  label << (e.mask ? " within " + e.mask->label() : std::string(" everywhere")) << " on day " << num(e.day);
  return label.str();
}

// Timeline edit k, as the season runs it and as the manifest records it.
void addEdit(size_t k, const EditSpec& e, RasterCache& rasters, ArtDirectionPlan& plan) {
  SeasonEdit edit;
  edit.day = e.day;
  edit.args.op = e.op;
  edit.args.layer = layerIndex(e.layer);
  edit.args.toLayer = e.to.empty() ? edit.args.layer : layerIndex(e.to);
  edit.args.hasDepth = e.depthM.has_value();
  edit.args.depthM = static_cast<float>(e.depthM.value_or(0.0));
  ManifestEdit rec;
  rec.day = e.day, rec.op = enumName(e.op), rec.layer = e.layer, rec.to = e.to, rec.depthM = e.depthM.value_or(-1.0);
  if (e.mask) {
    const std::string role = "edits[" + std::to_string(k) + "].mask";
    edit.weights = std::make_shared<const std::vector<float>>(rasters.get(*e.mask, RasterUse::Mask, role).values());
    rec.mask = e.mask->label();
  }
  edit.label = rec.label = editLabel(k, e);
  plan.edits.push_back(std::move(edit));
  plan.editRecords.push_back(rec);
}

// A masked avalanche releases from every unstable cell inside the mask (>= 0.5).
void addMaskedAvalanches(const Scene& scene, RasterCache& rasters, const Grid<uint8_t>& wholeValid, ArtDirectionPlan& plan) {
  const size_t n = wholeValid.size();
  const auto& valid = wholeValid.values();
  for (const auto& a : scene.userAvalanches) {
    if (!a.mask) continue;
    const Grid<float>& m = rasters.get(*a.mask, RasterUse::Mask, "events (avalanche, line " + std::to_string(a.line) + ").mask");
    auto zone = std::make_shared<std::vector<uint8_t>>(n, 0);
    size_t cells = 0;
    for (size_t i = 0; i < n; ++i)
      if (valid[i] && m.values()[i] >= 0.5f) (*zone)[i] = 1, ++cells;
    if (cells == 0)
      throw InputError(scene.sourceName + ":" + std::to_string(a.line) + ": events.mask: " + a.mask->label() +
                       " marks no terrain cell (no value >= 0.5 on the grid)");
    UserAvalanche u;
    u.day = a.day;
    u.zone = zone;
    plan.avalanches.push_back(u);
  }
}

// Masked skiers start from cells drawn by the mask's values.
void addMaskedSkiers(const Scene& scene, RasterCache& rasters, const Grid<uint8_t>& wholeValid, ArtDirectionPlan& plan) {
  const size_t n = wholeValid.size();
  const auto& valid = wholeValid.values();
  for (const auto& a : scene.userSkiers) {
    if (!a.mask) continue;
    const Grid<float>& m = rasters.get(*a.mask, RasterUse::Mask, "events (skier, line " + std::to_string(a.line) + ").mask");
    double total = 0.0;
    for (size_t i = 0; i < n; ++i) total += valid[i] ? m.values()[i] : 0.f;
    if (!(total > 0.0))
      throw InputError(scene.sourceName + ":" + std::to_string(a.line) + ": events.mask: " + a.mask->label() + " is 0 on every terrain cell");
    UserSkier u;
    u.day = a.day;
    u.count = a.count;
    u.startWeights = std::make_shared<const std::vector<float>>(m.values());
    plan.skiers.push_back(u);
  }
}

}  // namespace

ArtDirectionPlan prepareArtDirection(const Scene& scene, const Terrain& terrain, const CellRect& cells, SnowState& state, std::ostream& log) {
  ArtDirectionPlan plan;
  if (!needsArtDirection(scene)) return plan;
  if (state.spec.width != cells.width() || state.spec.height != cells.height())
    throw std::invalid_argument("prepareArtDirection: the state does not hold the cells");
  log << "art direction:\n";
  // The order below is the order of the log lines and of the manifest's raster records.
  const Grid<uint8_t>& valid = terrain.valid;
  RasterCache rasters(terrain, log, plan.rasters);
  plan.initialSnowM3 = placeInitialSnow(scene, rasters, valid, cells, state, log);
  applyMultipliers(scene.multipliers, rasters, valid, cells, state, log);
  if (scene.bedforms.enabled && scene.bedforms.mask) applyBedformMask(*scene.bedforms.mask, rasters, valid, cells, state, log);
  for (size_t k = 0; k < scene.edits.size(); ++k) addEdit(k, scene.edits[k], rasters, plan);
  addMaskedAvalanches(scene, rasters, valid, plan);
  addMaskedSkiers(scene, rasters, valid, plan);
  return plan;
}

}  // namespace snow
