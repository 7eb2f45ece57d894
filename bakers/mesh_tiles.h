// outputs.mesh_tile_size_m: a mesh made from the grid cut into square tiles along the tiles'
// borders. A triangle across a border is clipped to each tile it covers; the points where a
// border crosses an edge are computed from the edge alone (its two vertices in a fixed order),
// the corners where two borders meet from the plane of the first triangle that reaches them, and
// a point's attributes are kept once for all tiles, so both sides of a border hold the same
// vertices bit for bit and the tiles meet without cracks.
#pragma once
#include <vector>

#include "core/grid.h"
#include "mesh_writer.h"

namespace snow {

// `column`/`row` count from the west and the north; tiles with no triangle are left out.
std::vector<MeshTile> cutIntoTiles(const MeshData& mesh, const GridSpec& spec, int tileCells);

}  // namespace snow
