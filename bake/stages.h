// The stages of a bake, in the order bake.cpp runs them. Each is a function (or a small class)
// in a file of its own in this folder; the modes (mode_grid.cpp for season and occlusion,
// mode_mesh.cpp) are drivers that chain them.
#pragma once
#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <ostream>
#include <vector>

#include "art_direction.h"
#include "bake.h"
#include "bakers/manifest.h"
#include "bakers/output_writer.h"
#include "core/backend.h"
#include "core/grid_window.h"
#include "core/season.h"
#include "core/util.h"
#include "frame_writer.h"
#include "core/ski_runs.h"
#include "precompute/cache.h"
#include "precompute/exposure.h"
#include "inputs/mesh.h"
#include "scene/scene.h"
#include "inputs/terrain_loader.h"
#include "precompute/wind_timeline.h"
#include "scene/layers.h"

namespace snow {

// stage_scene.cpp: the scene file with the command line's overrides (--terrain, --seed,
// --threads, --backend) applied and checked.
Scene resolveScene(const BakeOptions& options);

// stage_terrain.cpp: the terrain, the occluder meshes and the site's latitude.
struct BakeTerrain {
  Terrain terrain;
  std::vector<TriangleMesh> occluders;
  double latitudeDeg = 45.0;
  const TerrainInfo& info() const { return terrain.info; }
};
BakeTerrain loadBakeTerrain(const Scene& scene, std::ostream& log);
// The state on `cells` of the terrain's grid, with the terrain's and the snow's fields: the record
// fields are made by the season (those an output reads, SeasonConfig::recordFields) and the static
// fields by the precompute's fill of day 0, so neither is held through the art direction and the
// precompute's sweeps. `cells` is the whole grid, or across ranks a rank's local grid: the cells
// the whole state's cut would hold (dist::cutLocalState), its spec's origin at their corner.
SnowState initialState(const BakeTerrain& terrain, const CellRect& cells);

// Whether a precompute stage runs, and why not: the one decision the bake acts on and
// `snowbake plan` reports (stage_precompute.cpp).
struct StageDecision {
  bool runs = true;
  std::string why;  // when it is skipped: "occlusion mode", "precompute.sun = false", "no wind in the season"
};
StageDecision sunExposureDecision(const Scene& scene);
StageDecision windDecision(const Scene& scene);

// stage_precompute.cpp: sun exposure (from the cache when it can) and the wind timeline; fills
// the state's static fields of day 0 and refreshes them on later days.
struct Precomputed {
  std::optional<Exposure> exposure;
  std::optional<WindTimeline> wind;  // a calm timeline in occlusion mode
  // A part was made on a rank's local grid alone (PrecomputeParts): the whole state's static
  // fields are not filled for day 0; each rank fills its local grid's.
  bool partsOnRanks = false;
  // T = T0 + k_t A + k_i I (§4.1), the exposure of the day interpolated between samples.
  void temperatureForDay(int day, SnowState& s, const ModelParameters& params) const;
  // The day's wind (calm: no wind, W_z on the ground).
  void windForDay(int day, SnowState& s) const;
  // One rectangle of cells of each (a rank's local grid, across ranks): its days' fields are
  // those cells' bytes of this one's.
  Precomputed window(int x0, int y0, int width, int height) const;
};
// The season's daily refresh of the static fields from `pre` (SeasonConfig::updateStaticFields;
// empty where they never change): the temperature from each day's exposure, a wind that varies.
std::function<void(int, SnowState&)> dailyStaticFill(const Precomputed& pre, const ModelParameters& params);
// The sun exposure's settings, and the cache key of its grids (every input they depend on).
ExposureSettings exposureSettings(const Scene& scene, const BakeTerrain& terrain);
std::string exposureCacheKey(const Grid<float>& bedrockM, const Grid<uint8_t>& valid, const GridSpec& spec,
                             const std::vector<TriangleMesh>& occluders, const ModelParameters& p, const ExposureSettings& es);
// Across ranks, the parts of the precompute a rank makes on its local grid alone (across_ranks.h:
// rankPrecomputeParts); none: the whole grid's.
struct PrecomputeParts {
  std::optional<CellRect> exposure;
  std::optional<WindPart> wind;
  bool any() const { return exposure || wind; }
  // Where the season runs on the whole grid's replica (no part above): the sun exposure computed
  // on these cells alone, then made whole by `wholeExposure` from every rank's (a gather), so the
  // ranks share its rays and sweeps instead of each computing the whole grid's; the wind alike.
  std::optional<CellRect> exposureShare;
  std::function<Exposure(const Exposure&)> wholeExposure;
  std::optional<WindPart> windShare;
  std::function<WindTimeline(const WindTimeline& share, const Grid<float>& wholeAltitude)> wholeWind;
};
Precomputed runPrecompute(const Scene& scene, const BakeTerrain& terrain, SnowState& state, const PrecomputeCache& cache,
                          const PrecomputeParts& parts, std::ostream& log);

// stage_backend.cpp: the season's backend (--backend, run.backend: cpu, cuda or auto).
std::unique_ptr<SnowBackend> chooseBackend(BackendChoice wanted, std::ostream& log);

// stage_occlusion.cpp: mode = "occlusion" (Foldes & Benes 2007) in place of the season: the
// four occlusion fields, the static cover in the state's stable layer, and on a mesh terrain the
// mesh with its snow.
struct OcclusionResult {
  OcclusionGrids grids;
  ManifestOcclusion manifest;
  std::optional<TriangleMesh> snowMesh;
  SeasonReport report;  // the final snow and the time taken
};
// Whether occlusion mode also writes the input mesh raised by its snow (snow_mesh.*): a mesh terrain with outputs.meshes.
bool occlusionWritesSnowMesh(const Scene& scene, const TerrainInfo& terrain);
void runOcclusion(const Scene& scene, const BakeTerrain& terrain, SnowState& state, OcclusionResult& result, std::ostream& log);

// season_config.cpp: what the season runs: the scene's events as cells, art direction's edits
// and masked events, the ski-track texture and route map when the outputs ask for them.
struct SeasonOutputs {
  std::optional<SkiTracks> skiTracks;  // when the layers ask for ski_tracks
  Grid<float> routeMap;                // when the layers ask for ski_route_map
};
SeasonConfig makeSeasonConfig(const Scene& scene, const BakeTerrain& terrain, const ArtDirectionPlan& art,
                              const Precomputed& pre, const std::vector<std::string>& layers, SeasonOutputs& outputs, std::ostream& log);
// Refuses [bedforms] settings that do not suit the grid (an odd grid's periodic window, a slab
// the cells cannot hold), naming the key's file and line; nothing when bedforms are off.
void checkBedformsSuitTheGrid(const Scene& scene, const GridSpec& spec);

// stage_season.cpp: the season, its frame days handed to `frames` (frame_writer.h: written beside
// it, in place, or held for writeHeld after it); logs its report.
SeasonReport runSeasonStage(const Scene& scene, SnowBackend& backend, SnowState& state, const SeasonConfig& config, FrameWriter& frames,
                            std::ostream& log);
// season_log.cpp: the season's report as the log prints it.
void logSeasonReport(const SeasonReport& report, const Scene& scene, const SeasonConfig& config, const std::string& backendName,
                     std::ostream& log);

}  // namespace snow
