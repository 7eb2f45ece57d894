// The scene schema's table (see scene_schema.h). Each rule binds its key to a member (a chain of
// member pointers into the Scene or an array element), or to a small setter where the value
// needs converting (scene_bindings.h); its doc string is what docs/scene.md says of the key.
#include "scene_schema.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <sstream>
#include <type_traits>

#include "core/errors.h"
#include "scene/sun_quality.h"
#include "scene/layers.h"
#include "scene_bindings.h"

namespace snow {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
using binding::at;
using binding::custom;
using binding::read;
using binding::show;

// An array of exactly n numbers (the rule already checked each is a number in range); `what` is
// the message when the count is wrong (default: how many it needs and has).
std::vector<double> numbersOf(const toml::node& node, size_t n, const BindContext& c, const std::string& what = {}) {
  std::vector<double> values;
  for (auto&& e : *node.as_array()) values.push_back(e.value<double>().value());
  if (values.size() != n)
    fail(c.source, node, c.path, what.empty() ? "needs " + std::to_string(n) + " numbers, has " + std::to_string(values.size()) : what);
  return values;
}
bool whole(const std::vector<double>& v) {
  for (double x : v)
    if (x != std::floor(x)) return false;
  return true;
}

// --- the setters that convert
Bind<Scene> terrainFile() {
  return custom<Scene>(
      [](Scene& s, const toml::node& n, const BindContext& c) {
        s.terrain.file = resolvePath(n.as_string()->get(), s.baseDir);
        s.terrain.declaredAt = where(c.source, n.source());
      },
      [](const Scene& s) { return show(s.terrain.file); });
}
Bind<Scene> terrainBuiltin() {
  return custom<Scene>(
      [](Scene& s, const toml::node& n, const BindContext& c) {
        s.terrain.builtin = true;
        s.terrain.declaredAt = where(c.source, n.source());
      },
      [](const Scene& s) { return s.terrain.builtin ? show(std::string("ridged")) : "none"; });
}
Bind<Scene> heightRange() {
  return custom<Scene>(
      [](Scene& s, const toml::node& n, const BindContext& c) {
        const auto r = numbersOf(n, 2, c);
        if (!(r[1] > r[0])) fail(c.source, n, c.path, "needs [lowest, highest] with highest > lowest");
        s.terrain.heightRangeM = std::array<double, 2>{r[0], r[1]};
      },
      [](const Scene& s) { return show(s.terrain.heightRangeM); });
}
Bind<Scene> heightLimits() {
  return custom<Scene>(
      [](Scene& s, const toml::node& n, const BindContext& c) {
        const auto r = numbersOf(n, 2, c);
        if (!(r[1] > r[0])) fail(c.source, n, c.path, "needs [lowest, highest] with highest > lowest");
        s.terrain.heightLimitsM = {r[0], r[1]};
      },
      [](const Scene& s) { return show(s.terrain.heightLimitsM); });
}
Bind<Scene> coverageDepths() {
  return custom<Scene>(
      [](Scene& s, const toml::node& n, const BindContext& c) {
        const auto r = numbersOf(n, 2, c);
        if (!(r[1] > r[0])) fail(c.source, n, c.path, "needs [bare, covered] depths with covered > bare");
        s.outputs.coverageDepthsM = {r[0], r[1]};
      },
      [](const Scene& s) { return show(s.outputs.coverageDepthsM); });
}
Bind<Scene> cropWindow() {
  return custom<Scene>(
      [](Scene& s, const toml::node& n, const BindContext& c) {
        const auto r = numbersOf(n, 4, c);
        if (!(r[2] > r[0] && r[3] > r[1]))
          fail(c.source, n, c.path, "needs [west, north, east, south] metres from the north-west corner, east > west and south > north");
        s.terrain.cropM = std::array<double, 4>{r[0], r[1], r[2], r[3]};
      },
      [](const Scene& s) { return show(s.terrain.cropM); });
}
Bind<Scene> resampleSize() {
  return custom<Scene>(
      [](Scene& s, const toml::node& n, const BindContext& c) {
        const auto r = numbersOf(n, 2, c);
        if (!whole(r)) fail(c.source, n, c.path, "needs whole numbers [width, height]");
        s.terrain.resampleSize = std::array<int, 2>{static_cast<int>(r[0]), static_cast<int>(r[1])};
      },
      [](const Scene& s) { return show(s.terrain.resampleSize); });
}
Bind<Scene> startDate() {
  return custom<Scene>(
      [](Scene& s, const toml::node& n, const BindContext& c) {
        const auto date = n.is_date() ? std::optional<toml::date>(n.as_date()->get()) : parseDate(n.as_string()->get());
        if (!isCalendarDate(*date)) {
          std::ostringstream o;
          o << *date << " is not a date: month " << int(date->month) << " of " << date->year << " has " << daysInMonth(date->year, date->month)
            << " days";
          fail(c.source, n, c.path, o.str());
        }
        s.startYear = date->year, s.startMonth = date->month, s.startDay = date->day;
      },
      [](const Scene& s) {
        char text[16];
        std::snprintf(text, sizeof text, "%04d-%02d-%02d", s.startYear, s.startMonth, s.startDay);
        return std::string(text);
      });
}
Bind<Scene> meshParts() {
  return custom<Scene>(
      [](Scene& s, const toml::node& n, const BindContext& c) {
        read(n, s.outputs.meshParts);
        if (s.outputs.meshParts.empty()) fail(c.source, n, c.path, "needs \"surface\", \"body\" or both");
      },
      [](const Scene& s) { return show(s.outputs.meshParts); });
}
Bind<Scene> displacementSize() {
  return custom<Scene>(
      [](Scene& s, const toml::node& n, const BindContext& c) {
        std::vector<double> a;
        read(n, a);
        if (a.size() != 2 || !whole(a)) fail(c.source, n, c.path, "needs whole numbers [width, height]");
        s.outputs.displacementWidth = static_cast<int>(a[0]);
        s.outputs.displacementHeight = static_cast<int>(a[1]);
      },
      [](const Scene& s) {
        return s.outputs.displacementWidth > 0 ? show(std::vector<int>{s.outputs.displacementWidth, s.outputs.displacementHeight}) : "none";
      });
}
// [outputs.ranges] LAYER = "own" | "season" | [lo, hi]; a layer not given takes its kind's default.
Bind<Scene> layerRange(const std::string& layer) {
  return custom<Scene>(
      [layer](Scene& s, const toml::node& n, const BindContext& c) {
        LayerRange r;
        if (const auto* text = n.as_string()) {
          if (text->get() != "own" && text->get() != "season") fail(c.source, n, c.path, "needs \"own\", \"season\" or [lo, hi]");
          r.mode = text->get() == "own" ? RangeMode::Own : RangeMode::Season;
        } else if (n.is_array()) {
          const auto* a = n.as_array();
          if (a->size() != 2 || !(*a)[0].is_number() || !(*a)[1].is_number()) fail(c.source, n, c.path, "needs [lo, hi], two numbers");
          r.mode = RangeMode::Fixed, r.lo = (*a)[0].value<double>().value(), r.hi = (*a)[1].value<double>().value();
          if (!std::isfinite(r.lo) || !std::isfinite(r.hi) || !(r.hi > r.lo)) fail(c.source, n, c.path, "needs [lo, hi] with hi > lo");
        } else {
          fail(c.source, n, c.path, "needs \"own\", \"season\" or [lo, hi]");
        }
        s.outputs.ranges[layer] = r;
      },
      [layer](const Scene& s) {
        const auto it = s.outputs.ranges.find(layer);
        if (it == s.outputs.ranges.end()) return std::string("the layer kind's (see Value ranges)");
        const LayerRange& r = it->second;
        return r.mode == RangeMode::Own ? show(std::string("own")) : r.mode == RangeMode::Season ? show(std::string("season")) : show(std::vector<double>{r.lo, r.hi});
      });
}
Bind<Scene> resize() {
  return custom<Scene>(
      [](Scene& s, const toml::node& n, const BindContext& c) {
        std::vector<double> a;
        read(n, a);
        if (a.size() != 2 || !whole(a)) fail(c.source, n, c.path, "needs whole numbers [width, height], each at least 1");
        s.outputs.resizeWidth = static_cast<int>(a[0]), s.outputs.resizeHeight = static_cast<int>(a[1]);
      },
      [](const Scene& s) { return s.outputs.resizeWidth > 0 ? show(std::vector<int>{s.outputs.resizeWidth, s.outputs.resizeHeight}) : "none"; });
}
Bind<Scene> tilesResize() {
  return custom<Scene>(
      [](Scene& s, const toml::node& n, const BindContext& c) {
        std::vector<double> a;
        read(n, a);
        if (a.size() != 2 || !whole(a)) fail(c.source, n, c.path, "needs whole numbers [width, height], each at least 1");
        s.outputs.tiles.resizeWidth = static_cast<int>(a[0]), s.outputs.tiles.resizeHeight = static_cast<int>(a[1]);
      },
      [](const Scene& s) {
        const OutputTiles& t = s.outputs.tiles;
        return t.resizeWidth > 0 ? show(std::vector<int>{t.resizeWidth, t.resizeHeight}) : "none";
      });
}
Bind<Scene> bedformMask() {
  return custom<Scene>([](Scene& s, const toml::node& n, const BindContext& c) { s.bedforms.mask = rasterRef(n, c.source, s, c.path); },
                       [](const Scene& s) { return s.bedforms.mask ? s.bedforms.mask->label() : "none"; });
}
Bind<OccluderSource> occluderFile() {
  return custom<OccluderSource>(
      [](OccluderSource& o, const toml::node& n, const BindContext& c) {
        o.file = resolvePath(n.as_string()->get(), c.scene.baseDir);
        o.declaredAt = where(c.source, n.source());
        std::error_code ec;
        if (!std::filesystem::exists(o.file, ec)) fail(c.source, n, c.path, "occluder file '" + o.file + "' does not exist");
      },
      [](const OccluderSource& o) { return show(o.file); });
}
Bind<OccluderSource> occluderOffset() {
  return custom<OccluderSource>(
      [](OccluderSource& o, const toml::node& n, const BindContext& c) {
        const auto v = numbersOf(n, 3, c, "needs 3 numbers [x, y, z]");
        o.offsetM = {v[0], v[1], v[2]};
      },
      [](const OccluderSource& o) { return show(o.offsetM); });
}
bool hasNegativeRange(const RasterRef& r) { return r.range && ((*r.range)[0] < 0.0 || (*r.range)[1] < 0.0); }

// initial_snow.LAYER: a depth in metres, a depth raster, or {mask, depth_m} (the depth where the mask is 1).
void readInitialLayer(InitialSnowLayer& layer, const toml::node& node, const BindContext& c) {
  const std::string& key = c.path;
  if (node.is_number()) {
    layer.kind = InitialSnowLayer::Kind::Constant;
    layer.depthM = node.value<double>().value();
    if (!(layer.depthM >= 0.0 && layer.depthM <= 10000.0)) fail(c.source, node, key, "a depth in metres, 0 to 10000");
  } else if (const toml::table* t = node.as_table(); t && t->contains("mask")) {
    for (auto&& [k, v] : *t)
      if (k.str() != "mask" && k.str() != "depth_m") fail(c.source, v, key + "." + std::string(k.str()), "unknown key (a masked depth takes mask and depth_m)");
    if (!t->contains("depth_m") || !t->get("depth_m")->is_number())
      throw InputError(where(c.source, t->source()) + ": " + key + ".depth_m: missing (the depth where the mask is 1, metres)");
    layer.kind = InitialSnowLayer::Kind::Mask;
    layer.depthM = t->get("depth_m")->value<double>().value();
    if (!(layer.depthM >= 0.0 && layer.depthM <= 10000.0)) fail(c.source, *t->get("depth_m"), key + ".depth_m", "a depth in metres, 0 to 10000");
    layer.raster = rasterRef(*t->get("mask"), c.source, c.scene, key + ".mask");
  } else {
    layer.kind = InitialSnowLayer::Kind::Raster;
    layer.raster = rasterRef(node, c.source, c.scene, key);
    if (hasNegativeRange(layer.raster)) fail(c.source, node, key, "a depth raster's range must not be negative");
  }
}
Bind<Scene> initialSnow(size_t l) {
  return custom<Scene>([l](Scene& s, const toml::node& n, const BindContext& c) { readInitialLayer(s.initialSnow[l], n, c); },
                       [l](const Scene& s) {
                         const InitialSnowLayer& layer = s.initialSnow[l];
                         if (layer.kind == InitialSnowLayer::Kind::None || layer.kind == InitialSnowLayer::Kind::Constant) return show(layer.depthM);
                         return (layer.kind == InitialSnowLayer::Kind::Mask ? show(layer.depthM) + " m in " : std::string()) + layer.raster.label();
                       });
}
Bind<Scene> multiplier(std::optional<RasterRef> Multipliers::*slot, std::string none = "1 (none)") {
  return custom<Scene>(
      [slot](Scene& s, const toml::node& n, const BindContext& c) {
        s.multipliers.*slot = rasterRef(n, c.source, s, c.path);
        if (hasNegativeRange(*(s.multipliers.*slot))) fail(c.source, n, c.path, "a multiplier's range must not be negative");
      },
      [slot, none](const Scene& s) { return (s.multipliers.*slot) ? (s.multipliers.*slot)->label() : none; });
}

template <class T>
Bind<T> pair(std::optional<std::array<double, 2>> T::*member) {
  return custom<T>(
      [member](T& e, const toml::node& n, const BindContext& c) {
        const auto v = numbersOf(n, 2, c, "needs two numbers");
        e.*member = std::array<double, 2>{v[0], v[1]};
      },
      [member](const T& e) { return show(e.*member); });
}
template <class T>
Bind<T> maskOf(std::optional<RasterRef> T::*member) {
  return custom<T>([member](T& e, const toml::node& n, const BindContext& c) { e.*member = rasterRef(n, c.source, c.scene, c.path); },
                   [member](const T& e) { return (e.*member) ? (e.*member)->label() : "none (everywhere)"; });
}

using S = Scene;
using OP = OcclusionParameters;
using MS = MeshSnowScene;
using TS = TerrainSource;
using OR = OutputRequest;
using BF = BedformScene;
using BP = BedformParameters;
using KF = WeatherKeyframe;
using WS = WeatherState;
using ED = EditSpec;
using EV = EventSpec;
// terrain.format's choices: every TerrainFormat but Builtin (that is terrain.builtin's).
std::vector<std::string> terrainFormatChoices() {
  std::vector<std::string> names = enumNames<TerrainFormat>();
  std::erase(names, enumName(TerrainFormat::Builtin));
  return names;
}

const std::vector<std::string> kSnowLayers = {"compacted", "stable", "unstable", "powder"};

}  // namespace

const char* kindName(Kind k) {
  switch (k) {
    case Kind::Table: return "a table";
    case Kind::TableArray: return "an array of tables ([[...]])";
    case Kind::String: return "a string";
    case Kind::Number: return "a number";
    case Kind::Integer: return "an integer";
    case Kind::Bool: return "true or false";
    case Kind::Date: return "a date (YYYY-MM-DD)";
    case Kind::NumberArray: return "an array of numbers";
    case Kind::StringArray: return "an array of strings";
    case Kind::Any: return "a value";
  }
  return "?";
}

// The layer names, from the layer table (scene/layers.cpp), in its order.
const std::vector<std::string> kLayerChoices = [] {
  std::vector<std::string> names;
  for (const LayerInfo& l : layerTable()) names.push_back(l.name);
  return names;
}();

namespace {

void topLevelRules(std::vector<Rule>& r) {  // name and mode
  // clang-format off
  r.push_back({"name", Kind::String, -kInf, kInf, {}, "", "shown in the log and manifest", at<S>(&S::name)});
  r.push_back({"mode", Kind::String, -kInf, kInf, enumNames<SceneMode>(), "",
       "season: the paper's simulated season; occlusion: the static snow cover of Foldes & Benes 2007 instead of a season (docs/models/occlusion.md); "
       "mesh: snow on the mesh terrain.file itself, Fearing's model, no grid and no season (docs/models/snow-on-meshes.md)", at<S>(&S::mode)});
  // clang-format on
}

void meshSnowRules(std::vector<Rule>& r) {  // [mesh_snow]
  // clang-format off
  r.push_back({"mesh_snow", Kind::Table, -kInf, kInf, {}, "",
       "Fearing's snow on meshes: with mode = \"mesh\" on terrain.file; in a season on the [[occluders]] (depth_m is then the terrain's snow round each one; "
       "it needs outputs.meshes, and a season without occluders is refused)"});
  r.push_back({"mesh_snow.depth_m", Kind::Number, 0, 100, {}, "m", "snowfall depth on open flat ground, metres of snow", at<S>(&S::meshSnow, &MS::placement, &FallenSnowSettings::depthM)});
  r.push_back({"mesh_snow.site_spacing_m", Kind::Number, 1e-4, 100, {}, "m", "the launch-site lattice", at<S>(&S::meshSnow, &MS::placement, &FallenSnowSettings::siteSpacingM)});
  r.push_back({"mesh_snow.sky_cell_sites", Kind::Integer, 1, 64, {}, "", "sky bucket side, in sites", at<S>(&S::meshSnow, &MS::placement, &FallenSnowSettings::skyCellSites)});
  r.push_back({"mesh_snow.flakes_per_site", Kind::Integer, 1, 1024, {}, "", "flakes traced from each site", at<S>(&S::meshSnow, &MS::placement, &FallenSnowSettings::flakesPerSite)});
  r.push_back({"mesh_snow.flutter_mean_m", Kind::Number, 0, 10, {}, "m", "mean of the flakes' sideways step per swirl, N(mean, sigma) truncated at +-3 sigma (the thesis: 1-7 cm)", at<S>(&S::meshSnow, &MS::placement, &FallenSnowSettings::flutterMeanM)});
  r.push_back({"mesh_snow.flutter_sigma_m", Kind::Number, 0, 10, {}, "m", "sigma of the flakes' sideways step per swirl", at<S>(&S::meshSnow, &MS::placement, &FallenSnowSettings::flutterSigmaM)});
  r.push_back({"mesh_snow.swirl_height_m", Kind::Number, 1e-4, 100, {}, "m", "a flake's rise per swirl", at<S>(&S::meshSnow, &MS::placement, &FallenSnowSettings::swirlHeightM)});
  r.push_back({"mesh_snow.max_coverage_diff", Kind::Number, 0, 1, {}, "", "refine lattice cells whose sites' sky coverage differs from a neighbour's by more (1: never)", at<S>(&S::meshSnow, &MS::placement, &FallenSnowSettings::maxCoverageDiff)});
  r.push_back({"mesh_snow.repose_angle_deg", Kind::Number, 0, 89, {}, "deg", "angle of repose of the snow tops (Kuroiwa's dry snow 40-50 deg, fresh dendritic snow up to 90 deg)", at<S>(&S::meshSnow, &MS::stability, &FallenSnowStability::reposeAngleDeg)});
  r.push_back({"mesh_snow.transition_width_deg", Kind::Number, 0, 90, {}, "deg", "width of the stochastic transition curve around the repose angle (0: a sharp angle)", at<S>(&S::meshSnow, &MS::stability, &FallenSnowStability::transitionWidthDeg)});
  r.push_back({"mesh_snow.deposit_rounds", Kind::Integer, 1, 100, {}, "", "the storm laid down in this many rounds, each relaxed", at<S>(&S::meshSnow, &MS::stability, &FallenSnowStability::depositRounds)});
  r.push_back({"mesh_snow.stop_fraction", Kind::Number, 1e-7, 0.5, {}, "", "a round ends when no site sheds more than this share of its mean deposit in a pass", at<S>(&S::meshSnow, &MS::stability, &FallenSnowStability::stopFraction)});
  r.push_back({"mesh_snow.max_passes_per_round", Kind::Integer, 1, 10000000, {}, "", "pass limit of a round (the log says when it is hit)", at<S>(&S::meshSnow, &MS::stability, &FallenSnowStability::maxPassesPerRound)});
  r.push_back({"mesh_snow.connect_angle_deg", Kind::Number, 1, 89, {}, "deg", "steepest base-to-base slope that still joins two sites", at<S>(&S::meshSnow, &MS::stability, &FallenSnowStability::connectAngleDeg)});
  r.push_back({"mesh_snow.voxel_size_m", Kind::Number, 0, 100, {}, "m", "the snow body's voxels (0: half the site spacing)", at<S>(&S::meshSnow, &MS::body, &MeshSnowBodyOptions::voxelSizeM)});
  r.push_back({"mesh_snow.smoothing_steps", Kind::Integer, 0, 20, {}, "", "mean-curvature smoothing passes of the level set", at<S>(&S::meshSnow, &MS::body, &MeshSnowBodyOptions::smoothingSteps)});
  r.push_back({"mesh_snow.adaptivity", Kind::Number, 0, 1, {}, "", "OpenVDB volume-to-mesh adaptivity (0-1: fewer triangles on flat snow)", at<S>(&S::meshSnow, &MS::body, &MeshSnowBodyOptions::adaptivity)});
  r.push_back({"mesh_snow.density_kg_per_m3", Kind::Number, 1, 1000, {}, "kg/m^3", "density in the VDB's fog volume", at<S>(&S::meshSnow, &MS::body, &MeshSnowBodyOptions::densityKgPerM3)});
  // clang-format on
}

void occlusionRules(std::vector<Rule>& r) {  // [occlusion]
  // clang-format off
  r.push_back({"occlusion", Kind::Table, -kInf, kInf, {}, "", "settings of mode = \"occlusion\" (Foldes & Benes 2007)"});
  r.push_back({"occlusion.s_max_m", Kind::Number, 0, 1000, {}, "m", "s_max, the height scale of Eq. 1", at<S>(&S::occlusion, &OP::sMaxM)});
  r.push_back({"occlusion.tau_ambient", Kind::Number, 0, 10, {}, "", "tau: snow where the ambient occlusion value a is below it (a = 1 on open ground, so above 1 open ground keeps s_max (tau - 1))", at<S>(&S::occlusion, &OP::tauAmbient)});
  r.push_back({"occlusion.tau_sun", Kind::Number, 0, 10, {}, "", "tau_sun: the sun dissipates snow where it sees the point for more than this fraction of its (luminance-weighted) day; 1 or more: no dissipation", at<S>(&S::occlusion, &OP::tauSun)});
  r.push_back({"occlusion.sun_positions", Kind::Integer, 0, 1000, {}, "", "sun positions along the day (the paper: about ten)", at<S>(&S::occlusion, &OP::sunPositions)});
  r.push_back({"occlusion.ao_rays", Kind::Integer, 0, 65536, {}, "", "cosine-weighted rays per point (0: by precompute.sun_quality: 64, 256, 1024)", at<S>(&S::occlusion, &OP::aoRays)});
  r.push_back({"occlusion.ao_radius_m", Kind::Number, 0, 1e7, {}, "m", "rays longer than this count as open, local occlusion only (0: unlimited)", at<S>(&S::occlusion, &OP::aoRadiusM)});
  r.push_back({"occlusion.day", Kind::Number, 0, 3650, {}, "day", "the season day whose sun path dissipates the snow", at<S>(&S::occlusion, &OP::day), "the season's middle"});
  r.push_back({"occlusion.turbidity", Kind::Number, 1.7, 10, {}, "", "clear-sky turbidity of the zenith luminance (2 very clear, 6 hazy)", at<S>(&S::occlusion, &OP::turbidity)});
  // clang-format on
}

// [terrain] and [[occluders]] (the builtin terrain's keys after the occluders, where they always were)
void terrainRules(std::vector<Rule>& r) {
  // clang-format off
  r.push_back({"terrain", Kind::Table, -kInf, kInf, {}, "", "the height field (docs/terrain.md): exactly one of terrain.file and terrain.builtin"});
  r.push_back({"terrain.file", Kind::String, -kInf, kInf, {}, "", "a DEM, heightmap, raw file or mesh, relative to the scene file's folder", terrainFile(), "none"});
  r.push_back({"terrain.builtin", Kind::String, -kInf, kInf, {"ridged"}, "", "the embedded generated range instead of a file", terrainBuiltin()});
  r.push_back({"terrain.format", Kind::String, -kInf, kInf, terrainFormatChoices(), "",
       "how to read the file; auto goes by extension (.r16/.r32/.raw raw, .png/.exr heightmap, .obj/.gltf/.glb/.fbx/.ply mesh, anything else a DEM through GDAL; a .tif with heightmap keys is read as a heightmap)", at<S>(&S::terrain, &TS::format)});
  r.push_back({"terrain.coordinates", Kind::String, -kInf, kInf, enumNames<TerrainCoordinates>(), "", "for DEMs with no coordinate system: how to read the cell size", at<S>(&S::terrain, &TS::coordinates)});
  r.push_back({"terrain.fill_nodata", Kind::Bool, -kInf, kInf, {}, "", "fill NODATA holes instead of masking them out", at<S>(&S::terrain, &TS::fillNodata)});
  r.push_back({"terrain.height_range_m", Kind::NumberArray, -12000, 12000, {}, "m", "heightmaps and raw files: [low, high], pixel value 0 -> low, 1 -> high", heightRange()});
  r.push_back({"terrain.height_scale_m", Kind::Number, -1e6, 1e6, {}, "m", "heightmaps and raw files: height = offset + scale x value (instead of a range; 1 when only the offset is given)", at<S>(&S::terrain, &TS::heightScaleM)});
  r.push_back({"terrain.height_offset_m", Kind::Number, -1e6, 1e6, {}, "m", "heightmaps and raw files: the offset of height = offset + scale x value (0 when only the scale is given)", at<S>(&S::terrain, &TS::heightOffsetM)});
  r.push_back({"terrain.raw_width", Kind::Integer, 1, 1 << 20, {}, "cells", "raw files: columns", at<S>(&S::terrain, &TS::rawWidth), "required for raw files"});
  r.push_back({"terrain.raw_height", Kind::Integer, 1, 1 << 20, {}, "cells", "raw files: rows", at<S>(&S::terrain, &TS::rawHeight), "required for raw files"});
  r.push_back({"terrain.byte_order", Kind::String, -kInf, kInf, enumNames<ByteOrder>(), "", "raw files: byte order", at<S>(&S::terrain, &TS::byteOrder)});
  r.push_back({"terrain.up_axis", Kind::String, -kInf, kInf, enumNames<UpAxis>(), "", "meshes: which axis is up (glTF is y-up)", at<S>(&S::terrain, &TS::upAxis)});
  r.push_back({"terrain.height_limits_m", Kind::NumberArray, -1e9, 1e9, {}, "m",
       "[lowest, highest] heights allowed after scale and offset; a terrain outside is refused (the default is the Earth's surface with a margin: widen it for other planets or units)", heightLimits()});
  r.push_back({"terrain.band", Kind::Integer, 1, 1 << 16, {}, "", "which band of a multi-band DEM, or channel of a multi-channel heightmap, holds the heights (from 1); such files are refused without it",
       at<S>(&S::terrain, &TS::band), "none (the file must have one band)"});
  r.push_back({"terrain.resample_cell_size_m", Kind::Number, 0.01, 100000, {}, "m", "bake at another cell size (or give terrain.resample_size)", at<S>(&S::terrain, &TS::resampleCellSizeM)});
  r.push_back({"terrain.crop_m", Kind::NumberArray, 0, 1e8, {}, "m",
       "bake a window [west, north, east, south]: the cells whose centres lie in it, metres east and south of the grid's north-west corner (before any resampling)", cropWindow()});
  r.push_back({"terrain.resample_size", Kind::NumberArray, 3, 1 << 20, {}, "cells", "bake at another grid size [width, height] (or give terrain.resample_cell_size_m)", resampleSize()});
  r.push_back({"occluders", Kind::TableArray, -kInf, kInf, {}, "",
       "meshes that block the sun (rocks, buildings), in the terrain's local frame: x east from the west edge, y north from the south edge, z altitude, metres; "
       "with a [mesh_snow] table they get snow bodies of their own (docs/models/snow-on-meshes.md)"});
  r.push_back({"occluders.file", Kind::String, -kInf, kInf, {}, "", "the mesh (OBJ, PLY, glTF/glb, FBX), relative to the scene file's folder", occluderFile(), "required"});
  r.push_back({"occluders.up_axis", Kind::String, -kInf, kInf, enumNames<UpAxis>(), "", "which axis of the mesh is up", at<OccluderSource>(&OccluderSource::upAxis)});
  r.push_back({"occluders.offset_m", Kind::NumberArray, -1e7, 1e7, {}, "m", "[x, y, z] added to the mesh's vertices (after scaling)", occluderOffset()});
  r.push_back({"occluders.scale", Kind::Number, 1e-6, 1e6, {}, "", "the mesh's vertices are multiplied by it", at<OccluderSource>(&OccluderSource::scale)});
  r.push_back({"terrain.size", Kind::Integer, 8, 16384, {}, "cells", "builtin: cells per side", at<S>(&S::terrain, &TS::builtinOptions, &DefaultTerrainOptions::size)});
  r.push_back({"terrain.cell_size_m", Kind::Number, 0.01, 10000, {}, "m", "cell size of heightmaps, raw files, mesh rasters and the builtin terrain", at<S>(&S::terrain, &TS::cellSizeM),
       "none (builtin: " + show(DefaultTerrainOptions{}.cellSizeM) + ")"});
  r.push_back({"terrain.seed", Kind::Integer, 0, 4294967295.0, {}, "", "builtin: the shape of its ridges", at<S>(&S::terrain, &TS::builtinOptions, &DefaultTerrainOptions::seed)});
  r.push_back({"terrain.min_altitude_m", Kind::Number, -500, 9000, {}, "m", "builtin: its lowest altitude", at<S>(&S::terrain, &TS::builtinOptions, &DefaultTerrainOptions::minAltitudeM)});
  r.push_back({"terrain.max_altitude_m", Kind::Number, -500, 9000, {}, "m", "builtin: its highest altitude (above terrain.min_altitude_m)", at<S>(&S::terrain, &TS::builtinOptions, &DefaultTerrainOptions::maxAltitudeM)});
  // clang-format on
}

void seasonRules(std::vector<Rule>& r) {  // [site], [season] and [weather]
  // clang-format off
  r.push_back({"site", Kind::Table, -kInf, kInf, {}, "", "where the terrain lies on the globe (the sun's path)"});
  r.push_back({"site.latitude_deg", Kind::Number, -90, 90, {}, "deg", "site latitude", at<S>(&S::latitudeDeg), "the DEM's latitude when known, else 45"});
  r.push_back({"site.longitude_deg", Kind::Number, -180, 180, {}, "deg", "site longitude", at<S>(&S::longitudeDeg)});
  r.push_back({"season", Kind::Table, -kInf, kInf, {}, "", "when the season starts and how long it runs"});
  r.push_back({"season.start_date", Kind::Date, -kInf, kInf, {}, "", "first day (a TOML date or \"YYYY-MM-DD\", a day of the calendar)", startDate()});
  r.push_back({"season.days", Kind::Number, 0.01, 3650, {}, "day", "season length", at<S>(&S::days)});
  r.push_back({"season.avalanche_flow", Kind::String, -kInf, kInf, enumNames<AvalancheFlow>(), "",
       "how avalanches flow: pipes, the paper's pipe model (calibrated against AvaFrame com1DFA); shallow_water, a depth-averaged layer whose momentum moves with the snow (experimental: its speed depends far less on the cell size than the pipes', but it is not fitted and costs several substeps a step; docs/models/avalanches.md)",
       at<S>(&S::params, &ModelParameters::avalancheFlow)});
  r.push_back({"weather", Kind::Table, -kInf, kInf, {}, "", "the weather timeline: keyframes and fixed snowfall periods"});
  r.push_back({"weather.keyframe", Kind::TableArray, -kInf, kInf, {}, "",
       "weather keyframes in increasing day order, interpolated linearly (wind direction the short way round); an omitted value carries over from the previous keyframe"});
  r.push_back({"weather.keyframe.day", Kind::Number, 0, 3650, {}, "day", "the keyframe's day", at<KF>(&KF::day), "required"});
  r.push_back({"weather.keyframe.sea_level_temperature_c", Kind::Number, -80, 60, {}, "degC", "T0, the temperature at sea level", at<KF>(&KF::state, &WS::seaLevelTemperatureC)});
  r.push_back({"weather.keyframe.wind_direction_deg", Kind::Number, 0, 360, {}, "deg", "where the wind blows from, clockwise from north (270: a westerly)", at<KF>(&KF::state, &WS::windDirectionDeg)});
  r.push_back({"weather.keyframe.wind_speed_mps", Kind::Number, 0, 100, {}, "m/s", "wind speed at sea level", at<KF>(&KF::state, &WS::windSpeedMps)});
  r.push_back({"weather.keyframe.snowfall_intensity", Kind::Number, 0, 100, {}, "", "multiplier on k_snow during snowfall", at<KF>(&KF::state, &WS::snowfallIntensity)});
  r.push_back({"weather.snowfall", Kind::TableArray, -kInf, kInf, {}, "", "fixed snowfall periods; when given they replace the random (Poisson) snowfall starts"});
  r.push_back({"weather.snowfall.start_day", Kind::Number, 0, 3650, {}, "day", "the snowfall's first day", at<SnowfallPeriod>(&SnowfallPeriod::startDay), "required"});
  r.push_back({"weather.snowfall.end_day", Kind::Number, 0, 3650, {}, "day", "the snowfall's end (after start_day)", at<SnowfallPeriod>(&SnowfallPeriod::endDay), "required"});
  // clang-format on
}

void eventRules(std::vector<Rule>& r) {  // [[events]]
  // clang-format off
  r.push_back({"events", Kind::TableArray, -kInf, kInf, {}, "",
       "events on given days: a storm (type = \"snowfall\") in addition to the weather's snowfall; an avalanche released at a point or in every unstable cell of a mask; "
       "skiers starting a descent from a point or from cells drawn from a mask (moved as one batch, docs/models/skiers.md)"});
  r.push_back({"events.type", Kind::String, -kInf, kInf, enumNames<EventType>(), "", "what happens", at<EV>(&EV::type), "required"});
  r.push_back({"events.count", Kind::Integer, 1, 10000, {}, "", "skiers: how many start together", at<EV>(&EV::count)});
  r.push_back({"events.position_m", Kind::NumberArray, -1e7, 1e7, {}, "m",
       "avalanche or skier: [x, y] metres east and south of the grid's north-west corner (a point outside the terrain or on NODATA is refused with the scene's line)", pair<EV>(&EV::positionM)});
  r.push_back({"events.map_position", Kind::NumberArray, -1e9, 1e9, {}, "m", "avalanche or skier: [easting, northing] in the DEM's own projected coordinates (refused for geographic DEMs)", pair<EV>(&EV::mapPosition)});
  r.push_back({"events.day", Kind::Number, 0, 3650, {}, "day", "the day it happens (an avalanche or skier after season.days is refused)", at<EV>(&EV::day), "required"});
  r.push_back({"events.duration_days", Kind::Number, 0.001, 365, {}, "day", "snowfall: how long the storm lasts (required for a snowfall)", at<EV>(&EV::durationDays)});
  r.push_back({"events.mask", Kind::Any, -kInf, kInf, {}, "",
       "avalanche or skier, instead of a point: release every unstable cell inside the mask, or draw each skier's start cell from it (docs/models/art-direction.md)", maskOf<EV>(&EV::mask), "none"});
  // clang-format on
}

void artDirectionRules(std::vector<Rule>& r) {  // [masks], [initial_snow], [multipliers] and [[edits]]
  // clang-format off
  r.push_back({"masks", Kind::Table, -kInf, kInf, {}, "", "named rasters ([masks.NAME]) that other keys refer to by NAME (docs/models/art-direction.md)"});
  r.push_back({"masks.*", Kind::Table, -kInf, kInf, {}, "", "a named raster; the name takes letters, digits, '_' and '-'"});
  r.push_back({"masks.*.file", Kind::String, -kInf, kInf, {}, "", "the raster's path, relative to the scene file's folder", {}, "required"});
  r.push_back({"masks.*.values", Kind::NumberArray, -1e30, 1e30, {}, "", "[value meaning 0, value meaning 1] of the file's values", {}, "the file's own range"});
  r.push_back({"masks.*.range", Kind::NumberArray, -1e30, 1e30, {}, "", "[first, second]: what 0 and 1 become", {}, "[0, 1]"});
  r.push_back({"masks.*.invert", Kind::Bool, -kInf, kInf, {}, "", "use 1 - value", {}, "false"});
  r.push_back({"initial_snow", Kind::Table, -kInf, kInf, {}, "", "each layer's depth at day 0: metres, a depth raster, or { mask = ..., depth_m = ... } (the depth where the mask is 1)"});
  for (size_t l = 0; l < kSnowLayers.size(); ++l)
    r.push_back({"initial_snow." + kSnowLayers[l], Kind::Any, -kInf, kInf, {}, "m", "the " + kSnowLayers[l] + " layer's depth at day 0", initialSnow(l)});
  r.push_back({"multipliers", Kind::Table, -kInf, kInf, {}, "", "per-cell multiplier rasters over the season (a [masks] name, a file or a table)"});
  r.push_back({"multipliers.snowfall", Kind::Any, -kInf, kInf, {}, "", "multiplies the snowfall", multiplier(&Multipliers::snowfall)});
  r.push_back({"multipliers.melt", Kind::Any, -kInf, kInf, {}, "", "multiplies the melt", multiplier(&Multipliers::melt)});
  r.push_back({"multipliers.wind_erosion", Kind::Any, -kInf, kInf, {}, "", "multiplies the wind erosion", multiplier(&Multipliers::windErosion)});
  r.push_back({"multipliers.avalanche_release", Kind::Any, -kInf, kInf, {}, "", "multiplies the avalanche release probability", multiplier(&Multipliers::avalancheRelease)});
  r.push_back({"multipliers.skier_spawn", Kind::Any, -kInf, kInf, {}, "", "multiplies where automatic skiers start", multiplier(&Multipliers::skierSpawn)});
  r.push_back({"multipliers.no_snow", Kind::Any, -kInf, kInf, {}, "", "a mask: cells >= 0.5 stay bare", multiplier(&Multipliers::noSnow, "none")});
  r.push_back({"edits", Kind::TableArray, -kInf, kInf, {}, "", "change a layer's depth on a given day (applied in day order)"});
  r.push_back({"edits.day", Kind::Number, 0, 3650, {}, "day", "the day of the edit", at<ED>(&ED::day), "required"});
  r.push_back({"edits.op", Kind::String, -kInf, kInf, enumNames<EditOp>(), "",
       "add: L += w d; remove: L -= min(L, w d); set: L = (1 - w) L + w d; move: m = w min(L, d) (w L without depth_m) from layer to to (w: the mask's value)", at<ED>(&ED::op), "required"});
  r.push_back({"edits.layer", Kind::String, -kInf, kInf, kSnowLayers, "", "the layer edited", at<ED>(&ED::layer), "required"});
  r.push_back({"edits.to", Kind::String, -kInf, kInf, kSnowLayers, "", "op = \"move\": the layer that receives", at<ED>(&ED::to), "none"});
  r.push_back({"edits.depth_m", Kind::Number, 0, 10000, {}, "m", "d, the depth (every op but \"move\" needs it)", at<ED>(&ED::depthM)});
  r.push_back({"edits.mask", Kind::Any, -kInf, kInf, {}, "", "weights w in [0, 1] of the edit", maskOf<ED>(&ED::mask)});
  // clang-format on
}

void bedformRules(std::vector<Rule>& r) {  // [bedforms]
  // clang-format off
  r.push_back({"bedforms", Kind::Table, -kInf, kInf, {}, "",
       "the slab-saltation wind-bedform model over the terrain or inside a mask, in place of the layered wind transport there (docs/models/bedforms.md)"});
  r.push_back({"bedforms.enabled", Kind::Bool, -kInf, kInf, {}, "", "run the bedform model", at<S>(&S::bedforms, &BF::enabled), "true when [bedforms] is given"});
  r.push_back({"bedforms.mask", Kind::Any, -kInf, kInf, {}, "", "a mask (name from [masks], file or table; cells >= 0.5)", bedformMask(), "whole terrain"});
  r.push_back({"bedforms.slab_m", Kind::Number, 0.001, 10, {}, "m", "slab thickness, m of snow; tan(repose) x cell size must be at least one slab", at<S>(&S::bedforms, &BF::params, &BP::slabM)});
  r.push_back({"bedforms.hop_length_m", Kind::Number, 0.01, 1000, {}, "m", "hop length at reference_wind_mps, scaled by the local wind speed", at<S>(&S::bedforms, &BF::params, &BP::hopLengthM)});
  r.push_back({"bedforms.reference_wind_mps", Kind::Number, 0.1, 100, {}, "m/s", "the wind speed of hop_length_m", at<S>(&S::bedforms, &BF::params, &BP::referenceWindMps)});
  r.push_back({"bedforms.threshold_wind_mps", Kind::Number, 0, 100, {}, "m/s", "no erosion below it (of loose snow; bonded snow needs more)", at<S>(&S::bedforms, &BF::params, &BP::thresholdWindMps)});
  r.push_back({"bedforms.deposit_on_snow", Kind::Number, 0.001, 1, {}, "", "p_s, landing probability on snow (the thesis's best Werner barchans)", at<S>(&S::bedforms, &BF::params, &BP::depositSnow)});
  r.push_back({"bedforms.deposit_on_bare", Kind::Number, 0.001, 1, {}, "", "p_ns, landing probability on bare (slab-free) ground", at<S>(&S::bedforms, &BF::params, &BP::depositBare)});
  r.push_back({"bedforms.shadow_angle_deg", Kind::Number, 1, 89, {}, "deg", "the wind shadow's angle", at<S>(&S::bedforms, &BF::params, &BP::shadowAngleDeg)});
  r.push_back({"bedforms.shadow_length_m", Kind::Number, 0, 1000, {}, "m", "how far upwind the shadow test looks", at<S>(&S::bedforms, &BF::params, &BP::shadowLengthM)});
  r.push_back({"bedforms.repose_angle_deg", Kind::Number, 1, 89, {}, "deg", "angle of repose of the slabs", at<S>(&S::bedforms, &BF::params, &BP::reposeAngleDeg)});
  r.push_back({"bedforms.speedup_linear", Kind::Number, 0, 100, {}, "",
       "Momiji's C1: hop speed-up per metre of take-off height above the domain's mean (1.2 is Momiji's 0.4 at Werner's scale; on snow-scale slabs it stopped forms from starting, so it is off)", at<S>(&S::bedforms, &BF::params, &BP::speedupLinear)});
  r.push_back({"bedforms.speedup_quadratic_per_m", Kind::Number, 0, 100, {}, "1/m", "Momiji's C2, the quadratic speed-up (0.018 is Momiji's 0.002 at Werner's scale; off like C1)", at<S>(&S::bedforms, &BF::params, &BP::speedupQuadraticPerM)});
  r.push_back({"bedforms.max_slope_deg", Kind::Number, 0, 89, {}, "deg", "the domain: cells whose snow bed is at most this steep", at<S>(&S::bedforms, &BF::params, &BP::maxSlopeDeg)});
  r.push_back({"bedforms.sintering_per_day", Kind::Number, 0, 1000, {}, "1/day", "cohesion gained per day at 0 degC", at<S>(&S::bedforms, &BF::params, &BP::sinteringPerDay)});
  r.push_back({"bedforms.sintering_scale_c", Kind::Number, 0.1, 100, {}, "degC", "the sintering rate halves at -scale degC", at<S>(&S::bedforms, &BF::params, &BP::sinteringScaleC)});
  r.push_back({"bedforms.rounds_per_hour", Kind::Number, 0.01, 3600, {}, "1/h", "polling rounds (each cell once) per hour of wind", at<S>(&S::bedforms, &BF::params, &BP::roundsPerHour)});
  r.push_back({"bedforms.batches", Kind::Integer, 1, 64, {}, "", "batches a round", at<S>(&S::bedforms, &BF::params, &BP::batches)});
  r.push_back({"bedforms.periodic", Kind::Bool, -kInf, kInf, {}, "", "wrap around the grid's edges (a tileable window; even sizes)", at<S>(&S::bedforms, &BF::params, &BP::periodic)});
  // clang-format on
}

void outputRules(std::vector<Rule>& r) {  // [parameters], [precompute], [outputs] and [run]
  // clang-format off
  r.push_back({"parameters", Kind::Table, -kInf, kInf, {}, "", "the model constants: any key of this table, a number each"});
  r.push_back({"precompute", Kind::Table, -kInf, kInf, {}, "", "the sun exposure precompute"});
  r.push_back({"precompute.sun", Kind::Bool, -kInf, kInf, {}, "", "compute sun exposure (false: temperature from altitude alone)", at<S>(&S::sunExposure)});
  r.push_back({"precompute.sun_quality", Kind::String, -kInf, kInf, sunQualityNames(), "", "sample counts of the sun exposure (docs/precompute.md), and occlusion mode's ray count", at<S>(&S::sunQuality)});
  r.push_back({"precompute.sun_method", Kind::String, -kInf, kInf, enumNames<SunMethod>(), "",
       "auto: the horizon-sweep fast path for pure height fields, Embree rays when the scene has occluders; horizon or embree: that one", at<S>(&S::sunMethod)});
  r.push_back({"outputs", Kind::Table, -kInf, kInf, {}, "", "what the bake writes (docs/outputs.md)"});
  r.push_back({"outputs.layers", Kind::StringArray, -kInf, kInf, kLayerChoices, "",
       "grids to write: the layers listed under Output layers below (a layer the mode does not make is an error; bedform_cohesion needs [bedforms])", at<S>(&S::outputs, &OR::layers)});
  r.push_back({"outputs.format", Kind::String, -kInf, kInf, enumNames<ImageFormat>(), "", "the layers' image format: 32-bit float, one channel", at<S>(&S::outputs, &OR::format)});
  r.push_back({"outputs.encodings", Kind::StringArray, -kInf, kInf, {"png16", "png8", "r16", "r32"}, "",
       "also write each layer quantised over its range (outputs.ranges): 16-bit PNG, 8-bit PNG mask, raw 16-bit heightmap; or r32: raw float32 as it is (the float file is always written)", at<S>(&S::outputs, &OR::encodings)});
  r.push_back({"outputs.multichannel_exr", Kind::Bool, -kInf, kInf, {}, "", "also write all layers in one EXR (layers.exr), a channel <layer>.Y each", at<S>(&S::outputs, &OR::multichannelExr)});
  r.push_back({"outputs.vdb", Kind::Bool, -kInf, kInf, {}, "", "also write the snow body as snow.vdb (OpenVDB)", at<S>(&S::outputs, &OR::vdb)});
  r.push_back({"outputs.ski_track_factor", Kind::Integer, 1, 16, {}, "", "texels of the ski_tracks texture per simulation cell, each way", at<S>(&S::outputs, &OR::skiTrackFactor)});
  r.push_back({"outputs.meshes", Kind::StringArray, -kInf, kInf, {"ply", "obj", "glb", "fbx"}, "",
       "also write meshes in each format (see mesh_parts); occlusion mode on a mesh terrain also writes the input mesh with its vertices raised by their snow (snow_mesh.<ext>)", at<S>(&S::outputs, &OR::meshes)});
  r.push_back({"outputs.mesh_parts", Kind::StringArray, -kInf, kInf, {"surface", "body"}, "",
       "surface: the snow-covered surface (snow_surface.<ext>); body: the snow body alone, closed (snow_body.<ext>)", meshParts()});
  r.push_back({"outputs.mesh_max_error_m", Kind::Number, 0, 10000, {}, "m", "the adaptive triangulation's vertical error bound (0: only exactly planar areas merge)", at<S>(&S::outputs, &OR::meshMaxErrorM)});
  r.push_back({"outputs.mesh_tile_size_m", Kind::Number, 0, 1e7, {}, "m",
       "split the surface mesh into square tiles of this size, cut along the tile borders so neighbours share their border vertices (snow_surface_x<column>_y<row>.<ext>, columns from the west, rows from the north; 0: one file)", at<S>(&S::outputs, &OR::meshTileSizeM)});
  r.push_back({"outputs.vdb_voxel_size_m", Kind::Number, 0.01, 1000, {}, "m", "the VDB's voxel size", at<S>(&S::outputs, &OR::vdbVoxelSizeM), "the grid's smaller cell size"});
  r.push_back({"outputs.compression_level", Kind::Integer, 0, 9, {}, "",
       "deflate effort of the lossless images: PNG's zlib level and EXR's zip level (0: EXR uncompressed; TIFF is always zip at its default level). "
       "On a 1024^2 season's layers EXR at level 4 is within 0.2 % of level 1's size for 28 % more time, and 16-bit PNG at level 6 is 2-16 % smaller than at level 1 "
       "for 1.6-4.8 times the time; sparse textures (the ski tracks) shrink 2.5-2.7 times at those levels. Up to level 3 PNG rows take libpng's \"sub\" filter alone "
       "(25-55 % faster than trying all five filters on every row, files 0-10 % larger); from level 4 libpng chooses per row", at<S>(&S::outputs, &OR::compressionLevel)});
  r.push_back({"outputs.displacement_size", Kind::NumberArray, 1, 65536, {}, "pixels",
       "also write displacement_depth and displacement_surface (float, m) resampled bilinearly to [width, height] over the same extent", displacementSize()});
  r.push_back({"outputs.avalanche_maps", Kind::Bool, -kInf, kInf, {}, "", "write each avalanche's release zone, scour and deposit (avalanches/NNN_*.exr)", at<S>(&S::outputs, &OR::avalancheMaps)});
  r.push_back({"outputs.avalanche_frame_interval_s", Kind::Number, 0.01, 3600, {}, "s",
       "write frames of each avalanche's motion at this interval of simulated time (avalanches/NNN/depth.FFFF.exr; implies the maps)", at<S>(&S::outputs, &OR::avalancheFrameIntervalS), "none"});
  r.push_back({"outputs.coverage_depths_m", Kind::NumberArray, 0, 100, {}, "m",
       "the snow_coverage layer's [bare, covered] snow depths: 0 at or below the first, 1 at or above the second, a smooth step between", coverageDepths()});
  r.push_back({"outputs.frames_days", Kind::NumberArray, 0, 3650, {}, "day", "also write the layers at these days (0: the season's start); frames are named by the whole day, so two days that round to the same one are refused", at<S>(&S::outputs, &OR::frameDays)});
  r.push_back({"outputs.ranges", Kind::Table, -kInf, kInf, {}, "",
       "per layer, how its png16, png8 and r16 files map values to pixels: [lo, hi] in the layer's unit (fixed), \"season\" (one range over every frame and tile of the bake) or \"own\" (each day's own range over all its tiles); "
       "NODATA cells are left out of every range and written as pixel 0. Default: [0, 1] for layers in unit 1 (masks and fractions), \"season\" for the others (docs/outputs.md)"});
  for (const LayerInfo& l : layerTable())
    if (l.kind == LayerKind::Float)
      r.push_back({std::string("outputs.ranges.") + l.name, Kind::Any, -kInf, kInf, {}, l.unit, std::string("the ") + l.name + " layer's range", layerRange(l.name),
           std::string(l.unit) == "1" ? "[0, 1]" : "\"season\""});
  r.push_back({"outputs.tiles", Kind::Table, -kInf, kInf, {}, "",
       "cut every raster output (layers, encodings, layers.exr, previews, engine and displacement maps, avalanche maps) into equal tiles for an engine's importer; the contact sheet stays whole, a picture rather than a map (docs/outputs.md)"});
  r.push_back({"outputs.tiles.convention", Kind::String, -kInf, kInf, {"unreal", "unity", "grid"}, "",
       "unreal: <name>_x<column>_y<row> from the north-west, sizes 127, 253, 505, 1009, 2017, 4033, 8129, one shared edge row and column; "
       "unity: <name>_<column>_<row> from the south-west (Unity's terrain grid), 2^n + 1 from 33 to 4097, one shared edge; grid: <name>_x<column>_y<row>, any size and overlap",
       at<S>(&S::outputs, &OR::tiles, &OutputTiles::convention), "required with [outputs.tiles]"});
  r.push_back({"outputs.tiles.size_px", Kind::Integer, 2, 65536, {}, "pixels", "each tile's width and height", at<S>(&S::outputs, &OR::tiles, &OutputTiles::sizePx), "required with [outputs.tiles]"});
  r.push_back({"outputs.tiles.overlap_px", Kind::Integer, 0, 65535, {}, "pixels", "grid: rows and columns neighbouring tiles share (unreal and unity share 1)", at<S>(&S::outputs, &OR::tiles, &OutputTiles::overlapPx)});
  r.push_back({"outputs.tiles.resize", Kind::NumberArray, 1, 65536, {}, "pixels",
       "the tile set's own size: the tiles are cut from the layers resampled to [width, height] over the same extent (as outputs.resize), and the untiled files are written too, at the grid's size (or outputs.resize); "
       "unreal and unity: each side a whole number of tiles, n (size_px - 1) + 1", tilesResize(), "none: the tiles are cut from the outputs at their size and replace the untiled files"});
  r.push_back({"outputs.resize", Kind::NumberArray, 1, 65536, {}, "pixels",
       "write the grid's layers, their encodings, the multi-channel EXR, the splat and normal maps and the avalanche maps at [width, height] over the same extent (bilinear, the layers over valid cells; the simulation grid is untouched; previews stay at the grid's size)", resize()});
  r.push_back({"outputs.normal_map_convention", Kind::String, -kInf, kInf, {"opengl", "directx"}, "",
       "the snow_normal layer's green channel: opengl (+v, north: Blender, Unity) or directx (flipped: Unreal)", at<S>(&S::outputs, &OR::normalMapConvention)});
  r.push_back({"run", Kind::Table, -kInf, kInf, {}, "", "how the bake runs"});
  r.push_back({"run.seed", Kind::Integer, 0, 9.007199254740992e15, {}, "", "random seed", at<S>(&S::seed)});
  r.push_back({"run.backend", Kind::String, -kInf, kInf, enumNames<BackendChoice>(), "", "compute backend (auto: CUDA when a device works)", at<S>(&S::backend)});
  r.push_back({"run.threads", Kind::Integer, 0, 4096, {}, "", "CPU threads (0: all cores)", at<S>(&S::threads)});
  r.push_back({"run.frame_writing", Kind::String, -kInf, kInf, enumNames<FrameWriting>(), "",
       "when outputs.frames_days' outputs are written (the same files whichever): paused, the season waiting with its working memory freed (the least memory); beside, on a thread of their own while the season goes on (faster by about the frame's writing time, with its writers and a copy of the state beside the season); after_season, from copies held through the season (docs/memory.md)",
       at<S>(&S::frameWriting)});
  r.push_back({"run.max_memory_gb", Kind::Number, 0.001, 1e6, {}, "GiB", "refuse the bake before any work when its predicted peak memory is above this (docs/memory.md)", at<S>(&S::maxMemoryGb), "80 % of the memory available"});
  // clang-format on
}

}  // namespace

// The rules in the order suggestions for misspelt keys were always searched (the reference
// groups them by sceneSections()).
const std::vector<Rule>& sceneRules() {
  static const std::vector<Rule> rules = [] {
    std::vector<Rule> r;
    for (auto* group : {topLevelRules, meshSnowRules, occlusionRules, terrainRules, seasonRules, eventRules, artDirectionRules, bedformRules, outputRules})
      group(r);
    return r;
  }();
  return rules;
}

const Rule* findRule(std::string path) {
  // [masks.NAME]: any name, the same keys.
  if (path.rfind("masks.", 0) == 0) {
    const size_t end = path.find('.', 6);
    path = "masks.*" + (end == std::string::npos ? std::string() : path.substr(end));
  }
  for (const auto& r : sceneRules())
    if (r.path == path) return &r;
  return nullptr;
}

const std::vector<SceneSection>& sceneSections() {
  static const std::vector<SceneSection> sections = {
      {"", "Top level"},
      {"terrain", "[terrain]"},
      {"occluders", "[[occluders]]"},
      {"site", "[site]"},
      {"season", "[season]"},
      {"weather", "[weather]"},
      {"events", "[[events]]"},
      {"masks", "[masks.NAME]"},
      {"initial_snow", "[initial_snow]"},
      {"multipliers", "[multipliers]"},
      {"edits", "[[edits]]"},
      {"bedforms", "[bedforms]"},
      {"mesh_snow", "[mesh_snow]"},
      {"occlusion", "[occlusion]"},
      {"precompute", "[precompute]"},
      {"outputs", "[outputs]"},
      {"run", "[run]"},
  };
  return sections;
}

std::string where(const std::string& fallbackSource, const toml::source_region& src) {
  std::ostringstream o;
  o << (src.path && !src.path->empty() ? *src.path : fallbackSource);
  if (src.begin.line > 0) o << ":" << src.begin.line;
  return o.str();
}

[[noreturn]] void fail(const std::string& source, const toml::node& node, const std::string& key, const std::string& what) {
  throw InputError(where(source, node.source()) + ": " + key + ": " + what);
}

std::string numberText(double v) {
  std::ostringstream o;
  o << std::setprecision(15) << v;
  return o.str();
}

int daysInMonth(int year, int month) {
  static const int days[12] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  const bool leap = (year % 4 == 0 && year % 100 != 0) || year % 400 == 0;
  return month < 1 || month > 12 ? 0 : days[month - 1] + (month == 2 && leap ? 1 : 0);
}

bool isCalendarDate(const toml::date& d) { return d.day >= 1 && d.day <= daysInMonth(d.year, d.month); }

std::optional<toml::date> parseDate(const std::string& s) {
  int y, m, d;
  char c1, c2;
  std::istringstream in(s);
  if (!(in >> y >> c1 >> m >> c2 >> d) || c1 != '-' || c2 != '-' || m < 1 || m > 12 || d < 1 || d > 31) return {};
  return toml::date{y, m, d};
}

}  // namespace snow
