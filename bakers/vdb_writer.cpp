#include "vdb_writer.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/TopologyToLevelSet.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "core/atomic_file.h"
#include "core/hash.h"
#include "vdb_file.h"

namespace snow {

void writeVdbGridsAtomically(const std::string& path, const openvdb::GridPtrVec& grids) {
  writeAtomically(path, [&](const std::string& temp) {
    openvdb::io::File file(temp);
    file.write(grids);
    const std::string tag = file.getUniqueTag();
    file.close();
    // OpenVDB stamps each file with a random UUID; replace it with one derived from the content
    // so the same bake gives the same bytes. The content is hashed in chunks as it is read (the
    // file is not held in memory: it was, twice) and the 36 bytes are patched in place.
    std::ifstream in(temp, std::ios::binary);
    std::string head(512, '\0');  // the tag is looked for in the first 256 bytes
    in.read(head.data(), static_cast<std::streamsize>(head.size()));
    head.resize(static_cast<size_t>(in.gcount()));
    const size_t at = head.find(tag);
    if (tag.size() == 36 && at != std::string::npos && at < 256) {
      head.replace(at, tag.size(), std::string(tag.size(), '0'));
      Fnv1a64 ha, hb;
      hb.add("snowbake");
      ha.add(head), hb.add(head);
      std::vector<char> chunk(1 << 20);
      while (in) {
        in.read(chunk.data(), static_cast<std::streamsize>(chunk.size()));
        const size_t n = static_cast<size_t>(in.gcount());
        ha.add(chunk.data(), n), hb.add(chunk.data(), n);
      }
      in.close();
      const uint64_t a = ha.value(), b = hb.value();
      char uuid[40];
      std::snprintf(uuid, sizeof uuid, "%08x-%04x-%04x-%04x-%012llx", static_cast<unsigned>(a >> 32), static_cast<unsigned>((a >> 16) & 0xffff),
                    static_cast<unsigned>(a & 0xffff), static_cast<unsigned>(b >> 48), static_cast<unsigned long long>(b & 0xffffffffffffull));
      std::fstream out(temp, std::ios::binary | std::ios::in | std::ios::out);
      out.seekp(static_cast<std::streamoff>(at));
      out.write(uuid, 36);
      if (!out) throw std::runtime_error("cannot write " + path);
    }
  });
}

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
  // Calls f(coord, layer) for every snow voxel, column by column.
  const int ni = static_cast<int>(std::ceil(w * dx / vs)), nj = static_cast<int>(std::ceil(h * dy / vs));
  auto forEachSnowVoxel = [&](auto&& f) {
    for (int j = 0; j < nj; ++j) {
      const double yNorth = (j + 0.5) * vs;  // metres north of the south edge
      const int row = h - 1 - std::min(h - 1, static_cast<int>(yNorth / dy));
      for (int i = 0; i < ni; ++i) {
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
  // The level set first, from the topology alone, which is then freed: its construction's
  // dilation and normalisation (the writer's largest transient) never stand beside the density
  // and layer grids.
  openvdb::FloatGrid::Ptr sdf;
  {
    auto topology = openvdb::BoolGrid::create(false);
    auto topoAcc = topology->getAccessor();
    forEachSnowVoxel([&](const openvdb::Coord& c, int) {
      topoAcc.setValue(c, true);
      ++summary.snowVoxels;
    });
    topology->setTransform(transform);  // the level set's distances in metres
    sdf = summary.snowVoxels > 0 ? openvdb::tools::topologyToLevelSet(*topology, 3, 0)
                                 : openvdb::createLevelSet<openvdb::FloatGrid>(vs, 3.0);
  }
  auto fog = openvdb::FloatGrid::create(0.f);
  const char* layerNames[4] = {"compacted", "stable", "unstable", "powder"};
  const double layerDensity[4] = {o.compactedKgPerM3, o.stableKgPerM3, o.unstableKgPerM3, o.powderKgPerM3};
  openvdb::FloatGrid::Ptr layers[4];
  for (int l = 0; l < 4; ++l) layers[l] = openvdb::FloatGrid::create(0.f);
  std::vector<openvdb::FloatGrid::Accessor> layerAcc;
  for (int l = 0; l < 4; ++l) layerAcc.push_back(layers[l]->getAccessor());
  auto fogAcc = fog->getAccessor();
  forEachSnowVoxel([&](const openvdb::Coord& c, int l) {
    fogAcc.setValue(c, 1.f);
    layerAcc[l].setValue(c, static_cast<float>(layerDensity[l]));
  });
  openvdb::GridPtrVec grids;
  sdf->setTransform(transform);
  sdf->setName("snow_sdf");
  sdf->setGridClass(openvdb::GRID_LEVEL_SET);
  grids.push_back(sdf);
  fog->setTransform(transform);
  fog->setName("density");
  fog->setGridClass(openvdb::GRID_FOG_VOLUME);
  grids.push_back(fog);
  for (int l = 0; l < 4; ++l) {
    layers[l]->setTransform(transform);
    layers[l]->setName(layerNames[l]);
    layers[l]->setGridClass(openvdb::GRID_FOG_VOLUME);
    layers[l]->insertMeta("density_kg_per_m3", openvdb::FloatMetadata(static_cast<float>(layerDensity[l])));
    grids.push_back(layers[l]);
  }
  writeVdbGridsAtomically(path, grids);
  return summary;
}

}  // namespace snow
