// The layer table (scene/layers.h): every row complete and its name unique, and the snow_coverage
// layer's smooth step checked cell by cell.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <set>
#include <string>

#include "core/season.h"
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

// A season keeps only the record fields its layers declare (LayerInfo::records;
// SeasonConfig::recordFields): every float layer computes the same from a state holding only the
// record fields it declares as from the whole state (a missing declaration reads an empty grid).
TEST(Layers, EveryLayerIsTheSameFromAStateHoldingOnlyTheRecordFieldsItDeclares) {
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
  ModelParameters params;
  OutputRequest outputs;
  outputs.coverageDepthsM = {0.02, 0.15};
  const Grid<float> windX(spec.width, spec.height, 3.f), windY(spec.width, spec.height, -2.f), windZ(spec.width, spec.height, 1002.f),
      sun(spec.width, spec.height, 6.f), ski(spec.width * 2, spec.height * 2, 0.1f), route(spec.width, spec.height, 40.f);
  OcclusionGrids occlusion{sun, sun, sun, sun};
  int compared = 0, readingRecords = 0;
  for (const LayerInfo& l : layerTable()) {
    if (l.kind != LayerKind::Float) continue;
    SnowState lean = whole;
    lean.keepRecordFields(l.records);
    ASSERT_EQ(lean.bytes([](FieldRole r) { return r == FieldRole::Record; }), std::popcount(l.records) * spec.cellCount() * sizeof(float)) << l.name;
    readingRecords += l.records != 0;
    auto compute = [&](const SnowState& s) {
      LayerInputs in{&s, &params, &outputs, &windX, &windY, &windZ, &sun, -2.0, &ski, &route, &occlusion};
      return l.compute(in);
    };
    EXPECT_TRUE(compute(whole).values() == compute(lean).values()) << l.name;
    ++compared;
  }
  EXPECT_GT(compared, 20);
  EXPECT_EQ(readingRecords, 7);  // wind scour and deposit, melt, avalanche scour, deposit, peak thickness and speed
}

// What a season keeps of its record fields: what its layers read, and the current avalanche's
// peaks where the season peaks or the per-avalanche maps are made from them.
TEST(Layers, SeasonKeepsTheRecordFieldsItsLayersReadAndThePeaksTheirsAreMadeFrom) {
  const auto bit = [](SnowField f) { return fieldBit(f); };
  const SnowFieldSet peaks = bit(SnowField::avalanchePeakThicknessM) | bit(SnowField::avalanchePeakSpeedMps);
  EXPECT_EQ(recordFieldsToKeep(layersRecords({"depth", "preview", "surface"}), false), 0u);
  EXPECT_EQ(recordFieldsToKeep(layersRecords({"melt", "wind_scour"}), false), bit(SnowField::meltedM) | bit(SnowField::windScourM));
  EXPECT_EQ(recordFieldsToKeep(layersRecords({"avalanche_peak_speed"}), false), bit(SnowField::avalancheSeasonPeakSpeedMps) | peaks);
  EXPECT_EQ(recordFieldsToKeep(layersRecords({"avalanche_preview"}), false),
            bit(SnowField::avalancheScourM) | bit(SnowField::avalancheDepositM));
  EXPECT_EQ(recordFieldsToKeep(0, true), peaks);
  EXPECT_EQ(std::popcount(kAllRecordFields), 9);
}

}  // namespace
}  // namespace snow
