// The bake's initial state made on a rank's local grid alone (bake/stages.h: initialState) holds
// exactly what the whole grid's initial state cut to that grid holds (dist::cutLocalState): the
// bake across ranks makes each rank's so (initialStateCells).
#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <string>

#include "bake/art_direction.h"
#include "bake/stages.h"
#include "distributed/local_state.h"

namespace snow {
namespace {

BakeTerrain someTerrain() {
  BakeTerrain t;
  GridSpec& spec = t.terrain.info.spec;
  spec.width = 37, spec.height = 23;
  spec.cellSizeXM = 10.0, spec.cellSizeYM = 12.5;
  spec.originX = 1000.0, spec.originY = 5000.0;
  t.terrain.heightsM.resize(spec.width, spec.height);
  t.terrain.valid.resize(spec.width, spec.height, 1);
  for (int y = 0; y < spec.height; ++y)
    for (int x = 0; x < spec.width; ++x) {
      t.terrain.heightsM(x, y) = 1500.0f + 7.0f * x - 3.0f * y + 0.25f * static_cast<float>((x * 31 + y * 17) % 11);
      if ((x * 7 + y * 5) % 13 == 0) t.terrain.valid(x, y) = 0;
    }
  return t;
}

template <class T>
void expectSameGrid(const Grid<T>& a, const Grid<T>& b, const char* name, const std::string& where) {
  ASSERT_EQ(a.width(), b.width()) << name << where;
  ASSERT_EQ(a.height(), b.height()) << name << where;
  if (a.size() > 0) {  // an absent field: no data
    EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(T))) << name << where;
  }
}

TEST(InitialState, MadeOnALocalGridIsTheWholeInitialStateCutToItFieldForField) {
  const BakeTerrain t = someTerrain();
  const GridSpec& spec = t.info().spec;
  const SnowState whole = initialState(t, CellRect::whole(spec));
  ASSERT_EQ(whole.bedrockM.width(), spec.width);
  for (const CellRect cells : {CellRect::whole(spec), CellRect{0, 0, 20, 12}, CellRect{13, 5, 37, 23}, CellRect{6, 9, 29, 16}}) {
    const std::string where = " on cells [" + std::to_string(cells.x0) + ", " + std::to_string(cells.x1) + ") x [" +
                              std::to_string(cells.y0) + ", " + std::to_string(cells.y1) + ")";
    const SnowState cut = dist::cutLocalState(whole, cells);
    const SnowState local = initialState(t, cells);
    EXPECT_EQ(local.spec.width, cut.spec.width) << where;
    EXPECT_EQ(local.spec.height, cut.spec.height) << where;
    EXPECT_EQ(local.spec.originX, cut.spec.originX) << where;
    EXPECT_EQ(local.spec.originY, cut.spec.originY) << where;
    EXPECT_EQ(local.spec.cellSizeXM, cut.spec.cellSizeXM) << where;
    EXPECT_EQ(local.spec.cellSizeYM, cut.spec.cellSizeYM) << where;
#define SNOW_EXPECT_SAME_FIELD(member, view, Element, role, access, fill) expectSameGrid(local.member, cut.member, #member, where);
    SNOW_STATE_FIELDS(SNOW_EXPECT_SAME_FIELD)
#undef SNOW_EXPECT_SAME_FIELD
    EXPECT_EQ(local.bedrockM(0, 0), t.terrain.heightsM(cells.x0, cells.y0)) << where;  // not a copy of the whole grid's corner
  }
}

// An initial depth of -0 (a scene's `-0.0`, or a raster's) is placed as +0: every kernel would
// drop the sign, so a step skipped as changing nothing (a zero rate) leaves the bytes it would.
TEST(InitialState, ADepthOfMinusZeroIsPlacedAsPlusZero) {
  const BakeTerrain t = someTerrain();
  const GridSpec& spec = t.info().spec;
  SnowState s = initialState(t, CellRect::whole(spec));
  Scene scene;
  scene.initialSnow[static_cast<size_t>(SnowLayer::Powder)] = InitialSnowLayer{InitialSnowLayer::Kind::Constant, -0.0, {}};
  scene.initialSnow[static_cast<size_t>(SnowLayer::Stable)] = InitialSnowLayer{InitialSnowLayer::Kind::Constant, 0.5, {}};
  std::ostringstream log;
  prepareArtDirection(scene, t.terrain, CellRect::whole(spec), s, log);
  size_t valid = 0;
  for (size_t i = 0; i < s.powderM.size(); ++i) {
    EXPECT_EQ(std::bit_cast<uint32_t>(s.powderM.values()[i]), 0u) << i;
    if (!s.validCell.values()[i]) continue;
    ++valid;
    EXPECT_EQ(s.stableM.values()[i], 0.5f) << i;
  }
  EXPECT_GT(valid, 0u);
}

}  // namespace
}  // namespace snow
