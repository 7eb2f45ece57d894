// The layer table (layers.h) and the compute function of every float layer.
#include "layers.h"

#include <algorithm>
#include <cmath>

#include "core/season.h"
#include "core/util.h"

namespace snow {
namespace {

// A grid of the state's size, `cell(s, x, y)` at valid cells and 0 at NODATA (valid_mask says which).
template <class CellValue>
Grid<float> perValidCell(const SnowState& s, CellValue cell) {
  Grid<float> g(s.spec.width, s.spec.height, 0.f);
  for (int y = 0; y < s.spec.height; ++y)
    for (int x = 0; x < s.spec.width; ++x)
      if (s.validCell(x, y)) g(x, y) = cell(x, y);
  return g;
}

// A state layer: one field (or a sum of fields) read cell by cell.
#define SNOW_STATE_LAYER(expr) \
  [](const LayerInputs& in) { \
    const SnowState& s = *in.state; \
    return perValidCell(s, [&]([[maybe_unused]] int x, [[maybe_unused]] int y) -> float { return expr; }); \
  }

// Wind layers from the output day's fields (W and W_z).
template <class WindValue>
Grid<float> windLayer(const LayerInputs& in, WindValue value) {
  const SnowState& s = *in.state;
  return perValidCell(s, [&](int x, int y) {
    const double wx = (*in.windXMps)(x, y), wy = (*in.windYMps)(x, y), depth = (*in.windEffectZM)(x, y) - s.bedrockM(x, y);
    return value(wx, wy, depth);
  });
}

// I of the output day, or T = T0 + k_t A + k_i I from it.
Grid<float> sunLayer(const LayerInputs& in, bool temperature) {
  const SnowState& s = *in.state;
  const Grid<float>& sun = *in.sunHours;
  Grid<float> g(s.spec.width, s.spec.height, 0.f);
  for (size_t i = 0; i < g.size(); ++i) {
    if (!s.validCell.values()[i]) continue;
    const float base = temperatureBaseC(*in.params, s.bedrockM.values()[i], sun.values()[i]);
    g.values()[i] = temperature ? static_cast<float>(in.seaLevelTemperatureC + base) : sun.values()[i];
  }
  return g;
}

// snow_coverage: a smooth step 3t^2 - 2t^3 of the depth between outputs.coverage_depths_m's two
// depths, so a material blend has no hard edge and no slope at either end.
Grid<float> snowCoverage(const LayerInputs& in) {
  const double bare = in.outputs->coverageDepthsM[0], covered = in.outputs->coverageDepthsM[1];
  return perValidCell(*in.state, [&](int x, int y) {
    const double t = std::clamp((in.state->depthM(x, y) - bare) / (covered - bare), 0.0, 1.0);
    return static_cast<float>(t * t * (3.0 - 2.0 * t));
  });
}

// Engine layers (docs/outputs.md, Engine layers): snow = snow_coverage; the bare rest split by
// the bedrock's slope into rock (a smooth step from kRockSlopeDeg[0] to [1]) and ground, so the
// three weights sum to 1 at every valid cell.
constexpr double kRockSlopeDeg[2] = {30.0, 45.0};
double smoothStep(double t) {
  t = std::clamp(t, 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}
double bedrockSlopeDeg(const SnowState& s, int x, int y) {
  const int w = s.spec.width, h = s.spec.height;
  auto at = [&](int i, int j) {
    i = std::clamp(i, 0, w - 1), j = std::clamp(j, 0, h - 1);
    return s.validCell(i, j) ? s.bedrockM(i, j) : s.bedrockM(x, y);  // NODATA neighbours: flat
  };
  const double gx = (at(x + 1, y) - at(x - 1, y)) / (2 * s.spec.cellSizeXM), gy = (at(x, y + 1) - at(x, y - 1)) / (2 * s.spec.cellSizeYM);
  return std::atan(std::hypot(gx, gy)) * 180.0 / kPi;
}
Grid<float> engineWeight(const LayerInputs& in, int which) {  // 0 snow, 1 rock, 2 ground
  const Grid<float> coverage = snowCoverage(in);
  return perValidCell(*in.state, [&](int x, int y) {
    const double c = coverage(x, y);
    const double rock = smoothStep((bedrockSlopeDeg(*in.state, x, y) - kRockSlopeDeg[0]) / (kRockSlopeDeg[1] - kRockSlopeDeg[0]));
    return static_cast<float>(which == 0 ? c : which == 1 ? (1 - c) * rock : (1 - c) * (1 - rock));
  });
}

constexpr uint8_t S = kSeasonMode, G = kGridModes, O = kOcclusionMode;
#define R(member) fieldBit(SnowField::member)  // a record field the layer reads

const LayerInfo kLayers[] = {
    {"compacted", "m", "snow layer: compacted", G, kNeedsState, LayerKind::Float, SNOW_STATE_LAYER(s.compactedM(x, y))},
    {"stable", "m", "snow layer: stable", G, kNeedsState, LayerKind::Float, SNOW_STATE_LAYER(s.stableM(x, y))},
    {"unstable", "m", "snow layer: unstable", G, kNeedsState, LayerKind::Float, SNOW_STATE_LAYER(s.unstableM(x, y))},
    {"powder", "m", "snow layer: powder", G, kNeedsState, LayerKind::Float, SNOW_STATE_LAYER(s.powderM(x, y))},
    {"depth", "m", "total snow depth C+S+U+P", G, kNeedsState, LayerKind::Float, SNOW_STATE_LAYER(s.depthM(x, y))},
    {"snow_coverage", "1",
     "soft snow cover for material blends: 0 on ground with at most the first of outputs.coverage_depths_m, 1 under at least the "
     "second, a smooth step (3t^2 - 2t^3) of the depth between",
     G, kNeedsState, LayerKind::Float, snowCoverage},
    {"bedrock", "m", "terrain altitude B", G, kNeedsState, LayerKind::Float, SNOW_STATE_LAYER(s.bedrockM(x, y))},
    {"surface", "m", "snow-surface altitude B+C+S+U+P", G, kNeedsState, LayerKind::Float,
     SNOW_STATE_LAYER(s.bedrockM(x, y) + s.depthM(x, y))},
    {"valid_mask", "1", "1 where the terrain has data, 0 at NODATA cells (written as 0 in every layer)", G, kNeedsState,
     LayerKind::Float, SNOW_STATE_LAYER(1.f)},
    {"wind_speed", "m/s", "wind speed |W| (venturi and terrain redirection, Eq. 2)", S, kNeedsWind, LayerKind::Float,
     [](const LayerInputs& in) {
       return windLayer(in, [](double wx, double wy, double) { return static_cast<float>(std::hypot(wx, wy)); });
     }},
    {"wind_direction", "deg", "direction the wind blows from, degrees clockwise from north", S, kNeedsWind, LayerKind::Float,
     [](const LayerInputs& in) {
       return windLayer(in, [](double wx, double wy, double) {
         return wx == 0 && wy == 0 ? 0.f : static_cast<float>(std::fmod(std::atan2(-wx, wy) * 180.0 / kPi + 360.0, 360.0));
       });
     }},
    {"wind_shadow_depth", "m", "wind shadow depth W_z - A (height of the wind-effect surface above the ground)", S, kNeedsWind,
     LayerKind::Float,
     [](const LayerInputs& in) {
       return windLayer(in, [](double, double, double depth) { return static_cast<float>(std::max(0.0, depth)); });
     }},
    {"wind_shadow_mask", "1", "1 where the wind-effect surface is more than wind_shadow_tolerance_m above the ground (wind shadow)", S,
     kNeedsWind, LayerKind::Float,
     [](const LayerInputs& in) {
       const double tolerance = in.params->windShadowToleranceM;
       return windLayer(in, [tolerance](double, double, double depth) { return depth > tolerance ? 1.f : 0.f; });
     }},
    {"sun_exposure", "h", "sun exposure I = I_sun + I_sky + I_ind, hours of equivalent direct sun per day (§4.1)", S, kNeedsSun,
     LayerKind::Float, [](const LayerInputs& in) { return sunLayer(in, false); }},
    {"temperature", "degC", "air temperature at the surface, T = T0 + k_t A + k_i I (§4.1)", S, kNeedsSun, LayerKind::Float,
     [](const LayerInputs& in) { return sunLayer(in, true); }},
    {"wind_scour", "m", "snow removed by wind transport since the season start (m)", S, kNeedsState, LayerKind::Float,
     SNOW_STATE_LAYER(s.windScourM(x, y)), R(windScourM)},
    {"wind_deposit", "m", "snow deposited by wind transport since the season start (m)", S, kNeedsState, LayerKind::Float,
     SNOW_STATE_LAYER(s.windDepositM(x, y)), R(windDepositM)},
    {"melt", "m", "snow melted since the season start (m)", S, kNeedsState, LayerKind::Float, SNOW_STATE_LAYER(s.meltedM(x, y)),
     R(meltedM)},
    {"avalanche_scour", "m", "snow taken away by avalanches since the season start, net per avalanche (m)", S, kNeedsState,
     LayerKind::Float, SNOW_STATE_LAYER(s.avalancheScourM(x, y)), R(avalancheScourM)},
    {"avalanche_deposit", "m", "snow left by avalanches since the season start, net per avalanche (m)", S, kNeedsState,
     LayerKind::Float, SNOW_STATE_LAYER(s.avalancheDepositM(x, y)), R(avalancheDepositM)},
    {"avalanche_peak_thickness", "m", "the deepest moving snow of any avalanche since the season start (peak flowing thickness, m)", S,
     kNeedsState, LayerKind::Float, SNOW_STATE_LAYER(s.avalancheSeasonPeakThicknessM(x, y)), R(avalancheSeasonPeakThicknessM)},
    {"avalanche_peak_speed", "m/s", "the fastest flow of any avalanche since the season start (peak speed: the snow's speed, or with season.avalanche_flow = \"pipes\" the fastest pipe's, m/s)", S, kNeedsState,
     LayerKind::Float, SNOW_STATE_LAYER(s.avalancheSeasonPeakSpeedMps(x, y)), R(avalancheSeasonPeakSpeedMps)},
    {"avalanche_preview", "sRGB", "preview: shaded snow surface, avalanche scour red (full at 1 m), deposit blue (full at 2 m)", S,
     kNeedsState, LayerKind::Preview, nullptr, R(avalancheScourM) | R(avalancheDepositM)},
    {"preview", "sRGB",
     "preview: shaded relief of the snow-covered terrain, sun at solar noon of the day; snow by top layer (powder white, "
     "unstable pale blue, stable cream, compacted grey)",
     G, kNeedsState, LayerKind::Preview, nullptr},
    {"ambient_occlusion", "1",
     "ambient occlusion value a (Foldes & Benes Eq. 1): cosine-weighted fraction of the hemisphere open to the sky, 1 = unoccluded", O,
     kNeedsOcclusion, LayerKind::Float, [](const LayerInputs& in) { return in.occlusion->ambient; }},
    {"sun_visibility", "1", "sun visibility v: luminance-weighted fraction of the day's sun trajectory that sees the point", O,
     kNeedsOcclusion, LayerKind::Float, [](const LayerInputs& in) { return in.occlusion->sunVisibility; }},
    {"occlusion_accumulation", "m", "snow placed by ambient occlusion, s_max max(0, tau_ambient - a) cos(theta) (Eq. 1)", O,
     kNeedsOcclusion, LayerKind::Float, [](const LayerInputs& in) { return in.occlusion->accumulationM; }},
    {"occlusion_dissipation", "m", "snow the sun dissipates, s_max max(0, v - tau_sun) cos(theta)", O, kNeedsOcclusion,
     LayerKind::Float, [](const LayerInputs& in) { return in.occlusion->dissipationM; }},
    {"ski_tracks", "m",
     "ski tracks: depth of the grooves below the snow surface (subtract from the surface), faded by snow since", S, kNeedsSkiTracks,
     LayerKind::Float, [](const LayerInputs& in) { return *in.skiDepth; }},
    {"ski_route_map", "m", "skiers' route map: length of the longest strictly descending path from the cell (m)", S, kNeedsRouteMap,
     LayerKind::Float,
     [](const LayerInputs& in) {
       return in.routeMap->empty() ? Grid<float>(in.state->spec.width, in.state->spec.height, 0.f) : *in.routeMap;
     }},
    {"bedform_cohesion", "1",
     "wind bedforms: cohesion of the loose snow, 0 loose .. 1 bonded; wind lifts it above threshold / (1 - cohesion)", S, kNeedsState,
     LayerKind::Float,
     SNOW_STATE_LAYER(s.bedformCohesion.size() == s.spec.cellCount() ? s.bedformCohesion(x, y) : 0.f)},
    // Engine layers (docs/outputs.md, Engine layers)
    {"snow_coverage_hard", "1", "hard snow cover: 1 where snow_coverage >= 0.5 (depth at least midway between outputs.coverage_depths_m's two), else 0",
     G, kNeedsState, LayerKind::Float,
     [](const LayerInputs& in) {
       Grid<float> g = snowCoverage(in);
       for (float& v : g.values()) v = v >= 0.5f ? 1.f : 0.f;
       return g;
     }},
    {"weight_snow", "1", "engine weight of the snow layer: snow_coverage (weight_snow + weight_rock + weight_ground = 1)", G, kNeedsState,
     LayerKind::Float, [](const LayerInputs& in) { return engineWeight(in, 0); }},
    {"weight_rock", "1", "engine weight of the rock layer: the bare share (1 - snow_coverage) on bedrock steeper than 30-45 deg (a smooth step)", G,
     kNeedsState, LayerKind::Float, [](const LayerInputs& in) { return engineWeight(in, 1); }},
    {"weight_ground", "1", "engine weight of the ground layer: the bare share on gentler bedrock", G, kNeedsState, LayerKind::Float,
     [](const LayerInputs& in) { return engineWeight(in, 2); }},
    {"splat_map", "1", "Unity RGBA splat map, 8 bits: R weight_snow, G weight_rock, B weight_ground, A 0; channels sum to 255 at every pixel (NODATA: ground)",
     G, kNeedsState, LayerKind::Preview, nullptr},
    {"snow_normal", "unit vector",
     "tangent-space normal map of the snow surface (u east, v north, 8-bit RGB = 0.5 + 0.5 n; outputs.normal_map_convention: opengl, or directx with G flipped)",
     G, kNeedsState, LayerKind::Preview, nullptr},
};
#undef R

#undef SNOW_STATE_LAYER

}  // namespace

std::span<const LayerInfo> layerTable() { return kLayers; }

const LayerInfo* findLayer(const std::string& name) {
  for (const LayerInfo& l : kLayers)
    if (name == l.name) return &l;
  return nullptr;
}

uint8_t layersNeeds(const std::vector<std::string>& names) {
  uint8_t needs = 0;
  for (const std::string& name : names)
    if (const LayerInfo* l = findLayer(name)) needs |= l->needs;
  return needs;
}

SnowFieldSet layersRecords(const std::vector<std::string>& names) {
  SnowFieldSet records = 0;
  for (const std::string& name : names)
    if (const LayerInfo* l = findLayer(name)) records |= l->records;
  return records;
}

}  // namespace snow
