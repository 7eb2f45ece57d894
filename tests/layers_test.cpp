// The layer table (scene/layers.h): every row complete and its name unique, and the snow_coverage
// layer's smooth step checked cell by cell.
#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <string>

#include "scene/layers.h"
#include "scene/scene.h"

namespace snow {
namespace {

TEST(Layers, EveryRowHasAUniqueNameAUnitAContentAModeAndAComputeFunction) {
  std::set<std::string> names;
  for (const LayerInfo& l : layerTable()) {
    EXPECT_TRUE(names.insert(l.name).second) << l.name << " is listed twice";
    EXPECT_FALSE(std::string(l.unit).empty()) << l.name;
    EXPECT_FALSE(std::string(l.content).empty()) << l.name;
    EXPECT_NE(l.modes & kGridModes, 0) << l.name;
    EXPECT_EQ(l.compute != nullptr, l.kind == LayerKind::Float) << l.name << ": float layers compute, previews are drawn";
    EXPECT_EQ(findLayer(l.name), &l);
  }
  EXPECT_EQ(findLayer("no_such_layer"), nullptr);
}

TEST(Layers, SnowCoverageIsASmoothStepOfTheDepth) {
  SnowState s;
  s.allocate(GridSpec{6, 1, 1.0, 1.0});
  const float depths[] = {0.f, 0.02f, 0.085f, 0.15f, 3.f, 1.f};
  for (int x = 0; x < 6; ++x) s.stableM(x, 0) = depths[x];
  s.validCell(5, 0) = 0;  // NODATA: 0 whatever its snow
  OutputRequest outputs;
  outputs.coverageDepthsM = {0.02, 0.15};
  LayerInputs in;
  in.state = &s;
  in.outputs = &outputs;
  const Grid<float> c = findLayer("snow_coverage")->compute(in);
  EXPECT_EQ(c(0, 0), 0.f);  // bare ground
  EXPECT_EQ(c(1, 0), 0.f);  // at the bare depth
  const double t = (static_cast<double>(0.085f) - 0.02) / 0.13;
  EXPECT_FLOAT_EQ(c(2, 0), static_cast<float>(t * t * (3 - 2 * t)));  // half way: 0.5 to float precision
  EXPECT_NEAR(c(2, 0), 0.5f, 1e-6f);
  EXPECT_EQ(c(3, 0), 1.f);  // at the covered depth
  EXPECT_EQ(c(4, 0), 1.f);  // deep snow
  EXPECT_EQ(c(5, 0), 0.f);  // NODATA
}

// A frame's copy of the state leaves the record fields out unless a layer asked for reads them
// (kNeedsRecords; SeasonConfig::framesNeedRecords): every float layer not flagged so computes the
// same from a state without its record fields as from the whole state (a missing flag reads an
// empty grid here).
TEST(Layers, EveryLayerNotNeedingRecordsIsTheSameWithoutTheRecordFields) {
  const GridSpec spec{12, 9, 2.0, 2.0};
  SnowState whole;
  whole.allocate(spec);
  float v = 0.1f;
#define SNOW_FILL(member, view, Element, role, access, fill)                                     \
  if (whole.member.size() == spec.cellCount())                                                   \
    for (auto& x : whole.member.values()) x = static_cast<Element>(FieldRole::role == FieldRole::Terrain ? 1 : 0) + \
                                              static_cast<Element>(std::fmod(v += 0.37f, 3.f));
  SNOW_STATE_FIELDS(SNOW_FILL)
#undef SNOW_FILL
  for (int x = 0; x < spec.width; ++x) whole.bedrockM(x, 4) = 1000.f + x;
  whole.validCell(3, 3) = 0;
  SnowState lean = whole;
  lean.releaseFields([](FieldRole r) { return r == FieldRole::Record; });
  ASSERT_EQ(lean.meltedM.size(), 0u);
  ModelParameters params;
  OutputRequest outputs;
  outputs.coverageDepthsM = {0.02, 0.15};
  const Grid<float> windX(spec.width, spec.height, 3.f), windY(spec.width, spec.height, -2.f), windZ(spec.width, spec.height, 1002.f),
      sun(spec.width, spec.height, 6.f), ski(spec.width * 2, spec.height * 2, 0.1f), route(spec.width, spec.height, 40.f);
  OcclusionGrids occlusion{sun, sun, sun, sun};
  int compared = 0;
  for (const LayerInfo& l : layerTable()) {
    if (l.kind != LayerKind::Float || (l.needs & kNeedsRecords)) continue;
    auto compute = [&](const SnowState& s) {
      LayerInputs in{&s, &params, &outputs, &windX, &windY, &windZ, &sun, -2.0, &ski, &route, &occlusion};
      return l.compute(in);
    };
    EXPECT_TRUE(compute(whole).values() == compute(lean).values()) << l.name;
    ++compared;
  }
  EXPECT_GT(compared, 20);
}

}  // namespace
}  // namespace snow
