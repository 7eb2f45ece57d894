#include "vdb_writer.h"

#include <openvdb/openvdb.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "vdb_file.h"
#include "vdb_level_set.h"

namespace snow {

VdbSummary writeSnowVdb(const std::string& path, const SnowState& s, const VdbOptions& o) {
  openvdb::initialize();
  if (!(o.voxelSizeM > 0.0)) throw std::runtime_error("VDB voxel size must be positive");
  const double vs = o.voxelSizeM;
  const int w = s.spec.width, h = s.spec.height;
  const double dx = s.spec.cellSizeXM, dy = s.spec.cellSizeYM;
  // Voxel (i, j, k) is filled from its centre ((i + 1/2) vs, ...): the transform puts it there.
  const auto transform = openvdb::math::Transform::createLinearTransform(vs);
  transform->postTranslate(openvdb::Vec3d(0.5 * vs, 0.5 * vs, 0.5 * vs));
  VdbSummary summary;
  summary.path = path;
  // Calls f(coord, layer) for every snow voxel of columns [i0, i1) x [j0, j1), column by column.
  const int ni = static_cast<int>(std::ceil(w * dx / vs)), nj = static_cast<int>(std::ceil(h * dy / vs));
  auto forEachSnowVoxelIn = [&](int i0, int j0, int i1, int j1, auto&& f) {
    for (int j = j0; j < j1; ++j) {
      const double yNorth = (j + 0.5) * vs;  // metres north of the south edge
      const int row = h - 1 - std::min(h - 1, static_cast<int>(yNorth / dy));
      for (int i = i0; i < i1; ++i) {
        const int col = std::min(w - 1, static_cast<int>((i + 0.5) * vs / dx));
        if (!s.validCell(col, row)) continue;
        const double bed = s.bedrockM(col, row);
        const double top[4] = {bed + s.compactedM(col, row), bed + s.compactedM(col, row) + s.stableM(col, row),
                               bed + s.compactedM(col, row) + s.stableM(col, row) + s.unstableM(col, row),
                               bed + s.depthM(col, row)};
        if (!(top[3] > bed)) continue;
        const int k0 = static_cast<int>(std::ceil(bed / vs - 0.5)), k1 = static_cast<int>(std::floor(top[3] / vs - 0.5));
        for (int k = k0; k <= k1; ++k) {
          const double z = (k + 0.5) * vs;
          if (!(z > bed && z < top[3])) continue;
          int l = 0;
          while (l < 3 && z >= top[l]) ++l;
          f(openvdb::Coord(i, j, k), l);
        }
      }
    }
  };
  auto forEachSnowVoxel = [&](auto&& f) { forEachSnowVoxelIn(0, 0, ni, nj, f); };
  // Each grid is made when the file reaches it and freed once written (vdb_file.h): the level
  // set's construction (its dilation and normalisation, the writer's largest transient) and the
  // fog grids never stand side by side; the level set is made tile by tile (vdb_level_set.h).
  auto finish = [&](openvdb::FloatGrid::Ptr g, const char* name, openvdb::GridClass cls) {
    g->setTransform(transform);
    g->setName(name);
    g->setGridClass(cls);
    return g;
  };
  std::vector<VdbGridMaker> makers;
  makers.push_back([&]() -> openvdb::GridBase::Ptr {
    forEachSnowVoxel([&](const openvdb::Coord&, int) { ++summary.snowVoxels; });
    const TopologyFill fill = [&](openvdb::BoolGrid::Accessor& acc, int i0, int j0, int i1, int j1) {
      forEachSnowVoxelIn(i0, j0, i1, j1, [&](const openvdb::Coord& c, int) { acc.setValue(c, true); });
    };
    auto sdf = summary.snowVoxels > 0 ? levelSetByTiles(fill, LevelSetTiling{ni, nj, o.levelSetTileColumns}, transform, kSnowLevelSetHalfWidth)
                                      : openvdb::createLevelSet<openvdb::FloatGrid>(vs, kSnowLevelSetHalfWidth);
    return finish(sdf, "snow_sdf", openvdb::GRID_LEVEL_SET);
  });
  makers.push_back([&]() -> openvdb::GridBase::Ptr {
    auto fog = openvdb::FloatGrid::create(0.f);
    auto acc = fog->getAccessor();
    forEachSnowVoxel([&](const openvdb::Coord& c, int) { acc.setValue(c, 1.f); });
    return finish(fog, "density", openvdb::GRID_FOG_VOLUME);
  });
  static const char* const layerNames[4] = {"compacted", "stable", "unstable", "powder"};
  const double layerDensity[4] = {o.compactedKgPerM3, o.stableKgPerM3, o.unstableKgPerM3, o.powderKgPerM3};
  for (int l = 0; l < 4; ++l)
    makers.push_back([&, l]() -> openvdb::GridBase::Ptr {
      auto layer = openvdb::FloatGrid::create(0.f);
      auto acc = layer->getAccessor();
      const float density = static_cast<float>(layerDensity[l]);
      forEachSnowVoxel([&](const openvdb::Coord& c, int at) {
        if (at == l) acc.setValue(c, density);
      });
      layer->insertMeta("density_kg_per_m3", openvdb::FloatMetadata(density));
      return finish(layer, layerNames[l], openvdb::GRID_FOG_VOLUME);
    });
  writeVdbGridsOneByOneAtomically(path, makers);
  return summary;
}

}  // namespace snow
