// The snow body's level set made tile by tile (private to bakers/: it includes OpenVDB).
// openvdb::tools::topologyToLevelSet over a whole grid's topology holds its mask, the dilated
// float tree and the normalisation's buffer at once, about 2.7 times the level set it returns:
// that was the VDB writer's peak. Here each tile of columns, with a halo wider than the
// construction reaches, goes through topologyToLevelSet alone and the nodes over the tile are
// moved into the result, which is then pruned as the whole one is: the same tree, so the same
// file bytes (Vdb.LevelSetByTilesIsTopologyToLevelSetsFileBytes), in about the level set's memory.
#pragma once
#include <openvdb/openvdb.h>

#include <functional>

#include "vdb_level_set_tiles.h"

namespace snow {

// Sets the voxels (i, j, k) of columns i0 <= i < i1, j0 <= j < j1 to true.
using TopologyFill = std::function<void(openvdb::BoolGrid::Accessor&, int i0, int j0, int i1, int j1)>;

// topologyToLevelSet(topology, halfWidth, 0) of the whole topology `fill` sets, with `transform`.
openvdb::FloatGrid::Ptr levelSetByTiles(const TopologyFill& fill, const LevelSetTiling& tiling,
                                        const openvdb::math::Transform::Ptr& transform, int halfWidth);

}  // namespace snow
