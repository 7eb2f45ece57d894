// The snow body as an OpenVDB file: `snow_sdf` (level set of the snow body, world units metres),
// `density` (fog volume, 1 inside the snow) and one fog grid per layer (`compacted`, `stable`,
// `unstable`, `powder`) holding that layer's density in kg/m^3 (VdbOptions). World axes: x east
// from the grid's west edge, y north from its south edge, z altitude (Blender's z-up). A voxel
// is snow when its centre lies between the bedrock and the snow surface of the cell under it, so
// snow thinner than about half a voxel is not in the volume.
#pragma once
#include <algorithm>
#include <string>

#include "core/snow_state.h"
#include "vdb_level_set_tiles.h"

namespace snow {

struct VdbOptions {
  double voxelSizeM = 1.0;
  // Documented per-layer densities (kg/m^3): fresh powder, wind- or warmth-loosened unstable
  // snow, settled stable snow, compacted (skied or avalanche-packed) snow.
  double powderKgPerM3 = 100.0, unstableKgPerM3 = 250.0, stableKgPerM3 = 350.0, compactedKgPerM3 = 500.0;
  // The level set's tiles, in voxel columns a side (a multiple of 128; vdb_level_set.h): the
  // same bytes at any size, the writer's peak memory falls and its time rises as they shrink.
  int levelSetTileColumns = LevelSetTiling{}.tileColumns;
};

struct VdbSummary {
  std::string path;
  size_t snowVoxels = 0;
};

// The voxel size the bake writes: outputs.vdb_voxel_size_m (`sceneVoxelSizeM`, 0 when unset),
// else the grid's smaller cell size.
inline double vdbVoxelSizeM(double sceneVoxelSizeM, const GridSpec& spec) {
  return sceneVoxelSizeM > 0.0 ? sceneVoxelSizeM : std::min(spec.cellSizeXM, spec.cellSizeYM);
}

// Written atomically. Throws std::runtime_error on failure.
VdbSummary writeSnowVdb(const std::string& path, const SnowState& state, const VdbOptions& options);

}  // namespace snow
