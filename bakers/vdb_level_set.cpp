#include "vdb_level_set.h"

#include <openvdb/tools/Prune.h>
#include <openvdb/tools/TopologyToLevelSet.h>

#include <algorithm>
#include <climits>
#include <stdexcept>
#include <vector>

namespace snow {
namespace {

using Tree = openvdb::FloatTree;
using Node2 = Tree::RootNodeType::ChildNodeType;  // 4096 voxels a side
using Node1 = Node2::ChildNodeType;               // 128 voxels a side: the tiles' unit

// Columns x0 <= x < x1, y0 <= y < y1, every altitude.
struct Columns {
  int x0, y0, x1, y1;
  bool holds(const openvdb::Coord& c) const { return c.x() >= x0 && c.x() < x1 && c.y() >= y0 && c.y() < y1; }
};

Node2& nodeOf(Tree& out, const openvdb::Coord& xyz) {
  if (Node2* n = out.root().probeNode<Node2>(xyz)) return *n;
  auto* n = new Node2(xyz, out.background(), false);
  out.root().addChild(n);
  return *n;
}

// Moves the part's 128-voxel nodes and tiles over `interior` into `out` (interior's edges are
// multiples of 128, so each lies wholly inside or outside). A level-2 node the part holds over the
// interior is made in `out` even where it holds nothing there, as the whole tree holds it: the
// final prune then ends it as the whole tree's prune does.
void moveInterior(Tree& part, const Columns& interior, Tree& out) {
  const int span = static_cast<int>(Node2::DIM), step = static_cast<int>(Node1::DIM);
  for (auto tile = part.root().cbeginValueAll(); tile; ++tile) {  // a level-2 region all one value
    const openvdb::Coord o = tile.getCoord();
    for (int z = o.z(); z < o.z() + span; z += step)
      for (int y = std::max(o.y(), interior.y0); y < std::min(o.y() + span, interior.y1); y += step)
        for (int x = std::max(o.x(), interior.x0); x < std::min(o.x() + span, interior.x1); x += step)
          nodeOf(out, {x, y, z}).addTile(Node2::LEVEL, {x, y, z}, *tile, tile.isValueOn());
  }
  std::vector<Node2*> parents;
  for (auto n = part.root().beginChildOn(); n; ++n) parents.push_back(&*n);
  for (Node2* from : parents) {
    const openvdb::Coord o = from->origin();
    if (o.x() >= interior.x1 || o.x() + span <= interior.x0 || o.y() >= interior.y1 || o.y() + span <= interior.y0)
      continue;
    Node2& to = nodeOf(out, o);
    for (auto tile = from->cbeginValueAll(); tile; ++tile)
      if (interior.holds(tile.getCoord())) to.addTile(Node2::LEVEL, tile.getCoord(), *tile, tile.isValueOn());
    std::vector<openvdb::Coord> children;
    for (auto c = from->cbeginChildOn(); c; ++c)
      if (interior.holds(c.getCoord())) children.push_back(c.getCoord());
    for (const openvdb::Coord& c : children) to.addChild(from->stealNode<Node1>(c, part.background(), false));
  }
}

}  // namespace

openvdb::FloatGrid::Ptr levelSetByTiles(const TopologyFill& fill, const LevelSetTiling& tiling,
                                        const openvdb::math::Transform::Ptr& transform, int halfWidth) {
  const int tile = tiling.tileColumns;
  if (tile <= 0 || tile % static_cast<int>(Node1::DIM) != 0) throw std::logic_error("level-set tiles must be multiples of 128 voxels");
  const int halo = levelSetHaloColumns(halfWidth);
  auto out = openvdb::FloatGrid::create(static_cast<float>(transform->voxelSize()[0]) * static_cast<float>(halfWidth));
  out->setTransform(transform);
  out->setGridClass(openvdb::GRID_LEVEL_SET);
  const int tilesI = std::max(1, (tiling.columnsI + tile - 1) / tile), tilesJ = std::max(1, (tiling.columnsJ + tile - 1) / tile);
  for (int tj = 0; tj < tilesJ; ++tj)
    for (int ti = 0; ti < tilesI; ++ti) {
      // The outer tiles' interiors run on past the grid, where the band's dilation reaches.
      const Columns interior{ti == 0 ? INT_MIN : ti * tile, tj == 0 ? INT_MIN : tj * tile,
                             ti + 1 == tilesI ? INT_MAX : (ti + 1) * tile, tj + 1 == tilesJ ? INT_MAX : (tj + 1) * tile};
      auto topology = openvdb::BoolGrid::create(false);
      topology->setTransform(transform);
      {
        auto acc = topology->getAccessor();
        fill(acc, std::max(0, ti * tile - halo), std::max(0, tj * tile - halo), std::min(tiling.columnsI, (ti + 1) * tile + halo),
             std::min(tiling.columnsJ, (tj + 1) * tile + halo));
      }
      if (topology->tree().activeVoxelCount() == 0) continue;
      auto part = openvdb::tools::topologyToLevelSet(*topology, halfWidth, 0);
      topology.reset();
      moveInterior(part->tree(), interior, out->tree());
    }
  openvdb::tools::pruneLevelSet(out->tree());
  return out;
}

}  // namespace snow
