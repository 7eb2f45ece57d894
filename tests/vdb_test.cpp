// The OpenVDB baker, read back by OpenVDB: grid names, classes and voxel size, the level set's
// zero crossing within one voxel of the snow surface, layer densities, same bytes twice, and the
// grid-by-grid file writer giving io::File::write's bytes.
#include <gtest/gtest.h>
#include <openvdb/openvdb.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "bakers/vdb_file.h"
#include "bakers/vdb_writer.h"
#include "temp_dir.h"

using namespace snow;
namespace fs = std::filesystem;

TEST(Vdb, SnowBodyReadsBackWithItsSurfaceWithinAVoxel) {
  SnowState s;
  GridSpec spec;
  spec.width = 24;
  spec.height = 16;
  spec.cellSizeXM = spec.cellSizeYM = 2.0;
  s.allocate(spec);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 24; ++x) {
      s.bedrockM(x, y) = 1000.f + 0.5f * x + 0.25f * y;
      s.compactedM(x, y) = 0.2f;
      s.stableM(x, y) = 0.6f + 0.05f * x;
      s.unstableM(x, y) = 0.3f;
      s.powderM(x, y) = 0.4f;
    }
  const fs::path dir = test::uniqueTempDir("vdb_test");
  VdbOptions o;
  o.voxelSizeM = 0.25;
  const std::string path = (dir / "snow.vdb").string();
  const VdbSummary summary = writeSnowVdb(path, s, o);
  EXPECT_GT(summary.snowVoxels, 0u);

  openvdb::initialize();
  openvdb::io::File file(path);
  file.open();
  auto sdf = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("snow_sdf"));
  auto density = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("density"));
  auto powder = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("powder"));
  auto stable = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("stable"));
  ASSERT_TRUE(sdf && density && powder && stable);
  for (const char* name : {"compacted", "unstable"}) EXPECT_TRUE(file.readGrid(name)) << name;
  file.close();
  EXPECT_EQ(sdf->getGridClass(), openvdb::GRID_LEVEL_SET);
  EXPECT_EQ(density->getGridClass(), openvdb::GRID_FOG_VOLUME);
  EXPECT_NEAR(sdf->voxelSize()[0], 0.25, 1e-12);
  EXPECT_NEAR(density->voxelSize()[2], 0.25, 1e-12);
  // Voxel (i, j, k) holds what lies around ((i + 1/2), (j + 1/2), (k + 1/2)) x 0.25 m: its world
  // position says so (it said i x 0.25 before: the body sat half a voxel off the terrain).
  const openvdb::Vec3d c = sdf->transform().indexToWorld(openvdb::Coord(4, 5, 6));
  EXPECT_NEAR(c[0], 4.5 * 0.25, 1e-12);
  EXPECT_NEAR(c[1], 5.5 * 0.25, 1e-12);
  EXPECT_NEAR(c[2], 6.5 * 0.25, 1e-12);
  EXPECT_NEAR(density->transform().indexToWorld(openvdb::Coord(4, 5, 6))[2], 6.5 * 0.25, 1e-12);

  // Along the vertical through the centre of each cell, the level set changes sign within one
  // voxel of the snow surface (and of the bedrock below).
  auto acc = sdf->getConstAccessor();
  double worst = 0;
  for (int row = 2; row < 14; row += 3)
    for (int col = 2; col < 22; col += 3) {
      const double xm = (col + 0.5) * 2.0, yNorth = (16 - row - 0.5) * 2.0;
      const int i = static_cast<int>(xm / 0.25), j = static_cast<int>(yNorth / 0.25);
      const double surface = s.bedrockM(col, row) + s.depthM(col, row);
      double crossing = -1;
      for (int k = static_cast<int>((surface - 3) / 0.25); k < static_cast<int>((surface + 3) / 0.25); ++k)
        if (acc.getValue(openvdb::Coord(i, j, k)) < 0.f && acc.getValue(openvdb::Coord(i, j, k + 1)) >= 0.f) crossing = (k + 1) * 0.25;
      ASSERT_GT(crossing, 0) << col << "," << row;
      worst = std::max(worst, std::abs(crossing - surface));
      // The top voxel inside is powder (100 kg/m^3), one at mid-depth of the stable layer is stable.
      const int kTop = static_cast<int>(std::floor(surface / 0.25 - 0.5));
      EXPECT_FLOAT_EQ(powder->getConstAccessor().getValue(openvdb::Coord(i, j, kTop)), 100.f);
      const double midStable = s.bedrockM(col, row) + s.compactedM(col, row) + 0.5 * s.stableM(col, row);
      EXPECT_FLOAT_EQ(stable->getConstAccessor().getValue(openvdb::Coord(i, j, static_cast<int>(midStable / 0.25))), 350.f);
      EXPECT_EQ(density->getConstAccessor().getValue(openvdb::Coord(i, j, kTop)), 1.f);
    }
  EXPECT_LE(worst, 0.25);
  std::printf("[ measure ] level set zero crossing vs snow surface: worst %.3f m (voxel 0.25 m)\n", worst);

  // Same bytes when written again (the random file UUID is replaced by one from the content).
  const std::string again = (dir / "again.vdb").string();
  writeSnowVdb(again, s, o);
  std::ifstream a(path, std::ios::binary), b(again, std::ios::binary);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(a), {}), std::string(std::istreambuf_iterator<char>(b), {}));
  fs::remove_all(dir);
}

// The grid-by-grid writer (bakers/vdb_file.h) gives io::File::write's bytes for the same grids,
// but for the 36-byte tag: OpenVDB's is random, the bakers' derived from the content.
TEST(Vdb, GridByGridFileIsIoFileWriteBytesButItsTag) {
  openvdb::initialize();
  openvdb::GridPtrVec grids;
  for (int g = 0; g < 3; ++g) {
    auto grid = g == 0 ? openvdb::createLevelSet<openvdb::FloatGrid>(0.5, 3.0) : openvdb::FloatGrid::create(0.f);
    auto acc = grid->getAccessor();
    for (int i = 0; i < 40; ++i)
      for (int j = 0; j < 30; j += 2) acc.setValue(openvdb::Coord(i, j, (i * j + g) % 17), 0.25f * (i + g));
    grid->setName(std::string("grid") + char('a' + g));
    grid->setTransform(openvdb::math::Transform::createLinearTransform(0.5));
    grid->insertMeta("density_kg_per_m3", openvdb::FloatMetadata(100.f * g));
    grids.push_back(grid);
  }
  const fs::path dir = test::uniqueTempDir("vdb_test");
  const std::string ours = (dir / "ours.vdb").string(), theirs = (dir / "theirs.vdb").string();
  writeVdbGridsAtomically(ours, grids);
  openvdb::io::File file(theirs);
  file.write(grids);
  const std::string tag = file.getUniqueTag();
  file.close();
  auto bytes = [](const std::string& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  std::string a = bytes(ours), b = bytes(theirs);
  ASSERT_GT(b.size(), 1000u);
  ASSERT_EQ(a.size(), b.size());
  const size_t at = b.find(tag);
  ASSERT_LT(at, 256u);
  EXPECT_NE(a.substr(at, 36), tag);  // the content's tag, not OpenVDB's random one
  a.replace(at, 36, tag);
  EXPECT_TRUE(a == b) << "the files differ outside their tags";
}
