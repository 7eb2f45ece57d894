#include "art_direction.h"

#include <fstream>
#include <iomanip>
#include <map>
#include <memory>
#include <sstream>
#include <tuple>

#include "core/errors.h"
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
  RasterCache(const TerrainInfo& terrain, const SnowState& state, std::ostream& log, std::vector<ManifestRaster>& records)
      : terrain_(terrain), state_(state), log_(log), records_(records) {}

  const Grid<float>& get(const RasterRef& ref, RasterUse use, const std::string& role) {
    auto pair = [](const std::optional<std::array<double, 2>>& p) {
      return p ? std::make_tuple(true, (*p)[0], (*p)[1]) : std::make_tuple(false, 0.0, 0.0);
    };
    const auto key = std::make_tuple(ref.file, pair(ref.values), pair(ref.range), ref.invert, static_cast<int>(use));
    auto it = cache_.find(key);
    if (it == cache_.end()) {
      // Read, placed and described once per raster; each use below only adds its role.
      Entry e{mapRaster(ref, use, terrain_, state_.validCell), {}};
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
  const TerrainInfo& terrain_;
  const SnowState& state_;
  std::ostream& log_;
  std::vector<ManifestRaster>& records_;
  struct Entry {
    MappedRaster mapped;
    ManifestRaster record;  // all but the role and the source
  };
  std::map<Key, Entry> cache_;
};

}  // namespace

ArtDirectionPlan prepareArtDirection(const Scene& scene, const TerrainInfo& terrain, SnowState& state, std::ostream& log) {
  ArtDirectionPlan plan;
  bool anyEvent = false;
  for (const auto* events : {&scene.userAvalanches, &scene.userSkiers})
    for (const auto& e : *events) anyEvent = anyEvent || e.mask.has_value();
  bool anyInitial = false;
  for (const auto& l : scene.initialSnow) anyInitial = anyInitial || l.kind != InitialSnowLayer::Kind::None;
  const bool bedformMask = scene.bedforms.enabled && scene.bedforms.mask.has_value();
  if (!anyEvent && !anyInitial && scene.edits.empty() && !scene.multipliers.any() && !bedformMask) return plan;

  log << "art direction:\n";
  RasterCache rasters(terrain, state, log, plan.rasters);
  const size_t n = state.spec.cellCount();
  const double area = state.spec.cellAreaM2();
  const auto& valid = state.validCell.values();

  // Initial snow cover, layer by layer.
  for (int l = 0; l < kSnowLayerCount; ++l) {
    const InitialSnowLayer& spec = scene.initialSnow[static_cast<size_t>(l)];
    if (spec.kind == InitialSnowLayer::Kind::None) continue;
    const std::string role = std::string("initial_snow.") + snowLayerName(static_cast<SnowLayer>(l));
    std::vector<float>& layer = state.layer(static_cast<SnowLayer>(l)).values();
    const Grid<float>* raster = nullptr;
    if (spec.kind == InitialSnowLayer::Kind::Raster) raster = &rasters.get(spec.raster, RasterUse::Depth, role);
    if (spec.kind == InitialSnowLayer::Kind::Mask) raster = &rasters.get(spec.raster, RasterUse::Mask, role + ".mask");
    double volume = 0.0;
    for (size_t i = 0; i < n; ++i) {
      if (!valid[i]) {
        layer[i] = 0.f;
        continue;
      }
      switch (spec.kind) {
        case InitialSnowLayer::Kind::Constant: layer[i] = static_cast<float>(spec.depthM); break;
        case InitialSnowLayer::Kind::Raster: layer[i] = raster->values()[i]; break;
        case InitialSnowLayer::Kind::Mask: layer[i] = static_cast<float>(raster->values()[i] * spec.depthM); break;
        case InitialSnowLayer::Kind::None: break;
      }
      volume += static_cast<double>(layer[i]) * area;
    }
    plan.initialSnowM3 += volume;
    if (spec.kind == InitialSnowLayer::Kind::Constant)
      log << "  " << role << ": " << num(spec.depthM) << " m everywhere\n";
    log << "  " << role << ": " << std::scientific << std::setprecision(4) << volume << std::defaultfloat << " m^3 placed\n";
  }

  // Multipliers and the no-snow mask.
  const Multipliers& mu = scene.multipliers;
  const std::pair<const std::optional<RasterRef>*, Grid<float>*> factors[] = {
      {&mu.snowfall, &state.snowfallFactor},
      {&mu.melt, &state.meltFactor},
      {&mu.windErosion, &state.windErosionFactor},
      {&mu.avalancheRelease, &state.avalancheReleaseFactor},
      {&mu.skierSpawn, &state.skierSpawnFactor}};
  const char* names[] = {"snowfall", "melt", "wind_erosion", "avalanche_release", "skier_spawn"};
  for (size_t k = 0; k < std::size(factors); ++k)
    if (*factors[k].first) *factors[k].second = rasters.get(**factors[k].first, RasterUse::Mask, std::string("multipliers.") + names[k]);
  if (mu.noSnow) {
    const Grid<float>& m = rasters.get(*mu.noSnow, RasterUse::Mask, "multipliers.no_snow");
    state.noSnow = Grid<uint8_t>(state.spec.width, state.spec.height, 0);
    size_t cells = 0;
    for (size_t i = 0; i < n; ++i)
      if (valid[i] && m.values()[i] >= 0.5f) state.noSnow.values()[i] = 1, ++cells;
    log << "  multipliers.no_snow: " << cells << " cells kept bare (" << num(100.0 * cells / std::max<size_t>(1, n)) << " % of the grid)\n";
  }

  // Where the wind bedforms run.
  if (bedformMask) {
    const Grid<float>& m = rasters.get(*scene.bedforms.mask, RasterUse::Mask, "bedforms.mask");
    state.bedformMask = Grid<uint8_t>(state.spec.width, state.spec.height, 0);
    size_t cells = 0;
    for (size_t i = 0; i < n; ++i)
      if (valid[i] && m.values()[i] >= 0.5f) state.bedformMask.values()[i] = 1, ++cells;
    log << "  bedforms.mask: " << cells << " cells (" << num(100.0 * cells / std::max<size_t>(1, n)) << " % of the grid)\n";
  }

  // Timeline edits.
  for (size_t k = 0; k < scene.edits.size(); ++k) {
    const EditSpec& e = scene.edits[k];
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
    std::ostringstream label;
    label << "edit " << k + 1 << ": " << enumName(e.op) << " " << e.layer;
    if (!e.to.empty()) label << " to " << e.to;
    if (e.depthM) label << " " << num(*e.depthM) << " m";
    label << (e.mask ? " within " + e.mask->label() : std::string(" everywhere")) << " on day " << num(e.day);
    edit.label = rec.label = label.str();
    plan.edits.push_back(std::move(edit));
    plan.editRecords.push_back(rec);
  }

  // Masked events: an avalanche from every unstable cell inside the mask (>= 0.5), skiers from
  // start cells drawn by the mask's values.
  for (size_t k = 0; k < scene.userAvalanches.size(); ++k) {
    const auto& a = scene.userAvalanches[k];
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
  for (size_t k = 0; k < scene.userSkiers.size(); ++k) {
    const auto& a = scene.userSkiers[k];
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
  return plan;
}

}  // namespace snow
