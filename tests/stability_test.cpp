// The stability rates' defaults against their documented targets (docs/models/season.md): a
// storm's unstable snow on release terrain halves in one to three days at T_cool, stays at
// T_freeze and below, and warmth above 0 °C destabilises stable snow within a day or two.
#include <gtest/gtest.h>

#include <cstdio>

#include "core/stability_study.h"

namespace snow {
namespace {

constexpr double kSlope = 0.7;   // 35 degrees
constexpr double kStormM = 0.4;  // a 3-day storm's snow at 2300 m

TEST(StabilityRates, StormSnowHalvesInOneToThreeDaysAtMinusFive) {
  const StabilityOutcome r = unstableHalfLife(ModelParameters{}, -5.0, kSlope, kStormM, 30.0);
  std::printf("[ measure ] half-life at -5 C on 35 deg: %.1f days\n", r.days);
  ASSERT_TRUE(r.reached);
  EXPECT_GE(r.days, 1.0);
  EXPECT_LE(r.days, 3.0);
}

TEST(StabilityRates, NothingStabilisesAtMinusTwentyFive) {
  const StabilityOutcome r = unstableHalfLife(ModelParameters{}, -25.0, kSlope, kStormM, 30.0);
  EXPECT_FALSE(r.reached) << "unstable snow halved in " << r.days << " days at -25 C";
}

TEST(StabilityRates, WarmthAboveZeroDestabilisesWithinTwoDays) {
  for (double t : {1.0, 2.0, 5.0}) {
    const StabilityOutcome r = stableHalfLife(ModelParameters{}, t, kSlope, kStormM, 30.0);
    std::printf("[ measure ] half of the stable snow unstable at %+.0f C: %.1f days\n", t, r.days);
    ASSERT_TRUE(r.reached) << t << " C";
    EXPECT_LE(r.days, 2.0) << t << " C";
  }
}

TEST(StabilityRates, TableTwosRateTurnsEverythingOverInOneStep) {
  ModelParameters p;
  p.stabilityByColdMPerDay = 1e4;  // still available as a setting: the switch it makes
  const StabilityOutcome r = unstableHalfLife(p, -10.0, kSlope, kStormM, 30.0);
  ASSERT_TRUE(r.reached);
  EXPECT_DOUBLE_EQ(r.days, 1.0 / p.stateChangeStepsPerDay);
}

}  // namespace
}  // namespace snow
