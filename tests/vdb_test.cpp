// The OpenVDB baker, read back by OpenVDB: grid names, classes and voxel size, the level set's
// zero crossing within one voxel of the snow surface, layer densities, same bytes twice, and the
// grid-by-grid file writer giving io::File::write's bytes; the level set made tile by tile giving
// the whole construction's bytes.
#include <gtest/gtest.h>
#include <openvdb/openvdb.h>

#include <openvdb/tools/TopologyToLevelSet.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "bakers/vdb_file.h"
#include "bakers/vdb_level_set.h"
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

namespace {

std::string fileBytes(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// A file holding one level set named snow_sdf.
std::string levelSetFile(const fs::path& dir, const char* name, openvdb::FloatGrid::Ptr g) {
  g->setName("snow_sdf");
  const std::string path = (dir / name).string();
  writeVdbGridsAtomically(path, {g});
  return fileBytes(path);
}

}  // namespace

// levelSetByTiles (bakers/vdb_level_set.h) against topologyToLevelSet over the whole topology,
// tiles of 128 columns (the smallest) on topologies 300 x 260 columns wide: snow sheets on a
// slope (thin, one voxel a column at most, and thick), holes, a lone column, a blob across a tile
// corner, columns only in one tile, snow at the domain's edges. The files' bytes are equal.
TEST(Vdb, LevelSetByTilesIsTopologyToLevelSetsFileBytes) {
  openvdb::initialize();
  const fs::path dir = test::uniqueTempDir("vdb_test");
  const int ni = 300, nj = 260;
  struct Case {
    const char* name;
    std::function<int(int, int)> depth;  // voxels of snow in column (i, j) above its bed
    double voxel;
  };
  auto bed = [](int i, int j) { return 40 + (i * 7 + j * 3) / 16 + static_cast<int>(6 * std::sin(0.05 * i) * std::cos(0.07 * j)); };
  const std::vector<Case> cases = {
      {"thin sheet with holes", [](int i, int j) { return ((i * 31 + j * 17) % 11 < 4 || (i > 120 && i < 140)) ? 0 : 1; }, 1.0},
      {"thick varying sheet", [](int i, int j) { return 3 + (i * j) % 9; }, 0.5},
      {"lone column and a blob across a corner",
       [](int i, int j) {
         if (i == 5 && j == 250) return 12;
         const double r = std::hypot(i - 128.0, j - 128.0);
         return r < 20 ? static_cast<int>(20 - r) : 0;
       },
       2.0},
      {"one tile only", [](int i, int j) { return i >= 140 && i < 250 && j >= 10 && j < 120 ? 2 : 0; }, 1.0},
  };
  for (const Case& c : cases) {
    auto transform = openvdb::math::Transform::createLinearTransform(c.voxel);
    const TopologyFill fill = [&](openvdb::BoolGrid::Accessor& acc, int i0, int j0, int i1, int j1) {
      for (int j = j0; j < j1; ++j)
        for (int i = i0; i < i1; ++i)
          for (int k = 0; k < c.depth(i, j); ++k) acc.setValue(openvdb::Coord(i, j, bed(i, j) + k), true);
    };
    auto topology = openvdb::BoolGrid::create(false);
    topology->setTransform(transform);
    {
      auto acc = topology->getAccessor();
      fill(acc, 0, 0, ni, nj);
    }
    ASSERT_GT(topology->activeVoxelCount(), 0u) << c.name;
    auto whole = openvdb::tools::topologyToLevelSet(*topology, kSnowLevelSetHalfWidth, 0);
    whole->setTransform(transform);
    const std::string expected = levelSetFile(dir, "whole.vdb", whole);
    for (int tile : {128, 256, 512}) {
      auto tiled = levelSetByTiles(fill, LevelSetTiling{ni, nj, tile}, transform, kSnowLevelSetHalfWidth);
      EXPECT_EQ(tiled->tree().leafCount(), whole->tree().leafCount()) << c.name << ", tiles of " << tile;
      EXPECT_TRUE(levelSetFile(dir, "tiled.vdb", tiled) == expected) << c.name << ", tiles of " << tile << ": the files differ";
    }
  }
  EXPECT_THROW(levelSetByTiles([](openvdb::BoolGrid::Accessor&, int, int, int, int) {}, LevelSetTiling{ni, nj, 100},
                               openvdb::math::Transform::createLinearTransform(1.0), kSnowLevelSetHalfWidth),
               std::logic_error);
  fs::remove_all(dir);
}

// The writer's tile size changes its memory, not its file: a 300 x 200 cell state at 1 m voxels
// (2 x 2 m cells: 600 x 400 columns) written with tiles of 128 and as one tile.
TEST(Vdb, SnowVdbIsTheSameBytesWhateverItsLevelSetTiles) {
  SnowState s;
  GridSpec spec;
  spec.width = 300;
  spec.height = 200;
  spec.cellSizeXM = spec.cellSizeYM = 2.0;
  s.allocate(spec);
  for (int y = 0; y < spec.height; ++y)
    for (int x = 0; x < spec.width; ++x) {
      s.bedrockM(x, y) = 1000.f + 0.3f * x + 0.2f * y + 4.f * std::sin(0.1f * x);
      s.stableM(x, y) = (x * 13 + y * 7) % 5 == 0 ? 0.f : 0.4f + 0.01f * (x % 50);
      s.powderM(x, y) = 0.2f;
      if (x > 200 && y < 40) s.validCell(x, y) = 0;
    }
  const fs::path dir = test::uniqueTempDir("vdb_test");
  VdbOptions o;
  o.voxelSizeM = 1.0;
  o.levelSetTileColumns = 1024;
  writeSnowVdb((dir / "one.vdb").string(), s, o);
  o.levelSetTileColumns = 128;
  writeSnowVdb((dir / "tiled.vdb").string(), s, o);
  const std::string one = fileBytes((dir / "one.vdb").string()), tiled = fileBytes((dir / "tiled.vdb").string());
  EXPECT_GT(one.size(), 100000u);
  EXPECT_TRUE(one == tiled) << "the files differ";
  fs::remove_all(dir);
}
