// How the snow body's level set is tiled (vdb_level_set.h), without OpenVDB: for the memory model.
#pragma once
#include <algorithm>

namespace snow {

// The level set's half width in voxels (the VDB writer's snow_sdf).
constexpr int kSnowLevelSetHalfWidth = 3;

// A tile's halo in voxel columns: twice how far topologyToLevelSet carries a change of topology
// (the mask's erosion and the float tree's dilation, halfWidth each, then 3 halfWidth
// normalisation steps of a one-voxel stencil), in whole leaves of 8.
constexpr int levelSetHaloColumns(int halfWidth) { return (2 * 5 * std::max(halfWidth, 1) + 7) / 8 * 8; }

struct LevelSetTiling {
  int columnsI = 0, columnsJ = 0;  // the voxel columns that can hold snow: [0, columnsI) x [0, columnsJ)
  int tileColumns = 512;           // a tile's side, a multiple of 128 (an internal node's)
};

}  // namespace snow
