#include "manifest.h"

#include <nlohmann/json.hpp>

namespace snow {

namespace {

using nlohmann::ordered_json;

ordered_json terrainJson(const Manifest& m) {
  return {{"source", m.terrainSource},
          {"hash_fnv1a64", m.terrainHash},
          {"coordinate_system", m.coordinateSystem},
          {"width", m.grid.width},
          {"height", m.grid.height},
          {"cell_size_x_m", m.grid.cellSizeXM},
          {"cell_size_y_m", m.grid.cellSizeYM},
          {"origin_x", m.grid.originX},
          {"origin_y", m.grid.originY},
          {"row_order", "north to south"}};
}

ordered_json phenomenaJson(const Manifest& m) {
  ordered_json phenomena = ordered_json::array();
  for (const auto& p : m.phenomena)
    phenomena.push_back({{"name", p.name}, {"starts", p.starts}, {"steps", p.steps}, {"stops", p.stops}, {"skipped_steps", p.skippedSteps}});
  return phenomena;
}

ordered_json avalanchesJson(const Manifest& m) {
  ordered_json avalanches = ordered_json::array();
  for (const auto& a : m.avalanches)
    avalanches.push_back({{"day", a.day}, {"rupture_cell", {a.x, a.y}}, {"user", a.user}, {"released", a.released},
                          {"outcome", a.why}, {"release_cells", a.releaseCells}, {"footprint_cells", a.footprintCells},
                          {"released_m3", a.releasedM3}, {"deposit_m3", a.depositM3}, {"runout_m", a.runoutM},
                          {"fall_height_m", a.fallHeightM}, {"steps", a.steps}, {"simulated_s", a.simulatedS},
                          {"rupture_slope_deg", a.ruptureSlopeDeg}});
  return avalanches;
}

ordered_json skiersJson(const Manifest& m) {
  ordered_json skiers = ordered_json::array();
  for (const auto& k : m.skiers)
    skiers.push_back({{"day", k.day}, {"start_cell", {k.x, k.y}}, {"user", k.user}, {"cells", k.cells}, {"length_m", k.lengthM},
                      {"drop_m", k.dropM}, {"triggered_avalanche", k.triggered}, {"outcome", k.why}});
  return skiers;
}

ordered_json parametersJson(const Manifest& m) {
  ordered_json parameters = ordered_json::object();
  for (const auto& [key, value] : m.parameters) parameters[key] = value;
  return parameters;
}

ordered_json occlusionJson(const ManifestOcclusion& o) {
  ordered_json sun = ordered_json::array();
  for (const auto& [hour, weight] : o.sunHoursAndWeights) sun.push_back({{"solar_hour", hour}, {"weight", weight}});
  return {{"method", "Foldes & Benes 2007: ambient occlusion (Eq. 1) and sun-trajectory dissipation (Eqs. 2-3)"},
          {"s_max_m", o.sMaxM},
          {"tau_ambient", o.tauAmbient},
          {"tau_sun", o.tauSun},
          {"ao_rays", o.aoRays},
          {"ao_radius_m", o.aoRadiusM},
          {"day", o.day},
          {"day_of_year", o.dayOfYear},
          {"turbidity", o.turbidity},
          {"sun_positions", sun},
          {"mesh_source", o.meshSource}};
}

// The run's settings, then what happened in it (key order is the file's order).
ordered_json runJson(const Manifest& m) {
  ordered_json run = {{"mode", m.mode},
                      {"seed", m.seed},
                      {"backend", m.backend},
                      {"latitude_deg", m.latitudeDeg},
                      {"season_start", m.seasonStartDate},
                      {"season_days", m.seasonDays},
                      {"events", m.events}};
  run["phenomena"] = phenomenaJson(m);
  run["avalanches"] = avalanchesJson(m);
  run["skiers"] = skiersJson(m);
  run["parameters"] = parametersJson(m);
  if (m.mode == "occlusion") run["occlusion"] = occlusionJson(m.occlusion);
  return run;
}

ordered_json editJson(const ManifestEdit& e) {
  ordered_json o = {{"day", e.day}, {"op", e.op}, {"layer", e.layer}};
  if (!e.to.empty()) o["to"] = e.to;
  if (e.depthM >= 0) o["depth_m"] = e.depthM;
  o["mask"] = e.mask.empty() ? ordered_json(nullptr) : ordered_json(e.mask);
  o["volume_m3"] = e.volumeM3;
  return o;
}

ordered_json artDirectionJson(const Manifest& m) {
  ordered_json rasters = ordered_json::array();
  for (const auto& r : m.artRasters)
    rasters.push_back({{"role", r.role}, {"source", r.source}, {"hash_fnv1a64", r.hash}, {"reader", r.reader}, {"width", r.width},
                       {"height", r.height}, {"placement", r.placement}, {"mapping", r.description}, {"coverage", r.coverage},
                       {"min", r.minValue}, {"max", r.maxValue}, {"mean", r.meanValue}});
  ordered_json edits = ordered_json::array();
  for (const auto& e : m.edits) edits.push_back(editJson(e));
  return {{"rasters", rasters}, {"edits", edits}, {"edits_net_m3", m.editsNetM3}, {"no_snow_removed_m3", m.noSnowRemovedM3}};
}

ordered_json filesJson(const Manifest& m) {
  ordered_json files = ordered_json::array();
  for (const auto& f : m.files) {
    ordered_json e = {{"path", f.path}, {"content", f.content}, {"unit", f.unit}, {"format", f.format}};
    if (f.day >= 0) e["day"] = f.day; else e["day"] = "final";
    e["min"] = f.minValue;
    e["max"] = f.maxValue;
    e["width"] = f.width > 0 ? f.width : m.grid.width;
    e["height"] = f.height > 0 ? f.height : m.grid.height;
    if (!f.rangeMode.empty())
      e["range"] = {{"mode", f.rangeMode}, {"lo", f.rangeLo}, {"hi", f.rangeHi}, {"nodata_pixel", f.nodataPixel}};
    if (!f.tileConvention.empty())
      e["tile"] = {{"convention", f.tileConvention}, {"column", f.tileColumn}, {"row", f.tileRow}, {"x", f.tileX}, {"y", f.tileY},
                   {"origin_x", f.tileOriginX}, {"origin_y", f.tileOriginY}, {"pixel_size_x", f.pixelSizeX}, {"pixel_size_y", f.pixelSizeY}};
    files.push_back(e);
  }
  return files;
}

// The memory object on a line of its own before "files" (the one line two runs of a bake differ by).
std::string withMemoryLine(std::string text, const std::string& memoryJson) {
  if (!memoryJson.empty())
    if (const size_t at = text.find("\n  \"files\": "); at != std::string::npos) text.insert(at, "\n  \"memory\": " + memoryJson + ",");
  return text;
}

}  // namespace

std::string manifestToJson(const Manifest& m) {
  ordered_json j;
  j["snowbake_manifest_version"] = 1;
  j["program"] = {{"name", "snowbake"}, {"version", m.programVersion}};
  j["scene"] = {{"source", m.sceneSource}, {"name", m.sceneName}, {"hash_fnv1a64", m.sceneHash}, {"resolved", "scene.resolved.toml"}};
  j["command_line"] = m.commandLine;
  j["inputs"] = ordered_json::array();
  for (const auto& [path, hash] : m.inputHashes) j["inputs"].push_back({{"path", path}, {"hash_fnv1a64", hash}});
  j["terrain"] = terrainJson(m);
  j["run"] = runJson(m);
  if (!m.artRasters.empty() || !m.edits.empty()) j["art_direction"] = artDirectionJson(m);
  j["mass_balance_m3"] = {{"initial_snow", m.initialSnowM3},
                          {"snowfall_added", m.snowfallAddedM3},
                          {"melt_removed", m.meltRemovedM3},
                          {"final_snow", m.finalSnowM3}};
  j["files"] = filesJson(m);
  return withMemoryLine(j.dump(2) + "\n", m.memoryJson);
}

std::string meshSnowManifestToJson(const MeshSnowManifest& m) {
  using nlohmann::ordered_json;
  ordered_json j;
  j["snowbake_manifest_version"] = 1;
  j["program"] = {{"name", "snowbake"}, {"version", m.programVersion}};
  j["scene"] = {{"source", m.sceneSource}, {"name", m.sceneName}, {"hash_fnv1a64", m.sceneHash}, {"resolved", "scene.resolved.toml"}};
  j["command_line"] = m.commandLine;
  j["mesh"] = {{"source", m.meshSource},
               {"hash_fnv1a64", m.meshHash},
               {"triangles", m.triangles},
               {"bounds_min_m", {m.boundsMin[0], m.boundsMin[1], m.boundsMin[2]}},
               {"bounds_max_m", {m.boundsMax[0], m.boundsMax[1], m.boundsMax[2]}},
               {"axes", "the input mesh's: x, y, z up, metres (glb, obj and fbx outputs are y-up, see docs/outputs.md)"}};
  const FallenSnowSettings& p = m.placement;
  const FallenSnowStability& s = m.stability;
  const FallenSnowStabilityReport& r = m.stabilityReport;
  j["run"] = {{"mode", "mesh"},
              {"seed", m.seed},
              {"method", "Fearing 2000: flake placement with flutter and sky buckets (Ch. 7), angle-of-repose stability (Ch. 8)"},
              {"placement",
               {{"depth_m", p.depthM}, {"site_spacing_m", p.siteSpacingM}, {"sky_cell_sites", p.skyCellSites},
                {"flakes_per_site", p.flakesPerSite}, {"flutter_mean_m", p.flutterMeanM}, {"flutter_sigma_m", p.flutterSigmaM},
                {"swirl_height_m", p.swirlHeightM}, {"max_coverage_diff", p.maxCoverageDiff}, {"sites", m.sites}}},
              {"stability",
               {{"repose_angle_deg", s.reposeAngleDeg}, {"transition_width_deg", s.transitionWidthDeg}, {"deposit_rounds", s.depositRounds},
                {"stop_fraction", s.stopFraction}, {"connect_angle_deg", s.connectAngleDeg}, {"passes", r.passes},
                {"unconverged_rounds", r.unconvergedRounds}, {"wall_directions", r.wallDirections}, {"drop_directions", r.dropDirections},
                {"buried_sites", r.buriedSites}}},
              {"body", {{"voxel_size_m", m.voxelSizeM}, {"triangles", m.bodyTriangles}}}};
  j["mass_balance_m3"] = {{"sky", m.skyM3}, {"placed", m.placedM3}, {"over_edges", r.overEdgesM3},
                          {"left_the_world", r.leftTheWorldM3}, {"kept", r.finalM3}};
  ordered_json files = ordered_json::array();
  for (const auto& f : m.files) files.push_back({{"path", f.path}, {"content", f.content}, {"unit", f.unit}, {"format", f.format}});
  j["files"] = files;
  return withMemoryLine(j.dump(2) + "\n", m.memoryJson);
}

}  // namespace snow
