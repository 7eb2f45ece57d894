// Art direction (docs/models/art-direction.md): the scene's painted rasters read, placed on the grid,
// and turned into what the season runs with: the initial snow cover, the per-cell multipliers
// and no-snow mask in the SnowState, timeline edits, and masked avalanche and skier events.
#pragma once
#include <ostream>
#include <string>
#include <vector>

#include "bakers/manifest.h"
#include "core/grid_window.h"
#include "core/season.h"
#include "inputs/terrain_loader.h"
#include "scene/scene.h"

namespace snow {

struct ArtDirectionPlan {
  std::vector<ManifestRaster> rasters;    // every raster mapped (for the manifest)
  std::vector<SeasonEdit> edits;          // in day order
  std::vector<ManifestEdit> editRecords;  // the same, described (volumes filled after the season)
  std::vector<UserAvalanche> avalanches;  // masked releases
  std::vector<UserSkier> skiers;          // skiers from start masks
  double initialSnowM3 = 0.0;             // placed by [initial_snow]
  bool any() const { return !rasters.empty() || !edits.empty(); }
};

// Reads the rasters the scene names and fills `state` (initial layers, multipliers, noSnow) on
// `cells` of the terrain's grid, the cells it holds: the whole grid, or across ranks a rank's
// local grid. The rasters are placed, and the volumes and cells the log and the manifest report
// taken, on the whole grid (in its order), so every rank's plan is the single process's.
// Throws InputError naming the raster file and the problem.
ArtDirectionPlan prepareArtDirection(const Scene& scene, const Terrain& terrain, const CellRect& cells, SnowState& state, std::ostream& log);

}  // namespace snow
